//! Boundary conditions of a boundary part and where their values come from: the
//! vocabulary both models read (the Navier model turns them into equations at its
//! boundary nodes, peridynamics into volume constraints and layer loads).

use crate::scene::choice::choice;
use crate::scene::expression::VectorExpression;
use serde::Serialize;
use std::sync::Arc;

choice! {
    /// How a displacement component is constrained on a boundary part.
    pub enum ComponentCondition("boundary[k].x, boundary[k].y", default None, note "required for kind = \"mixed\"", serde "lowercase") {
        /// Prescribed displacement component.
        Displacement = "displacement" => "the component of `value` is the displacement u_c",
        /// Prescribed traction component `(sigma n)_c`.
        Traction = "traction" => "the component of `value` is the traction (sigma n)_c",
    }
}

choice! {
    /// What a `[[boundary]]` entry prescribes on its part.
    pub enum ConditionKind("boundary[k].kind", default None) {
        /// Both displacement components.
        Displacement = "displacement" => "u = `value` (m)",
        /// Both traction components.
        Traction = "traction" => "sigma n = `value` (Pa); a free edge is [0, 0]",
        /// One condition per component (`x`, `y`).
        Mixed = "mixed" => "per component: `x` and `y` name the condition of each (e.g. symmetry)",
    }
}

/// Where a boundary value, body force or initial state comes from.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Value {
    /// A constant vector.
    Constant([f64; 2]),
    /// The scene's exact solution (displacement, traction `sigma n`, or body force).
    Exact,
    /// A formula per component in `x`, `y` (`[0, "-rho * g"]`).
    Expression(Arc<VectorExpression>),
}

impl Value {
    /// The value at `p` of a constant or an expression; `None` for [`Value::Exact`],
    /// which needs the exact solution (`exact::value`).
    pub fn explicit_at(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        match self {
            Value::Constant(c) => Some(*c),
            Value::Expression(e) => Some(e.at(p)),
            Value::Exact => None,
        }
    }

    /// Whether the value changes in time (a formula in `t`).
    pub fn depends_on_time(&self) -> bool {
        matches!(self, Value::Expression(e) if e.uses_time())
    }

    /// The value at the fixed time `t` (unchanged unless it depends on time).
    pub fn at_time(&self, t: f64) -> Value {
        match self {
            Value::Expression(e) if e.uses_time() => Value::Expression(Arc::new(e.at_time(t))),
            other => other.clone(),
        }
    }

    /// `d/dt` of the value: zero unless it depends on time (the exact solutions are
    /// static), the symbolic derivative of a formula in `t`; else the field and why.
    pub fn time_derivative(&self) -> Result<Value, (String, String)> {
        match self {
            Value::Expression(e) if e.uses_time() => match e.time_derivative() {
                Ok(rate) => Ok(Value::Expression(Arc::new(rate))),
                Err(why) => Err((e.origin.clone(), why.to_string())),
            },
            _ => Ok(Value::Constant([0.0, 0.0])),
        }
    }

    /// Whether the value is the zero vector everywhere.
    pub fn is_zero(&self) -> bool {
        *self == Value::Constant([0.0, 0.0])
    }
}

/// The condition imposed on one boundary part.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoundaryCondition {
    /// Condition on the x and y components.
    pub components: [ComponentCondition; 2],
    /// Prescribed displacement or traction.
    pub value: Value,
}

impl BoundaryCondition {
    /// A free edge: zero traction on both components.
    pub const FREE: BoundaryCondition =
        BoundaryCondition { components: [ComponentCondition::Traction; 2], value: Value::Constant([0.0, 0.0]) };

    /// Whether both components are prescribed by `kind`.
    pub fn is_all(&self, kind: ComponentCondition) -> bool {
        self.components == [kind; 2]
    }
}
