//! The time loop shared by every model: step size from the stability limit,
//! snapshots, the energy history and a throughput report.

use super::{DynamicsParams, Integrator, SecondOrderSystem, State};
use crate::physics::elasticity::stress::StressField;
use crate::scene::choice::Choice;
use crate::stages::{interrupt, RunError, Stage, StageTimer};
use serde::Serialize;

/// The stage of the time loop (shown with a progress bar).
pub const INTEGRATE: Stage = Stage::new("integrate");

/// What a dynamic run did.
#[derive(Debug, Clone, Serialize)]
pub struct DynamicReport {
    /// Scheme.
    pub integrator: Integrator,
    /// Step used.
    pub time_step: f64,
    /// Stable step of the central-difference schemes.
    pub stable_time_step: f64,
    /// Steps taken.
    pub steps: usize,
    /// Force evaluations (including the initial one).
    pub force_evaluations: usize,
    /// Wall-clock seconds of the stepping (energies and snapshots excluded).
    pub seconds: f64,
    /// The median step's wall-clock seconds: a step's cost with the pauses a loaded
    /// machine puts into a few steps left out (`seconds / steps` counts them).
    pub median_step_seconds: f64,
}

/// The state handed to a snapshot writer: nodal displacement and velocity at step
/// `step`, time `t`.
#[derive(Debug, Clone, Copy)]
pub struct Snapshot<'a> {
    /// Step number (0: the initial state).
    pub step: usize,
    /// Time.
    pub t: f64,
    /// Node positions.
    pub positions: &'a [[f64; 2]],
    /// Displacement of each node.
    pub u: &'a [[f64; 2]],
    /// Velocity of each node.
    pub v: &'a [[f64; 2]],
    /// Stress at each node, when the scene's outputs ask for stress or von Mises.
    pub stress: Option<&'a StressField>,
    /// Damage at each node (the share of its bonds' volume broken), when bonds break
    /// or the solid has pre-cracks.
    pub damage: Option<&'a [f64]>,
}

/// One line of the energy history: `(t, E_kin, E_el, E_ext, E_released, broken bonds)`
/// (the last two zero unless bonds break: the energy the broken bonds held when they
/// broke, and their count, both directions counted).
pub type EnergyRow = [f64; 6];

/// `(E_kin, E_el, E_ext, E_released, broken bonds)` of a state ([`EnergyRow`]).
pub type Energies = [f64; 5];

/// The step and step count of a run, checked against the stability limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeGrid {
    /// Step.
    pub dt: f64,
    /// Number of steps to `end_time`.
    pub steps: usize,
    /// Stable step of the central-difference schemes.
    pub stable: f64,
}

/// Step count above which an explicit run must be asked for (`--allow-long`): at
/// 1e8 steps even a 1e3-node run takes hours.
pub const MAX_STEPS: f64 = 1e8;

/// The step of `params` (fixed, or `safety` times the scheme's limit `stable x
/// stability_factor`), refused when a fixed step exceeds the limit, or when the run
/// has more than [`MAX_STEPS`] steps and `params.allow_long` is off.
pub fn time_grid(stable: f64, params: &DynamicsParams) -> Result<TimeGrid, RunError> {
    let limit = stable * params.integrator.stability_factor();
    let dt = match params.time_step {
        Some(dt) if dt > limit => return Err(RunError::UnstableTimeStep { given: dt, limit, integrator: params.integrator.name() }),
        Some(dt) => dt,
        None => params.safety * limit,
    };
    let steps = (params.end_time / dt).ceil().max(1.0);
    if steps > MAX_STEPS && !params.allow_long {
        return Err(RunError::TooManySteps { steps, dt });
    }
    Ok(match params.time_step {
        Some(dt) => TimeGrid { dt, steps: (params.end_time / dt).round().max(1.0) as usize, stable },
        None => TimeGrid { dt: params.end_time / steps, steps: steps as usize, stable },
    })
}

