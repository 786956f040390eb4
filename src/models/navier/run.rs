//! A Navier run with its error estimate: the run's stages ([`super::solve`],
//! [`super::dynamics`]), then the reference run the estimate compares it with
//! ([`super::estimate`]: the same nodes at two degrees higher for a static run, half
//! the spacing and a smaller time step for a dynamic one), timed as the `estimate`
//! stage of the same run.

use super::discrete::Discretisation;
use super::dynamics::{simulate_sampled, Sampling, Simulation};
use super::estimate::{compared_states, reference_approximation, stage, ErrorEstimate, Estimate, EstimateMethod, EstimateParams};
use super::solve::{assemble_and_solve, stages, Solution};
use super::NavierParams;
use crate::domain::{NodeSet, Point};
use crate::linalg::SolverParams;
use crate::mlsm::interpolate::mls_values;
use crate::models::dynamics::driver::Snapshot;
use crate::models::dynamics::DynamicsParams;
use crate::parallel::distributed;
use crate::physics::case::Case;
use crate::physics::elasticity::stress::StressField;
use crate::physics::exact::ExactSolution;
use crate::quality::post::ExactFields;
use crate::scene::choice::Choice;
use crate::stages::{Progress, RunError, StageTimer, Within};
use std::time::Instant;

/// Run every stage of the static run of `case` with `params`, then its error estimate
/// (`estimate.method`).
pub fn solve(case: &Case, params: &NavierParams, progress: &dyn Progress) -> Result<Solution, RunError> {
    let mut timer = StageTimer::new(progress);
    let exact = case.exact_solution();
    let exact = exact.as_deref();
    let mut solution = stages(case, params, exact, &mut timer)?;
    let method = params.estimate.method;
    // `defect` is made by the run's own stages, with its operator at hand; `auto`
    // takes it unless it cannot be trusted, and then the higher-degree reference.
    let reference = match method {
        EstimateMethod::Defect => None,
        EstimateMethod::Auto => untrusted_defect(case, params, &solution),
        _ => Some(String::new()),
    };
    if let Some(why) = reference {
        let made = stage(method, method.static_navier_estimates(), &mut timer, || {
            higher_degree(case, params, &solution.nodes, &solution.displacement, solution.stress.as_ref(), exact, progress)
        })?;
        solution.estimate = match (made, std::mem::replace(&mut solution.estimate, Estimate::Off)) {
            (Estimate::Done(mut e), _) if !why.is_empty() => {
                e.reference = format!("{}; auto took it because {why}", e.reference);
                Estimate::Done(e)
            }
            (Estimate::Unavailable(..), defect @ Estimate::Done(_)) => defect,
            (made, _) => made,
        };
    }
    solution.timings = timer.finish();
    if let Some(ranks) = solution.solver.ranks.as_mut() {
        ranks.stage_seconds = distributed::stage_seconds_per_rank(&solution.timings.named())?;
    }
    Ok(solution)
}

/// Why `auto` does not take the `defect` estimate of a static run, or `None` when it
/// does: the estimate is unavailable (too few nodes for its fits, MPI ranks); or the
/// estimate reaches the warning threshold (at most 1e-2), where the run's own error
/// pollutes the fits of its solution (Lame at nu = 0.49 in the displacement form:
/// true e_inf(u) 7.4, defect 0.95, higher-degree 7.4). The stress is judged away from
/// singular corners, as the warning judges it: there the defect estimate takes the
/// higher-degree operator's rows ([`super::corner_defect`]). A run that is warned is
/// then warned with the higher-degree reference's number
/// (docs/notebook/2026-11-28-cheap-estimate.md).
fn untrusted_defect(case: &Case, params: &NavierParams, solution: &Solution) -> Option<String> {
    let e = match &solution.estimate {
        Estimate::Done(e) => e,
        Estimate::Unavailable(_, why) => return Some(format!("the defect estimate is unavailable ({why})")),
        Estimate::Off => return Some("the run made no defect estimate".into()),
    };
    let corners = crate::physics::case::singular_corners(case, &solution.nodes);
    let away = |i: usize| !corners.iter().any(|c| c.covers(solution.nodes.positions[i]));
    let sigma = match &e.per_node_sigma {
        Some(per_node) => (0..per_node.len()).filter(|&i| away(i)).map(|i| per_node[i]).fold(0.0, |a: f64, b| if b.is_nan() { b } else { a.max(b) }),
        None => e.norms.e_inf_sigma.unwrap_or(0.0),
    };
    let limit = params.estimate.threshold.min(super::estimate::DEFAULT_THRESHOLD);
    (e.norms.e_inf_u.is_nan() || sigma.is_nan() || e.norms.e_inf_u > limit || sigma > limit).then(|| {
        format!(
            "the defect estimate (e_inf(u) ~ {:.1e}, e_inf(sigma) ~ {sigma:.1e}) reaches {limit:.0e}, where the run's own error pollutes its fits",
            e.norms.e_inf_u
        )
    })
}

