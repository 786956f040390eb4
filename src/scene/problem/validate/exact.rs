//! `[exact]` and the values that may refer to it: the named solution with its
//! parameters (each solution declares them, see `exact::named`), and `"exact"` as a
//! body force or boundary value.

use super::expressions::{formula_of, vector};
use super::Ctx;
use crate::scene::choice::Choice;
use crate::physics::elasticity::conditions::Value;
use crate::physics::elasticity::material::Material;
use crate::physics::exact::{ExactKind, ExpressionSolution, NamedSolution, ParameterKind, ParameterValue, Parameters};
use crate::scene::expression::Scope;
use crate::scene::problem::spec::{ExactSpec, NumberOrFormula, VectorOrExact};
use crate::scene::problem::ProblemError;

/// The numbers of a parameter value: a number, or an array of numbers.
fn numbers(v: &toml::Value) -> Option<Vec<f64>> {
    let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    match v {
        toml::Value::Array(a) => a.iter().map(number).collect(),
        v => number(v).map(|x| vec![x]),
    }
}

/// `[exact]`: the solution and its parameters, checked by building it for `material`.
pub(super) fn exact(c: &Ctx, s: &ExactSpec, material: Material) -> Result<NamedSolution, ProblemError> {
    let kind: ExactKind = c.choose("exact.kind", Some(&s.kind))?;
    let declared = kind.parameters();
    let takes = || declared.iter().map(|p| p.name).collect::<Vec<_>>().join(", ");
    if let Some(k) = s.parameters.keys().find(|k| !declared.iter().any(|p| p.name == k.as_str())) {
        return c.err(format!("exact.{k}"), format!("not a parameter of the {} solution (it takes: {})", kind.name(), takes()));
    }
    let mut parameters = Parameters::default();
    for p in declared {
        let field = format!("exact.{}", p.name);
        let given = c.need(&field, s.parameters.get(p.name), &format!("the {} solution needs {}", kind.name(), p.name))?;
        if p.kind == ParameterKind::Expression {
            let formula = match given {
                toml::Value::String(text) => NumberOrFormula::Formula(text.clone()),
                v => match numbers(v) {
                    Some(x) if x.len() == 1 && !v.is_array() => NumberOrFormula::Number(x[0]),
                    _ => return c.err(&field, format!("must be a formula in quotes or a number ({})", p.help)),
                },
            };
            parameters.set(p.name, ParameterValue::Expression(Box::new(formula_of(c, &field, &formula, Scope::Space)?)));
            continue;
        }
        let values = match (p.kind, given.is_array(), numbers(given)) {
            (ParameterKind::Coefficients(n), true, Some(v)) if v.len() == n => v,
            (ParameterKind::Coefficients(n), is_array, v) => {
                let got = match v {
                    Some(v) if is_array => v.len().to_string(),
                    _ => "something else".to_string(),
                };
                return c.err(&field, format!("needs {n} coefficients ({}); got {got}", p.help));
            }
            (_, false, Some(v)) => v,
            _ => return c.err(&field, format!("must be a number ({})", p.help)),
        };
        c.finite(&field, &values)?;
        if p.kind == ParameterKind::Length {
            c.positive(&field, values[0])?;
        }
        parameters.insert(p.name, values);
    }
    if kind == ExactKind::Expression {
        let (ux, uy) = (parameters.expression("ux").clone(), parameters.expression("uy").clone());
        if let Err(e) = ExpressionSolution::derive(ux, uy, material) {
            let which = if parameters.expression("ux").text() == e.text { "ux" } else { "uy" };
            return c.err(format!("exact.{which}"), e.to_string());
        }
    }
    let named = NamedSolution { kind, parameters };
    if let Err(pe) = named.build(material) {
        return c.err(format!("exact.{}", pe.parameter), pe.to_string());
    }
    Ok(named)
}

/// A value given as `"exact"`: valid only with an `[exact]` table.
pub(super) fn exact_word(c: &Ctx, field: &str, word: &str, has_exact: bool) -> Result<Value, ProblemError> {
    if word != "exact" {
        return c.err(field, format!("expected [x, y] or \"exact\", got \"{word}\""));
    }
    if !has_exact {
        return c.err(field, "\"exact\" needs an [exact] table naming the solution");
    }
    Ok(Value::Exact)
}

/// A boundary value or body force: a vector of numbers or formulas (in `x`, `y`, and
/// `t` when the scene has `[dynamics]`), or `"exact"` (default zero).
pub(super) fn value(c: &Ctx, field: &str, v: Option<&VectorOrExact>, has_exact: bool) -> Result<Value, ProblemError> {
    let scope = if c.dynamic { Scope::SpaceTime } else { Scope::Space };
    match v {
        None => Ok(Value::Constant([0.0, 0.0])),
        Some(VectorOrExact::Vector(v)) => vector(c, field, v, scope),
        Some(VectorOrExact::Word(w)) => exact_word(c, field, w, has_exact),
    }
}

/// `body_force`; the manufactured solution needs its own.
pub(super) fn body_force(c: &Ctx, v: Option<&VectorOrExact>, exact: Option<&NamedSolution>) -> Result<Value, ProblemError> {
    let body_force = value(c, "body_force", v, exact.is_some())?;
    if exact.is_some_and(|e| e.kind == ExactKind::Manufactured) && body_force != Value::Exact {
        return c.err("body_force", "the manufactured solution needs its own body force: set body_force = \"exact\"");
    }
    Ok(body_force)
}
