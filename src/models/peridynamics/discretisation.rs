//! The discretisation error of a static peridynamic run: how far its solution is from
//! the nonlocal model's own continuum solution at the same horizon, apart from the
//! model difference to the local (Navier) solution, which `mlsm compare` and the
//! `local-model` estimate measure.
//!
//! At a fixed horizon `delta` the quadrature of the bond integral converges as the
//! spacing `h = delta / m` shrinks. The run is solved again at `m -> 2m` (the same
//! horizon, half the spacing), the finer solution is interpolated to the run's free
//! nodes by moving least squares ([`crate::mlsm::interpolate`]), and
//!
//! ```text
//! e_h ~ (u_h - I u_{h/2}) / sqrt((1 - 2^-1)(1 - 2^-2)),
//! ```
//!
//! since `u_h - u_{h/2} = (1 - 2^-p) e_h` for an error of order `p`: the divisor is the
//! geometric mean of the factors of orders 1 and 2, so that the effectivity lies in
//! [0.82, 1.22] for any order from 1 to 2 (1.43 at order 3). Where the run does not
//! converge at its horizon (a load applied as a layer one spacing thick concentrates as
//! `h` shrinks), the difference is the size of the error, and the estimate warns.
//!
//! It costs one run with four times the nodes and four times the bonds per node
//! (about 10x the run measured on the shipped scenes: 0.004 s -> 0.045 s of solve).

use crate::mlsm::interpolate::mls_values_of_degree;
use crate::physics::case::Case;
use crate::quality::post::relative_errors;
use crate::stages::Silent;
use std::time::Instant;

use super::solve::DiscretisationEstimate;
use super::{solve, PdParams, PdSolution};

/// `sqrt((1 - 1/2)(1 - 1/4))`: the divisor of the difference (module docs).
pub const DIVISOR: f64 = 0.612_372_435_695_794_5;

