//! Strain, stress and von Mises stress at the nodes, from first-derivative shapes.
//!
//! `eps = (grad u + grad u^T) / 2`; `sigma` by Hooke's law in the planar model
//! ([`Lame::stress`]); `sigma_zz = nu (sigma_xx + sigma_yy)` in plane strain, 0 in
//! plane stress; von Mises
//! `sqrt(((sxx - syy)^2 + (syy - szz)^2 + (szz - sxx)^2) / 2 + 3 sxy^2)`.

use super::dofs::DofMap;
use super::material::Material;
use crate::domain::neighbors::Supports;
use crate::mlsm::{Op, Shapes};
use rayon::prelude::*;

/// Displacement gradient `[[u_x, u_y], [v_x, v_y]]` at every node.
pub fn gradients(dofs: &DofMap, supports: &Supports, shapes: &Shapes, x: &[f64], nodes: usize) -> Vec<[[f64; 2]; 2]> {
    (0..nodes)
        .into_par_iter()
        .map(|i| {
            let (dx, dy) = (shapes.get(i, Op::Dx), shapes.get(i, Op::Dy));
            let mut g = [[0.0; 2]; 2];
            for (k, &j) in supports.of(i).iter().enumerate() {
                let u = dofs.displacement(x, j as usize);
                for c in 0..2 {
                    g[c][0] += dx[k] * u[c];
                    g[c][1] += dy[k] * u[c];
                }
            }
            g
        })
        .collect()
}

/// Small-strain tensor components `[eps_xx, eps_yy, eps_xy]`.
pub fn strain(g: [[f64; 2]; 2]) -> [f64; 3] {
    [g[0][0], g[1][1], 0.5 * (g[0][1] + g[1][0])]
}

/// Von Mises stress from `[sxx, syy, sxy]` and `szz`.
pub fn von_mises(s: [f64; 3], szz: f64) -> f64 {
    let [sxx, syy, sxy] = s;
    (0.5 * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2)) + 3.0 * sxy * sxy).sqrt()
}

/// Stress `[sxx, syy, sxy]`, `sigma_zz` and von Mises at every node.
pub fn stresses(material: &Material, grads: &[[[f64; 2]; 2]]) -> (Vec<[f64; 3]>, Vec<f64>, Vec<f64>) {
    let lame = material.lame();
    let s: Vec<[f64; 3]> = grads.iter().map(|g| lame.stress(*g)).collect();
    let szz: Vec<f64> = s.iter().map(|s| material.sigma_zz(s[0], s[1])).collect();
    let vm = s.iter().zip(&szz).map(|(s, z)| von_mises(*s, *z)).collect();
    (s, szz, vm)
}
