//! Expressions of the scene file: loads, initial states and exact solutions written
//! as formulas in `x` and `y`, with the scene's named
//! constants, e.g. `"-P * (D^2/4 - y^2) / (2 * I)"`.
//!
//! Parsing, compilation and symbolic differentiation are done by `exmex`. Measured
//! against `evalexpr`, `fasteval` and `meval` on a five-variable load expression
//! (1e6 evaluations, release build, this project's machine): an exmex evaluation took
//! a tenth of evalexpr's (docs/guide/formulas.md); fasteval and meval are unmaintained
//! since 2020 and 2017, and evalexpr accepts `2x` and `x +* y` without an error.
//! exmex is also the only candidate that differentiates (`Differentiate::partial`),
//! which gives the body force and the stresses of a manufactured solution without
//! hand algebra (`exact::ExpressionSolution`). Its error texts are terse, so
//! [`Expression::parse`] checks names and functions itself and rewords the syntax
//! errors.
//!
//! Syntax: numbers (`2`, `1.5e-3`), `+ - * /`, `^` (power), parentheses, the
//! variables `x`, `y` (and the time `t` in the loads of a scene with `[dynamics]`),
//! `pi`, the scene's `[constants]`, and the functions listed in [`FUNCTIONS`].

mod syntax;

pub use syntax::NumberLiteral;

use exmex::prelude::*;
use exmex::{Differentiate, FloatOpsFactory};
use serde::Serialize;
use std::fmt;
use syntax::{check_tokens, syntax_reason};

/// Functions an expression may call (one argument each).
pub const FUNCTIONS: &[&str] = &[
    "sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "asinh", "acosh", "atanh", "exp", "ln", "log", "log10", "log2",
    "sqrt", "cbrt", "abs", "signum", "floor", "ceil", "round", "trunc", "fract",
];

/// Names exmex reads as built-in constants or binary operators: a scene constant may
/// not take them (`E` would silently be Euler's number).
const RESERVED: &[&str] = &["x", "y", "t", "pi", "PI", "E", "e", "TAU", "π", "τ", "atan2", "min", "max"];

/// The longest formula (characters) and the deepest nesting of parentheses accepted.
const MAX_LENGTH: usize = 4000;
const MAX_NESTING: usize = 64;

/// The most variables and constants one expression may use.
const MAX_VARIABLES: usize = 32;

/// An expression that cannot be used, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("\"{text}\": {reason}")]
pub struct ExpressionError {
    /// The expression as written.
    pub text: String,
    /// What is wrong and what to write instead.
    pub reason: String,
}

/// The named constants of a scene (`[constants]`), by name.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Constants(Vec<(String, f64)>);

impl Constants {
    /// Whether `name` may name a constant: an identifier (letters, digits, `_`, not
    /// starting with a digit) that is no variable, function or built-in constant.
    pub fn check_name(name: &str) -> Result<(), String> {
        let identifier = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !identifier {
            Err("a constant name is letters, digits and _, starting with a letter".into())
        } else if RESERVED.contains(&name) || FUNCTIONS.contains(&name) {
            Err(format!("\"{name}\" is a variable, function or built-in constant of expressions; choose another name"))
        } else {
            Ok(())
        }
    }

    /// Add `name = value` (the name checked by [`Constants::check_name`]).
    pub fn insert(&mut self, name: &str, value: f64) {
        self.0.retain(|(n, _)| n != name);
        self.0.push((name.to_string(), value));
    }

    /// The value of `name`, if defined.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }

    /// The names, in definition order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|(n, _)| n.as_str())
    }
}

/// What an expression may refer to besides the constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// `x` and `y` (static loads, exact solutions, initial states).
    Space,
    /// `x`, `y` and the time `t` (the loads of a time-dependent run).
    SpaceTime,
    /// Constants only (a constant defined by other constants).
    Constants,
}

/// Where a variable of the compiled expression takes its value from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Slot {
    X,
    Y,
    T,
    Fixed(f64),
}

/// A compiled scalar expression `g(x, y, t)`.
#[derive(Clone)]
pub struct Expression {
    text: String,
    flat: Flat,
    slots: Vec<Slot>,
}

