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
//!
//! In the displacement-pressure form (`navier::formulation`) the displacement terms
//! are those above with `lambda = 0`, the Navier rows gain `-grad p`, the traction rows
//! `-p n`, and every node and ghost a continuity row `a div u + b p / mu = 0`
//! (stabilised by `- tau h^2 ((a + 2b) lap p - a div f) / mu` where the node has
//! second-derivative shapes, `navier::formulation`). The
//! pressure unknown is `p / mu` (a strain, like the displacement gradient), so that
//! the columns of `u` and `p` have comparable scales whatever the units.

use crate::domain::neighbors::Supports;
use crate::physics::elasticity::dofs::{DofMap, Unknowns, PRESSURE};
use crate::physics::elasticity::material::Lame;
use crate::linalg::triplets::{stored, StoredEntry};
use crate::mlsm::{Op, Shapes};

/// Coefficients `(row, column, value)` written for one node.
pub type Entries = Vec<StoredEntry>;

/// Writes rows for nodes of one discretisation.
pub struct RowWriter<'a> {
    /// Unknown layout.
    pub dofs: DofMap,
    /// Material in the planar model.
    pub lame: Lame,
    /// Weights `(a, b)` of the continuity row (`Material::pressure_weights`).
    pub pressure_weights: (f64, f64),
    /// Support of each node.
    pub supports: &'a Supports,
    /// Shape functions.
    pub shapes: &'a Shapes,
    /// `tau` of the continuity rows' stabilisation (`navier::formulation`; 0: none).
    pub stabilisation: f64,
    /// Local spacing `h` of each node, for that stabilisation.
    pub local_spacing: &'a [f64],
}

