//! Closed-form and manufactured solutions of 2D linear elasticity, for verification.
//!
//! Every solution solves the static Navier equation
//!
//! ```text
//! (lambda + mu) grad div u + mu lap u + f = 0
//! ```
//!
//! with `lambda` the in-plane first Lame parameter of its [`Material`] (plane stress uses
//! `lambda* = 2 mu lambda / (lambda + 2 mu)`, see `Material::lame`). Stresses are ordered
//! `[sigma_xx, sigma_yy, sigma_xy]` and gradients `[[u_x, u_y], [v_x, v_y]]`, as in
//! `Lame::stress`.
//!
//! | solution | source (verification.md) | body force | plane models |
//! |---|---|---|---|
//! | [`Cantilever`] | 1, variant A (Timoshenko & Goodier) | 0 | stress; strain via `E'`, `nu'` |
//! | [`Kirsch`] | 2 (Kirsch 1898; Barber) | 0 | both, through `kappa` |
//! | [`Flamant`] (line load on a half-plane) | 5 (Flamant 1892; Barber) | 0 | both, through `lambda` |
//! | [`LameCylinder`] (thick cylinder) | 3 (Lame) | 0 | both |
//! | [`Manufactured`] | 6 | analytic | both |
//! | [`Polynomial`] | 6 (patch tests) | analytic | both |
//! | [`ExpressionSolution`] | any formulas `ux`, `uy` | derived symbolically | both |
//!
//! The closed-form cases return their published stress formulas from
//! [`ExactSolution::stress`]; the tests check that these agree with
//! `Lame::stress(gradient)`, which is where a wrong `kappa` or `lambda` shows up.
//!
//! Constructors (`new`) check the parameters once and say what to change; the fields stay
//! public so a problem can be read, printed and serialised as it is.

mod cantilever;
mod expression;
mod flamant;
mod kirsch;
mod lame;
mod manufactured;
pub mod named;
mod polynomial;
#[cfg(test)]
mod tests;

use std::fmt;

use crate::physics::elasticity::conditions::Value;
use crate::physics::elasticity::material::{self, Material, PlaneModel};

pub use cantilever::Cantilever;
pub use expression::ExpressionSolution;
pub use flamant::Flamant;
pub use kirsch::Kirsch;
pub use lame::LameCylinder;
pub use manufactured::Manufactured;
pub use named::{ExactKind, NamedSolution, Parameter, ParameterKind, ParameterValue, Parameters};
pub use polynomial::Polynomial;

/// A closed-form displacement field that solves the Navier equation with a known body force.
pub trait ExactSolution: Send + Sync {
    /// Short name for logs and summaries, e.g. `"kirsch"`.
    fn name(&self) -> &'static str;
    /// The material the field was derived for (its `lame()` enters the Navier operator).
    fn material(&self) -> Material;
    /// Displacement `[u, v]` at `p`.
    fn displacement(&self, p: [f64; 2]) -> [f64; 2];
    /// `[[u_x, u_y], [v_x, v_y]]`.
    fn gradient(&self, p: [f64; 2]) -> [[f64; 2]; 2];
    /// `[sigma_xx, sigma_yy, sigma_xy]`; equals `Lame::stress(gradient)`, which is the
    /// default (the closed-form solutions give their own stress formulas).
    fn stress(&self, p: [f64; 2]) -> [f64; 3] {
        self.material().lame().stress(self.gradient(p))
    }
    /// `f` in `(lambda + mu) grad div u + mu lap u + f = 0`; zero for the closed-form cases.
    fn body_force(&self, p: [f64; 2]) -> [f64; 2];
    /// Traction `sigma n` for the unit outward normal `n` of the body.
    fn traction(&self, p: [f64; 2], n: [f64; 2]) -> [f64; 2] {
        let [sxx, syy, sxy] = self.stress(p);
        [sxx * n[0] + sxy * n[1], sxy * n[0] + syy * n[1]]
    }
}

/// Kolosov constant: `kappa = 3 - 4 nu` (plane strain), `(3 - nu)/(1 + nu)` (plane stress)
/// (verification.md, notation). Equals `(lambda + 3 mu)/(lambda + mu)` with the in-plane
/// `lambda`.
pub fn kolosov(material: &Material) -> f64 {
    let nu = material.elastic.poisson;
    match material.plane {
        PlaneModel::Strain => 3.0 - 4.0 * nu,
        PlaneModel::Stress => (3.0 - nu) / (1.0 + nu),
    }
}

