//! Flamant: a concentrated line load `P` on the surface of a half-plane.
//!
//! Source: verification.md, section 5; A. Flamant, C. R. Acad. Sci. 114 (1892); J. R.
//! Barber, *Elasticity*, chapter 12 (the concentrated force on a half-plane). The body is
//! `y < 0`, the force `P` pushes into it at the origin (`P > 0` compresses):
//!
//! ```text
//! s_xx = 2P x^2 y / (pi r^4),  s_yy = 2P y^3 / (pi r^4),  s_xy = 2P x y^2 / (pi r^4)
//! u = A [2xy/r^2 + k1 atan2(y, x)],   v = A [(y^2 - x^2)/r^2 - k2 ln r^2]
//! A = -P / (4 pi mu),  k1 = 2 mu / (lambda + mu),  k2 = (lambda + 2 mu) / (lambda + mu)
//! ```
//!
//! with the in-plane `lambda` (plane stress uses `lambda*`), up to a rigid motion. The
//! stresses fall as `1/r` and are singular at the load point, so the solution is meant
//! for a domain that keeps away from the origin (e.g. `[-1, 1] x [-1, -0.1]`), loaded by
//! its exact tractions: the stress gradient near the top edge is what graded node
//! density is for. `atan2` is continuous in the open lower half-plane.
//!
//! Gradient, term by term:
//!
//! ```text
//! u_x = A [2y(y^2 - x^2)/r^4 - k1 y/r^2],   u_y = A [2x(x^2 - y^2)/r^4 + k1 x/r^2]
//! v_x = A [-4x y^2/r^4 - 2 k2 x/r^2],       v_y = A [4x^2 y/r^4 - 2 k2 y/r^2]
//! ```

use std::f64::consts::PI;

use serde::Serialize;

use super::named::{Parameter, ParameterKind, Parameters};
use super::{Check, ExactSolution, ParameterError};
use crate::physics::elasticity::material::Material;

/// Line load `P` into the half-plane `y < 0` at the origin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Flamant {
    /// Load per unit thickness `P` (N/m), positive pushing into the body (along -y).
    pub load: f64,
    /// Material; `lambda` (in-plane) and `mu` come from it.
    pub material: Material,
}

impl Flamant {
    /// Parameters of `[exact] kind = "flamant"`.
    pub const PARAMETERS: &'static [Parameter] = &[Parameter {
        name: "load",
        kind: ParameterKind::Number,
        help: "line load P at the origin, positive into the half-plane y < 0 (N/m)",
    }];

    /// From validated scene parameters.
    pub fn from_parameters(p: &Parameters, material: Material) -> Result<Self, ParameterError> {
        Flamant::new(p.number("load"), material)
    }

    /// Checked constructor.
    pub fn new(load: f64, material: Material) -> Result<Self, ParameterError> {
        let check = Check("flamant");
        check.finite("load", load)?;
        check.material(&material)?;
        Ok(Flamant { load, material })
    }

    /// `(A, k1, k2)` of the module formula.
    fn constants(&self) -> (f64, f64, f64) {
        // k1 = 2 mu / (lambda + mu) = 2 b, k2 = (lambda + 2 mu) / (lambda + mu) = 1 + b,
        // finite at lambda = inf (nu = 1/2 in plane strain).
        let (_, b) = self.material.pressure_weights();
        (-self.load / (4.0 * PI * self.material.mu()), 2.0 * b, 1.0 + b)
    }
}

impl ExactSolution for Flamant {
    fn name(&self) -> &'static str {
        "flamant"
    }

    fn material(&self) -> Material {
        self.material
    }

    fn displacement(&self, [x, y]: [f64; 2]) -> [f64; 2] {
        let (a, k1, k2) = self.constants();
        let r2 = x * x + y * y;
        [a * (2.0 * x * y / r2 + k1 * y.atan2(x)), a * ((y * y - x * x) / r2 - k2 * r2.ln())]
    }

    fn gradient(&self, [x, y]: [f64; 2]) -> [[f64; 2]; 2] {
        let (a, k1, k2) = self.constants();
        let r2 = x * x + y * y;
        let r4 = r2 * r2;
        [
            [a * (2.0 * y * (y * y - x * x) / r4 - k1 * y / r2), a * (2.0 * x * (x * x - y * y) / r4 + k1 * x / r2)],
            [a * (-4.0 * x * y * y / r4 - 2.0 * k2 * x / r2), a * (4.0 * x * x * y / r4 - 2.0 * k2 * y / r2)],
        ]
    }

    fn stress(&self, [x, y]: [f64; 2]) -> [f64; 3] {
        let r2 = x * x + y * y;
        let c = 2.0 * self.load / (PI * r2 * r2);
        [c * x * x * y, c * y * y * y, c * x * y * y]
    }

    fn body_force(&self, _: [f64; 2]) -> [f64; 2] {
        [0.0, 0.0]
    }
}
