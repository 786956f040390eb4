//! Lame's thick-walled cylinder under internal pressure.
//!
//! Source: verification.md, section 3; G. Lame, *Lecons sur la theorie mathematique de
//! l'elasticite des corps solides* (1852); see also Timoshenko & Goodier, chapter 4.
//! Ring `a <= r <= b` centred at the origin, pressure `p` on `r = a`, free `r = b`,
//! `K = p a^2 / (b^2 - a^2)`:
//!
//! ```text
//! s_r = K (1 - b^2/r^2),   s_t = K (1 + b^2/r^2)            (both planar models)
//! u_r = A r + B / r,       B = K (1 + nu) b^2 / E
//! A = K (1 + nu)(1 - 2 nu) / E     (plane strain)
//! A = K (1 - nu) / E               (plane stress)
//! ```
//!
//! which are verification.md's `u_r` formulas regrouped. In Cartesian components
//! `u = (A + B/r^2) x`, so `grad u = (A + B/r^2) I - 2 B x x^T / r^4` and
//! `sigma = s_r e_r e_r^T + s_t e_t e_t^T`.
//!
//! Both `A x` and `B x / r^2` are harmonic and `B x / r^2` is divergence-free, so the
//! Navier residual vanishes for any `lambda`: the plane model is checked by the stresses.

use serde::Serialize;

use super::named::{Parameter, ParameterKind, Parameters};
use super::{Check, ExactSolution, ParameterError};
use crate::physics::elasticity::material::{Material, PlaneModel, YoungPoisson};

/// Thick cylinder `a <= r <= b` centred at the origin under internal pressure `p`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LameCylinder {
    /// Internal pressure `p` (Pa); positive pushes the inner wall outwards.
    pub pressure: f64,
    /// Inner radius `a` (m).
    pub inner: f64,
    /// Outer radius `b` (m).
    pub outer: f64,
    /// Material; the radial displacement depends on the planar model.
    pub material: Material,
}

impl LameCylinder {
    /// Parameters of `[exact] kind = "lame"`.
    pub const PARAMETERS: &'static [Parameter] = &[
        Parameter { name: "pressure", kind: ParameterKind::Number, help: "internal pressure p (Pa)" },
        Parameter { name: "inner", kind: ParameterKind::Length, help: "inner radius a (m)" },
        Parameter { name: "outer", kind: ParameterKind::Length, help: "outer radius b > a (m)" },
    ];

    /// From validated scene parameters.
    pub fn from_parameters(p: &Parameters, material: Material) -> Result<Self, ParameterError> {
        LameCylinder::new(p.number("pressure"), p.number("inner"), p.number("outer"), material)
    }

    /// Checked constructor.
    pub fn new(pressure: f64, inner: f64, outer: f64, material: Material) -> Result<Self, ParameterError> {
        let check = Check("lame");
        check.finite("pressure", pressure)?;
        check.positive("inner", inner)?;
        check.require("outer", outer, outer.is_finite() && outer > inner, "must exceed the inner radius")?;
        check.material(&material)?;
        Ok(LameCylinder { pressure, inner, outer, material })
    }

    /// The published set-up: `a = 0.01`, `b = 0.02`, `E = 210e9`, `nu = 0.3`,
    /// `p = 100e6`, plane strain; `u_r(a) = 9.08e-6`, `s_t(a) = 166.7e6`,
    /// `s_t(b) = 66.7e6` (verification.md, section 3).
    pub fn reference() -> Self {
        let elastic = YoungPoisson { young: 210e9, poisson: 0.3 };
        let material = Material { elastic, plane: PlaneModel::Strain };
        LameCylinder { pressure: 100e6, inner: 0.01, outer: 0.02, material }
    }

    /// `K = p a^2 / (b^2 - a^2)`.
    fn k(&self) -> f64 {
        let (a, b) = (self.inner, self.outer);
        self.pressure * a * a / (b * b - a * a)
    }

    /// Coefficients `(A, B)` of `u_r = A r + B / r`.
    fn coefficients(&self) -> (f64, f64) {
        let YoungPoisson { young: e, poisson: nu } = self.material.elastic;
        let k = self.k();
        let a = match self.material.plane {
            PlaneModel::Strain => k * (1.0 + nu) * (1.0 - 2.0 * nu) / e,
            PlaneModel::Stress => k * (1.0 - nu) / e,
        };
        (a, k * (1.0 + nu) * self.outer * self.outer / e)
    }

    /// Radial displacement `u_r(r)`.
    pub fn radial_displacement(&self, r: f64) -> f64 {
        let (a, b) = self.coefficients();
        a * r + b / r
    }

    /// Radial stress `s_r(r) = K (1 - b^2/r^2)`.
    pub fn radial_stress(&self, r: f64) -> f64 {
        self.k() * (1.0 - (self.outer / r).powi(2))
    }

    /// Hoop stress `s_t(r) = K (1 + b^2/r^2)`.
    pub fn hoop_stress(&self, r: f64) -> f64 {
        self.k() * (1.0 + (self.outer / r).powi(2))
    }
}

