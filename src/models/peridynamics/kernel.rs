//! Micromodulus `lambda(r)` of the linear bond-based model and its calibration.
//!
//! Kernels (seed 000, eqs. 4.1.3 and 4.1.5), for `r < delta`:
//!
//! ```text
//! plain:        lambda(r) = c / r^3
//! regularised:  lambda(r) = c r^alpha exp(-1 / (1 - r^2/delta^2))      (alpha = -3 is the physical one)
//! ```
//!
//! Calibration. For a smooth `u`, Taylor expansion of `u(x + xi) - u(x)` in the
//! operator leaves only the even terms; with the isotropic fourth moment
//! `int lambda(|xi|) xi_a xi_b xi_c xi_d dA = M (d_ab d_cd + d_ac d_bd + d_ad d_bc)`,
//! `M = (1/8) int lambda r^4 dA = (pi/4) int_0^delta lambda(r) r^5 dr`, the local limit is
//!
//! ```text
//! L u -> (M/2) (lap u + 2 grad div u) = mu lap u + (lambda + mu) grad div u   with lambda = mu = M/2,
//! ```
//!
//! exact for polynomials of degree <= 3 (the fifth moments vanish). So a kernel is
//! calibrated by `M = 2 mu`, and bond-based PD can only represent in-plane Lame
//! parameters with `lambda = mu`: `nu = 1/4` in plane strain, `nu = 1/3` in plane stress.
//! Per unit thickness, `M = 2 mu` gives
//!
//! ```text
//! plain:        c = 12 M / (pi delta^3)   = 48 E / (5 pi delta^3)  (plane strain),  9 E / (pi delta^3)  (plane stress)
//! regularised:  c = 4 M / (pi delta^(alpha+6) I_alpha),   I_alpha = int_0^1 s^(alpha+5) exp(-1/(1 - s^2)) ds
//! ```
//!
//! The plain constants are those of the seed (`c_2 = 72 K/(5 pi delta^3)`, `K = 2E/3`)
//! and of Gerstle et al. / Bobaru et al. for plane stress; `I_alpha` is computed by
//! composite Gauss-Legendre quadrature (the integrand is smooth, flat at `s = 1`).
//! The thickness cancels: a plate of thickness `t` has `c t` per area and `b t` per area.

use crate::scene::choice::choice;
use crate::physics::elasticity::material::Material;
use gauss_quad::GaussLegendre;
use serde::Serialize;
use std::num::NonZeroUsize;

/// Shape of the micromodulus.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Kernel {
    /// `c / r^3`.
    Plain,
    /// `c r^alpha exp(-1/(1 - r^2/delta^2))`.
    Regularised {
        /// Exponent alpha (> -4 so that the operator is bounded).
        alpha: f64,
    },
}

choice! {
    /// The name of a kernel in a scene (`peridynamics.kernel`); `alpha` is its own field.
    pub enum KernelKind("peridynamics.kernel", default Some(KernelKind::Plain)) {
        Plain = "plain" => "c / r^3",
        Regularised = "regularised" => "c r^alpha exp(-1/(1 - r^2/delta^2)), alpha > -4 (default -3)",
    }
}

impl Kernel {
    /// Its name in a scene.
    pub fn kind(&self) -> KernelKind {
        match self {
            Kernel::Plain => KernelKind::Plain,
            Kernel::Regularised { .. } => KernelKind::Regularised,
        }
    }

    /// Short label, e.g. `plain` or `alpha=-3`.
    pub fn label(&self) -> String {
        match self {
            Kernel::Plain => "plain".into(),
            Kernel::Regularised { alpha } => format!("alpha={alpha}"),
        }
    }
}

/// A kernel with its calibrated constant for one horizon.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Micromodulus {
    /// Kernel shape.
    pub kernel: Kernel,
    /// Horizon delta.
    pub horizon: f64,
    /// Calibrated constant c.
    pub constant: f64,
}

/// The fourth moment `M = 2 mu` a calibrated kernel must have (module docs).
pub fn fourth_moment(material: &Material) -> f64 {
    2.0 * material.lame().mu
}

/// Whether bond-based PD can represent the material: in-plane `lambda = mu`
/// (`nu = 1/4` plane strain, `nu = 1/3` plane stress), to a relative `1e-9`.
pub fn representable(material: &Material) -> bool {
    let l = material.lame();
    (l.lambda - l.mu).abs() <= 1e-9 * l.mu
}