/// Run `case` (with `dynamics`) by explicit MLSM elastodynamics, calling `snapshot`
/// at the snapshot steps, and estimate its error over the history. Energies:
/// `E_kin = sum rho A_i |v_i|^2 / 2`, `E_el = sum A_i sigma : eps / 2`,
/// `E_ext = -sum A_i f(x_i) . u_i`, `A_i` lumped Delaunay areas.
pub fn simulate(
    case: &Case,
    params: &NavierParams,
    dynamics: &DynamicsParams,
    progress: &dyn Progress,
    snapshot: impl FnMut(Snapshot) -> Result<(), RunError>,
) -> Result<Simulation, RunError> {
    let mut timer = StageTimer::new(progress);
    let mut sim = simulate_sampled(case, params, dynamics, &mut timer, Sampling::Estimate, snapshot)?;
    let method = params.estimate.method;
    sim.estimate = stage(method, method.dynamic_navier_estimates(), &mut timer, || {
        refined_dynamic(case, params, dynamics, sim.report.time_step, &sim.positions, &sim.history, progress)
    })?;
    sim.timings = timer.finish();
    Ok(sim)
}

/// The higher-degree estimate of the run `(displacement, stress)` on `nodes`; the
/// reference's iterative solve reports its progress to the estimate stage of
/// `progress` ([`Within`]).
pub fn higher_degree(
    case: &Case,
    params: &NavierParams,
    nodes: &NodeSet,
    displacement: &[[f64; 2]],
    stress: Option<&StressField>,
    exact: Option<&dyn ExactSolution>,
    progress: &dyn Progress,
) -> Estimate {
    let t0 = Instant::now();
    let approximation = match reference_approximation(&params.approximation, params.fill.kind, nodes.len()) {
        Ok(a) => a,
        Err(reason) => return Estimate::Unavailable(EstimateMethod::HigherDegree.name(), reason),
    };
    let solver = SolverParams { kind: params.solver.kind.for_reference(), ..params.solver };
    let estimate = EstimateParams { method: EstimateMethod::None, ..params.estimate };
    let reference_params = NavierParams { approximation, keep_system: false, solver, estimate, ..params.clone() };
    let within = Within(progress);
    let mut timer = StageTimer::new(&within);
    let solved = Discretisation::on_nodes(case, &reference_params, nodes.clone(), exact, &mut timer)
        .and_then(|mut disc| assemble_and_solve(case, &mut disc, exact, &reference_params, &mut timer).map(|s| (disc, s)));
    let solved = solved.and_then(|(mut disc, solved)| {
        if stress.is_some() {
            disc.restore_gradient_shapes(&approximation)?;
        }
        Ok((disc, solved))
    });
    let (disc, solved) = match solved {
        Ok(s) => s,
        Err(e) => {
            return Estimate::Unavailable(
                EstimateMethod::HigherDegree.name(),
                format!("the reference ({}) failed: {e}", approximation.basis.describe()),
            )
        }
    };
    let n = nodes.len();
    let u_ref = disc.dofs.displacements(&solved.x, n);
    let sigma_ref = stress.map(|_| disc.stress(&case.material, &disc.gradients(&solved.x), &solved.x));
    let reference = ExactFields { displacement: u_ref, stress: sigma_ref.map(|s| s.sigma) };
    Estimate::Done(Box::new(ErrorEstimate {
        reference_degree: approximation.basis.polynomial_degree(),
        reference_unknowns: disc.dofs.len(),
        reference_nonzeros: solved.nonzeros,
        ..ErrorEstimate::between(
            EstimateMethod::HigherDegree,
            format!("{}, {} nodes per stencil", approximation.basis.describe(), approximation.support),
            &nodes.positions,
            displacement,
            stress,
            &reference,
            t0,
        )
    }))
}

