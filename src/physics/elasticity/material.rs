//! Isotropic linear-elastic material in 2D.
//!
//! Hooke's law `sigma = lambda tr(eps) I + 2 mu eps` with `mu = E / (2 (1 + nu))`.
//! The two planar models share the 2D Navier equations and differ only in the
//! in-plane first Lame parameter (seeds-digest, 002, "Navier equation, 2D"):
//! - plane strain: `lambda = E nu / ((1 + nu)(1 - 2 nu))`;
//! - plane stress: `lambda* = E nu / (1 - nu^2) = 2 mu lambda / (lambda + 2 mu)`.
//!
//! A plane-strain problem with `(E, nu)` is the plane-stress problem with
//! `E' = E / (1 - nu^2)`, `nu' = nu / (1 - nu)` (verification.md, notation);
//! conversely a plane-stress `(E, nu)` is the plane-strain
//! `E'' = E (1 + 2 nu) / (1 + nu)^2`, `nu'' = nu / (1 + nu)`.

use crate::scene::choice::choice;
use serde::Serialize;

choice! {
    /// Which planar reduction of 3D elasticity is solved.
    pub enum PlaneModel("material.plane", default None, serde "lowercase") {
        /// Thin plate: `sigma_zz = sigma_xz = sigma_yz = 0`.
        Stress = "stress" => "thin plate: sigma_zz = 0",
        /// Long prism: `eps_zz = eps_xz = eps_yz = 0`; `sigma_zz = nu (sigma_xx + sigma_yy)`.
        Strain = "strain" => "long prism: eps_zz = 0, sigma_zz = nu (sigma_xx + sigma_yy)",
    }
}

/// Young's modulus and Poisson's ratio of an isotropic solid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct YoungPoisson {
    /// Young's modulus `E` (Pa).
    pub young: f64,
    /// Poisson's ratio `nu` (dimensionless, `-1 < nu < 1/2`).
    pub poisson: f64,
}

/// Lame parameters as they enter the 2D Navier equation (in-plane `lambda`, shear `mu`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Lame {
    /// First Lame parameter of the planar model (plane stress: `lambda*`).
    pub lambda: f64,
    /// Shear modulus `mu` (Pa).
    pub mu: f64,
}

/// A material together with its planar model: everything rows and stresses need.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Material {
    /// 3D elastic constants.
    pub elastic: YoungPoisson,
    /// Plane stress or plane strain.
    pub plane: PlaneModel,
}

impl YoungPoisson {
    /// Build from 3D Lame parameters: `E = mu (3 lambda + 2 mu)/(lambda + mu)`,
    /// `nu = lambda / (2 (lambda + mu))`.
    pub fn from_lame_3d(lambda: f64, mu: f64) -> Self {
        YoungPoisson { young: mu * (3.0 * lambda + 2.0 * mu) / (lambda + mu), poisson: lambda / (2.0 * (lambda + mu)) }
    }
}

impl Material {
    /// Shear modulus `mu = E / (2 (1 + nu))`.
    pub fn mu(&self) -> f64 {
        self.elastic.young / (2.0 * (1.0 + self.elastic.poisson))
    }

    /// In-plane Lame parameters for the chosen planar model (module docs).
    pub fn lame(&self) -> Lame {
        let YoungPoisson { young: e, poisson: nu } = self.elastic;
        let lambda = match self.plane {
            PlaneModel::Strain => e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            PlaneModel::Stress => e * nu / (1.0 - nu * nu),
        };
        Lame { lambda, mu: self.mu() }
    }

    /// Weights `(a, b) = (lambda / (lambda + mu), mu / (lambda + mu))` of the
    /// constitutive pressure equation of the displacement-pressure form,
    /// `p = -lambda div u`  <=>  `a mu div u + b p = 0`, finite for every `nu` in
    /// `(-1, 1/2]`: plane strain `(2 nu, 1 - 2 nu)`, plane stress
    /// `(2 nu / (1 + nu), (1 - nu) / (1 + nu))`. At `nu = 1/2` in plane strain the
    /// equation is the incompressibility constraint `div u = 0`.
    pub fn pressure_weights(&self) -> (f64, f64) {
        let nu = self.elastic.poisson;
        match self.plane {
            PlaneModel::Strain => (2.0 * nu, 1.0 - 2.0 * nu),
            PlaneModel::Stress => (2.0 * nu / (1.0 + nu), (1.0 - nu) / (1.0 + nu)),
        }
    }

    /// Whether the solid is incompressible in its planar model (`nu = 1/2` in plane
    /// strain): `lambda` is infinite and only the displacement-pressure form applies.
    pub fn is_incompressible(&self) -> bool {
        self.plane == PlaneModel::Strain && self.elastic.poisson >= 0.5
    }

    /// Out-of-plane normal stress: `nu (sigma_xx + sigma_yy)` in plane strain, 0 in plane stress.
    pub fn sigma_zz(&self, sxx: f64, syy: f64) -> f64 {
        match self.plane {
            PlaneModel::Strain => self.elastic.poisson * (sxx + syy),
            PlaneModel::Stress => 0.0,
        }
    }

