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
//! order 2 in `delta`); a static reference carries its own higher-degree estimate
//! (`reference_estimated_e_inf_u`) so that this can be checked.

use crate::choice::Choice;
use crate::domain::Point;
use crate::elasticity::stress::StressField;
use crate::mlsm::interpolate::mls_values;
use crate::model::{self, Outcome};
use crate::navier::{ErrorEstimate, Estimate, EstimateMethod};
use crate::pipeline::Silent;
use crate::post::ExactFields;
use crate::problem::{Model, Problem};
use std::time::Instant;

/// The `local-model` estimate of the peridynamic run of `problem` whose free nodes
/// `positions` carry `displacement` (and `stress`, when computed).
pub fn local_model(problem: &Problem, positions: &[Point], displacement: &[[f64; 2]], stress: Option<&StressField>) -> Estimate {
    let t0 = Instant::now();
    let unavailable = |why: String| Estimate::Unavailable(EstimateMethod::LocalModel.name(), why);
    let dynamic = problem.case.dynamics.is_some();
    let mut navier = Problem { model: Model::Navier, ..problem.clone() };
    navier.navier.keep_system = false;
    // A static reference estimates its own error; a dynamic one would need a second
    // integration of its own, which costs more than it tells here.
    navier.navier.estimate.method = if dynamic { EstimateMethod::None } else { EstimateMethod::HigherDegree };
    if let Err(e) = crate::resources::check(&navier) {
        return unavailable(format!("the Navier model's run does not fit: {}", e.reason));
    }
    let outcome = match model::solve(&navier, &Silent, |_| Ok(())) {
        Ok(o) => o,
        Err(e) => return unavailable(format!("the Navier model's run failed: {e}")),
    };
    let description = outcome.describe(&navier);
    let (nodes, u, sigma, own, unknowns, nonzeros) = match outcome {
        Outcome::NavierStatic(s) => {
            let own = s.estimate.done().map(|e| e.norms.e_inf_u);
            (s.nodes.positions, s.displacement, s.stress.map(|s| s.sigma), own, s.unknowns, s.nonzeros)
        }
        Outcome::NavierDynamic(s) => {
            let unknowns = s.unknowns.0 + s.unknowns.1;
            (s.positions, s.u, None, None, unknowns, 0)
        }
        Outcome::PdStatic(_) | Outcome::PdDynamic(_) => unreachable!("the reference runs the Navier model"),
    };
    let interpolated = mls_values(&nodes, &u, positions).and_then(|u| {
        let sigma = match (stress, &sigma) {
            (Some(_), Some(s)) => Some(mls_values(&nodes, s, positions)?),
            _ => None,
        };
        Ok(ExactFields { displacement: u, stress: sigma })
    });
    let reference = match interpolated {
        Ok(r) => r,
        Err(e) => return unavailable(format!("the Navier solution could not be interpolated to the peridynamic nodes: {e}")),
    };
    Estimate::Done(Box::new(ErrorEstimate {
        reference_degree: navier.navier.approximation.basis.polynomial_degree(),
        reference_estimated_e_inf_u: own,
        reference_unknowns: unknowns,
        reference_nonzeros: nonzeros,
        ..ErrorEstimate::between(EstimateMethod::LocalModel, description, positions, displacement, stress, &reference, t0)
    }))
}