/// The discretisation error of `sol` (a static run of `case` with `params`) against the
/// run at `m -> 2m` with the same horizon (module docs); `Err` says why there is none
/// (the reference's solve or interpolation failed).
pub fn estimate(case: &Case, params: &PdParams, sol: &PdSolution) -> Result<DiscretisationEstimate, String> {
    let t0 = Instant::now();
    let fine = PdParams { ratio: 2.0 * params.ratio, ..*params };
    let reference = solve(case, &fine, &Silent).map_err(|e| format!("the run at m = {} failed: {e}", fine.ratio))?;
    let (n, nf) = (sol.nodes.free, reference.nodes.free);
    let targets = &sol.nodes.positions[..n];
    let interpolated = mls_values_of_degree(&reference.nodes.positions[..nf], &reference.displacement[..nf], targets, 2)
        .map_err(|e| format!("the run at m = {} could not be interpolated to the run's nodes: {e}", fine.ratio))?;
    let u = &sol.displacement[..n];
    let (e_inf, rel_l2) = relative_errors(u, &interpolated);
    let largest = (0..n)
        .max_by(|&a, &b| {
            let d = |i: usize| (u[i][0] - interpolated[i][0]).abs().max((u[i][1] - interpolated[i][1]).abs());
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    Ok(DiscretisationEstimate {
        method: "fixed-horizon",
        reference: format!(
            "the run at half the spacing with the same horizon (m = {}, {nf} nodes), divided by {DIVISOR:.2} (orders 1 to 2)",
            fine.ratio
        ),
        e_inf_u: e_inf / DIVISOR,
        rel_l2_u: rel_l2 / DIVISOR,
        largest_at: targets.get(largest).copied().unwrap_or([0.0, 0.0]),
        reference_ratio: fine.ratio,
        reference_nodes: nf,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The discretisation error of a dynamic run `sim` (of `case` with `params` and
/// `dynamics`) at its horizon, over its kept history: against the run at `m / 2` with
/// the same horizon and time step where `m >= 6` (`u_h - I u_{2h} = (2^p - 1) e_h`,
/// divided by `sqrt 3`: effectivity in [0.58, 1.73] for an order from 1 to 2, a
/// sixteenth of the run's bonds), else against the run at `2m` with half the step
/// (divided by [`DIVISOR`]; 32 times the run's bond updates). The largest difference
/// over the kept states, relative to the largest displacement over them.
pub fn estimate_dynamic(
    case: &Case,
    params: &PdParams,
    dynamics: &crate::models::dynamics::DynamicsParams,
    sim: &super::Simulation,
) -> Result<DiscretisationEstimate, String> {
    let t0 = Instant::now();
    if sim.history.is_empty() {
        return Err("the run kept no history to compare".into());
    }
    let dt = sim.report.time_step;
    let coarse = params.ratio >= 6.0;
    let (ratio, step, divisor) = if coarse { (params.ratio / 2.0, dt, 3f64.sqrt()) } else { (2.0 * params.ratio, dt / 2.0, DIVISOR) };
    let reference_params = PdParams { ratio, ..*params };
    let reference_dynamics = crate::models::dynamics::DynamicsParams { time_step: Some(step), snapshots: 0, snapshot_every: None, ..dynamics.clone() };
    let reference = super::simulate_sampled(case, &reference_params, &reference_dynamics, &Silent, true, |_| Ok(()))
        .map_err(|e| format!("the run at m = {ratio} failed: {e}"))?;
    if reference.history.len() != sim.history.len() {
        return Err(format!("the run at m = {ratio} kept {} states, the run {}", reference.history.len(), sim.history.len()));
    }
    let tolerance = 1e-6 * dynamics.end_time;
    if let Some(((t, _), (r, _))) = sim.history.iter().zip(&reference.history).find(|((t, _), (r, _))| (t - r).abs() > tolerance) {
        return Err(format!("the run at m = {ratio} kept a state at t = {r:e}, the run at t = {t:e}"));
    }
    let nodes = &sim.discretisation.nodes;
    let targets = &nodes.positions[..nodes.free];
    let rn = &reference.discretisation.nodes;
    let states: Vec<&[[f64; 2]]> = reference.history.iter().map(|(_, u)| &u[..rn.free]).collect();
    let interpolated = crate::mlsm::interpolate::mls_fields_of_degree(&rn.positions[..rn.free], &states, targets, 2)
        .map_err(|e| format!("the run at m = {ratio} could not be interpolated to the run's nodes: {e}"))?;
    let (mut largest_u, mut largest_d, mut sum_u, mut sum_d, mut at) = (0.0f64, 0.0f64, 0.0, 0.0, [0.0, 0.0]);
    for ((_, u), v) in sim.history.iter().zip(&interpolated) {
        for (i, (a, b)) in u[..nodes.free].iter().zip(v).enumerate() {
            let d = (a[0] - b[0]).abs().max((a[1] - b[1]).abs());
            if d > largest_d {
                (largest_d, at) = (d, targets[i]);
            }
            largest_u = largest_u.max(b[0].abs()).max(b[1].abs());
            sum_d += (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
            sum_u += b[0] * b[0] + b[1] * b[1];
        }
    }
    let ratio_of = |d: f64, u: f64| if d == 0.0 { 0.0 } else { d / u };
    Ok(DiscretisationEstimate {
        method: "fixed-horizon",
        reference: format!(
            "the run at {} the spacing with the same horizon (m = {ratio}, {} nodes, time step {step:.3e} s), over {} states, divided by {divisor:.2}",
            if coarse { "twice" } else { "half" },
            rn.free,
            sim.history.len()
        ),
        e_inf_u: ratio_of(largest_d, largest_u) / divisor,
        rel_l2_u: ratio_of(sum_d, sum_u).sqrt() / divisor,
        largest_at: at,
        reference_ratio: ratio,
        reference_nodes: rn.free,
        seconds: t0.elapsed().as_secs_f64(),
    })
}
