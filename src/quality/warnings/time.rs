//! The checks of a time-dependent run: its estimate over the history, the drift of its
//! total energy, and each load formula in `t` against the time step.

use super::peridynamics::estimate_of_peridynamics;
use super::{exceeds, unestimated, Checks, Warning};
use crate::physics::case::Case;
use crate::scene::choice::Choice;
use crate::domain::Point;
use crate::models::dynamics::driver::EnergyRow;
use crate::models::dynamics::integrators::Integrator;
use crate::physics::elasticity::conditions::Value;
use crate::models::navier::Estimate;
use rayon::prelude::*;

/// The largest change of the total energy (kinetic + elastic + external + released by
/// broken bonds) over the history, relative to the largest sum of the magnitudes of its
/// parts: the integrators conserve it up to their time-discretisation error (there is
/// no damping, and the external part is the potential of the loads).
pub fn energy_drift(energies: &[EnergyRow]) -> f64 {
    let total = |e: &EnergyRow| e[1] + e[2] + e[3] + e[4];
    let Some(first) = energies.first() else { return 0.0 };
    let scale = energies.iter().map(|e| e[1].abs() + e[2].abs() + e[3].abs() + e[4].abs()).fold(0.0, f64::max);
    let change = energies.iter().map(|e| (total(e) - total(first)).abs()).fold(0.0, f64::max);
    if scale > 0.0 {
        change / scale
    } else {
        0.0
    }
}

/// The checks of a time-dependent run: the estimate at `end_time` (a Navier run's
/// `higher-degree` estimate above `threshold` is warned; a peridynamic run's
/// `local-model` one, with its `horizon`, is read by [`estimate_of_peridynamics`]),
/// and the energy drift ([`energy_drift`]) above `threshold` is warned, unless
/// `loads_vary` (loads that depend on time do work, so the total is not conserved: a
/// note says the check was not made).
pub fn dynamic(energies: &[EnergyRow], threshold: f64, loads_vary: bool, estimate: &Estimate, (horizon, integrator): (Option<f64>, Integrator)) -> Checks {
    let mut checks = Checks::default();
    match horizon {
        Some(horizon) => estimate_of_peridynamics(estimate, threshold, horizon, true, &mut checks),
        None => {
            if let Some(e) = unestimated(estimate, &mut checks).filter(|e| exceeds(e.norms.e_inf_u, threshold)) {
                checks.warnings.push(Warning {
                    check: "estimate",
                    message: format!(
                        "estimated error over the history above the threshold {threshold:.0e}: e_inf(u) ~ {:.1e} (largest \
                         at ({:.4e}, {:.4e}), t = {:.4e} s; space and time, against {}); try a smaller nodes.spacing, a \
                         higher approximation.degree or a smaller dynamics.time_step",
                        e.norms.e_inf_u,
                        e.largest_u_at[0],
                        e.largest_u_at[1],
                        e.largest_u_time.unwrap_or(f64::NAN),
                        e.reference
                    ),
                });
            }
        }
    }
    if loads_vary {
        checks.notes.push(
            "no energy check (only load-time-resolution): the loads depend on t, so their work changes the total energy \
             (energies.csv; its external part is -b(t).u)"
                .into(),
        );
        return checks;
    }
    let drift = energy_drift(energies);
    if exceeds(drift, threshold) {
        // RK4 is offered unless the run already takes it.
        let remedy = match integrator {
            Integrator::Rk4 => "try a smaller dynamics.time_step (or dynamics.safety)",
            _ => "try dynamics.integrator = \"rk4\" or a smaller dynamics.time_step",
        };
        checks.warnings.push(Warning {
            check: "energy-drift",
            message: format!(
                "the total energy changed by up to {drift:.1e} of its scale over the run (threshold {threshold:.0e}): \
                 the time integration is inaccurate; {remedy}"
            ),
        });
    }
    checks.notes.push(format!("the total energy is conserved to {drift:.1e} (energies.csv)"));
    checks
}

/// Instants at which [`load_time_resolution`] samples the loads over the run.
const LOAD_SAMPLE_TIMES: usize = 2000;

/// Boundary samples per part at most at which [`load_time_resolution`] reads a load
/// (every k-th sample of the run's spacing beyond that).
const LOAD_SAMPLE_POINTS: usize = 2000;

/// Where [`load_time_resolution`] reads each load: the boundary sampled at the run's
/// `spacing` (a boundary value on the samples of its part, where it acts; the body
/// force on all of them), and a 5 x 5 lattice over the bounding box for the body force
/// inside. A narrow load (a spot, a moving front) acts between the lattice's points,
/// where its value may underflow to zero, but never between the nodes that carry it.
struct LoadPoints {
    lattice: Vec<Point>,
    /// Boundary samples of each part (strided to [`LOAD_SAMPLE_POINTS`]).
    parts: Vec<Vec<Point>>,
}

impl LoadPoints {
    fn new(case: &Case, spacing: f64) -> Self {
        let (lo, hi) = case.domain.bounding_box();
        let lattice =
            (0..25).map(|k| [lo[0] + (hi[0] - lo[0]) * (k % 5) as f64 / 4.0, lo[1] + (hi[1] - lo[1]) * (k / 5) as f64 / 4.0]).collect();
        let samples = crate::domain::boundary::discretise_boundary(&case.domain, spacing);
        let parts = (0..case.conditions.len())
            .map(|part| {
                let on: Vec<Point> = samples.iter().filter(|s| s.touches.iter().any(|(p, _)| *p == part)).map(|s| s.position).collect();
                let stride = on.len().div_ceil(LOAD_SAMPLE_POINTS).max(1);
                on.into_iter().step_by(stride).collect()
            })
            .collect();
        LoadPoints { lattice, parts }
    }

