//! The error estimate of a dynamic Navier run over its history: the scene is
//! integrated again on another node set with another time step, the reference's
//! states at the run's history times ([`crate::models::dynamics::history`]) are
//! brought to the run's nodes by moving least squares, and the space-time difference
//! over those states is the estimate ([`ErrorEstimate::over_history`]):
//!
//! ```text
//! est e_inf(u)  = max_{t,i,c} |u - u_ref| / max_{t,i,c} |u_ref|
//! est rel_l2(u) = sqrt(sum_{t,i} |u - u_ref|^2 / sum_{t,i} |u_ref|^2)
//! ```
//!
//! Two references:
//!
//! - [`richardson`] (what `auto` takes): the run at **twice** the spacing and the time
//!   step `2^(2/q)` times the run's (`q` the integrator's order; 2 for Verlet, `sqrt 2`
//!   for RK4), so that its time error grows by the factor its spatial error grows by
//!   when that is of second order. Its difference to the run is `2^p - 1` times the
//!   run's error for an order `p` in `h`: 3 for smooth fields (`p = 2`), down to 1
//!   where a front or a kink lowers the order to 1. The estimate divides it by
//!   `sqrt 3`, the geometric mean of the two, so that its effectivity is within
//!   `[1/sqrt 3, sqrt 3] = [0.58, 1.73]` for every order from 1 to 2 (the reference is
//!   the extrapolation `u_R = u + (u - u_2h) / sqrt 3`). It costs 1/8 of the run's
//!   nodes x steps (0.18 with RK4).
//! - [`refined`]: the run at **half** the spacing with the step `2^-ceil(2/q)` times the
//!   run's; its error is at most a quarter of the run's, so the estimate is 0.75 to 1
//!   of the run's error whatever the order (at least 1), but it costs 8x the run's
//!   nodes x steps (16x with EMU).
//!
//! Why not a higher degree on the same nodes as for static runs: the PHS stencils of
//! such a reference have growing modes in explicit elastodynamics (both shipped
//! dynamic scenes diverged within 1500 steps), while the run's own basis on another
//! node set keeps the stability the run had.

use super::dynamics::{simulate_sampled, Sampling, Simulation};
use super::estimate::{compared_states, ErrorEstimate, Estimate, EstimateMethod, EstimateParams};
use super::NavierParams;
use crate::domain::Point;
use crate::mlsm::interpolate::mls_fields_of_degree;
use crate::mlsm::ShapeError;
use crate::models::dynamics::{DynamicsParams, Integrator};
use crate::physics::case::Case;
use crate::scene::choice::Choice;
use crate::stages::{Progress, RunError, StageTimer, Within};
use std::time::Instant;

/// `sqrt 3`: what [`richardson`] divides the difference to the coarse run by.
const SQRT_3: f64 = 1.732_050_807_568_877_2;

/// Fewest nodes the coarse run of [`richardson`] takes: below it the coarse run is
/// too far from the asymptotic range for its factor (measured on the standing
/// wave, docs/notebook/2026-11-28-cheap-estimate.md), and `auto` takes [`refined`].
pub const RICHARDSON_MIN_COARSE_NODES: usize = 50;

/// The run a dynamic estimate compares with.
pub struct Run<'a> {
    /// The scene.
    pub case: &'a Case,
    /// The run's discretisation.
    pub params: &'a NavierParams,
    /// The run's dynamics.
    pub dynamics: &'a DynamicsParams,
    /// The run's time step.
    pub time_step: f64,
    /// The run's nodes.
    pub positions: &'a [Point],
    /// The run's states at its history times.
    pub history: &'a [(f64, Vec<[f64; 2]>)],
}