/// The `refined` estimate of a dynamic run over its history: the scene integrated
/// again with the run's approximation on nodes at half the spacing
/// ([`crate::domain::FillParams::scaled`]) and the run's `time_step` divided by
/// `2^ceil(2 / order)` (halved for Verlet and RK4, quartered for the first-order emu;
/// the reference's own stable step when the finer nodes need a smaller one), so that
/// both the reference's spatial error (order >= 2 in h) and its time error are at most
/// a quarter of the run's. At each of the run's `history` states
/// ([`crate::models::dynamics::driver::history_steps`]) the reference's state at the same time
/// (its own step's, or interpolated between its two steps around it,
/// [`crate::models::dynamics::history`]: only when it had to take its own stable step) is
/// interpolated to the run's `positions` by moving least squares; the estimate is the
/// space-time difference over those states ([`ErrorEstimate::over_history`]),
///
/// ```text
/// est e_inf(u)  = max_{t,i,c} |u - u_ref| / max_{t,i,c} |u_ref|
/// est rel_l2(u) = sqrt(sum_{t,i} |u - u_ref|^2 / sum_{t,i} |u_ref|^2)
/// ```
///
/// which is 0.75 to 1 times the run's error (space and time together). The per-node
/// indicator is the largest over the states.
///
/// Why not a higher degree on the same nodes as for static runs: the PHS stencils
/// of the reference have growing modes in explicit elastodynamics (both shipped
/// dynamic scenes diverged within 1500 steps), while the run's own basis on finer
/// nodes keeps the stability the run had.
pub fn refined_dynamic(
    case: &Case,
    params: &NavierParams,
    dynamics: &DynamicsParams,
    time_step: f64,
    positions: &[Point],
    history: &[(f64, Vec<[f64; 2]>)],
    progress: &dyn Progress,
) -> Estimate {
    let t0 = Instant::now();
    let unavailable = |why: String| Estimate::Unavailable(EstimateMethod::Refined.name(), why);
    if history.is_empty() {
        return unavailable("the run kept no state to compare".into());
    }
    let estimate = EstimateParams { method: EstimateMethod::None, ..params.estimate };
    let reference_params = NavierParams { fill: params.fill.scaled(0.5), keep_system: false, estimate, ..params.clone() };
    let divisor = f64::from(1u32 << 2u32.div_ceil(dynamics.integrator.order()));
    let fine = DynamicsParams { time_step: Some(time_step / divisor), ..dynamics.clone() };
    let times: Vec<f64> = history.iter().map(|h| h.0).collect();
    let run = |d: &DynamicsParams| {
        simulate_sampled(case, &reference_params, d, &mut StageTimer::new(&Within(progress)), Sampling::Times(&times), |_| Ok(()))
    };
    let simulated = match run(&fine) {
        Err(RunError::UnstableTimeStep { .. }) => run(&DynamicsParams { time_step: None, ..fine.clone() }),
        other => other,
    };
    let sim = match simulated {
        Ok(s) => s,
        Err(e) => return unavailable(format!("the reference at half the spacing failed: {e}")),
    };
    let r = &sim.report;
    let description = format!(
        "{} nodes at spacing {:.3e}, {} steps of {:.3e} s ({}); compared at {}",
        sim.positions.len(),
        reference_params.fill.spacing,
        r.steps,
        r.time_step,
        dynamics.integrator.name(),
        compared_states(history)
    );
    let interpolate = |u: &[[f64; 2]]| mls_values(&sim.positions, u, positions);
    match ErrorEstimate::over_history(EstimateMethod::Refined, description, positions, history, &sim.history, interpolate, t0) {
        Ok(e) => Estimate::Done(Box::new(ErrorEstimate {
            reference_degree: params.approximation.basis.polynomial_degree(),
            reference_unknowns: sim.unknowns.0 + sim.unknowns.1,
            ..e
        })),
        Err(e) => unavailable(format!("the reference could not be interpolated to the run's nodes: {e}")),
    }
}
