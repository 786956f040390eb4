//! A nonlocal strain for output: the displacement gradient that best fits the bond
//! elongations of the family in the least-squares sense (the "shape tensor" of
//! correspondence models),
//!
//! ```text
//! grad u_i = (sum_j V_j (u_j - u_i) ⊗ xi_j) K_i^-1,    K_i = sum_j V_j xi_j ⊗ xi_j,
//! ```
//!
//! exact for linear fields; stresses follow from the model's Lame parameters.

use super::family::Families;
use super::nodes::PdNodes;
use rayon::prelude::*;

/// `[[u_x, u_y], [v_x, v_y]]` at every free node `wanted` picks (zero at the
/// others); `u` holds all nodes.
pub fn gradients(nodes: &PdNodes, families: &Families, u: &[[f64; 2]], wanted: impl Fn(usize) -> bool + Sync) -> Vec<[[f64; 2]; 2]> {
    (0..nodes.free)
        .into_par_iter()
        .map(|i| {
            if !wanted(i) {
                return [[0.0; 2]; 2];
            }
            let x = nodes.positions[i];
            let (mut k, mut b) = ([[0.0; 2]; 2], [[0.0; 2]; 2]);
            for &j in families.of(i) {
                let j = j as usize;
                let v = nodes.volumes[j];
                let xi = [nodes.positions[j][0] - x[0], nodes.positions[j][1] - x[1]];
                let d = [u[j][0] - u[i][0], u[j][1] - u[i][1]];
                for a in 0..2 {
                    for c in 0..2 {
                        k[a][c] += v * xi[a] * xi[c];
                        b[a][c] += v * d[a] * xi[c];
                    }
                }
            }
            let det = k[0][0] * k[1][1] - k[0][1] * k[1][0];
            let inv = [[k[1][1] / det, -k[0][1] / det], [-k[1][0] / det, k[0][0] / det]];
            let mut g = [[0.0; 2]; 2];
            for a in 0..2 {
                for c in 0..2 {
                    g[a][c] = b[a][0] * inv[0][c] + b[a][1] * inv[1][c];
                }
            }
            g
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::peridynamics::test_case::{params, plate, plate_nodes};
    use crate::models::peridynamics::weights::search_radius as radius;
    use crate::models::peridynamics::Quadrature;

    /// The least-squares gradient is exact for linear fields, at complete and
    /// truncated families alike (round-off 1e-12 relative to |grad u| = O(1)).
    #[test]
    fn linear_fields_have_their_exact_gradient() {
        let (domain, conditions) = plate([1.0, 0.0]);
        let g = [[0.3, -1.2], [0.7, 0.05]];
        for rule in [Quadrature::FullArea, Quadrature::TriangleP2] {
            let p = params(0.06, rule);
            let nodes = plate_nodes(&domain, &conditions, &p);
            let families = Families::within(&nodes.positions, nodes.free, radius(&p));
            let u: Vec<[f64; 2]> =
                nodes.positions.iter().map(|x| [1.0 + g[0][0] * x[0] + g[0][1] * x[1], -2.0 + g[1][0] * x[0] + g[1][1] * x[1]]).collect();
            for (i, gi) in gradients(&nodes, &families, &u, |_| true).iter().enumerate() {
                for a in 0..2 {
                    for c in 0..2 {
                        assert!((gi[a][c] - g[a][c]).abs() < 1e-12, "{rule:?} node {i}: {gi:?}");
                    }
                }
            }
        }
    }
}