/// Navier body force `f = -((lambda + mu) grad div u + mu lap u)` from the Hessians
/// `hu = [[u_xx, u_xy], [u_xy, u_yy]]` and `hv` of the two displacement components
/// (verification.md, section 6).
pub fn navier_body_force(lame: material::Lame, hu: [[f64; 2]; 2], hv: [[f64; 2]; 2]) -> [f64; 2] {
    let material::Lame { lambda, mu } = lame;
    let grad_div = [hu[0][0] + hv[0][1], hu[0][1] + hv[1][1]];
    let lap = [hu[0][0] + hu[1][1], hv[0][0] + hv[1][1]];
    [-((lambda + mu) * grad_div[0] + mu * lap[0]), -((lambda + mu) * grad_div[1] + mu * lap[1])]
}

/// A parameter of an exact solution that cannot describe a physical problem.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterError {
    /// Which solution, e.g. `"lame"`.
    pub solution: &'static str,
    /// Which parameter, e.g. `"outer"`.
    pub parameter: &'static str,
    /// The value given.
    pub value: f64,
    /// What the value must satisfy, e.g. `"must exceed the inner radius"`.
    pub requirement: &'static str,
}

impl fmt::Display for ParameterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Extreme values in exponent form (5e-300, not 300 digits).
        let v = self.value;
        let value = if v != 0.0 && v.is_finite() && !(1e-4..1e6).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") };
        write!(f, "exact solution {}: parameter {} = {value} {}", self.solution, self.parameter, self.requirement)
    }
}

impl std::error::Error for ParameterError {}

/// Checks shared by the constructors: finite values, positive lengths, admissible material.
pub(crate) struct Check(pub &'static str);

impl Check {
    pub(crate) fn finite(&self, parameter: &'static str, value: f64) -> Result<(), ParameterError> {
        self.require(parameter, value, value.is_finite(), "must be finite")
    }

    pub(crate) fn positive(&self, parameter: &'static str, value: f64) -> Result<(), ParameterError> {
        self.require(parameter, value, value.is_finite() && value > 0.0, "must be positive and finite")
    }

    /// `E > 0` and `-1 < nu < 1/2`, or `nu = 1/2` in plane strain (incompressible:
    /// the closed-form solutions stay finite there).
    pub(crate) fn material(&self, material: &Material) -> Result<(), ParameterError> {
        self.positive("young", material.elastic.young)?;
        let nu = material.elastic.poisson;
        let ok = nu.is_finite() && nu > -1.0 && (nu < 0.5 || material.is_incompressible() && nu == 0.5);
        self.require("poisson", nu, ok, "must lie in (-1, 0.5), or be 0.5 in plane strain")
    }

    /// [`Check::material`] and `nu < 1/2`, for a field that is not divergence-free: its
    /// stress `lambda div u` is infinite in an incompressible solid.
    pub(crate) fn compressible_material(&self, material: &Material) -> Result<(), ParameterError> {
        self.material(material)?;
        let nu = material.elastic.poisson;
        let requirement = "must lie below 0.5: the field is not divergence-free, so its stress lambda div u is infinite at nu = 0.5";
        self.require("poisson", nu, !material.is_incompressible(), requirement)
    }

    pub(crate) fn require(&self, parameter: &'static str, value: f64, ok: bool, requirement: &'static str) -> Result<(), ParameterError> {
        if ok {
            Ok(())
        } else {
            Err(ParameterError { solution: self.0, parameter, value, requirement })
        }
    }
}

/// The vector a boundary or body-force [`Value`] stands for at `p`: the constant, the
/// expression's value, or `pick` applied to the exact solution (validation makes sure
/// one exists).
pub fn value(value: &Value, p: [f64; 2], exact: Option<&dyn ExactSolution>, pick: impl FnOnce(&dyn ExactSolution) -> [f64; 2]) -> [f64; 2] {
    value.explicit_at(p).unwrap_or_else(|| pick(exact.expect("validated: \"exact\" values need an exact solution")))
}