impl RowWriter<'_> {
    /// Whether the unknowns include the pressure.
    fn has_pressure(&self) -> bool {
        self.dofs.unknowns() == Unknowns::DisplacementPressure
    }

    /// The Lame parameters of the displacement terms: `lambda = 0` in the
    /// displacement-pressure form, where `lambda div u` is the unknown `-p`.
    fn displacement_lame(&self) -> Lame {
        if self.has_pressure() {
            Lame { lambda: 0.0, mu: self.lame.mu }
        } else {
            self.lame
        }
    }

    /// Navier rows (x and y) at node `i`, `(lambda + mu) grad div u + mu lap u`,
    /// component `c` written in row `c` of node `row_nodes[c]` (`i` itself, or its
    /// ghost).
    pub fn navier(&self, i: usize, row_nodes: [usize; 2], out: &mut Entries) {
        let Lame { lambda, mu } = self.displacement_lame();
        let pressure = self.has_pressure();
        let (xx, xy, yy) = (self.shapes.get(i, Op::Dxx), self.shapes.get(i, Op::Dxy), self.shapes.get(i, Op::Dyy));
        let (rx, ry) = (self.dofs.dof(row_nodes[0], 0), self.dofs.dof(row_nodes[1], 1));
        for (k, &j) in self.supports.of(i).iter().enumerate() {
            let (uj, vj) = (self.dofs.dof(j as usize, 0), self.dofs.dof(j as usize, 1));
            out.push(stored(rx, uj, (lambda + 2.0 * mu) * xx[k] + mu * yy[k]));
            out.push(stored(rx, vj, (lambda + mu) * xy[k]));
            out.push(stored(ry, uj, (lambda + mu) * xy[k]));
            out.push(stored(ry, vj, mu * xx[k] + (lambda + 2.0 * mu) * yy[k]));
        }
        if pressure {
            let (dx, dy) = (self.shapes.get(i, Op::Dx), self.shapes.get(i, Op::Dy));
            for (k, &j) in self.supports.of(i).iter().enumerate() {
                let pj = self.dofs.dof(j as usize, PRESSURE);
                out.push(stored(rx, pj, -mu * dx[k]));
                out.push(stored(ry, pj, -mu * dy[k]));
            }
        }
    }

    /// Traction row of component `c` at node `i`, `(sigma(u) n)_c`, written in row `c`
    /// of node `row_node` (`i` itself, or its ghost).
    pub fn traction(&self, i: usize, row_node: usize, c: usize, n: [f64; 2], out: &mut Entries) {
        let Lame { lambda, mu } = self.displacement_lame();
        let (dx, dy) = (self.shapes.get(i, Op::Dx), self.shapes.get(i, Op::Dy));
        let r = self.dofs.dof(row_node, c);
        for (k, &j) in self.supports.of(i).iter().enumerate() {
            let (uj, vj) = (self.dofs.dof(j as usize, 0), self.dofs.dof(j as usize, 1));
            let (cu, cv) = if c == 0 {
                ((lambda + 2.0 * mu) * dx[k] * n[0] + mu * dy[k] * n[1], lambda * dy[k] * n[0] + mu * dx[k] * n[1])
            } else {
                (mu * dy[k] * n[0] + lambda * dx[k] * n[1], mu * dx[k] * n[0] + (lambda + 2.0 * mu) * dy[k] * n[1])
            };
            out.push(stored(r, uj, cu));
            out.push(stored(r, vj, cv));
        }
        if self.has_pressure() {
            out.push(stored(r, self.dofs.dof(i, PRESSURE), -mu * n[c]));
        }
    }

    /// Continuity row of the displacement-pressure form at node `i`, written in its
    /// own pressure row: `a div u + b p / mu = 0`, stabilised where the node has
    /// second-derivative shapes by `- tau h^2 (a + 2b) lap p / mu` (its right-hand side
    /// `- tau h^2 a div f / mu`, [`continuity_load`]; `navier::formulation`).
    pub fn continuity(&self, i: usize, out: &mut Entries) {
        let (a, b) = self.pressure_weights;
        let (dx, dy) = (self.shapes.get(i, Op::Dx), self.shapes.get(i, Op::Dy));
        let r = self.dofs.dof(i, PRESSURE);
        for (k, &j) in self.supports.of(i).iter().enumerate() {
            out.push(stored(r, self.dofs.dof(j as usize, 0), a * dx[k]));
            out.push(stored(r, self.dofs.dof(j as usize, 1), a * dy[k]));
        }
        out.push(stored(r, r, b));
        if let Some(w) = self.stabilisation(i) {
            let (xx, yy) = (self.shapes.get(i, Op::Dxx), self.shapes.get(i, Op::Dyy));
            for (k, &j) in self.supports.of(i).iter().enumerate() {
                out.push(stored(r, self.dofs.dof(j as usize, PRESSURE), -w * (a + 2.0 * b) * (xx[k] + yy[k])));
            }
        }
    }

    /// `tau h^2` of node `i`'s continuity row, where it is stabilised (the node has
    /// second-derivative shapes: interior nodes and nodes with a ghost).
    pub fn stabilisation(&self, i: usize) -> Option<f64> {
        (self.stabilisation > 0.0 && self.shapes.computed_at(i).contains(Op::Dxx))
            .then(|| self.stabilisation * self.local_spacing[i].powi(2))
    }

    /// Right-hand side of node `i`'s stabilised continuity row, `- tau h^2 a div f / mu`,
    /// with `div f` from the gradient shapes over the body force `f_at(j)` at the
    /// support's nodes; zero where the row is not stabilised.
    pub fn continuity_load(&self, i: usize, f_at: impl Fn(usize) -> [f64; 2]) -> f64 {
        let Some(w) = self.stabilisation(i) else { return 0.0 };
        let (dx, dy) = (self.shapes.get(i, Op::Dx), self.shapes.get(i, Op::Dy));
        let div_f: f64 = self
            .supports
            .of(i)
            .iter()
            .enumerate()
            .map(|(k, &j)| {
                let f = f_at(j as usize);
                dx[k] * f[0] + dy[k] * f[1]
            })
            .sum();
        -w * self.pressure_weights.0 * div_f / self.lame.mu
    }

    /// Normal derivative of the continuity row at boundary node `i` with outward
    /// normal `n`, `d/dn (a div u + b p / mu) = 0`, written in the pressure row of
    /// `row_node` (its ghost).
    pub fn continuity_normal_derivative(&self, i: usize, row_node: usize, n: [f64; 2], out: &mut Entries) {
        let (a, b) = self.pressure_weights;
        let (dx, dy) = (self.shapes.get(i, Op::Dx), self.shapes.get(i, Op::Dy));
        let (xx, xy, yy) = (self.shapes.get(i, Op::Dxx), self.shapes.get(i, Op::Dxy), self.shapes.get(i, Op::Dyy));
        let r = self.dofs.dof(row_node, PRESSURE);
        for (k, &j) in self.supports.of(i).iter().enumerate() {
            let j = j as usize;
            out.push(stored(r, self.dofs.dof(j, 0), a * (n[0] * xx[k] + n[1] * xy[k])));
            out.push(stored(r, self.dofs.dof(j, 1), a * (n[0] * xy[k] + n[1] * yy[k])));
            out.push(stored(r, self.dofs.dof(j, PRESSURE), b * (n[0] * dx[k] + n[1] * dy[k])));
        }
    }

    /// Displacement row of component `c` at node `i`, `u_c`, written in row `c` of
    /// node `row_node` (`i` itself, or its ghost).
    pub fn displacement(&self, i: usize, row_node: usize, c: usize, out: &mut Entries) {
        out.push(stored(self.dofs.dof(row_node, c), self.dofs.dof(i, c), 1.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::dofs::Unknowns;
    use crate::mlsm::{compute_shapes, OpSet};

    /// A 7 x 7 lattice of spacing 0.1 (node 24 at the centre), supports of 13 nodes and
    /// degree-2 shapes of every derivative at every node.
    fn lattice() -> (Vec<[f64; 2]>, Supports, Shapes) {
        let positions: Vec<[f64; 2]> = (0..49).map(|k| [0.1 * (k % 7) as f64 - 0.3, 0.1 * (k / 7) as f64 - 0.3]).collect();
        let supports = Supports::nearest(&positions, 13);
        let approximation = crate::mlsm::shapes::test_least_squares(13);
        let shapes = compute_shapes(&positions, &supports, &approximation, &[OpSet::D1 | OpSet::D2; 49]).unwrap();
        (positions, supports, shapes)
    }

    /// `sum_j a_rj x_j` for every row the entries touch.
    fn apply(entries: &Entries, x: &[f64]) -> std::collections::BTreeMap<usize, f64> {
        let mut rows = std::collections::BTreeMap::new();
        for &(r, c, v) in entries {
            *rows.entry(r as usize).or_insert(0.0) += v * x[c as usize];
        }
        rows
    }

    /// Degree-2 shapes differentiate quadratics exactly, so every row evaluated on the
    /// nodal values of a quadratic field equals its equation evaluated on the field
    /// itself, up to round-off of the local solves (1e-9 of the second derivatives,
    /// which are O(1) here while the shapes are O(1/h^2) = O(100)).
    #[test]
    fn rows_are_exact_on_quadratic_fields() {
        let (positions, supports, shapes) = lattice();
        let lame = Lame { lambda: 2.0, mu: 0.7 };
        let dofs = DofMap::displacement_only(positions.len());
        let writer = RowWriter {
            dofs,
            lame,
            pressure_weights: (0.0, 1.0),
            supports: &supports,
            shapes: &shapes,
            stabilisation: 0.0,
            local_spacing: &[],
        };
        // u = x + 0.5 x^2 - xy + 2 y^2, v = -y + 3 x y + 0.25 x^2.
        let field =
            |p: [f64; 2]| [p[0] + 0.5 * p[0] * p[0] - p[0] * p[1] + 2.0 * p[1] * p[1], -p[1] + 3.0 * p[0] * p[1] + 0.25 * p[0] * p[0]];
        let x = dofs.from_displacements(|i| field(positions[i]));
        let (uxx, uxy, uyy, vxx, vxy, vyy) = (1.0, -1.0, 4.0, 0.5, 3.0, 0.0);
        let (l, m) = (lame.lambda, lame.mu);

        let mut e = Entries::new();
        writer.navier(24, [24, 24], &mut e);
        let rows = apply(&e, &x);
        let navier = [(l + 2.0 * m) * uxx + m * uyy + (l + m) * vxy, (l + m) * uxy + m * vxx + (l + 2.0 * m) * vyy];
        for c in 0..2 {
            assert!((rows[&dofs.dof(24, c)] - navier[c]).abs() < 1e-9, "Navier row {c}: {} vs {}", rows[&dofs.dof(24, c)], navier[c]);
        }

        // Traction rows at node 23 with a unit normal, written into the rows of node 5.
        let n = [0.6, 0.8];
        let p = positions[23];
        let g = [[1.0 + p[0] - p[1], -p[0] + 4.0 * p[1]], [3.0 * p[1] + 0.5 * p[0], -1.0 + 3.0 * p[0]]];
        let sigma = lame.stress(g);
        let sn = [sigma[0] * n[0] + sigma[2] * n[1], sigma[2] * n[0] + sigma[1] * n[1]];
        for c in 0..2 {
            let mut e = Entries::new();
            writer.traction(23, 5, c, n, &mut e);
            let rows = apply(&e, &x);
            assert_eq!(rows.keys().copied().collect::<Vec<_>>(), vec![dofs.dof(5, c)]);
            assert!((rows[&dofs.dof(5, c)] - sn[c]).abs() < 1e-9, "traction row {c}");
        }

        // A displacement row is the identity row of its unknown.
        let mut e = Entries::new();
        writer.displacement(3, 3, 1, &mut e);
        assert_eq!(e, vec![stored(dofs.dof(3, 1), dofs.dof(3, 1), 1.0)]);
    }

    /// The stabilised continuity row on a quadratic `u` and pressure unknown `q = p / mu`
    /// is `a div u + b q - tau h^2 (a + 2b) lap q`, its right-hand side
    /// `- tau h^2 a div f / mu` (exact for quadratics and a linear `f` on degree-2
    /// shapes, up to the local solves' round-off, 1e-9 as above); with `tau = 0` both
    /// terms are absent.
    #[test]
    fn the_stabilised_continuity_row_adds_the_pressure_laplacian() {
        let (positions, supports, shapes) = lattice();
        let (lame, (a, b), tau, h) = (Lame { lambda: 2.0, mu: 0.7 }, (0.6, 0.4), 0.3, 0.1);
        let dofs = DofMap::new(positions.len(), Unknowns::DisplacementPressure);
        let spacing = vec![h; positions.len()];
        let writer = |stabilisation| RowWriter {
            dofs,
            lame,
            pressure_weights: (a, b),
            supports: &supports,
            shapes: &shapes,
            stabilisation,
            local_spacing: &spacing,
        };
        // u as above (div u = 4x - y), q = 1 + x + 2y + 0.5 x^2 + y^2 (lap q = 3), at node 24 = (0, 0).
        let mut x = dofs.from_displacements(|i| {
            let p = positions[i];
            [p[0] + 0.5 * p[0] * p[0] - p[0] * p[1] + 2.0 * p[1] * p[1], -p[1] + 3.0 * p[0] * p[1] + 0.25 * p[0] * p[0]]
        });
        for (i, p) in positions.iter().enumerate() {
            x[dofs.dof(i, PRESSURE)] = 1.0 + p[0] + 2.0 * p[1] + 0.5 * p[0] * p[0] + p[1] * p[1];
        }
        let f = |j: usize| [2.0 * positions[j][0] + positions[j][1], positions[j][0] - 3.0 * positions[j][1]]; // div f = -1
        for (stabilisation, row, load) in [(tau, b - tau * h * h * (a + 2.0 * b) * 3.0, tau * h * h * a / lame.mu), (0.0, b, 0.0)] {
            let mut e = Entries::new();
            writer(stabilisation).continuity(24, &mut e);
            let got = apply(&e, &x)[&dofs.dof(24, PRESSURE)];
            assert!((got - row).abs() < 1e-9, "tau = {stabilisation}: row {got} against {row}");
            let got = writer(stabilisation).continuity_load(24, f);
            assert!((got - load).abs() < 1e-9, "tau = {stabilisation}: load {got} against {load}");
        }
    }
}