/// Whether step `step` (0: the initial state) of `steps` is a snapshot. With
/// `snapshot_every = k`: every k-th step from 0, and the last one. With `snapshots =
/// N >= 1`: the N + 1 steps `round(j steps / N)`, j = 0..=N (t = 0, N - 1 evenly spaced
/// states and the final one), every step when N >= steps. With N = 0: the last step only.
pub fn is_snapshot(step: usize, steps: usize, params: &DynamicsParams) -> bool {
    match params.snapshot_every {
        Some(k) => step.is_multiple_of(k) || step == steps,
        None => evenly_spaced(step, steps, params.snapshots),
    }
}

/// Whether `step` is one of the `n + 1` steps `round(j steps / n)`, j = 0..=n (every
/// step when `n >= steps`, the last one only when `n = 0`).
fn evenly_spaced(step: usize, steps: usize, n: usize) -> bool {
    if n == 0 {
        step == steps
    } else if n >= steps {
        true
    } else {
        // Nearest j; for N < steps the targets are more than one step apart.
        let round_div = |a: usize, b: usize| (a + b / 2) / b;
        round_div(round_div(step * n, steps) * steps, n) == step
    }
}

/// The energy history's cadence: a row every `k`-th step, the history within about 1000
/// rows. Where the energies cost about one force evaluation (a pass over the operator or
/// the bonds), `k` keeps them within a quarter of the stepping as well (`k >= 4 /
/// evaluations per step`: every fourth step with Verlet and `emu`, every step with RK4);
/// where the step's last evaluation kept them (`from_evaluation`: peridynamics under
/// Verlet), every step.
pub fn energy_every(steps: usize, integrator: Integrator, from_evaluation: bool) -> usize {
    let rows = steps.div_ceil(1000);
    if from_evaluation {
        rows.max(1)
    } else {
        rows.max(4usize.div_ceil(integrator.evaluations()))
    }
}

/// States over the history at which a dynamic run's error is estimated (besides none
/// at t = 0, where every run starts from the same prescribed state).
pub const HISTORY_SAMPLES: usize = 8;

/// The steps of the error estimate's history, `round(j steps / HISTORY_SAMPLES)` for
/// j = 1..=[`HISTORY_SAMPLES`] (the steps `snapshots = HISTORY_SAMPLES` writes, the
/// initial one excepted), the last step included.
pub fn history_steps(steps: usize) -> Vec<usize> {
    (1..=steps).filter(|&s| evenly_spaced(s, steps, HISTORY_SAMPLES)).collect()
}