/// The estimate `estimate.method` asks for (`auto`: [`richardson`] where it applies,
/// else [`refined`], and the estimate says why).
pub fn estimate(run: &Run, progress: &dyn Progress) -> Estimate {
    match run.params.estimate.method {
        EstimateMethod::Refined => refined(run, progress),
        EstimateMethod::Richardson => richardson(run, progress),
        _ => match richardson(run, progress) {
            Estimate::Unavailable(_, why) => match refined(run, progress) {
                Estimate::Done(mut e) => {
                    e.reference = format!("{}; auto took it because Richardson's estimate is unavailable ({why})", e.reference);
                    Estimate::Done(e)
                }
                other => other,
            },
            made => made,
        },
    }
}

/// Richardson's estimate (module docs): the run on nodes at twice the spacing
/// ([`crate::domain::FillParams::scaled`]) with the step `2^(2/q)` times the run's
/// (its own stable step when that is smaller), brought to the run's nodes `I u_2h`,
/// and the reference at each history state
///
/// ```text
/// u_R = u + (u - I u_2h) / sqrt(3),
/// ```
///
/// so that `u - u_R = -(u - I u_2h) / sqrt 3`: between 0.58 and 1.73 of the run's
/// error for any order from 1 to 2 in `h` (module docs). Unavailable for runs of a basis above degree 2,
/// for EMU (first order in time: the coarse run would need four times the step, beyond
/// its stable one), and when the coarse run has fewer than
/// [`RICHARDSON_MIN_COARSE_NODES`] nodes.
pub fn richardson(run: &Run, progress: &dyn Progress) -> Estimate {
    let t0 = Instant::now();
    let unavailable = |why: String| Estimate::Unavailable(EstimateMethod::Richardson.name(), why);
    if let Err(why) = richardson_applies(run.params, run.dynamics.integrator) {
        return unavailable(why);
    }
    let q = run.dynamics.integrator.order();
    let ratio = 2f64.powf(2.0 / f64::from(q));
    let sim = match reference_run(run, 2.0, run.time_step * ratio, progress) {
        Ok(s) => s,
        Err(why) => return unavailable(format!("the run at twice the spacing {why}")),
    };
    if sim.positions.len() < RICHARDSON_MIN_COARSE_NODES {
        return unavailable(format!(
            "the run at twice the spacing has {} nodes, fewer than {RICHARDSON_MIN_COARSE_NODES}: too coarse for its asymptotic range",
            sim.positions.len()
        ));
    }
    let coarse = match interpolate_history(&sim, run.positions) {
        Ok(c) => c,
        Err(e) => return unavailable(format!("the coarse run could not be interpolated to the run's nodes: {e}")),
    };
    let extrapolated: Vec<_> = run
        .history
        .iter()
        .zip(&coarse)
        .map(|((_, u), c)| u.iter().zip(c).map(|(a, b)| [a[0] + (a[0] - b[0]) / SQRT_3, a[1] + (a[1] - b[1]) / SQRT_3]).collect())
        .collect();
    let description = format!("Richardson's extrapolation u + (u - u_2h) / sqrt 3 from {}", describe(run, &sim, 2.0));
    finish(run, EstimateMethod::Richardson, description, extrapolated, &sim, t0)
}

/// The `refined` estimate (module docs): the run on nodes at half the spacing with
/// the run's step divided by `2^ceil(2 / q)` (halved for Verlet and RK4, quartered for
/// the first-order EMU; the reference's own stable step when the finer nodes need a
/// smaller one), so that both the reference's spatial error (order >= 2 in h) and its
/// time error are at most a quarter of the run's: the estimate is 0.75 to 1 times the
/// run's error (space and time together).
pub fn refined(run: &Run, progress: &dyn Progress) -> Estimate {
    let t0 = Instant::now();
    let divisor = f64::from(1u32 << 2u32.div_ceil(run.dynamics.integrator.order()));
    let sim = match reference_run(run, 0.5, run.time_step / divisor, progress) {
        Ok(s) => s,
        Err(why) => return Estimate::Unavailable(EstimateMethod::Refined.name(), format!("the reference at half the spacing {why}")),
    };
    let description = describe(run, &sim, 0.5);
    match interpolate_history(&sim, run.positions) {
        Ok(fine) => finish(run, EstimateMethod::Refined, description, fine, &sim, t0),
        Err(e) => Estimate::Unavailable(EstimateMethod::Refined.name(), format!("the reference could not be interpolated to the run's nodes: {e}")),
    }
}

