//! Kirsch: infinite plate with a traction-free circular hole, uniaxial tension along x.
//!
//! Source: verification.md, section 2; G. Kirsch, "Die Theorie der Elastizitat und die
//! Bedurfnisse der Festigkeitslehre", Z. VDI 42 (1898); J. R. Barber, *Elasticity*,
//! chapter 8 (plate with a circular hole). Hole of radius `a` at the origin,
//! `x = r cos t`, `y = r sin t`:
//!
//! ```text
//! s_rr = T/2 (1 - a^2/r^2) + T/2 (1 + 3a^4/r^4 - 4a^2/r^2) cos 2t
//! s_tt = T/2 (1 + a^2/r^2) - T/2 (1 + 3a^4/r^4) cos 2t
//! s_rt = -T/2 (1 - 3a^4/r^4 + 2a^2/r^2) sin 2t
//! s_xx = T [1 - (a^2/r^2)(3/2 cos 2t + cos 4t) + 3a^4/(2r^4) cos 4t]
//! s_yy = T [-(a^2/r^2)(1/2 cos 2t - cos 4t) - 3a^4/(2r^4) cos 4t]
//! s_xy = T [-(a^2/r^2)(1/2 sin 2t + sin 4t) + 3a^4/(2r^4) sin 4t]
//! u = T a/(8 mu) [(r/a)(kappa+1) cos t + (2a/r)((1+kappa) cos t + cos 3t) - (2a^3/r^3) cos 3t]
//! v = T a/(8 mu) [(r/a)(kappa-3) sin t + (2a/r)((1-kappa) sin t + sin 3t) - (2a^3/r^3) sin 3t]
//! ```
//!
//! `kappa` is the Kolosov constant of the planar model ([`super::kolosov`]). The field is
//! singular at the origin only; it is meant for `r >= a`. The gradient is the chain rule
//! `d/dx = cos t d/dr - (sin t / r) d/dt`, `d/dy = sin t d/dr + (cos t / r) d/dt` applied
//! to the polar derivatives written out in [`Kirsch::gradient`].

use serde::Serialize;

use super::named::{Parameter, ParameterKind, Parameters};
use super::{kolosov, Check, ExactSolution, ParameterError};
use crate::physics::elasticity::material::Material;

/// Infinite plate with a circular hole of radius `a` at the origin, tension `T` along x.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Kirsch {
    /// Remote tension `T` along x (Pa).
    pub tension: f64,
    /// Hole radius `a` (m).
    pub radius: f64,
    /// Material; `kappa` and `mu` come from it.
    pub material: Material,
}

impl Kirsch {
    /// Parameters of `[exact] kind = "kirsch"`.
    pub const PARAMETERS: &'static [Parameter] = &[
        Parameter { name: "tension", kind: ParameterKind::Number, help: "far-field tension T along x (Pa)" },
        Parameter { name: "radius", kind: ParameterKind::Length, help: "hole radius a (m)" },
    ];

    /// From validated scene parameters.
    pub fn from_parameters(p: &Parameters, material: Material) -> Result<Self, ParameterError> {
        Kirsch::new(p.number("tension"), p.number("radius"), material)
    }

    /// Checked constructor.
    pub fn new(tension: f64, radius: f64, material: Material) -> Result<Self, ParameterError> {
        let check = Check("kirsch");
        check.finite("tension", tension)?;
        check.positive("radius", radius)?;
        check.material(&material)?;
        Ok(Kirsch { tension, radius, material })
    }

    /// Polar stresses `[s_rr, s_tt, s_rt]` at radius `r` and angle `t`.
    pub fn polar_stress(&self, r: f64, t: f64) -> [f64; 3] {
        let (tt, q2, q4) = (self.tension, (self.radius / r).powi(2), (self.radius / r).powi(4));
        let (c2, s2) = ((2.0 * t).cos(), (2.0 * t).sin());
        [
            tt / 2.0 * (1.0 - q2) + tt / 2.0 * (1.0 + 3.0 * q4 - 4.0 * q2) * c2,
            tt / 2.0 * (1.0 + q2) - tt / 2.0 * (1.0 + 3.0 * q4) * c2,
            -tt / 2.0 * (1.0 - 3.0 * q4 + 2.0 * q2) * s2,
        ]
    }

    /// `T a / (8 mu)`.
    fn scale(&self) -> f64 {
        self.tension * self.radius / (8.0 * self.material.mu())
    }
}

