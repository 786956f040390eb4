//! Timoshenko cantilever with an end load distributed as parabolic shear.
//!
//! Source: verification.md, section 1, variant A; Timoshenko & Goodier, *Theory of
//! Elasticity*, 3rd ed., section 21 ("bending of a cantilever loaded at the end"), with
//! the origin at the loaded end. Domain `[0, L] x [-D/2, D/2]`, `I = D^3/12`:
//!
//! ```text
//! sigma_xx = P x y / I,   sigma_yy = 0,   sigma_xy = P (D^2/4 - y^2) / (2 I)
//! u =  P y [3 D^2 (1+nu) - 4 (3 L^2 + (2+nu) y^2 - 3 x^2)] / (24 E I)
//! v = -P [3 D^2 (1+nu)(L - x) + 4 (L - x)^2 (2 L + x) + 12 nu x y^2] / (24 E I)
//! ```
//!
//! The load acts at `x = 0` (traction `(0, -P (D^2 - 4 y^2)/(8 I))` for `n = (-1, 0)`,
//! resultant `-P` per unit thickness), the displacement is imposed exactly at `x = L` and
//! `y = +-D/2` are traction-free.
//!
//! The formulas are for plane stress. For a plane-strain material `(E, nu)` the same
//! formulas hold with `E' = E/(1 - nu^2)` and `nu' = nu/(1 - nu)` (verification.md,
//! notation); the stresses do not depend on the material.
//!
//! Gradient, written out by hand (`C = P / (24 E I)`):
//!
//! ```text
//! u_x = 24 C x y
//! u_y = C [3 D^2 (1+nu) - 12 L^2 + 12 x^2 - 12 (2+nu) y^2]
//! v_x = C [3 D^2 (1+nu) + 12 L^2 - 12 x^2 - 12 nu y^2]
//! v_y = -24 C nu x y
//! ```

use serde::Serialize;

use super::named::{Parameter, ParameterKind, Parameters};
use super::{Check, ExactSolution, ParameterError};
use crate::physics::elasticity::material::{Material, PlaneModel, YoungPoisson};

/// Timoshenko cantilever, variant A: loaded at `x = 0`, clamped (exact `u`) at `x = L`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Cantilever {
    /// End load `P` (N per unit thickness); positive `P` deflects the tip downwards.
    pub load: f64,
    /// Length `L` (m).
    pub length: f64,
    /// Depth `D` (m); the beam spans `-D/2 <= y <= D/2`.
    pub depth: f64,
    /// Material; plane strain is handled by the `E'`, `nu'` substitution.
    pub material: Material,
}

impl Cantilever {
    /// Parameters of `[exact] kind = "cantilever"`.
    pub const PARAMETERS: &'static [Parameter] = &[
        Parameter { name: "load", kind: ParameterKind::Number, help: "end shear load P (N/m)" },
        Parameter { name: "length", kind: ParameterKind::Length, help: "length L (m)" },
        Parameter { name: "depth", kind: ParameterKind::Length, help: "depth D (m)" },
    ];

    /// From validated scene parameters.
    pub fn from_parameters(p: &Parameters, material: Material) -> Result<Self, ParameterError> {
        Cantilever::new(p.number("load"), p.number("length"), p.number("depth"), material)
    }

    /// Checked constructor.
    pub fn new(load: f64, length: f64, depth: f64, material: Material) -> Result<Self, ParameterError> {
        let check = Check("cantilever");
        check.finite("load", load)?;
        check.positive("length", length)?;
        check.positive("depth", depth)?;
        check.material(&material)?;
        let beam = Cantilever { load, length, depth, material };
        // I = D^3 / 12 and C = P / (24 E I) must be representable: a depth of 5e-300
        // has D^3 = 0 (the field would be NaN at every node).
        let inertia = beam.inertia();
        check.require("depth", depth, inertia.is_normal(), "must have a cube D^3 / 12 within the double range (1e-308 to 1e308)")?;
        let c = beam.scale();
        check.require("load", load, c.is_finite(), "must keep P / (24 E I) within the double range; rescale the units")?;
        Ok(beam)
    }

    /// The published set-up: `L = 30`, `D = 5`, `E = 72.1e9`, `nu = 0.33`, `P = 1000`,
    /// plane stress; tip deflection `v(0, 0) = -1.2149e-5` (verification.md, section 1).
    pub fn reference() -> Self {
        let elastic = YoungPoisson { young: 72.1e9, poisson: 0.33 };
        let material = Material { elastic, plane: PlaneModel::Stress };
        Cantilever { load: 1000.0, length: 30.0, depth: 5.0, material }
    }

    /// Second moment of area `I = D^3 / 12`.
    pub fn inertia(&self) -> f64 {
        self.depth.powi(3) / 12.0
    }

    /// `(E, nu)` to use in the plane-stress formulas: the material itself in plane stress,
    /// `(E/(1 - nu^2), nu/(1 - nu))` in plane strain.
    pub fn formula_constants(&self) -> (f64, f64) {
        let YoungPoisson { young: e, poisson: nu } = self.material.elastic;
        match self.material.plane {
            PlaneModel::Stress => (e, nu),
            PlaneModel::Strain => (e / (1.0 - nu * nu), nu / (1.0 - nu)),
        }
    }

    /// `C = P / (24 E I)` with the formula constants.
    fn scale(&self) -> f64 {
        let (e, _) = self.formula_constants();
        self.load / (24.0 * e * self.inertia())
    }
}

