//! The `local-model` error estimate of a peridynamic run: the same scene is solved by
//! the Navier model (MLSM on the scene's `[nodes]`, static or to `end_time`), its
//! displacement (and stress) is interpolated to the peridynamic nodes by moving least
//! squares, and the difference is the estimate:
//!
//! ```text
//! est e_inf(u)  = max_{i,c} |u_pd - u_navier| / max_{i,c} |u_navier|
//! est rel_l2(u) = sqrt(sum |u_pd - u_navier|^2 / sum |u_navier|^2)
//! ```
//!
//! the same quantity the errors of a peridynamic run against an exact (local) solution
//! measure: the model difference of the finite horizon plus the bond quadrature's
//! error. It holds while the Navier solution is much closer to the local solution
//! than the peridynamic one (MLSM converges at order 2 to 4 in `h`, peridynamics at
//! order 2 in `delta`); a static reference carries its own estimate (`auto`, the defect
//! estimate where it can be trusted; `reference_estimated_e_inf_u`) so that this can
//! be checked, and is refined until it holds ([`local_model`]).

use crate::scene::choice::Choice;
use crate::domain::Point;
use crate::physics::elasticity::stress::StressField;
use crate::mlsm::interpolate::{mls_fields_of_degree, mls_values_of_degree};
use crate::models::dispatch::{self, Outcome};
use crate::models::navier::{self, ErrorEstimate, Estimate, EstimateMethod, Sampling};
use crate::stages::{Silent, StageTimer};
use crate::quality::post::ExactFields;
use crate::scene::problem::Problem;
use crate::quality::warnings::LOCAL_REFERENCE_MARGIN;
use std::time::Instant;

/// Halvings of the Navier spacing a static `local-model` estimate takes at most to get
/// a reference [`LOCAL_REFERENCE_MARGIN`] times more accurate (by its own estimate)
/// than the difference it measures; a halving that would give the reference more nodes
/// than the peridynamic run has is not taken either, unless the reference is still
/// coarser than the scene's `[nodes]` (its degree-4 basis is then accurate enough, or
/// the check `estimate-reference` warns).
pub const MAX_REFINEMENTS: usize = 3;

/// The `local-model` estimate of the peridynamic run of `problem` whose free nodes
/// `positions` carry `displacement` (and `stress`, when computed), against the Navier
/// run of [`Problem::local_reference`], refined as [`MAX_REFINEMENTS`] says. A dynamic
/// run's `history` (its kept states) is compared over the history, state by state
/// with the Navier run's at the same times ([`ErrorEstimate::over_history`]).
pub fn local_model(
    problem: &Problem,
    positions: &[Point],
    (displacement, stress): (&[[f64; 2]], Option<&StressField>),
    history: &[(f64, Vec<[f64; 2]>)],
) -> Estimate {
    let t0 = Instant::now();
    let mut navier = problem.local_reference();
    let scene_spacing = problem.navier.fill.spacing;
    for refinement in 0.. {
        let compared = match (&navier.case.dynamics, history.is_empty()) {
            (Some(d), false) => over_history(&navier, d, positions, history),
            _ => against_navier(&navier, positions, displacement, stress),
        };
        let mut e = match compared {
            Ok(e) => e,
            Err(why) => return Estimate::Unavailable(EstimateMethod::LocalModel.name(), why),
        };
        let coarse = e.reference_estimated_e_inf_u.is_some_and(|own| own * LOCAL_REFERENCE_MARGIN >= e.norms.e_inf_u);
        let per_node = navier.navier.formulation.unknowns(&navier.case.material).per_node();
        let affordable = 4 * e.reference_unknowns <= positions.len() * per_node || navier.navier.fill.spacing > scene_spacing;
        let finer = (coarse && affordable && refinement < MAX_REFINEMENTS)
            .then(|| navier.with_spacing(navier.navier.fill.spacing / 2.0).ok())
            .flatten()
            .filter(|f| crate::models::resources::check(f).is_ok());
        match finer {
            Some(f) => navier = f,
            None => {
                e.seconds = t0.elapsed().as_secs_f64();
                return Estimate::Done(e);
            }
        }
    }
    unreachable!("the loop returns")
}

