//! Strain, stress and von Mises stress from the displacement gradient
//! `g = [[u_x, u_y], [v_x, v_y]]` (each model computes `g` its own way).
//!
//! `eps = (grad u + grad u^T) / 2`; `sigma` by Hooke's law in the planar model
//! ([`Lame::stress`](super::material::Lame::stress)); `sigma_zz = nu (sigma_xx +
//! sigma_yy)` in plane strain, 0 in plane stress; von Mises
//! `sqrt(((sxx - syy)^2 + (syy - szz)^2 + (szz - sxx)^2) / 2 + 3 sxy^2)`.

use super::material::Material;

/// A displacement gradient `[[u_x, u_y], [v_x, v_y]]`.
pub type Gradient = [[f64; 2]; 2];

/// Small-strain tensor components `[eps_xx, eps_yy, eps_xy]`.
pub fn strain(g: Gradient) -> [f64; 3] {
    [g[0][0], g[1][1], 0.5 * (g[0][1] + g[1][0])]
}

/// Von Mises stress from `[sxx, syy, sxy]` and `szz`.
pub fn von_mises(s: [f64; 3], szz: f64) -> f64 {
    let [sxx, syy, sxy] = s;
    (0.5 * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2)) + 3.0 * sxy * sxy).sqrt()
}

/// Stress at every node.
#[derive(Debug, Clone, PartialEq)]
pub struct StressField {
    /// In-plane components `[sigma_xx, sigma_yy, sigma_xy]`.
    pub sigma: Vec<[f64; 3]>,
    /// Out-of-plane normal stress (zero in plane stress).
    pub sigma_zz: Vec<f64>,
    /// Von Mises stress.
    pub von_mises: Vec<f64>,
}

impl StressField {
    /// Hooke's law in the planar model of `material` at every gradient.
    pub fn from_gradients(material: &Material, gradients: &[Gradient]) -> Self {
        let lame = material.lame();
        Self::from_sigma(material, gradients.iter().map(|g| lame.stress(*g)).collect())
    }

    /// The displacement-pressure form's stress `-p I + mu (g + g^T)` at every
    /// gradient `g` with its pressure `p` (finite up to `nu = 1/2`).
    pub fn from_gradients_and_pressure(material: &Material, gradients: &[Gradient], pressure: &[f64]) -> Self {
        let lame = material.lame();
        Self::from_sigma(material, gradients.iter().zip(pressure).map(|(g, p)| lame.stress_with_pressure(*g, *p)).collect())
    }

    /// `sigma_zz` and von Mises of the in-plane stresses `sigma`.
    fn from_sigma(material: &Material, sigma: Vec<[f64; 3]>) -> Self {
        let sigma_zz: Vec<f64> = sigma.iter().map(|s| material.sigma_zz(s[0], s[1])).collect();
        let von_mises = sigma.iter().zip(&sigma_zz).map(|(s, z)| von_mises(*s, *z)).collect();
        StressField { sigma, sigma_zz, von_mises }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::material::{PlaneModel, YoungPoisson};

    #[test]
    fn uniaxial_tension_in_both_planar_models() {
        // u = (eps x, -nu' eps y) with the planar model's lateral contraction gives
        // sigma_yy = 0 and sigma_xx = E' eps; von Mises of uniaxial stress is |sigma_xx|
        // in plane stress.
        let elastic = YoungPoisson { young: 200.0, poisson: 0.25 };
        let stress_plate = Material { elastic, plane: PlaneModel::Stress };
        let g = [[1e-3, 0.0], [0.0, -0.25e-3]];
        let s = StressField::from_gradients(&stress_plate, &[g]);
        assert!((s.sigma[0][0] - 0.2).abs() < 1e-15 && s.sigma[0][1].abs() < 1e-15 && s.sigma[0][2] == 0.0);
        assert_eq!(s.sigma_zz[0], 0.0);
        assert!((s.von_mises[0] - 0.2).abs() < 1e-15);
        // Plane strain: nu' = nu / (1 - nu), E' = E / (1 - nu^2); sigma_zz = nu sigma_xx.
        let strain_plate = Material { elastic, plane: PlaneModel::Strain };
        let nu = 0.25 / 0.75;
        let s = StressField::from_gradients(&strain_plate, &[[[1e-3, 0.0], [0.0, -nu * 1e-3]]]);
        assert!((s.sigma[0][0] - 200.0 / (1.0 - 0.0625) * 1e-3).abs() < 1e-14);
        assert!(s.sigma[0][1].abs() < 1e-14);
        assert!((s.sigma_zz[0] - 0.25 * s.sigma[0][0]).abs() < 1e-15);
        assert_eq!(strain(g), [1e-3, -0.25e-3, 0.0]);
    }
}
