//! The solutions a scene can name: `[exact] kind = "..."` and the parameters each
//! takes. Each solution declares its parameters next to its formulas
//! (`PARAMETERS`, `from_parameters`); [`ExactKind`] lists them.

use super::{Cantilever, ExactSolution, ExpressionSolution, Flamant, Kirsch, LameCylinder, Manufactured, ParameterError, Polynomial};
use crate::scene::choice::choice;
use crate::physics::elasticity::material::Material;
use crate::scene::expression::Expression;

/// What values a parameter accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParameterKind {
    /// Any finite number (loads, pressures).
    Number,
    /// A positive finite number (lengths).
    Length,
    /// An array of this many finite numbers.
    Coefficients(usize),
    /// A formula in `x`, `y` and the scene's constants.
    Expression,
}

/// A parameter of a named solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Parameter {
    /// Key in the `[exact]` table.
    pub name: &'static str,
    /// Accepted values.
    pub kind: ParameterKind,
    /// Meaning and unit.
    pub help: &'static str,
}

/// A validated parameter value.
#[derive(Debug, Clone, PartialEq)]
pub enum ParameterValue {
    /// Numbers (a number is an array of one).
    Numbers(Vec<f64>),
    /// A formula (boxed: it is much larger than a vector).
    Expression(Box<Expression>),
}

/// Validated parameter values, by name.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Parameters(Vec<(&'static str, ParameterValue)>);

impl Parameters {
    /// Set `name` to `values`.
    pub fn insert(&mut self, name: &'static str, values: Vec<f64>) {
        self.set(name, ParameterValue::Numbers(values));
    }

    /// Set `name` to `value`.
    pub fn set(&mut self, name: &'static str, value: ParameterValue) {
        self.0.retain(|(n, _)| *n != name);
        self.0.push((name, value));
    }

    fn value(&self, name: &str) -> &ParameterValue {
        self.0.iter().find(|(n, _)| *n == name).map(|(_, v)| v).unwrap_or_else(|| panic!("parameter {name} was validated"))
    }

    fn get(&self, name: &str) -> &[f64] {
        match self.value(name) {
            ParameterValue::Numbers(v) => v,
            ParameterValue::Expression(_) => panic!("parameter {name} was validated as numbers"),
        }
    }

    /// The formula `name`.
    pub fn expression(&self, name: &str) -> &Expression {
        match self.value(name) {
            ParameterValue::Expression(e) => e.as_ref(),
            ParameterValue::Numbers(_) => panic!("parameter {name} was validated as a formula"),
        }
    }

    /// The number `name`.
    pub fn number(&self, name: &str) -> f64 {
        self.get(name)[0]
    }

    /// The `N` coefficients `name`.
    pub fn coefficients<const N: usize>(&self, name: &str) -> [f64; N] {
        self.get(name).try_into().unwrap_or_else(|_| panic!("parameter {name} was validated to {N} coefficients"))
    }
}

choice! {
    /// The closed-form solutions a scene can name.
    pub enum ExactKind("exact.kind", default None) {
        Cantilever = "cantilever" => "Timoshenko cantilever under an end load (`load`, `length`, `depth`)",
        Kirsch = "kirsch" => "infinite plate with a hole under uniaxial tension (`tension`, `radius`)",
        Flamant = "flamant" => "line load on the half-plane y < 0 at the origin (`load`)",
        Lame = "lame" => "thick cylinder under internal pressure (`pressure`, `inner`, `outer`)",
        Manufactured = "manufactured" => "u = (sin(pi x) cos(pi y), x^2 y^3) with its body force (needs body_force = \"exact\")",
        Tension = "tension" => "uniform uniaxial stress sigma_xx = `tension`",
        Polynomial = "polynomial" => "a cubic field with its body force (`ux`, `uy`: 10 coefficients each)",
        Expression = "expression" => "any smooth field given as formulas `ux`, `uy` in x, y; body force, stress and tractions derived symbolically",
    }
}

impl ExactKind {
    /// The parameters of the `[exact]` table of this solution.
    pub fn parameters(self) -> &'static [Parameter] {
        match self {
            ExactKind::Cantilever => Cantilever::PARAMETERS,
            ExactKind::Kirsch => Kirsch::PARAMETERS,
            ExactKind::Flamant => Flamant::PARAMETERS,
            ExactKind::Lame => LameCylinder::PARAMETERS,
            ExactKind::Manufactured => &[],
            ExactKind::Tension => Polynomial::TENSION_PARAMETERS,
            ExactKind::Polynomial => Polynomial::PARAMETERS,
            ExactKind::Expression => ExpressionSolution::PARAMETERS,
        }
    }

    /// The solution with validated `parameters` for `material`.
    pub fn build(self, p: &Parameters, material: Material) -> Result<Box<dyn ExactSolution>, ParameterError> {
        Ok(match self {
            ExactKind::Cantilever => Box::new(Cantilever::from_parameters(p, material)?),
            ExactKind::Kirsch => Box::new(Kirsch::from_parameters(p, material)?),
            ExactKind::Flamant => Box::new(Flamant::from_parameters(p, material)?),
            ExactKind::Lame => Box::new(LameCylinder::from_parameters(p, material)?),
            ExactKind::Manufactured => Box::new(Manufactured::new(material)?),
            ExactKind::Tension => Box::new(Polynomial::uniaxial_tension(p.number("tension"), material)?),
            ExactKind::Polynomial => Box::new(Polynomial::new(p.coefficients("ux"), p.coefficients("uy"), material)?),
            ExactKind::Expression => Box::new(ExpressionSolution::from_parameters(p, material)?),
        })
    }
}

/// The `[exact]` table, validated: which solution and its parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedSolution {
    /// Which solution.
    pub kind: ExactKind,
    /// Its parameters.
    pub parameters: Parameters,
}

impl NamedSolution {
    /// The solution for `material`.
    pub fn build(&self, material: Material) -> Result<Box<dyn ExactSolution>, ParameterError> {
        self.kind.build(&self.parameters, material)
    }
}