impl fmt::Debug for Expression {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Expression({:?})", self.text)
    }
}

impl PartialEq for Expression {
    fn eq(&self, other: &Self) -> bool {
        self.text == other.text
    }
}

impl Serialize for Expression {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.text)
    }
}

/// The compiled form: exmex's flat expression with our literals.
type Flat = FlatEx<f64, FloatOpsFactory<f64>, NumberLiteral>;

impl Expression {
    /// Parse and compile `text`; every name must be a variable of `scope`, `pi`, or one
    /// of `constants`, and every called function one of [`FUNCTIONS`].
    pub fn parse(text: &str, scope: Scope, constants: &Constants) -> Result<Expression, ExpressionError> {
        let fail = |reason: String| ExpressionError { text: text.to_string(), reason };
        if text.trim().is_empty() {
            return Err(fail("empty expression".into()));
        }
        check_tokens(text).map_err(fail)?;
        let flat = Flat::parse(text).map_err(|e| fail(syntax_reason(&e.to_string())))?;
        let mut slots = Vec::new();
        for name in flat.var_names() {
            let slot = match (name.as_str(), scope) {
                ("x", Scope::Space | Scope::SpaceTime) => Slot::X,
                ("y", Scope::Space | Scope::SpaceTime) => Slot::Y,
                ("t", Scope::SpaceTime) => Slot::T,
                ("t", _) => {
                    return Err(fail("the time t exists only in the loads (boundary values, body force) of a scene with [dynamics]".into()))
                }
                ("pi", _) => Slot::Fixed(std::f64::consts::PI),
                (n, _) => match constants.get(n) {
                    Some(v) => Slot::Fixed(v),
                    None => {
                        let mut known: Vec<&str> = match scope {
                            Scope::Space => vec!["x", "y", "pi"],
                            Scope::SpaceTime => vec!["x", "y", "t", "pi"],
                            Scope::Constants => vec!["pi"],
                        };
                        known.extend(constants.names());
                        return Err(fail(format!("unknown name \"{n}\" (known: {}; define constants in [constants])", known.join(", "))));
                    }
                },
            };
            slots.push(slot);
        }
        if slots.len() > MAX_VARIABLES {
            return Err(fail(format!("uses {} names; at most {MAX_VARIABLES}", slots.len())));
        }
        Ok(Expression { text: text.to_string(), flat, slots })
    }

    /// The constant `value` as an expression.
    pub fn constant(value: f64) -> Expression {
        let flat = Flat::parse(&format!("{value:e}")).unwrap_or_else(|_| Flat::parse("0").expect("zero parses"));
        let text = if value.is_finite() { format!("{value}") } else { "0".into() };
        Expression { text, flat, slots: Vec::new() }
    }

