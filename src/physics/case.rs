//! The physical problem of a scene, independent of any discretisation: the solid,
//! its material, body force and boundary conditions, the closed-form solution it is
//! checked against, the time settings, and the fields the user asked for. Both
//! models read a [`Case`]; each adds its own discretisation parameters
//! (`navier::NavierParams`, `peridynamics::PdParams`).

use crate::domain::corner::corners;
use crate::domain::Point;
use crate::domain::{Domain, NodeSet};
use crate::models::dynamics::DynamicsParams;
use crate::physics::elasticity::conditions::ComponentCondition;
use crate::physics::elasticity::conditions::{BoundaryCondition, Value};
use crate::physics::elasticity::material::Material;
use crate::physics::exact::{ExactKind, ExactSolution, ExpressionSolution, NamedSolution};
use crate::quality::post::probe::Probe;
use crate::scene::choice::choice;
use crate::scene::expression::VectorExpression;
use crate::stages::RunError;
use rayon::prelude::*;
use serde::Serialize;

/// Output fields a run writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Outputs {
    /// Displacement vector.
    pub displacement: bool,
    /// Strain components.
    pub strain: bool,
    /// Stress components.
    pub stress: bool,
    /// Von Mises stress.
    pub von_mises: bool,
    /// Error fields and norms against the exact solution.
    pub error: bool,
    /// Stress at the probes only (a stress `[[probe]]`; not written as a field).
    pub stress_at_probes: bool,
}

choice! {
    /// A field of `output.fields`.
    pub enum OutputField("output.fields[k]", default None, note "displacement, stress, von_mises, and error when the scene has [exact]") {
        /// Displacement (always written).
        Displacement = "displacement" => "the displacement vector (always written)",
        /// Strain components.
        Strain = "strain" => "eps_xx, eps_yy, eps_xy",
        /// Stress components.
        Stress = "stress" => "sigma_xx, sigma_yy, sigma_xy (and sigma_zz in plane strain)",
        /// Von Mises stress.
        VonMises = "von_mises" => "von Mises stress",
        /// Errors against the exact solution.
        Error = "error" => "exact displacement and the error fields and norms (needs [exact])",
    }
}

impl Outputs {
    /// Request `field`.
    pub fn request(&mut self, field: OutputField) {
        let slot = match field {
            OutputField::Displacement => &mut self.displacement,
            OutputField::Strain => &mut self.strain,
            OutputField::Stress => &mut self.stress,
            OutputField::VonMises => &mut self.von_mises,
            OutputField::Error => &mut self.error,
        };
        *slot = true;
    }

    /// Whether post-processing needs the displacement gradient.
    pub fn needs_gradient(&self) -> bool {
        self.strain || self.stress || self.von_mises || self.error || self.stress_at_probes
    }
}

/// The solid, its loads and what to report (see the module docs).
#[derive(Debug, Clone)]
pub struct Case {
    /// The solid.
    pub domain: Domain,
    /// Material.
    pub material: Material,
    /// Body force.
    pub body_force: Value,
    /// Condition of each boundary part, indexed like `domain.parts`.
    pub conditions: Vec<BoundaryCondition>,
    /// Closed-form solution, if any.
    pub exact: Option<NamedSolution>,
    /// Requested fields.
    pub outputs: Outputs,
    /// Time-dependent run settings, when the scene has a `[dynamics]` table.
    pub dynamics: Option<DynamicsParams>,
    /// Point values the scene asks for (`[[probe]]`).
    pub probes: Vec<Probe>,
}

/// The loads of a case at one instant: the body force and the boundary conditions
/// with the time `t` of their formulas bound.
#[derive(Debug, Clone)]
pub struct Loads {
    /// Body force.
    pub body_force: Value,
    /// Condition of each boundary part.
    pub conditions: Vec<BoundaryCondition>,
}

impl Loads {
    /// The first load formula that is not finite at `p`, as the error naming it,
    /// its value, the point and the time `t`.
    pub fn non_finite_at(&self, p: Point, t: f64) -> Option<RunError> {
        let values = std::iter::once(&self.body_force).chain(self.conditions.iter().map(|c| &c.value));
        values.filter_map(|v| if let Value::Expression(e) = v { Some(e) } else { None }).find_map(|e| {
            e.non_finite_at(p).map(|(field, text, value)| RunError::BadFormula {
                field,
                text: text.to_string(),
                value,
                x: p[0],
                y: p[1],
                context: format!(" at t = {t:.6e}"),
            })
        })
    }

    /// Whether a load is a formula in `t`.
    pub fn depend_on_time(&self) -> bool {
        self.body_force.depends_on_time() || self.conditions.iter().any(|c| c.value.depends_on_time())
    }

    /// The loads at the fixed time `t` ([`Value::at_time`]).
    pub fn at_time(&self, t: f64) -> Loads {
        Loads {
            body_force: self.body_force.at_time(t),
            conditions: self.conditions.iter().map(|c| BoundaryCondition { value: c.value.at_time(t), ..c.clone() }).collect(),
        }
    }