impl ExactSolution for Cantilever {
    fn name(&self) -> &'static str {
        "cantilever"
    }

    fn material(&self) -> Material {
        self.material
    }

    fn displacement(&self, [x, y]: [f64; 2]) -> [f64; 2] {
        let (_, nu) = self.formula_constants();
        let (l, d, c) = (self.length, self.depth, self.scale());
        let u = c * y * (3.0 * d * d * (1.0 + nu) - 4.0 * (3.0 * l * l + (2.0 + nu) * y * y - 3.0 * x * x));
        let v = -c * (3.0 * d * d * (1.0 + nu) * (l - x) + 4.0 * (l - x) * (l - x) * (2.0 * l + x) + 12.0 * nu * x * y * y);
        [u, v]
    }

    fn gradient(&self, [x, y]: [f64; 2]) -> [[f64; 2]; 2] {
        let (_, nu) = self.formula_constants();
        let (l, d, c) = (self.length, self.depth, self.scale());
        let shear = 3.0 * d * d * (1.0 + nu);
        [
            [24.0 * c * x * y, c * (shear - 12.0 * l * l + 12.0 * x * x - 12.0 * (2.0 + nu) * y * y)],
            [c * (shear + 12.0 * l * l - 12.0 * x * x - 12.0 * nu * y * y), -24.0 * c * nu * x * y],
        ]
    }

    fn stress(&self, [x, y]: [f64; 2]) -> [f64; 3] {
        let (p, i, d) = (self.load, self.inertia(), self.depth);
        [p * x * y / i, 0.0, p * (d * d / 4.0 - y * y) / (2.0 * i)]
    }

    fn body_force(&self, _p: [f64; 2]) -> [f64; 2] {
        [0.0, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tip_deflection_matches_published_value() {
        let beam = Cantilever::reference();
        let v = beam.displacement([0.0, 0.0])[1];
        // verification.md gives five significant digits: -1.2149e-5; half a unit in the
        // last digit is 5e-10. The closed form is -1.21494e-5.
        assert!((v + 1.2149e-5).abs() <= 0.5e-9, "tip v(0, 0) = {v:e}");
        // A loaded tip of a clamped beam moves far more than the clamped end.
        let clamp = beam.displacement([beam.length, 0.0]);
        assert!(clamp[0].abs() + clamp[1].abs() < 1e-3 * v.abs(), "clamp moves {clamp:?}");
    }

    #[test]
    fn end_traction_is_parabolic_shear_with_resultant_minus_p() {
        let beam = Cantilever::reference();
        let (p, d, i) = (beam.load, beam.depth, beam.inertia());
        // Simpson's rule is exact for the quadratic traction profile.
        let n = 20;
        let h = d / n as f64;
        let mut resultant = [0.0, 0.0];
        for k in 0..=n {
            let y = -d / 2.0 + k as f64 * h;
            let t = beam.traction([0.0, y], [-1.0, 0.0]);
            let expected = [0.0, -p * (d * d - 4.0 * y * y) / (8.0 * i)];
            // Closed form against closed form: only round-off, relative to the peak
            // traction 3P/(2D) = 300 N/m^2.
            for c in 0..2 {
                assert!((t[c] - expected[c]).abs() <= 1e-12 * p / d, "t({y}) = {t:?}, expected {expected:?}");
            }
            let w = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            resultant[0] += w * h / 3.0 * t[0];
            resultant[1] += w * h / 3.0 * t[1];
        }
        assert!(resultant[0].abs() <= 1e-12 * p, "resultant {resultant:?}");
        assert!((resultant[1] + p).abs() <= 1e-12 * p, "resultant {resultant:?}");
    }

    #[test]
    fn top_and_bottom_are_traction_free() {
        let beam = Cantilever::reference();
        let (d, l) = (beam.depth, beam.length);
        for k in 0..=10 {
            let x = l * k as f64 / 10.0;
            for (y, n) in [(d / 2.0, [0.0, 1.0]), (-d / 2.0, [0.0, -1.0])] {
                let t = beam.traction([x, y], n);
                // sigma_xy(+-D/2) = P (D^2/4 - D^2/4)/(2I) is exactly zero in floating
                // point for D = 5; allow round-off relative to the peak shear 3P/(2D).
                assert!(t[0].abs() + t[1].abs() <= 1e-12 * beam.load / d, "t({x}, {y}) = {t:?}");
            }
        }
    }

    #[test]
    fn plane_strain_uses_substituted_constants() {
        let stress = Cantilever::reference();
        let strain = Cantilever { material: Material { plane: PlaneModel::Strain, ..stress.material }, ..stress };
        let (e, nu) = strain.formula_constants();
        assert!((e - 72.1e9 / (1.0 - 0.33 * 0.33)).abs() <= 1e-6 && (nu - 0.33 / 0.67).abs() <= 1e-15);
        // Plane strain is stiffer (E' > E), so the tip moves less; the stresses are the same.
        let (vs, ve) = (stress.displacement([0.0, 0.0])[1], strain.displacement([0.0, 0.0])[1]);
        assert!(ve.abs() < vs.abs(), "plane strain tip {ve:e} vs plane stress {vs:e}");
        assert_eq!(stress.stress([3.0, 1.0]), strain.stress([3.0, 1.0]));
    }

    #[test]
    fn constructor_rejects_nonphysical_parameters() {
        let m = Cantilever::reference().material;
        let err = Cantilever::new(1000.0, 30.0, -5.0, m).unwrap_err();
        assert_eq!(err.parameter, "depth");
        assert!(err.to_string().contains("depth = -5"), "{err}");
        assert!(Cantilever::new(1000.0, 30.0, 5.0, m).is_ok());
    }
}
