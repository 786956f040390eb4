//! `[constants]` and the values written as formulas: boundary values, body force and
//! initial states (`[0, "-rho * g"]`), checked once here (names, syntax); the values a
//! formula takes at the nodes are checked where the nodes are known
//! (`case::Case::check_values`).

use super::Ctx;
use crate::physics::elasticity::conditions::Value;
use crate::scene::expression::{Constants, Expression, Scope, VectorExpression};
use crate::scene::problem::spec::{InitialSpec, NumberOrFormula};
use crate::scene::problem::ProblemError;
use std::collections::BTreeMap;
use std::sync::Arc;

/// `[constants]`: every name checked, every formula of other constants evaluated (in
/// any order; a cycle or an unknown name is an error).
pub(super) fn constants(c: &Ctx, spec: Option<&BTreeMap<String, NumberOrFormula>>) -> Result<Constants, ProblemError> {
    let mut out = Constants::default();
    let Some(spec) = spec else { return Ok(out) };
    for name in spec.keys() {
        Constants::check_name(name).map_err(|reason| c.error(format!("constants.{name}"), reason))?;
    }
    let mut pending: Vec<(&String, &NumberOrFormula)> = spec.iter().collect();
    while !pending.is_empty() {
        let before = pending.len();
        let mut last_error = None;
        pending.retain(|&(name, v)| {
            let field = format!("constants.{name}");
            let value = match v {
                NumberOrFormula::Number(x) => Ok(*x),
                NumberOrFormula::Formula(text) => {
                    Expression::parse(text, Scope::Constants, &out).map(|e| e.eval([0.0, 0.0])).map_err(|e| c.error(&field, e.to_string()))
                }
            };
            match value {
                Ok(x) if x.is_finite() => {
                    out.insert(name, x);
                    false
                }
                Ok(x) => {
                    last_error = Some(c.error(&field, format!("evaluates to {x}; a constant must be finite")));
                    true
                }
                Err(e) => {
                    last_error = Some(e);
                    true
                }
            }
        });
        if pending.len() == before {
            // No progress: an unknown name, a cycle, or a non-finite value.
            return Err(last_error.expect("an entry failed"));
        }
    }
    Ok(out)
}

/// A formula or number as an expression of the variables of `scope` and the constants.
pub(super) fn formula_of(c: &Ctx, field: &str, v: &NumberOrFormula, scope: Scope) -> Result<Expression, ProblemError> {
    match v {
        NumberOrFormula::Number(x) => {
            c.finite(field, &[*x])?;
            Ok(Expression::constant(*x))
        }
        NumberOrFormula::Formula(text) => Expression::parse(text, scope, &c.constants).map_err(|e| c.error(field, e.to_string())),
    }
}

/// `[x, y]` of numbers or formulas in the variables of `scope`: a constant when both
/// are numbers.
pub(super) fn vector(c: &Ctx, field: &str, v: &[NumberOrFormula], scope: Scope) -> Result<Value, ProblemError> {
    if v.len() != 2 {
        return c.err(field, format!("needs exactly 2 components [x, y], got {}", v.len()));
    }
    if let [NumberOrFormula::Number(x), NumberOrFormula::Number(y)] = v {
        c.finite(field, &[*x, *y])?;
        return Ok(Value::Constant([*x, *y]));
    }
    let x = formula_of(c, &format!("{field}[0]"), &v[0], scope)?;
    let y = formula_of(c, &format!("{field}[1]"), &v[1], scope)?;
    Ok(Value::Expression(Arc::new(VectorExpression { x, y, origin: field.to_string() })))
}

/// An initial displacement or velocity: affine coefficients or a vector.
pub(super) fn initial(c: &Ctx, field: &str, v: Option<&InitialSpec>) -> Result<Value, ProblemError> {
    match v {
        None => Ok(Value::Constant([0.0, 0.0])),
        Some(InitialSpec::Vector(v)) => vector(c, field, v, Scope::Space),
        Some(InitialSpec::Affine(a)) => {
            c.finite(&format!("{field}.x"), &a.x.0)?;
            c.finite(&format!("{field}.y"), &a.y.0)?;
            // `c0 + cx x + cy y`, written with round-trip exact numbers.
            let affine = |k: [f64; 3]| NumberOrFormula::Formula(format!("{:e} + {:e}*x + {:e}*y", k[0], k[1], k[2]));
            vector(c, field, &[affine(a.x.0), affine(a.y.0)], Scope::Space)
        }
    }
}