    /// The points of the body force: the lattice and every part's samples.
    fn body(&self) -> Vec<Point> {
        self.lattice.iter().chain(self.parts.iter().flatten()).copied().collect()
    }
}

/// The time scale of one load formula in `t`: `tau = max |g| / max |dg/dt|` over the
/// sampled `times` and `points` (both maxima over the components; `1 / omega` for
/// `g = A sin(omega t)`, `T / pi` for the pulse `A sin(pi t / T)^2`). `None` for a load
/// that does not vary in time or that is zero or non-finite at every sample.
fn time_scale(value: &Value, points: &[Point], times: &[f64]) -> Option<f64> {
    if !value.depends_on_time() {
        return None;
    }
    let rate = value.time_derivative().ok()?;
    let largest = |v: &Value, t: f64| {
        let at = v.at_time(t);
        points.iter().filter_map(|&p| at.explicit_at(p)).flatten().filter(|x| x.is_finite()).fold(0.0f64, |m, x| m.max(x.abs()))
    };
    let (g, r) =
        times.par_iter().map(|&t| (largest(value, t), largest(&rate, t))).reduce(|| (0.0f64, 0.0f64), |a, b| (a.0.max(b.0), a.1.max(b.1)));
    (g > 0.0 && r > 0.0).then(|| g / r)
}

/// A load formula in `t` that the time step resolves poorly: its time scale `tau`
/// ([`time_scale`], sampled over the run) against the step `dt`, judged by the
/// integrator's error per radian for an oscillation on that time scale,
/// [`Integrator::error_per_radian`] at `h = dt / tau`. Warned above `threshold` (the
/// estimate's, default 1e-2: RK4 from 1.05 steps per time scale, Verlet from 2.0,
/// `emu` from 50), naming the load, its time scale and a step that would do (half the
/// threshold). Measured on plate_pulse with a 10x shorter pulse (tests/time_loads.rs).
/// The loads are read at [`LoadPoints`] for the run's node `spacing`.
pub fn load_time_resolution(
    case: &Case,
    spacing: f64,
    time_step: f64,
    end_time: f64,
    integrator: Integrator,
    threshold: f64,
) -> Option<Warning> {
    let loads = case.loads();
    let at = LoadPoints::new(case, spacing);
    let body = at.body();
    let times: Vec<f64> = (0..LOAD_SAMPLE_TIMES).map(|k| end_time * k as f64 / (LOAD_SAMPLE_TIMES - 1) as f64).collect();
    let fields = std::iter::once(("body_force".to_string(), &loads.body_force, &body[..]))
        .chain(loads.conditions.iter().enumerate().map(|(k, c)| (format!("boundary[{k}].value"), &c.value, &at.parts[k][..])));
    let (field, tau) = fields
        .filter_map(|(field, v, points)| {
            let name = match v {
                Value::Expression(e) if !e.origin.is_empty() => e.origin.clone(),
                _ => field,
            };
            time_scale(v, points, &times).map(|tau| (name, tau))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let error = integrator.error_per_radian(time_step / tau);
    exceeds(error, threshold).then(|| Warning {
        check: "load-time-resolution",
        message: format!(
            "the load {field} varies on a time scale of {tau:.2e} s (max |g| / max |dg/dt| over the run), {:.2} steps of \
             dt = {time_step:.2e} s: {} integrates an oscillation on that scale with an error of {error:.1e} per radian, \
             above {threshold:.0e}; the response to this load is poorly resolved in time: try dynamics.time_step = {:.2e} \
             or smaller",
            tau / time_step,
            integrator.name(),
            tau * integrator.step_for_error(threshold / 2.0)
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Energy exchanged between kinetic and elastic at constant total: no drift; a total
    /// that wanders by 3 % of the scale at one row: drift 0.03, warned at 1e-2, except
    /// when the loads depend on time (their work changes the total; a note says so).
    #[test]
    fn energy_drift_is_the_largest_change_of_the_total() {
        let conserved: Vec<EnergyRow> =
            (0..50).map(|k| (k as f64 * 0.1).sin()).map(|s| [0.0, 100.0 * s * s, 100.0 * (1.0 - s * s), 0.0, 0.0, 0.0]).collect();
        assert!(energy_drift(&conserved) < 1e-14);
        let off = Estimate::Off;
        assert!(dynamic(&conserved, 1e-2, false, &off, (None, Integrator::Verlet)).warnings.is_empty());
        let mut wandering = conserved.clone();
        wandering[20][1] += 3.0;
        assert!((energy_drift(&wandering) - 3.0 / 103.0).abs() < 1e-3 * 0.03, "{}", energy_drift(&wandering));
        let drifted = dynamic(&wandering, 1e-2, false, &off, (None, Integrator::Verlet));
        assert_eq!(drifted.warnings[0].check, "energy-drift");
        assert!(drifted.warnings[0].message.contains("integrator = \"rk4\""));
        // A run that takes RK4 already is not offered it.
        let rk4 = dynamic(&wandering, 1e-2, false, &off, (None, Integrator::Rk4));
        assert!(rk4.warnings[0].message.contains("smaller dynamics.time_step") && !rk4.warnings[0].message.contains("integrator"));
        let varying = dynamic(&wandering, 1e-2, true, &off, (None, Integrator::Verlet));
        assert!(varying.warnings.is_empty() && varying.notes.iter().any(|n| n.contains("no energy check")), "{:?}", varying.notes);
    }
}
