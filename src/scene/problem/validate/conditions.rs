//! `[[boundary]]`: one condition per boundary part (displacement, traction, or mixed
//! per component), every part that holds boundary nodes covered, and each
//! displacement component fixed somewhere in a static problem.

use super::exact::value;
use super::Ctx;
use crate::scene::choice::Choice;
use crate::domain::Domain;
use crate::physics::elasticity::conditions::{BoundaryCondition, ComponentCondition, ConditionKind};
use crate::scene::problem::spec::BoundarySpec;
use crate::scene::problem::ProblemError;

/// The condition of entry `k`, whose part is known to exist.
fn condition(c: &Ctx, k: usize, b: &BoundarySpec, has_exact: bool) -> Result<BoundaryCondition, ProblemError> {
    let f = |s: &str| format!("boundary[{k}].{s}");
    let component = |field: &str, w: &Option<String>| -> Result<ComponentCondition, ProblemError> {
        match w {
            None => c.err(f(field), "a mixed condition names the condition of each component: x = \"displacement\" or \"traction\""),
            Some(w) => c.choose(&f(field), Some(w)),
        }
    };
    let components = match c.choose(&f("kind"), Some(&b.kind))? {
        kind @ (ConditionKind::Displacement | ConditionKind::Traction) => {
            if b.x.is_some() || b.y.is_some() {
                return c.err(f("x"), format!("per-component conditions need kind = \"mixed\", not \"{}\"", kind.name()));
            }
            let cc = if kind == ConditionKind::Displacement { ComponentCondition::Displacement } else { ComponentCondition::Traction };
            [cc, cc]
        }
        ConditionKind::Mixed => [component("x", &b.x)?, component("y", &b.y)?],
    };
    Ok(BoundaryCondition { components, value: value(c, &f("value"), b.value.as_ref(), has_exact)? })
}

/// `[[boundary]]` entries -> the condition of every boundary part (`present`: whether
/// the part holds boundary nodes at all).
pub(super) fn conditions(
    c: &Ctx,
    specs: &[BoundarySpec],
    domain: &Domain,
    present: &[bool],
    has_exact: bool,
    dynamic: bool,
) -> Result<Vec<BoundaryCondition>, ProblemError> {
    let mut out: Vec<Option<BoundaryCondition>> = vec![None; domain.parts.len()];
    let known = || domain.parts.iter().map(|p| format!("\"{p}\"")).collect::<Vec<_>>().join(", ");
    for (k, b) in specs.iter().enumerate() {
        let field = format!("boundary[{k}].part");
        let Some(part) = domain.parts.iter().position(|p| *p == b.part) else {
            return c.err(field, format!("\"{}\" is not a boundary part of the domain (known: {})", b.part, known()));
        };
        if !present[part] {
            return c.err(
                field,
                format!(
                    "\"{}\" does not reach the boundary of the solid (it lies inside or outside the other regions); remove this condition",
                    b.part
                ),
            );
        }
        if out[part].is_some() {
            return c.err(field, format!("\"{}\" already has a condition; give one [[boundary]] per part", b.part));
        }
        out[part] = Some(condition(c, k, b, has_exact)?);
    }
    let mut conditions = Vec::new();
    for (i, o) in out.into_iter().enumerate() {
        match o {
            Some(bc) => conditions.push(bc),
            // A part with no boundary nodes (e.g. an edge cut away by a subtraction) needs no condition.
            None if !present[i] => conditions.push(BoundaryCondition::FREE),
            None => {
                return c.err(
                    "boundary",
                    format!(
                        "part \"{}\" has no condition; add [[boundary]] part = \"{}\" with kind = \"traction\" (free edge: value = [0, 0]) or another condition",
                        domain.parts[i], domain.parts[i]
                    ),
                )
            }
        }
    }
    // A static problem needs each component fixed somewhere; a time-dependent one is
    // well posed with free edges only (initial conditions fix the motion).
    if !dynamic {
        for (comp, axis) in ["x", "y"].iter().enumerate() {
            if !conditions.iter().zip(present).any(|(bc, &here)| here && bc.components[comp] == ComponentCondition::Displacement) {
                return c.err(
                    "boundary",
                    format!("no part prescribes the {axis} displacement: the solution is then fixed only up to a rigid motion; constrain it on at least one part"),
                );
            }
        }
    }
    Ok(conditions)
}
