//! Equation rows of the collocation system. Each method writes every coefficient of
//! its equation(s) for one node; [`DofMap`] places them.
//!
//! With shape functions `phi_L` over the support `I(i)` (seeds-digest, 002):
//! * Navier (interior), `(lambda + mu) grad div u + mu lap u + f = 0`:
//!   x: `(lambda+2mu) u_xx + mu u_yy + (lambda+mu) v_xy = -f_x`,
//!   y: `(lambda+mu) u_xy + mu v_xx + (lambda+2mu) v_yy = -f_y`;
//! * traction, `sigma(u) n = t` with `sigma_xx = (lambda+2mu) u_x + lambda v_y`,
//!   `sigma_yy = lambda u_x + (lambda+2mu) v_y`, `sigma_xy = mu (u_y + v_x)`:
//!   x: `sigma_xx n_x + sigma_xy n_y = t_x`, y: `sigma_xy n_x + sigma_yy n_y = t_y`;
//! * displacement, `u_c = g_c`.

use crate::domain::neighbors::Supports;
use crate::elasticity::dofs::DofMap;
use crate::elasticity::material::Lame;
use crate::mlsm::{Op, Shapes};

/// Coefficients `(row, column, value)` written for one node.
pub type Entries = Vec<(usize, usize, f64)>;

/// Writes rows for nodes of one discretisation.
pub struct RowWriter<'a> {
    /// Unknown layout.
    pub dofs: DofMap,
    /// Material in the planar model.
    pub lame: Lame,
    /// Support of each node.
    pub supports: &'a Supports,
    /// Shape functions.
    pub shapes: &'a Shapes,
}

impl RowWriter<'_> {
    /// Navier rows (x and y) at node `i` with body force `f`, written in the rows of
    /// node `row_node` (`i` itself, or its ghost); returns the right-hand sides.
    pub fn navier(&self, i: usize, row_node: usize, f: [f64; 2], out: &mut Entries) -> [f64; 2] {
        let Lame { lambda, mu } = self.lame;
        let (xx, xy, yy) = (self.shapes.get(i, Op::Dxx), self.shapes.get(i, Op::Dxy), self.shapes.get(i, Op::Dyy));
        let (rx, ry) = (self.dofs.dof(row_node, 0), self.dofs.dof(row_node, 1));
        for (k, &j) in self.supports.of(i).iter().enumerate() {
            let (uj, vj) = (self.dofs.dof(j as usize, 0), self.dofs.dof(j as usize, 1));
            out.push((rx, uj, (lambda + 2.0 * mu) * xx[k] + mu * yy[k]));
            out.push((rx, vj, (lambda + mu) * xy[k]));
            out.push((ry, uj, (lambda + mu) * xy[k]));
            out.push((ry, vj, mu * xx[k] + (lambda + 2.0 * mu) * yy[k]));
        }
        [-f[0], -f[1]]
    }

    /// Traction row of component `c` at node `i`, `(sigma(u) n)_c = t`, written in row `c`
    /// of node `row_node` (`i` itself, or its ghost); returns the right-hand side.
    pub fn traction(&self, i: usize, row_node: usize, c: usize, n: [f64; 2], t: f64, out: &mut Entries) -> f64 {
        let Lame { lambda, mu } = self.lame;
        let (dx, dy) = (self.shapes.get(i, Op::Dx), self.shapes.get(i, Op::Dy));
        let r = self.dofs.dof(row_node, c);
        for (k, &j) in self.supports.of(i).iter().enumerate() {
            let (uj, vj) = (self.dofs.dof(j as usize, 0), self.dofs.dof(j as usize, 1));
            let (cu, cv) = if c == 0 {
                ((lambda + 2.0 * mu) * dx[k] * n[0] + mu * dy[k] * n[1], lambda * dy[k] * n[0] + mu * dx[k] * n[1])
            } else {
                (mu * dy[k] * n[0] + lambda * dx[k] * n[1], mu * dx[k] * n[0] + (lambda + 2.0 * mu) * dy[k] * n[1])
            };
            out.push((r, uj, cu));
            out.push((r, vj, cv));
        }
        t
    }

    /// Displacement row of component `c` at node `i`: `u_c = g`; returns the right-hand side.
    pub fn displacement(&self, i: usize, c: usize, g: f64, out: &mut Entries) -> f64 {
        let r = self.dofs.dof(i, c);
        out.push((r, r, 1.0));
        g
    }
}
