//! The time settings of a scene's `[dynamics]` table, validated: density, end time,
//! scheme, step, initial state and snapshots.

use super::Integrator;
use crate::physics::elasticity::conditions::Value;
use serde::Serialize;

/// The `[dynamics]` table, validated.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DynamicsParams {
    /// Mass density rho (kg/m^3).
    pub density: f64,
    /// Final time (s).
    pub end_time: f64,
    /// Time integrator.
    pub integrator: Integrator,
    /// Fixed time step, if the scene gives one.
    pub time_step: Option<f64>,
    /// Fraction of the stable step used otherwise.
    pub safety: f64,
    /// Initial displacement (a constant or an expression).
    pub initial_displacement: Value,
    /// Initial velocity (a constant or an expression).
    pub initial_velocity: Value,
    /// N: the series holds N + 1 states from t = 0 to the end (0: the final state
    /// only); see [`is_snapshot`](crate::models::dynamics::driver::is_snapshot).
    pub snapshots: usize,
    /// A snapshot every k steps and at the end, when given (instead of `snapshots`).
    pub snapshot_every: Option<usize>,
    /// Run more than [`MAX_STEPS`](crate::models::dynamics::driver::MAX_STEPS) steps
    /// (`mlsm run --allow-long`).
    pub allow_long: bool,
}
