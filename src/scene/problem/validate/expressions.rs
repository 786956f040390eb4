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
/// any order; a cycle or an unknown name is an error). The constants are evaluated
/// once each, in the order of their references (a depth-first topological sort of the
/// names each formula mentions): linear in their number and length, where retrying the
/// unresolved ones pass after pass took cubic time on a chain that refers forward
/// (1 000 chained constants 12 s, 3 000 over a minute).
pub(super) fn constants(c: &Ctx, spec: Option<&BTreeMap<String, NumberOrFormula>>) -> Result<Constants, ProblemError> {
    let mut out = Constants::default();
    let Some(spec) = spec else { return Ok(out) };
    for name in spec.keys() {
        Constants::check_name(name).map_err(|reason| c.error(format!("constants.{name}"), reason))?;
    }
    let names: Vec<&String> = spec.keys().collect();
    let index: BTreeMap<&str, usize> = names.iter().enumerate().map(|(k, n)| (n.as_str(), k)).collect();
    let refers: Vec<Vec<usize>> = spec
        .values()
        .map(|v| match v {
            NumberOrFormula::Number(_) => Vec::new(),
            NumberOrFormula::Formula(text) => identifiers(text).filter_map(|w| index.get(w).copied()).collect(),
        })
        .collect();
    // Iterative depth-first search: 0 unvisited, 1 on the path, 2 done.
    let mut state = vec![0u8; names.len()];
    let mut order = Vec::with_capacity(names.len());
    for root in 0..names.len() {
        if state[root] != 0 {
            continue;
        }
        let mut stack = vec![(root, 0usize)];
        state[root] = 1;
        while let Some((node, next)) = stack.pop() {
            if let Some(&dep) = refers[node].get(next) {
                stack.push((node, next + 1));
                match state[dep] {
                    0 => {
                        state[dep] = 1;
                        stack.push((dep, 0));
                    }
                    1 => {
                        let mut on_path: Vec<&str> =
                            stack.iter().map(|&(k, _)| names[k].as_str()).skip_while(|n| *n != names[dep]).collect();
                        let length = on_path.len();
                        if length > 8 {
                            on_path.splice(4..length - 2, ["..."]);
                        }
                        return c.err(
                            format!("constants.{}", names[dep]),
                            format!("the constants refer to each other in a cycle of {length}: {} -> {}", on_path.join(" -> "), names[dep]),
                        );
                    }
                    _ => {}
                }
            } else {
                state[node] = 2;
                order.push(node);
            }
        }
    }
    for k in order {
        let (name, v) = (names[k], &spec[names[k]]);
        let field = format!("constants.{name}");
        let x = match v {
            NumberOrFormula::Number(x) => *x,
            NumberOrFormula::Formula(text) => {
                Expression::parse(text, Scope::Constants, &out).map(|e| e.eval([0.0, 0.0])).map_err(|e| c.error(&field, e.to_string()))?
            }
        };
        if !x.is_finite() {
            return c.err(&field, format!("evaluates to {x}; a constant must be finite"));
        }
        out.insert(name, x);
    }
    Ok(out)
}

/// The identifiers (`[A-Za-z_][A-Za-z0-9_]*`, not preceded by a digit or a dot: not
/// the exponent of `1e5`) a formula mentions.
fn identifiers(text: &str) -> impl Iterator<Item = &str> {
    let bytes = text.as_bytes();
    let mut k = 0;
    std::iter::from_fn(move || {
        while k < bytes.len() {
            let b = bytes[k];
            if b.is_ascii_alphabetic() || b == b'_' {
                let start = k;
                while k < bytes.len() && (bytes[k].is_ascii_alphanumeric() || bytes[k] == b'_') {
                    k += 1;
                }
                let after_number = start > 0 && (bytes[start - 1].is_ascii_digit() || bytes[start - 1] == b'.');
                if !after_number {
                    return Some(&text[start..k]);
                }
            } else {
                k += 1;
            }
        }
        None
    })
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
