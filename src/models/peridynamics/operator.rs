//! The discrete operator `(L_h u)_i = sum_j c_ij (xi_ij ⊗ xi_ij)(u_j - u_i)` and the
//! static stiffness.
//!
//! The equation of free node `i` is multiplied by its volume `V_i` (force instead of
//! force density): `-V_i (L_h u)_i = V_i b_i`. Then `K_ij = -V_i c_ij xi ⊗ xi` for
//! `j != i` and `K_ii = V_i sum_j c_ij xi ⊗ xi`, symmetric whenever
//! `V_i c_ij = V_j c_ji` (every rule but the compatible one, see `weights`), and the
//! constrained nodes' prescribed displacements move to the right-hand side.
//! Unknowns are those of `PdNodes::dofs` (the free nodes' displacements, interleaved,
//! so that the two rows of a node are consecutive).

use super::family::Families;
use super::nodes::PdNodes;
use crate::domain::Point;
use crate::linalg::Csr;
use rayon::prelude::*;

/// Families with their bond coefficients.
#[derive(Clone, Copy)]
pub struct Bonds<'a> {
    /// Nodes (positions, volumes, constrained values).
    pub nodes: &'a PdNodes,
    /// Neighbours of each free node.
    pub families: &'a Families,
    /// `c_ij` per bond, in family order.
    pub coefficients: &'a [f64],
}

/// `xi ⊗ xi` as `[xx, xy, yy]`.
fn outer(xi: Point) -> [f64; 3] {
    [xi[0] * xi[0], xi[0] * xi[1], xi[1] * xi[1]]
}

impl Bonds<'_> {
    fn bond(&self, i: usize, b: usize, j: u32) -> (usize, f64, [f64; 3]) {
        let (p, q) = (self.nodes.positions[i], self.nodes.positions[j as usize]);
        (j as usize, self.coefficients[b], outer([q[0] - p[0], q[1] - p[1]]))
    }

    /// `(L_h u)_i` at free node `i`, with `u_of(j)` the displacement of node `j`.
    pub fn force_at(&self, i: usize, u_of: impl Fn(usize) -> [f64; 2]) -> [f64; 2] {
        let ui = u_of(i);
        let mut f = [0.0, 0.0];
        for (b, &j) in self.families.range(i).zip(self.families.of(i)) {
            let (j, c, [xx, xy, yy]) = self.bond(i, b, j);
            let uj = u_of(j);
            let d = [uj[0] - ui[0], uj[1] - ui[1]];
            f[0] += c * (xx * d[0] + xy * d[1]);
            f[1] += c * (xy * d[0] + yy * d[1]);
        }
        f
    }

    /// `(L_h u)_i` for every free node; `u` holds all nodes (constrained ones too).
    pub fn apply(&self, u: &[[f64; 2]]) -> Vec<[f64; 2]> {
        (0..self.nodes.free).into_par_iter().map(|i| self.force_at(i, |j| u[j])).collect()
    }

    /// The stiffness over the free unknowns, built row by row directly in compressed
    /// form (families are sorted, so every row's columns are too), and the right-hand
    /// side `V_i b_i + sum_{j constrained} V_i c_ij (xi ⊗ xi) u_j`. Returns the first
    /// row holding a non-finite coefficient as an error.
    pub fn stiffness(&self, body_force: &[[f64; 2]]) -> Result<(Csr, Vec<f64>), usize> {
        self.stiffness_rows(body_force, |_| true)
    }

    /// [`Bonds::stiffness`] with only the rows of the free nodes `own` accepts: the
    /// other nodes' rows are empty and their right-hand side zero (an MPI rank
    /// assembles the rows of the nodes it owns, [`crate::parallel::distributed`]).
    pub fn stiffness_rows(&self, body_force: &[[f64; 2]], own: impl Fn(usize) -> bool + Sync) -> Result<(Csr, Vec<f64>), usize> {
        let free = self.nodes.free;
        let dofs = self.nodes.dofs();
        let node_cols = |i: usize| [dofs.dof(i, 0), dofs.dof(i, 1)];
        // Per node: the column indices of its rows and the values of its x and y rows.
        // Per node: columns, x-row values, y-row values, right-hand side.
        type NodeRows = (Vec<usize>, Vec<f64>, Vec<f64>, [f64; 2]);
        let rows: Vec<NodeRows> = (0..free)
            .into_par_iter()
            .map(|i| {
                if !own(i) {
                    return (Vec::new(), Vec::new(), Vec::new(), [0.0; 2]);
                }
                let v = self.nodes.volumes[i];
                let k = self.families.of(i).len() + 1;
                let (mut cols, mut top, mut bottom) = (Vec::with_capacity(2 * k), Vec::with_capacity(2 * k), Vec::with_capacity(2 * k));
                let mut diag = [0.0; 3];
                let mut diag_at = None;
                let mut rhs = [v * body_force[i][0], v * body_force[i][1]];
                for (b, &j) in self.families.range(i).zip(self.families.of(i)) {
                    let (j, c, m) = self.bond(i, b, j);
                    let kb = [v * c * m[0], v * c * m[1], v * c * m[2]];
                    for a in 0..3 {
                        diag[a] += kb[a];
                    }
                    if j < free {
                        if diag_at.is_none() && j > i {
                            diag_at = Some(cols.len());
                            cols.extend(node_cols(i));
                            top.extend([0.0, 0.0]);
                            bottom.extend([0.0, 0.0]);
                        }
                        cols.extend(node_cols(j));
                        top.extend([-kb[0], -kb[1]]);
                        bottom.extend([-kb[1], -kb[2]]);
                    } else {
                        let u = self.nodes.prescribed[j - free];
                        rhs[0] += kb[0] * u[0] + kb[1] * u[1];
                        rhs[1] += kb[1] * u[0] + kb[2] * u[1];
                    }
                }
                let d = match diag_at {
                    Some(d) => d,
                    None => {
                        cols.extend(node_cols(i));
                        top.extend([0.0, 0.0]);
                        bottom.extend([0.0, 0.0]);
                        cols.len() - 2
                    }
                };
                top[d] = diag[0];
                top[d + 1] = diag[1];
                bottom[d] = diag[1];
                bottom[d + 1] = diag[2];
                (cols, top, bottom, rhs)
            })
            .collect();
        if let Some(bad) = rows.iter().position(|r| r.1.iter().chain(&r.2).chain(&r.3).any(|v| !v.is_finite())) {
            return Err(bad);
        }
        let nnz: usize = rows.iter().map(|r| 2 * r.0.len()).sum();
        let n = dofs.len();
        let (mut row_ptr, mut col_idx, mut values) = (Vec::with_capacity(n + 1), Vec::with_capacity(nnz), Vec::with_capacity(nnz));
        let mut rhs = Vec::with_capacity(n);
        row_ptr.push(0);
        for (cols, top, bottom, r) in rows {
            for vals in [top, bottom] {
                col_idx.extend(cols.iter().map(|&c| c as u32));
                values.extend(vals);
                row_ptr.push(col_idx.len());
            }
            rhs.extend(r);
        }
        Ok((Csr::from_parts(n, n, row_ptr, col_idx, values), rhs))
    }
}