impl ExactSolution for LameCylinder {
    fn name(&self) -> &'static str {
        "lame"
    }

    fn material(&self) -> Material {
        self.material
    }

    fn displacement(&self, [x, y]: [f64; 2]) -> [f64; 2] {
        let (a, b) = self.coefficients();
        let g = a + b / (x * x + y * y);
        [g * x, g * y]
    }

    fn gradient(&self, [x, y]: [f64; 2]) -> [[f64; 2]; 2] {
        let (a, b) = self.coefficients();
        let r2 = x * x + y * y;
        let (g, h) = (a + b / r2, 2.0 * b / (r2 * r2));
        [[g - h * x * x, -h * x * y], [-h * x * y, g - h * y * y]]
    }

    fn stress(&self, [x, y]: [f64; 2]) -> [f64; 3] {
        let r = x.hypot(y);
        let (c, s) = (x / r, y / r);
        let (sr, st) = (self.radial_stress(r), self.hoop_stress(r));
        [sr * c * c + st * s * s, sr * s * s + st * c * c, (sr - st) * c * s]
    }

    fn body_force(&self, _p: [f64; 2]) -> [f64; 2] {
        [0.0, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn published_values() {
        let cyl = LameCylinder::reference();
        let (a, b, p) = (cyl.inner, cyl.outer, cyl.pressure);
        // Each expected value is checked to half a unit in its last published digit.
        let ur = cyl.displacement([a, 0.0])[0];
        assert!((ur - 9.08e-6).abs() <= 0.005e-6, "u_r(a) = {ur:e}");
        assert!((cyl.hoop_stress(a) - 166.7e6).abs() <= 0.05e6, "s_t(a) = {:e}", cyl.hoop_stress(a));
        assert!((cyl.hoop_stress(b) - 66.7e6).abs() <= 0.05e6, "s_t(b) = {:e}", cyl.hoop_stress(b));
        // The same numbers through the Cartesian stress at (0, a): s_xx is the hoop stress.
        let s = cyl.stress([0.0, a]);
        assert!((s[0] - 166.7e6).abs() <= 0.05e6 && (s[1] + p).abs() <= 1e-9 * p, "{s:?}");
    }

    #[test]
    fn inner_wall_carries_the_pressure_and_outer_wall_is_free() {
        for plane in [PlaneModel::Strain, PlaneModel::Stress] {
            let cyl = LameCylinder { material: Material { plane, ..LameCylinder::reference().material }, ..LameCylinder::reference() };
            let p = cyl.pressure;
            // s_r(a) = K (1 - b^2/a^2) = -p: compressive radial stress at the pressurised wall.
            assert!((cyl.radial_stress(cyl.inner) + p).abs() <= 1e-12 * p);
            assert!(cyl.radial_stress(cyl.outer).abs() <= 1e-12 * p);
            for i in 0..24 {
                let t = std::f64::consts::TAU * i as f64 / 24.0;
                let e_r = [t.cos(), t.sin()];
                // Inner wall: outward normal of the body is -e_r; the fluid pushes the
                // material outwards, t = sigma n = -s_r(a) e_r = p e_r.
                let ti = cyl.traction([cyl.inner * e_r[0], cyl.inner * e_r[1]], [-e_r[0], -e_r[1]]);
                assert!((ti[0] - p * e_r[0]).abs() + (ti[1] - p * e_r[1]).abs() <= 1e-9 * p, "{ti:?}");
                let to = cyl.traction([cyl.outer * e_r[0], cyl.outer * e_r[1]], e_r);
                assert!(to[0].abs() + to[1].abs() <= 1e-9 * p, "{to:?}");
            }
        }
    }

    #[test]
    fn plane_stress_displacement_formula() {
        // verification.md: u_r = p a^2 r / (E (b^2 - a^2)) [(1 - nu) + (1 + nu) b^2/r^2].
        let mut cyl = LameCylinder::reference();
        cyl.material.plane = PlaneModel::Stress;
        let (a, b, p, e, nu) = (cyl.inner, cyl.outer, cyl.pressure, 210e9, 0.3);
        for r in [a, 0.015, b] {
            let expected = p * a * a * r / (e * (b * b - a * a)) * ((1.0 - nu) + (1.0 + nu) * b * b / (r * r));
            let got = cyl.radial_displacement(r);
            assert!((got - expected).abs() <= 1e-13 * expected, "{got:e} vs {expected:e}");
        }
        // Plane stress is the more compliant model: the inner wall moves further.
        assert!(cyl.radial_displacement(a) > LameCylinder::reference().radial_displacement(a));
    }

    #[test]
    fn stresses_hold_near_incompressibility() {
        // verification.md: stresses do not depend on nu. Check that the plane-strain
        // displacement still reproduces them through Hooke's law as lambda/mu -> 5000.
        for nu in [0.3, 0.49, 0.499, 0.4999] {
            let mut cyl = LameCylinder::reference();
            cyl.material.elastic.poisson = nu;
            let lame = cyl.material.lame();
            for p in [[0.01, 0.0], [0.0105, 0.0071], [-0.014, 0.009], [0.0, -0.02]] {
                let (closed, hooke) = (cyl.stress(p), lame.stress(cyl.gradient(p)));
                // lambda div u cancels B/r^2 terms of size ~ p/(E(1-2nu)) * lambda ~ 5000
                // p eps in round-off at nu = 0.4999: 1e-9 p leaves a margin of ~1e3.
                for i in 0..3 {
                    assert!((closed[i] - hooke[i]).abs() <= 1e-9 * cyl.pressure, "nu = {nu}: {closed:?} vs {hooke:?}");
                }
            }
        }
    }

    #[test]
    fn constructor_rejects_inverted_radii() {
        let m = LameCylinder::reference().material;
        let err = LameCylinder::new(1e6, 0.02, 0.01, m).unwrap_err();
        assert_eq!(err.parameter, "outer");
        assert!(err.to_string().contains("must exceed the inner radius"), "{err}");
    }
}