    /// The expression as written (or as derived, for a derivative).
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Value at `p` and time 0 (NaN or infinite where the formula is, e.g. `1/x` at
    /// `x = 0`: callers check).
    pub fn eval(&self, p: [f64; 2]) -> f64 {
        self.eval_at(p, 0.0)
    }

    /// Value at `p` and time `t`.
    pub fn eval_at(&self, p: [f64; 2], t: f64) -> f64 {
        let mut values = [0.0; MAX_VARIABLES];
        for (v, s) in values.iter_mut().zip(&self.slots) {
            *v = match *s {
                Slot::X => p[0],
                Slot::Y => p[1],
                Slot::T => t,
                Slot::Fixed(c) => c,
            };
        }
        self.flat.eval(&values[..self.slots.len()]).unwrap_or(f64::NAN)
    }

    /// Whether the expression uses the time `t`.
    pub fn uses_time(&self) -> bool {
        self.slots.contains(&Slot::T)
    }

    /// The expression at the fixed time `t` (a function of `x` and `y` only): the
    /// same compiled formula with `t` bound, so this costs no parsing.
    pub fn at_time(&self, t: f64) -> Expression {
        let slots = self.slots.iter().map(|&s| if s == Slot::T { Slot::Fixed(t) } else { s }).collect();
        Expression { text: self.text.clone(), flat: self.flat.clone(), slots }
    }

    /// `d/dx` (`axis` 0) or `d/dy` (`axis` 1), symbolically; refused for functions
    /// without a derivative (`abs`, `floor`, ...).
    pub fn derivative(&self, axis: usize) -> Result<Expression, ExpressionError> {
        self.partial(if axis == 0 { Slot::X } else { Slot::Y })
    }

    /// `d/dt`, symbolically (zero for an expression without `t`).
    pub fn time_derivative(&self) -> Result<Expression, ExpressionError> {
        self.partial(Slot::T)
    }

    /// The partial derivative in the variable `wanted`.
    fn partial(&self, wanted: Slot) -> Result<Expression, ExpressionError> {
        let Some(index) = self.slots.iter().position(|&s| s == wanted) else {
            return Ok(Expression::constant(0.0));
        };
        let flat = self.flat.clone().partial(index).map_err(|e| ExpressionError {
            text: self.text.clone(),
            reason: format!("cannot be differentiated: {e}; write it without abs, signum, floor, ceil, round, trunc, fract"),
        })?;
        let text = flat.unparse().replace(['{', '}'], "");
        Ok(Expression { text, flat, slots: self.slots.clone() })
    }
}

/// A vector field `(g_x, g_y)` of two expressions.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VectorExpression {
    /// x component.
    pub x: Expression,
    /// y component.
    pub y: Expression,
    /// Where it was written (`boundary[2].value`), for messages.
    #[serde(skip)]
    pub origin: String,
}

impl VectorExpression {
    /// Value at `p` (and time 0).
    pub fn at(&self, p: [f64; 2]) -> [f64; 2] {
        [self.x.eval(p), self.y.eval(p)]
    }

    /// Whether either component uses the time `t`.
    pub fn uses_time(&self) -> bool {
        self.x.uses_time() || self.y.uses_time()
    }

    /// Both components at the fixed time `t` ([`Expression::at_time`]).
    pub fn at_time(&self, t: f64) -> VectorExpression {
        VectorExpression { x: self.x.at_time(t), y: self.y.at_time(t), origin: self.origin.clone() }
    }

    /// `d/dt` of both components, symbolically.
    pub fn time_derivative(&self) -> Result<VectorExpression, ExpressionError> {
        Ok(VectorExpression { x: self.x.time_derivative()?, y: self.y.time_derivative()?, origin: format!("d/dt {}", self.origin) })
    }