impl ExactSolution for Kirsch {
    fn name(&self) -> &'static str {
        "kirsch"
    }

    fn material(&self) -> Material {
        self.material
    }

    fn displacement(&self, [x, y]: [f64; 2]) -> [f64; 2] {
        let (r, t) = (x.hypot(y), y.atan2(x));
        let (a, k, c) = (self.radius, kolosov(&self.material), self.scale());
        let (q1, q3) = (a / r, (a / r).powi(3));
        let u = (r / a) * (k + 1.0) * t.cos() + 2.0 * q1 * ((1.0 + k) * t.cos() + (3.0 * t).cos()) - 2.0 * q3 * (3.0 * t).cos();
        let v = (r / a) * (k - 3.0) * t.sin() + 2.0 * q1 * ((1.0 - k) * t.sin() + (3.0 * t).sin()) - 2.0 * q3 * (3.0 * t).sin();
        [c * u, c * v]
    }

    fn gradient(&self, [x, y]: [f64; 2]) -> [[f64; 2]; 2] {
        let (r, t) = (x.hypot(y), y.atan2(x));
        let (a, k, c) = (self.radius, kolosov(&self.material), self.scale());
        let (ct, st, c3, s3) = (t.cos(), t.sin(), (3.0 * t).cos(), (3.0 * t).sin());
        // Polar derivatives of u/c and v/c, term by term from the module formula.
        let (b, d) = (2.0 * a, 2.0 * a.powi(3));
        let u_r = (k + 1.0) / a * ct - b / (r * r) * ((1.0 + k) * ct + c3) + 3.0 * d / r.powi(4) * c3;
        let u_t = -(k + 1.0) / a * r * st + b / r * (-(1.0 + k) * st - 3.0 * s3) + 3.0 * d / r.powi(3) * s3;
        let v_r = (k - 3.0) / a * st - b / (r * r) * ((1.0 - k) * st + s3) + 3.0 * d / r.powi(4) * s3;
        let v_t = (k - 3.0) / a * r * ct + b / r * ((1.0 - k) * ct + 3.0 * c3) - 3.0 * d / r.powi(3) * c3;
        [[c * (ct * u_r - st / r * u_t), c * (st * u_r + ct / r * u_t)], [c * (ct * v_r - st / r * v_t), c * (st * v_r + ct / r * v_t)]]
    }

    fn stress(&self, [x, y]: [f64; 2]) -> [f64; 3] {
        let (r, t) = (x.hypot(y), y.atan2(x));
        let (tt, q2, q4) = (self.tension, (self.radius / r).powi(2), (self.radius / r).powi(4));
        let (c2, s2, c4, s4) = ((2.0 * t).cos(), (2.0 * t).sin(), (4.0 * t).cos(), (4.0 * t).sin());
        [
            tt * (1.0 - q2 * (1.5 * c2 + c4) + 1.5 * q4 * c4),
            tt * (-q2 * (0.5 * c2 - c4) - 1.5 * q4 * c4),
            tt * (-q2 * (0.5 * s2 + s4) + 1.5 * q4 * s4),
        ]
    }

    fn body_force(&self, _p: [f64; 2]) -> [f64; 2] {
        [0.0, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::material::{PlaneModel, YoungPoisson};
    use std::f64::consts::PI;

    fn plate(plane: PlaneModel) -> Kirsch {
        let elastic = YoungPoisson { young: 210e9, poisson: 0.3 };
        Kirsch::new(100e6, 1.0, Material { elastic, plane }).unwrap()
    }

    /// All stress checks compare closed forms evaluated in floating point; the largest
    /// stress is 3T and the terms are O(T), so 1e-12 T is round-off with a wide margin.
    const TOL: f64 = 1e-12;

    #[test]
    fn hoop_stress_concentration_is_three() {
        let k = plate(PlaneModel::Strain);
        let t = k.tension;
        let [_, s_tt, _] = k.polar_stress(k.radius, PI / 2.0);
        assert!((s_tt - 3.0 * t).abs() <= TOL * t, "s_tt(a, pi/2) = {s_tt:e}");
        // The same value from the Cartesian formula (s_xx at the top of the hole) ...
        let s = k.stress([0.0, k.radius]);
        assert!((s[0] - 3.0 * t).abs() <= TOL * t, "s_xx(0, a) = {:e}", s[0]);
        // ... and the compressive -T at the side of the hole.
        let [_, s_tt0, _] = k.polar_stress(k.radius, 0.0);
        assert!((s_tt0 + t).abs() <= TOL * t, "s_tt(a, 0) = {s_tt0:e}");
    }

    #[test]
    fn hole_is_traction_free() {
        for plane in [PlaneModel::Strain, PlaneModel::Stress] {
            let k = plate(plane);
            for i in 0..72 {
                let t = 2.0 * PI * i as f64 / 72.0;
                let e_r = [t.cos(), t.sin()];
                let p = [k.radius * e_r[0], k.radius * e_r[1]];
                let tr = k.traction(p, [-e_r[0], -e_r[1]]);
                assert!(tr[0].abs() + tr[1].abs() <= TOL * k.tension, "traction {tr:?} at t = {t}");
            }
        }
    }

    #[test]
    fn polar_and_cartesian_stresses_agree() {
        let k = plate(PlaneModel::Stress);
        for (r, t) in [(1.0, 0.3), (1.5, 2.0), (3.0, -0.7), (7.0, 4.0)] {
            let [srr, stt, srt] = k.polar_stress(r, t);
            let (c, s) = (f64::cos(t), f64::sin(t));
            let rotated = [
                srr * c * c + stt * s * s - 2.0 * srt * c * s,
                srr * s * s + stt * c * c + 2.0 * srt * c * s,
                (srr - stt) * c * s + srt * (c * c - s * s),
            ];
            let cart = k.stress([r * c, r * s]);
            for i in 0..3 {
                assert!((rotated[i] - cart[i]).abs() <= TOL * k.tension, "{rotated:?} vs {cart:?}");
            }
        }
    }

    #[test]
    fn far_field_tends_to_uniaxial_tension() {
        let k = plate(PlaneModel::Strain);
        let t = k.tension;
        for r in [10.0, 100.0, 1000.0] {
            let q2 = (k.radius / r).powi(2);
            // From the Cartesian formulas: |s - (T, 0, 0)| <= T (5/2 q2 + 3/2 q2^2) per
            // component, so the error decays like (a/r)^2.
            let bound = t * (2.5 * q2 + 1.5 * q2 * q2) + TOL * t;
            for i in 0..16 {
                let th = 2.0 * PI * (i as f64 + 0.25) / 16.0;
                let s = k.stress([r * th.cos(), r * th.sin()]);
                let err = [s[0] - t, s[1], s[2]];
                assert!(err.iter().all(|e| e.abs() <= bound), "r = {r}: {s:?}");
            }
        }
        let s = k.stress([1e4, 3e3]);
        assert!((s[0] - t).abs() + s[1].abs() + s[2].abs() <= 1e-7 * t, "{s:?}");
    }

    #[test]
    fn symmetry_lines_of_the_quarter_plate() {
        // u = 0 and sigma_xy = 0 on x = 0; v = 0 and sigma_xy = 0 on y = 0: the symmetry
        // rows of verification.md's quarter-plate test rely on these.
        let k = plate(PlaneModel::Strain);
        let scale = k.displacement([5.0, 0.0])[0].abs();
        for s in [1.0, 1.7, 3.0, 5.0] {
            let on_y = k.displacement([0.0, s]);
            let on_x = k.displacement([s, 0.0]);
            assert!(on_y[0].abs() <= 1e-14 * scale && on_x[1].abs() <= 1e-14 * scale);
            assert!(k.stress([0.0, s])[2].abs() <= TOL * k.tension);
            assert!(k.stress([s, 0.0])[2].abs() <= TOL * k.tension);
        }
    }

    #[test]
    fn constructor_rejects_nonphysical_parameters() {
        let m = plate(PlaneModel::Strain).material;
        assert_eq!(Kirsch::new(1.0, 0.0, m).unwrap_err().parameter, "radius");
        // nu = 0.5 is incompressible plane strain (accepted), but not a plane-stress material.
        let incompressible = Material { elastic: YoungPoisson { young: 1.0, poisson: 0.5 }, ..m };
        assert!(Kirsch::new(1.0, 1.0, incompressible).is_ok());
        let bad = Material { plane: PlaneModel::Stress, ..incompressible };
        assert_eq!(Kirsch::new(1.0, 1.0, bad).unwrap_err().parameter, "poisson");
    }
}