/// `I_alpha = int_0^1 s^(alpha+5) exp(-1/(1 - s^2)) ds` (composite Gauss-Legendre,
/// 64 panels of 20 points: converged to round-off, see the tests).
pub fn radial_integral(alpha: f64) -> f64 {
    radial_integral_with(alpha, 64)
}

fn radial_integral_with(alpha: f64, panels: usize) -> f64 {
    let rule = GaussLegendre::new(NonZeroUsize::new(20).unwrap());
    let f = |s: f64| if s < 1.0 { s.powf(alpha + 5.0) * (-1.0 / (1.0 - s * s)).exp() } else { 0.0 };
    (0..panels).map(|k| rule.integrate(k as f64 / panels as f64, (k + 1) as f64 / panels as f64, f)).sum()
}

impl Micromodulus {
    /// The kernel calibrated so that its fourth moment equals `moment` (module docs).
    pub fn calibrated(kernel: Kernel, horizon: f64, moment: f64) -> Self {
        let constant = match kernel {
            Kernel::Plain => 12.0 * moment / (std::f64::consts::PI * horizon.powi(3)),
            Kernel::Regularised { alpha } => 4.0 * moment / (std::f64::consts::PI * horizon.powf(alpha + 6.0) * radial_integral(alpha)),
        };
        Micromodulus { kernel, horizon, constant }
    }

    /// `lambda(r)`; the plain kernel is not cut at the horizon here (the family
    /// decides which bonds exist), the regularised one vanishes for `r >= delta`.
    pub fn value(&self, r: f64) -> f64 {
        match self.kernel {
            Kernel::Plain => self.constant / (r * r * r),
            Kernel::Regularised { alpha } => {
                let q = 1.0 - (r / self.horizon).powi(2);
                if q <= 0.0 {
                    0.0
                } else {
                    self.constant * r.powf(alpha) * (-1.0 / q).exp()
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::material::{PlaneModel, YoungPoisson};

    #[test]
    fn radial_integral_is_converged() {
        for alpha in [-3.0, -2.0, 0.0, 1.0, 0.5] {
            let a = radial_integral_with(alpha, 64);
            let b = radial_integral_with(alpha, 256);
            assert!((a - b).abs() <= 1e-15 * b.abs().max(1e-300) * 10.0, "alpha {alpha}: {a} vs {b}");
        }
    }

    /// The fourth moment `(pi/4) int lambda r^5 dr` of every calibrated kernel equals `M`,
    /// computed here by an independent quadrature in r (1000 panels, midpoint on a
    /// smooth or polynomial integrand: relative error below 1e-6).
    #[test]
    fn calibrated_kernels_have_the_target_moment() {
        let m = Material { elastic: YoungPoisson { young: 210e9, poisson: 0.25 }, plane: PlaneModel::Strain };
        let moment = fourth_moment(&m);
        assert!((moment - 0.8 * 210e9).abs() < 1e-3, "M = 4E/5 in plane strain");
        for kernel in [Kernel::Plain, Kernel::Regularised { alpha: -3.0 }, Kernel::Regularised { alpha: 1.0 }] {
            let delta = 0.05;
            let mm = Micromodulus::calibrated(kernel, delta, moment);
            let n = 20000;
            let dr = delta / n as f64;
            let integral: f64 = (0..n).map(|k| (k as f64 + 0.5) * dr).map(|r| mm.value(r) * r.powi(5) * dr).sum();
            let got = std::f64::consts::PI / 4.0 * integral;
            assert!((got / moment - 1.0).abs() < 1e-6, "{kernel:?}: {got} vs {moment}");
        }
        let plain = Micromodulus::calibrated(Kernel::Plain, 0.1, moment);
        let seed = 48.0 * 210e9 / (5.0 * std::f64::consts::PI * 0.1f64.powi(3));
        assert!((plain.constant / seed - 1.0).abs() < 1e-14);
    }

    #[test]
    fn representable_poisson_ratios() {
        let mat = |nu, plane| Material { elastic: YoungPoisson { young: 1.0, poisson: nu }, plane };
        assert!(representable(&mat(0.25, PlaneModel::Strain)));
        assert!(representable(&mat(1.0 / 3.0, PlaneModel::Stress)));
        assert!(!representable(&mat(0.3, PlaneModel::Strain)));
        assert!(!representable(&mat(0.25, PlaneModel::Stress)));
        let m = mat(1.0 / 3.0, PlaneModel::Stress);
        assert!((fourth_moment(&m) - 0.75).abs() < 1e-14, "M = 3E/4 in plane stress");
    }
}