    /// The first component that is not finite at `p`: its field (`origin[c]`), text
    /// and value.
    pub fn non_finite_at(&self, p: [f64; 2]) -> Option<(String, &str, f64)> {
        [&self.x, &self.y].into_iter().enumerate().find_map(|(c, e)| {
            let v = e.eval(p);
            (!v.is_finite()).then(|| (format!("{}[{c}]", self.origin), e.text(), v))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constants() -> Constants {
        let mut c = Constants::default();
        c.insert("P", 1000.0);
        c.insert("D", 2.0);
        c
    }

    #[test]
    fn evaluates_with_constants_pi_and_functions() {
        let e = Expression::parse("P * (D^2/4 - y^2) + sin(pi * x)", Scope::Space, &constants()).unwrap();
        let (x, y) = (0.3, -0.4);
        let want = 1000.0 * (1.0 - y * y) + (std::f64::consts::PI * x).sin();
        assert!((e.eval([x, y]) - want).abs() < 1e-12 * want.abs());
    }

    #[test]
    fn derivatives_are_exact_and_finite_at_negative_bases() {
        // d/dx (x^3 y) = 3 x^2 y; d2/dx2 = 6 x y; the power rule must not take ln(x) of x < 0.
        let e = Expression::parse("x^3 * y", Scope::Space, &Constants::default()).unwrap();
        let dx = e.derivative(0).unwrap();
        let dxx = dx.derivative(0).unwrap();
        let dy = e.derivative(1).unwrap();
        let p = [-1.5, 0.7];
        assert!((dx.eval(p) - 3.0 * 2.25 * 0.7).abs() < 1e-12);
        assert!((dxx.eval(p) - 6.0 * -1.5 * 0.7).abs() < 1e-12);
        assert!((dy.eval(p) - -3.375).abs() < 1e-12);
        let c = Expression::parse("5 * y", Scope::Space, &Constants::default()).unwrap();
        assert_eq!(c.derivative(0).unwrap().eval(p), 0.0);
        let a = Expression::parse("abs(x)", Scope::Space, &Constants::default()).unwrap();
        assert!(a.derivative(0).is_err());
    }

    /// `t` is bound by [`Expression::at_time`] and differentiated by
    /// [`Expression::time_derivative`]: `d/dt (x sin(3 t)) = 3 x cos(3 t)`.
    #[test]
    fn time_is_a_variable_of_the_loads() {
        let e = Expression::parse("x * sin(3 * t) + P", Scope::SpaceTime, &constants()).unwrap();
        let (p, t) = ([0.5, 2.0], 0.4);
        assert!(e.uses_time() && !e.at_time(t).uses_time());
        assert!((e.eval_at(p, t) - (0.5 * (1.2f64).sin() + 1000.0)).abs() < 1e-12);
        assert_eq!(e.at_time(t).eval(p), e.eval_at(p, t));
        assert_eq!(e.eval(p), 1000.0);
        let rate = e.time_derivative().unwrap();
        assert!((rate.eval_at(p, t) - 1.5 * (1.2f64).cos()).abs() < 1e-12);
        let still = Expression::parse("x * P", Scope::SpaceTime, &constants()).unwrap();
        assert!(!still.uses_time());
        assert_eq!(still.time_derivative().unwrap().eval_at(p, t), 0.0);
    }

    #[test]
    fn errors_name_the_problem() {
        let c = constants();
        let reason = |text: &str, scope| Expression::parse(text, scope, &c).unwrap_err().reason;
        assert!(reason("x + z", Scope::Space).contains("unknown name \"z\""));
        assert!(reason("x * t", Scope::Space).contains("[dynamics]"));
        assert!(reason("x * t", Scope::Constants).contains("[dynamics]"));
        assert!(reason("x * s", Scope::SpaceTime).contains("known: x, y, t, pi"));
        assert!(reason("sin(x", Scope::Space).contains("unbalanced parentheses"));
        assert!(reason("x +* y", Scope::Space).contains("two operators in a row"));
        assert!(reason("2x", Scope::Space).contains("write 2*x"));
        assert!(reason("foo(x)", Scope::Space).contains("unknown function \"foo\""));
        assert!(reason("pow(x, 2)", Scope::Space).contains("a^b"));
        assert!(reason("  ", Scope::Space).contains("empty"));
        assert!(reason("x", Scope::Constants).contains("unknown name \"x\""));
        assert!(reason("-x^2", Scope::Space).contains("sign before a power"));
        assert!(reason("2*-sin(x)^2", Scope::Space).contains("sign before a power"));
        assert!(reason("x^2^3", Scope::Space).contains("chained powers"));
        assert!(reason("E*x", Scope::Space).contains("ambiguous"));
        assert!(reason("sin x", Scope::Space).contains("parentheses"));
        // Exponents of numbers; signed exponents; a power of a signed group.
        let ok = |text: &str, p: [f64; 2], want: f64| {
            let got = Expression::parse(text, Scope::Space, &c).unwrap().eval(p);
            assert!((got - want).abs() <= 1e-12 * want.abs(), "{text}: {got} != {want}");
        };
        ok("1e-3*(x+1)", [1.0, 0.0], 2e-3);
        ok("1.5E3 + .5 + 3.", [0.0, 0.0], 1503.5);
        ok("x^-2", [2.0, 0.0], 0.25);
        ok("-(x^2) + (-y)^2 - 2*(x^2)", [3.0, 2.0], -23.0);
        ok("sin(x)^2 + cos(x)^2", [0.7, 0.0], 1.0);
    }

    #[test]
    fn constant_names_are_checked() {
        assert!(Constants::check_name("rho_w").is_ok());
        for bad in ["E", "pi", "sin", "x", "1a", "a-b", ""] {
            assert!(Constants::check_name(bad).is_err(), "{bad}");
        }
    }
}