/// Integrate `system` from `state` over `grid` with the scheme of `params`, calling
/// `visit` at the steps [`is_snapshot`] picks and at the steps `also` (sorted; the
/// callback tells them apart; `(grid, also)` is the schedule), and recording `energies` (kinetic,
/// elastic, external) every [`energy_every`]-th step, at the last one and at the first
/// step where [`SecondOrderSystem::settle`] changed the forces (the first bonds broke; a
/// row at every such step cost a step's time again where a plate shatters). The loop is the [`INTEGRATE`] stage
/// of `timer`, interruptible by Ctrl-C between steps (`pipeline::interrupt`). Returns
/// the report and the history.
pub fn integrate(
    system: &dyn SecondOrderSystem,
    energies: &dyn Fn(&State) -> Energies,
    state: &mut State,
    (grid, also): (TimeGrid, &[usize]),
    params: &DynamicsParams,
    timer: &mut StageTimer,
    mut visit: impl FnMut(usize, &State) -> Result<(), RunError>,
) -> Result<(DynamicReport, Vec<EnergyRow>), RunError> {
    let TimeGrid { dt, steps, stable } = grid;
    let visited = |step: usize| is_snapshot(step, steps, params) || also.binary_search(&step).is_ok();
    let energy_every = energy_every(steps, params.integrator, system.energies_from_evaluation());
    let mut history = Vec::with_capacity(steps.min(1000) + 2);
    let record = |s: &State, history: &mut Vec<EnergyRow>| {
        let [k, e, x, r, b] = energies(s);
        history.push([s.t, k, e, x, r, b]);
    };
    record(state, &mut history);
    if visited(0) {
        visit(0, state)?;
    }
    let progress = timer.progress();
    let _listening = interrupt::Interruptible::listen();
    let (looped, median_step_seconds) = timer.run(INTEGRATE, || {
        let (mut looped, mut broken) = (0.0, false);
        let mut step_seconds = Vec::with_capacity(steps);
        for step in 1..=steps {
            if interrupt::requested() {
                return Err(RunError::Interrupted { step, t: state.t, signal: interrupt::signal() });
            }
            let ts = std::time::Instant::now();
            let t0 = state.t;
            params.integrator.step(system, state, dt);
            let first_break = system.settle(state) && !broken;
            broken |= first_break;
            let took = ts.elapsed().as_secs_f64();
            looped += took;
            step_seconds.push(took as f32);
            if state.u.iter().chain(&state.a).any(|v| !v.is_finite()) {
                return Err(system.explain(t0, state.t).unwrap_or(RunError::Diverged { step, t: state.t }));
            }
            if step % energy_every == 0 || step == steps || first_break {
                record(state, &mut history);
            }
            if visited(step) {
                visit(step, state)?;
            }
            progress.advance(step as u64, steps as u64, "steps");
        }
        let middle = step_seconds.len() / 2;
        let median = if step_seconds.is_empty() { 0.0 } else { f64::from(*step_seconds.select_nth_unstable_by(middle, f32::total_cmp).1) };
        Ok(((looped, median), format!("{steps} steps")))
    })?;
    let report = DynamicReport {
        integrator: params.integrator,
        time_step: dt,
        stable_time_step: stable,
        steps,
        force_evaluations: 1 + steps * params.integrator.evaluations(),
        seconds: looped,
        median_step_seconds,
    };
    Ok((report, history))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(snapshots: usize, snapshot_every: Option<usize>) -> DynamicsParams {
        DynamicsParams {
            density: 1.0,
            end_time: 1.0,
            integrator: Integrator::Verlet,
            time_step: None,
            safety: 0.8,
            initial_displacement: crate::physics::elasticity::conditions::Value::Constant([0.0, 0.0]),
            initial_velocity: crate::physics::elasticity::conditions::Value::Constant([0.0, 0.0]),
            snapshots,
            snapshot_every,
            allow_long: false,
        }
    }

    fn taken(steps: usize, p: &DynamicsParams) -> Vec<usize> {
        (0..=steps).filter(|&s| is_snapshot(s, steps, p)).collect()
    }

    #[test]
    fn snapshots_n_gives_n_plus_one_states_with_the_start_and_the_end() {
        for steps in [1, 2, 7, 10, 99, 100, 101, 1005, 123_457] {
            for n in [1, 2, 3, 10, 20, 99, 100, 101, 10_000] {
                let s = taken(steps, &params(n, None));
                assert_eq!(s.len(), (n + 1).min(steps + 1), "steps {steps}, N {n}: {s:?}");
                assert_eq!((s[0], *s.last().unwrap()), (0, steps), "steps {steps}, N {n}");
                // Evenly spaced: gaps differ by at most one step.
                let gaps: Vec<usize> = s.windows(2).map(|w| w[1] - w[0]).collect();
                let (lo, hi) = (gaps.iter().min().unwrap(), gaps.iter().max().unwrap());
                assert!(hi - lo <= 1, "steps {steps}, N {n}: gaps {lo}..{hi}");
            }
        }
    }

    /// The estimate's history is what `snapshots = HISTORY_SAMPLES` writes after t = 0.
    #[test]
    fn history_steps_are_the_snapshots_of_history_samples_without_the_start() {
        for steps in [1, 5, 8, 9, 100, 1001] {
            let snapshots = taken(steps, &params(HISTORY_SAMPLES, None));
            assert_eq!(history_steps(steps), snapshots[1..], "steps {steps}");
        }
    }

    #[test]
    fn snapshots_zero_is_the_final_state_only_and_every_k_keeps_the_end() {
        assert_eq!(taken(57, &params(0, None)), [57]);
        assert_eq!(taken(25, &params(10, Some(10))), [0, 10, 20, 25]);
        assert_eq!(taken(20, &params(10, Some(10))), [0, 10, 20]);
    }
}