    /// The time derivatives of the loads (still functions of `t`; zero where a load
    /// does not depend on time), or the field of the formula that cannot be
    /// differentiated and why.
    pub fn time_derivative(&self) -> Result<Loads, (String, String)> {
        let conditions = self.conditions.iter().map(|c| Ok(BoundaryCondition { value: c.value.time_derivative()?, ..c.clone() }));
        Ok(Loads { body_force: self.body_force.time_derivative()?, conditions: conditions.collect::<Result<_, (String, String)>>()? })
    }
}

impl Case {
    /// The body force and boundary conditions.
    pub fn loads(&self) -> Loads {
        Loads { body_force: self.body_force.clone(), conditions: self.conditions.clone() }
    }

    /// The loads at time `t`.
    pub fn loads_at(&self, t: f64) -> Loads {
        self.loads().at_time(t)
    }

    /// The exact solution the scene names, if any (its parameters were validated).
    pub fn exact_solution(&self) -> Option<Box<dyn ExactSolution>> {
        self.exact.as_ref().map(|e| e.build(self.material).expect("validated exact solution parameters"))
    }

    /// Every formula of the scene evaluated where a run uses it: the body force, the
    /// initial state and an `[exact] kind = "expression"` (with its derivatives) at
    /// `points`, each boundary value at the `boundary` points `(position, part)` of its
    /// part. The first value that is not finite is an error naming the formula and
    /// the point.
    pub fn check_formulas(&self, points: &[Point], boundary: &[(Point, usize)]) -> Result<(), RunError> {
        let bad = |(field, text, value): (String, &str, f64), p: Point| RunError::BadFormula {
            field,
            text: text.to_string(),
            value,
            x: p[0],
            y: p[1],
            context: String::new(),
        };
        let mut everywhere: Vec<&VectorExpression> = Vec::new();
        let dynamics = self.dynamics.iter().flat_map(|d| [&d.initial_displacement, &d.initial_velocity]);
        for v in std::iter::once(&self.body_force).chain(dynamics) {
            if let Value::Expression(e) = v {
                everywhere.push(e);
            }
        }
        let exact = match &self.exact {
            Some(named) if named.kind == ExactKind::Expression => {
                Some(ExpressionSolution::from_parameters(&named.parameters, self.material).expect("validated exact solution"))
            }
            _ => None,
        };
        if !everywhere.is_empty() || exact.is_some() {
            let found = points.par_iter().find_map_first(|&p| {
                let at = everywhere.iter().find_map(|e| e.non_finite_at(p)).or_else(|| exact.as_ref()?.non_finite_at(p));
                at.map(|a| bad(a, p))
            });
            if let Some(e) = found {
                return Err(e);
            }
        }
        for &(p, part) in boundary {
            if let Value::Expression(e) = &self.conditions[part].value {
                if let Some(a) = e.non_finite_at(p) {
                    return Err(bad(a, p));
                }
            }
        }
        Ok(())
    }
}

/// Radius of the neighbourhood of a singular corner that the stress check skips, in
/// local node spacings (on the steel plate, h = 0.01, the estimated stress error falls
/// from 0.36 at the clamped corners to 2.2e-3 at ten spacings).
pub const SINGULAR_RADIUS: f64 = 10.0;

/// A corner where the stress is singular.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SingularCorner {
    /// Position.
    pub at: Point,
    /// Why: `re-entrant` or `clamped meets traction`.
    pub reason: &'static str,
    /// Radius skipped by the stress check.
    pub radius: f64,
}

impl SingularCorner {
    /// Whether `p` lies within [`SingularCorner::radius`] of the corner, `|p - at| <= radius`.
    pub fn covers(&self, p: Point) -> bool {
        (p[0] - self.at[0]).hypot(p[1] - self.at[1]) <= self.radius
    }
}

/// The singular corners of `case` on `nodes`: where a clamped part meets a part with
/// a traction component, and re-entrant corners; none when the case has an exact
/// solution (exact solutions are smooth). There the exact stress is unbounded.
pub fn singular_corners(case: &Case, nodes: &NodeSet) -> Vec<SingularCorner> {
    if case.exact.is_some() {
        return Vec::new();
    }
    let clamped = |part: usize| case.conditions[part].components.iter().all(|c| *c == ComponentCondition::Displacement);
    let traction = |part: usize| case.conditions[part].components.contains(&ComponentCondition::Traction);
    corners(&case.domain, nodes)
        .into_iter()
        .filter_map(|c| {
            let [a, b] = c.parts;
            let reason = if c.reentrant {
                "re-entrant"
            } else if (clamped(a) && traction(b)) || (clamped(b) && traction(a)) {
                "clamped meets traction"
            } else {
                return None;
            };
            Some(SingularCorner { at: c.position, reason, radius: SINGULAR_RADIUS * nodes.local_spacing[c.node] })
        })
        .collect()
}
