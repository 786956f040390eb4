//! `[dynamics]`: density, end time, integrator, time step (fixed, or a fraction of
//! the stable step), affine initial state, snapshots.

use super::expressions::initial;
use super::Ctx;
use crate::models::dynamics::{DynamicsParams, Integrator};
use crate::scene::problem::spec::DynamicsSpec;
use crate::scene::problem::ProblemError;

/// `[dynamics]`.
pub(super) fn dynamics(c: &Ctx, s: &DynamicsSpec) -> Result<DynamicsParams, ProblemError> {
    let density = c.positive("dynamics.density", c.need("dynamics.density", s.density, "the mass density rho (kg/m^3)")?)?;
    let end_time = c.positive("dynamics.end_time", c.need("dynamics.end_time", s.end_time, "the final time (s)")?)?;
    let integrator: Integrator = c.choose("dynamics.integrator", s.integrator.as_deref())?;
    let time_step = match s.time_step {
        Some(dt) => Some(c.positive("dynamics.time_step", dt)?),
        None => None,
    };
    if let Some(dt) = time_step {
        if dt > end_time {
            return c.err("dynamics.time_step", format!("{dt} is longer than end_time = {end_time}"));
        }
        if s.safety.is_some() {
            return c.err("dynamics.safety", "only used without a fixed time_step");
        }
    }
    let safety = s.safety.unwrap_or(0.8);
    if !(safety > 0.0 && safety <= 1.0) {
        return c.err("dynamics.safety", format!("must lie in (0, 1], got {safety}"));
    }
    if s.snapshots.is_some() && s.snapshot_every.is_some() {
        return c.err("dynamics.snapshot_every", "give either snapshots (a count) or snapshot_every (steps), not both");
    }
    if s.snapshot_every == Some(0) {
        return c.err("dynamics.snapshot_every", "must be at least 1");
    }
    let snapshots = s.snapshots.unwrap_or(10);
    if snapshots > 10_000 {
        return c.err("dynamics.snapshots", format!("{snapshots} snapshots; at most 10000"));
    }
    Ok(DynamicsParams {
        allow_long: false,
        density,
        end_time,
        integrator,
        time_step,
        safety,
        initial_displacement: initial(c, "dynamics.initial_displacement", s.initial_displacement.as_ref())?,
        initial_velocity: initial(c, "dynamics.initial_velocity", s.initial_velocity.as_ref())?,
        snapshots,
        snapshot_every: s.snapshot_every,
    })
}