    /// The plane-stress material with the same in-plane `lambda`, `mu`:
    /// `E' = E / (1 - nu^2)`, `nu' = nu / (1 - nu)` (identity for plane stress).
    pub fn as_plane_stress(&self) -> Material {
        match self.plane {
            PlaneModel::Stress => *self,
            PlaneModel::Strain => {
                let YoungPoisson { young: e, poisson: nu } = self.elastic;
                Material { elastic: YoungPoisson { young: e / (1.0 - nu * nu), poisson: nu / (1.0 - nu) }, plane: PlaneModel::Stress }
            }
        }
    }

    /// The plane-strain material with the same in-plane `lambda`, `mu`:
    /// `E'' = E (1 + 2 nu) / (1 + nu)^2`, `nu'' = nu / (1 + nu)` (identity for plane strain).
    pub fn as_plane_strain(&self) -> Material {
        match self.plane {
            PlaneModel::Strain => *self,
            PlaneModel::Stress => {
                let YoungPoisson { young: e, poisson: nu } = self.elastic;
                Material {
                    elastic: YoungPoisson { young: e * (1.0 + 2.0 * nu) / (1.0 + nu).powi(2), poisson: nu / (1.0 + nu) },
                    plane: PlaneModel::Strain,
                }
            }
        }
    }
}

impl Lame {
    /// Cauchy stress `[sigma_xx, sigma_yy, sigma_xy]` from the displacement gradient
    /// `g = [[u_x, u_y], [v_x, v_y]]` (Hooke's law in 2D).
    pub fn stress(&self, g: [[f64; 2]; 2]) -> [f64; 3] {
        let div = g[0][0] + g[1][1];
        [self.lambda * div + 2.0 * self.mu * g[0][0], self.lambda * div + 2.0 * self.mu * g[1][1], self.mu * (g[0][1] + g[1][0])]
    }

    /// Cauchy stress of the displacement-pressure form, `sigma = -p I + mu (g + g^T)`
    /// (equal to [`Lame::stress`] when `p = -lambda div u`; finite at `lambda = inf`).
    pub fn stress_with_pressure(&self, g: [[f64; 2]; 2], p: f64) -> [f64; 3] {
        [-p + 2.0 * self.mu * g[0][0], -p + 2.0 * self.mu * g[1][1], self.mu * (g[0][1] + g[1][0])]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn substitutions_keep_in_plane_constants() {
        for plane in [PlaneModel::Stress, PlaneModel::Strain] {
            let m = Material { elastic: YoungPoisson { young: 72.1e9, poisson: 0.33 }, plane };
            for other in [m.as_plane_strain(), m.as_plane_stress()] {
                let (a, b) = (m.lame(), other.lame());
                assert!((a.lambda - b.lambda).abs() <= 1e-12 * a.lambda, "{plane:?}: {a:?} vs {b:?}");
                assert!((a.mu - b.mu).abs() <= 1e-12 * a.mu);
            }
        }
        // The textbook substitution (verification.md): plane strain (E, nu) = plane stress (E/(1-nu^2), nu/(1-nu)).
        let strain = Material { elastic: YoungPoisson { young: 1.0, poisson: 0.3 }, plane: PlaneModel::Strain };
        let ps = strain.as_plane_stress().elastic;
        assert!((ps.young - 1.0 / 0.91).abs() < 1e-15 && (ps.poisson - 0.3 / 0.7).abs() < 1e-15);
    }

    /// `a mu div u + b p = 0` is `p = -lambda div u` for finite lambda, and the two
    /// stress forms agree there; at nu = 1/2 (plane strain) it is `div u = 0`.
    #[test]
    fn pressure_weights_are_the_constitutive_pressure_equation() {
        let g = [[1e-3, 2e-4], [-5e-4, 3e-4]];
        for plane in [PlaneModel::Stress, PlaneModel::Strain] {
            for nu in [-0.5, 0.0, 0.3, 0.49] {
                let m = Material { elastic: YoungPoisson { young: 7.0, poisson: nu }, plane };
                let (lame, (a, b)) = (m.lame(), m.pressure_weights());
                let p = -lame.lambda * (g[0][0] + g[1][1]);
                assert!((a * lame.mu * (g[0][0] + g[1][1]) + b * p).abs() < 1e-15, "{plane:?} nu = {nu}");
                let (s, t) = (lame.stress(g), lame.stress_with_pressure(g, p));
                assert!((0..3).all(|k| (s[k] - t[k]).abs() < 1e-14), "{plane:?} nu = {nu}: {s:?} vs {t:?}");
            }
        }
        let m = Material { elastic: YoungPoisson { young: 7.0, poisson: 0.5 }, plane: PlaneModel::Strain };
        assert_eq!(m.pressure_weights(), (1.0, 0.0));
        assert!(m.is_incompressible());
    }

    #[test]
    fn lame_roundtrip() {
        let yp = YoungPoisson::from_lame_3d(2.0, 3.0);
        let m = Material { elastic: yp, plane: PlaneModel::Strain }.lame();
        assert!((m.lambda - 2.0).abs() < 1e-12 && (m.mu - 3.0).abs() < 1e-12);
    }
}