/// The estimate of a dynamic peridynamic run's `history` at `positions` against the
/// states of the Navier problem `navier` (with `dynamics`) at the same times, or why
/// there is none.
fn over_history(
    navier: &Problem,
    dynamics: &crate::models::dynamics::DynamicsParams,
    positions: &[Point],
    history: &[(f64, Vec<[f64; 2]>)],
) -> Result<Box<ErrorEstimate>, String> {
    let t0 = Instant::now();
    crate::models::resources::check(navier).map_err(|e| format!("the Navier model's run does not fit: {}", e.reason))?;
    let times: Vec<f64> = history.iter().map(|h| h.0).collect();
    let sim = navier::simulate_sampled(&navier.case, &navier.navier, dynamics, &mut StageTimer::new(&Silent), Sampling::Times(&times), |_| Ok(()))
        .map_err(|e| format!("the Navier model's run failed: {e}"))?;
    let description = format!(
        "MLSM elastodynamics ({} nodes, spacing {:.3e}, {} steps of {:.3e} s); compared at {}",
        sim.positions.len(),
        navier.navier.fill.spacing,
        sim.report.steps,
        sim.report.time_step,
        navier::estimate::compared_states(history)
    );
    let degree = navier.navier.approximation.basis.polynomial_degree().max(2);
    let states: Vec<&[[f64; 2]]> = sim.history.iter().map(|(_, u)| u.as_slice()).collect();
    let reference = mls_fields_of_degree(&sim.positions, &states, positions, degree)
        .map_err(|e| format!("the Navier solution could not be interpolated to the peridynamic nodes: {e}"))?;
    let e = ErrorEstimate::over_history(EstimateMethod::LocalModel, description, positions, history, reference, t0);
    Ok(Box::new(ErrorEstimate {
        reference_degree: navier.navier.approximation.basis.polynomial_degree(),
        reference_unknowns: sim.unknowns.0 + sim.unknowns.1,
        ..e
    }))
}

/// The estimate of `(displacement, stress)` at `positions` against the run of the
/// Navier problem `navier`, or why there is none.
fn against_navier(
    navier: &Problem,
    positions: &[Point],
    displacement: &[[f64; 2]],
    stress: Option<&StressField>,
) -> Result<Box<ErrorEstimate>, String> {
    let t0 = Instant::now();
    crate::models::resources::check(navier).map_err(|e| format!("the Navier model's run does not fit: {}", e.reason))?;
    let outcome = dispatch::solve(navier, &Silent, |_| Ok(())).map_err(|e| format!("the Navier model's run failed: {e}"))?;
    let description = outcome.describe(navier);
    let (nodes, u) = (outcome.positions(), outcome.displacement());
    // What only a static run has: stress, its own estimate, its matrix.
    let (sigma, own, unknowns, nonzeros) = match &outcome {
        Outcome::NavierStatic(s) => {
            (s.stress.as_ref().map(|s| &s.sigma), s.estimate.done().map(|e| e.norms.e_inf_u), s.unknowns, s.nonzeros)
        }
        Outcome::NavierDynamic(s) => (None, None, s.unknowns.0 + s.unknowns.1, 0),
        Outcome::PdStatic(_) | Outcome::PdDynamic(_) => unreachable!("the reference runs the Navier model"),
    };
    // Interpolated at the reference's degree: a degree-2 interpolation from a coarse
    // reference was several times the difference it measured
    // (docs/notebook/round1-peridynamics-static-m3.md, "From the code comments").
    let degree = navier.navier.approximation.basis.polynomial_degree().max(2);
    let interpolated = mls_values_of_degree(nodes, u, positions, degree).and_then(|u| {
        let sigma = match (stress, sigma) {
            (Some(_), Some(s)) => Some(mls_values_of_degree(nodes, s, positions, degree)?),
            _ => None,
        };
        Ok(ExactFields { displacement: u, stress: sigma })
    });
    let reference = interpolated.map_err(|e| format!("the Navier solution could not be interpolated to the peridynamic nodes: {e}"))?;
    Ok(Box::new(ErrorEstimate {
        reference_degree: navier.navier.approximation.basis.polynomial_degree(),
        reference_estimated_e_inf_u: own,
        reference_unknowns: unknowns,
        reference_nonzeros: nonzeros,
        ..ErrorEstimate::between(EstimateMethod::LocalModel, description, positions, displacement, stress, &reference, t0)
    }))
}
