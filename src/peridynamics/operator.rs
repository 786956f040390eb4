//! The discrete operator `(L_h u)_i = sum_j c_ij (xi_ij ⊗ xi_ij)(u_j - u_i)` and the
//! static stiffness.
//!
//! The equation of free node `i` is multiplied by its volume `V_i` (force instead of
//! force density): `-V_i (L_h u)_i = V_i b_i`. Then `K_ij = -V_i c_ij xi ⊗ xi` for
//! `j != i` and `K_ii = V_i sum_j c_ij xi ⊗ xi`, symmetric whenever
//! `V_i c_ij = V_j c_ji` (every rule but the compatible one, see `weights`), and the
//! constrained nodes' prescribed displacements move to the right-hand side.
//! Unknowns are interleaved: `2 i + c` for free node `i`, component `c`.

use super::family::Families;
use super::nodes::PdNodes;
use crate::domain::Point;
use crate::linalg::Triplets;
use rayon::prelude::*;

/// Families with their bond coefficients.
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

    /// `(L_h u)_i` for every free node; `u` holds all nodes (constrained ones too).
    pub fn apply(&self, u: &[[f64; 2]]) -> Vec<[f64; 2]> {
        (0..self.nodes.free)
            .into_par_iter()
            .map(|i| {
                let mut f = [0.0, 0.0];
                for (b, &j) in self.families.range(i).zip(self.families.of(i)) {
                    let (j, c, [xx, xy, yy]) = self.bond(i, b, j);
                    let d = [u[j][0] - u[i][0], u[j][1] - u[i][1]];
                    f[0] += c * (xx * d[0] + xy * d[1]);
                    f[1] += c * (xy * d[0] + yy * d[1]);
                }
                f
            })
            .collect()
    }

    /// Stiffness triplets over the free unknowns and the right-hand side
    /// `V_i b_i + sum_{j constrained} V_i c_ij (xi ⊗ xi) u_j`.
    pub fn stiffness(&self, body_force: &[[f64; 2]]) -> (Triplets, Vec<f64>) {
        let free = self.nodes.free;
        let rows: Vec<(Vec<(usize, usize, f64)>, [f64; 2])> = (0..free)
            .into_par_iter()
            .map(|i| {
                let v = self.nodes.volumes[i];
                let mut e = Vec::with_capacity(4 * (self.families.of(i).len() + 1));
                let mut diag = [0.0; 3];
                let mut rhs = [v * body_force[i][0], v * body_force[i][1]];
                for (b, &j) in self.families.range(i).zip(self.families.of(i)) {
                    let (j, c, m) = self.bond(i, b, j);
                    let k = [v * c * m[0], v * c * m[1], v * c * m[2]];
                    for a in 0..3 {
                        diag[a] += k[a];
                    }
                    if j < free {
                        e.extend([
                            (2 * i, 2 * j, -k[0]),
                            (2 * i, 2 * j + 1, -k[1]),
                            (2 * i + 1, 2 * j, -k[1]),
                            (2 * i + 1, 2 * j + 1, -k[2]),
                        ]);
                    } else {
                        let u = self.nodes.prescribed[j - free];
                        rhs[0] += k[0] * u[0] + k[1] * u[1];
                        rhs[1] += k[1] * u[0] + k[2] * u[1];
                    }
                }
                e.extend([
                    (2 * i, 2 * i, diag[0]),
                    (2 * i, 2 * i + 1, diag[1]),
                    (2 * i + 1, 2 * i, diag[1]),
                    (2 * i + 1, 2 * i + 1, diag[2]),
                ]);
                (e, rhs)
            })
            .collect();
        let total: usize = rows.iter().map(|r| r.0.len()).sum();
        let mut t = Triplets::with_capacity(2 * free, total);
        let mut rhs = vec![0.0; 2 * free];
        for (i, (e, r)) in rows.into_iter().enumerate() {
            for (row, col, v) in e {
                t.push(row, col, v);
            }
            rhs[2 * i] = r[0];
            rhs[2 * i + 1] = r[1];
        }
        (t, rhs)
    }
}