/// The scene integrated with the run's basis on nodes at `factor` times the spacing
/// and the step `time_step` (its own stable step when that one is unstable), keeping
/// the states at the run's history times; or why it failed.
fn reference_run(run: &Run, factor: f64, time_step: f64, progress: &dyn Progress) -> Result<Simulation, String> {
    if run.history.is_empty() {
        return Err("has no state to compare: the run kept none".into());
    }
    let estimate = EstimateParams { method: EstimateMethod::None, ..run.params.estimate };
    let params = NavierParams { fill: run.params.fill.scaled(factor), keep_system: false, estimate, ..run.params.clone() };
    let times: Vec<f64> = run.history.iter().map(|h| h.0).collect();
    let simulate = |d: &DynamicsParams| {
        simulate_sampled(run.case, &params, d, &mut StageTimer::new(&Within(progress)), Sampling::Times(&times), |_| Ok(()))
    };
    let fixed = DynamicsParams { time_step: Some(time_step), ..run.dynamics.clone() };
    match simulate(&fixed) {
        Err(RunError::UnstableTimeStep { .. }) => simulate(&DynamicsParams { time_step: None, ..fixed.clone() }),
        other => other,
    }
    .map_err(|e| format!("failed: {e}"))
}

/// What the reference `sim` at `factor` times the spacing was.
fn describe(run: &Run, sim: &Simulation, factor: f64) -> String {
    let r = &sim.report;
    format!(
        "{} nodes at spacing {:.3e}, {} steps of {:.3e} s ({}); compared at {}",
        sim.positions.len(),
        run.params.fill.spacing * factor,
        r.steps,
        r.time_step,
        run.dynamics.integrator.name(),
        compared_states(run.history)
    )
}

/// The reference states of `sim` (on its own nodes) brought to `targets` by moving
/// least squares, all states in one pass ([`mls_fields_of_degree`], degree 2).
fn interpolate_history(sim: &Simulation, targets: &[Point]) -> Result<Vec<Vec<[f64; 2]>>, ShapeError> {
    let states: Vec<&[[f64; 2]]> = sim.history.iter().map(|(_, u)| u.as_slice()).collect();
    mls_fields_of_degree(&sim.positions, &states, targets, 2)
}

/// The estimate of `run` against the `reference` states (on the run's nodes), made by
/// `sim`.
fn finish(run: &Run, method: EstimateMethod, description: String, reference: Vec<Vec<[f64; 2]>>, sim: &Simulation, t0: Instant) -> Estimate {
    let e = ErrorEstimate::over_history(method, description, run.positions, run.history, reference, t0);
    Estimate::Done(Box::new(ErrorEstimate {
        reference_degree: run.params.approximation.basis.polynomial_degree(),
        reference_unknowns: sim.unknowns.0 + sim.unknowns.1,
        ..e
    }))
}

/// Whether [`richardson`] applies to a run of `params` with `integrator`, or why not:
/// the run must be of second order in space (basis degree <= 2) and of order 2 or
/// more in time.
pub fn richardson_applies(params: &NavierParams, integrator: Integrator) -> Result<(), String> {
    let degree = params.approximation.basis.polynomial_degree();
    if degree > 2 {
        return Err(format!("the run's basis has degree {degree}: the factor 1/sqrt 3 holds for runs of order 1 to 2 in h (degree <= 2)"));
    }
    let q = integrator.order();
    if q < 2 {
        return Err(format!(
            "{} is of order {q} in time: a coarse run with the same share of time error needs four times the step, beyond its stable step",
            integrator.name()
        ));
    }
    Ok(())
}
