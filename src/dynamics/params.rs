//! The time settings of a scene's `[dynamics]` table, validated: density, end time,
//! scheme, step, initial state and snapshots.

use super::Integrator;
use serde::Serialize;

/// An affine vector field `u_c(x, y) = c[0] + c[1] x + c[2] y` per component.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Affine {
    /// Coefficients of the x component.
    pub x: [f64; 3],
    /// Coefficients of the y component.
    pub y: [f64; 3],
}

impl Affine {
    /// The zero field.
    pub const ZERO: Affine = Affine { x: [0.0; 3], y: [0.0; 3] };

    /// Value at `p`.
    pub fn at(&self, p: [f64; 2]) -> [f64; 2] {
        [self.x[0] + self.x[1] * p[0] + self.x[2] * p[1], self.y[0] + self.y[1] * p[0] + self.y[2] * p[1]]
    }
}

/// The `[dynamics]` table, validated.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
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
    /// Initial displacement.
    pub initial_displacement: Affine,
    /// Initial velocity.
    pub initial_velocity: Affine,
    /// N: the series holds N + 1 states from t = 0 to the end (0: the final state
    /// only); see [`is_snapshot`](crate::dynamics::driver::is_snapshot).
    pub snapshots: usize,
    /// A snapshot every k steps and at the end, when given (instead of `snapshots`).
    pub snapshot_every: Option<usize>,
    /// Run more than [`MAX_STEPS`](crate::dynamics::driver::MAX_STEPS) steps
    /// (`mlsm run --allow-long`).
    pub allow_long: bool,
}
