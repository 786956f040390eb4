//! A Navier run with its error estimate: the run's stages ([`super::solve`],
//! [`super::dynamics`]), then the reference run the estimate compares it with
//! ([`super::estimate`]: the same nodes at two degrees higher for a static run;
//! [`super::dynamic_estimate`] for a dynamic one), timed as the `estimate` stage of
//! the same run.

use super::discrete::Discretisation;
use super::dynamic_estimate::{self, Run};
use super::dynamics::{simulate_sampled, Sampling, Simulation};
use super::estimate::{reference_approximation, stage, ErrorEstimate, Estimate, EstimateMethod, EstimateParams};
use super::solve::{assemble_and_solve, stages, Solution};
use super::NavierParams;
use crate::domain::NodeSet;
use crate::linalg::SolverParams;
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
            // The reference failed: the defect estimate stands, saying that auto did
            // not trust it and why the reference is missing.
            (Estimate::Unavailable(_, failed), Estimate::Done(mut defect)) => {
                defect.reference = format!("{}; auto did not trust it ({why}), but the higher-degree reference is unavailable: {failed}", defect.reference);
                Estimate::Done(defect)
            }
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
        let run = Run { case, params, dynamics, time_step: sim.report.time_step, positions: &sim.positions, history: &sim.history };
        dynamic_estimate::estimate(&run, progress)
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
        reference_solver: Some(solved.report.method.clone()),
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

