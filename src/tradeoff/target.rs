//! `mlsm run --target-error E`: solve, estimate, refine where the estimate's per-node
//! indicator is large, and repeat until the estimated error is below `E` or a limit
//! (time budget, memory, node count, a stalled estimate, [`MAX_STEPS`]) ends the loop.
//!
//! Each step solves the static Navier problem on the current nodes with the
//! scene's error estimate (`auto` if it had none: [`crate::models::navier::estimate`]); its per-node indicator
//! `eta_i` (relative to the field's largest value, as the e_inf norms) sets the next
//! spacing ([`crate::domain::adapt`]):
//!
//! * `local` (default, scattered fills): every node asks for
//!   `h_i (SAFETY tau / eta_i)^(1/q)` (clamped to `[1/4, 1]`), graded so that the
//!   spacing grows at most [`GROWTH`] per unit of distance; the nodes next to a
//!   singular corner (re-entrant, or clamped meeting traction) take the square of
//!   the smallest factor of any node, down to a floor
//!   ([`adapt::CORNER_POWER`], [`adapt::CORNER_FLOOR`]): the estimate's reference is
//!   about as wrong as the run there, so the indicator cannot see the error such a
//!   corner makes (on the bracket it left the clamped base 4 mm coarse, and the step's
//!   estimate rose from 0.147 to 0.346), and a corner's error falls more slowly than
//!   the rest's;
//! * `uniform` (and any grid fill, which has one spacing): the whole spacing function
//!   is scaled by the smallest of those factors, with `q` the order the last two
//!   steps showed once there are two ([`hp::observed_order`]);
//! * `auto` (the command line's default): `uniform` where the solution is smooth,
//!   `local` at singular corners ([`hp::is_smooth`]).
//!
//! With [`DegreeRule::Auto`] (the command line's default) on a smooth plate the loop
//! also raises an RBF-FD degree to 6, starts from about 1 000 nodes and predicts with
//! `q = p` ([`hp`]).
//!
//! The tolerance per node is `tau = E` for an e_inf target; for a relative-L2 target
//! it is `E * est_e_inf / est_rel_l2` of the same field (a node error at that level
//! keeps the L2 norm at `E` if the ratio of the two norms holds). The order `q` is the
//! approximation's polynomial degree minus one (at least 1): for degree `p` the
//! second-derivative operators are consistent to `O(h^(p-1))`, the pessimistic end of
//! the measured orders, so a step overshoots rather than falls short.

use super::hp;
pub use super::request::{refusal, DegreeRule, Refinement, Target, TargetNorm};
use crate::domain::adapt::{self, GROWTH};
use crate::domain::{FillKind, SpacingSamples};
use crate::models::navier::{self, ErrorEstimate, EstimateMethod};
use crate::stages::{Progress, RunError};
use crate::quality::post::ErrorNorms;
use crate::scene::problem::Problem;
use serde::Serialize;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Radius, in local spacings, around a singular corner within which nodes are refined
/// as much as the most refined node.
pub const PINNED_SPACINGS: f64 = 2.0;

/// Steps after which the loop stops even if the target is not reached.
pub const MAX_STEPS: usize = 12;

/// Exponent of the time of a solve against its node count, for the prediction of the
/// next step's time (sparse LU grows a little faster than linearly).
pub const TIME_EXPONENT: f64 = 1.2;

/// A step whose estimate fell by less than this fraction makes no progress; two in a
/// row end the loop.
pub const STALL_FALL: f64 = 0.1;

/// One solve of the loop.
#[derive(Debug, Clone, Serialize)]
pub struct Step {
    /// Nodes of the step.
    pub nodes: usize,
    /// Smallest and largest target spacing of its nodes (m).
    pub spacing_min: f64,
    /// Largest target spacing (m).
    pub spacing_max: f64,
    /// Seconds of the step (solve and estimate).
    pub seconds: f64,
    /// The estimated error in the target's norm.
    pub estimate: f64,
    /// The true error in the target's norm, when the scene has an exact solution.
    pub error: Option<f64>,
    /// All estimated norms.
    pub estimated: ErrorNorms,
    /// All true norms, when known.
    pub errors: Option<ErrorNorms>,
}

/// Why the loop ended.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "stop", rename_all = "snake_case")]
pub enum Stop {
    /// The estimate is at or below the target.
    Reached,
    /// The next step was predicted to take longer than the budget left.
    Budget {
        /// Predicted seconds of the next step.
        predicted_s: f64,
        /// Seconds left.
        left_s: f64,
    },
    /// The next step's nodes would not fit (memory estimate or node limit).
    Memory {
        /// The refusal.
        reason: String,
    },
    /// The estimate stopped falling (round-off, or a singularity the estimate cannot
    /// resolve).
    Stalled,
    /// The target's `max_steps` solves were made.
    Steps {
        /// Solves made.
        made: usize,
    },
    /// The next solve failed; the last good step is kept.
    Failed {
        /// The failure.
        reason: String,
    },
}

impl Stop {
    /// A sentence for the terminal.
    pub fn describe(&self) -> String {
        match self {
            Stop::Reached => "target reached".into(),
            Stop::Budget { predicted_s, left_s } => {
                format!("the budget ends: the next step would take about {predicted_s:.1} s, {left_s:.1} s are left")
            }
            Stop::Memory { reason } => format!("the next step does not fit: {reason}"),
            Stop::Stalled => format!("the estimate stalled (fell less than {:.0} % in two steps running)", 100.0 * STALL_FALL),
            Stop::Steps { made } => format!("{made} steps made"),
            Stop::Failed { reason } => format!("the next step failed: {reason}"),
        }
    }
}

/// The loop's result: its history, why it ended, and the problem and solution of the
/// step with the smallest estimate (usually the last; a refinement can make the
/// estimate rise, and the better step is then kept).
pub struct Outcome {
    /// One entry per solve.
    pub history: Vec<Step>,
    /// Why the loop ended.
    pub stop: Stop,
    /// Index into `history` of the step returned.
    pub best: usize,
    /// The problem of the best step (its node spacing).
    pub problem: Problem,
    /// The solution of the best step.
    pub solution: navier::Solution,
    /// What the loop changed in the request, to print (a grid refined uniformly, the
    /// estimate switched on, the degree raised).
    pub notes: Vec<String>,
    /// How the loop refined (never `Auto`).
    pub refinement: Refinement,
}

/// The target the loop aims at: with singular corners a displacement estimate counts
/// double (the `estimate` check's rule), so the tolerance is divided by that factor
/// (and a note says so).
fn aimed(target: &Target, problem: &Problem, solution: &navier::Solution, notes: &mut Vec<String>) -> Target {
    let factor = if target.norm.of_stress() {
        1.0
    } else {
        crate::quality::warnings::displacement_estimate_factor(&crate::quality::warnings::singular_corners(&problem.case, &solution.nodes))
    };
    if factor != 1.0 {
        notes.push(format!(
            "the scene has singular corners, where the estimate's reference is about as wrong as the run: \
             the displacement estimate counts x{factor}, so the loop stops at an estimate of {:.2e}",
            target.tolerance / factor
        ));
    }
    Target { tolerance: target.tolerance / factor, ..*target }
}

impl Step {
    /// The step of `solution`, whose estimate `estimated` is `value` in `norm`, made in
    /// `seconds`.
    fn of(solution: &navier::Solution, estimated: ErrorNorms, value: f64, norm: TargetNorm, seconds: f64) -> Step {
        Step {
            nodes: solution.nodes.len(),
            spacing_min: solution.nodes.local_spacing.iter().copied().fold(f64::INFINITY, f64::min),
            spacing_max: solution.nodes.local_spacing.iter().copied().fold(0.0, f64::max),
            seconds,
            estimate: value,
            error: solution.errors.as_ref().and_then(|e| norm.of(e)),
            estimated,
            errors: solution.errors,
        }
    }
}

/// Pursue `target` from the nodes of `p`, reporting each step to `on_step`.
pub fn pursue(p: &Problem, target: &Target, progress: &dyn Progress, mut on_step: impl FnMut(&Step)) -> Result<Outcome, RunError> {
    let t0 = Instant::now();
    let mut notes = Vec::new();
    let mut problem = p.clone();
    if !problem.navier.estimate.method.static_navier_estimates() {
        problem.navier.estimate.method = EstimateMethod::Auto;
        notes.push("the error estimate is switched on (estimate.method = \"auto\"): the target is set on it".into());
    }
    // The degree does not change the fill, so one count serves both hp choices.
    let nodes = problem.expected_nodes();
    let smooth = hp::is_smooth(&problem, nodes);
    let mut refinement = match target.refinement {
        Refinement::Auto if smooth => Refinement::Uniform,
        Refinement::Auto => Refinement::Local,
        chosen => chosen,
    };
    if refinement == Refinement::Local && problem.navier.fill.kind == FillKind::Grid {
        refinement = Refinement::Uniform;
        notes.push("a grid has one spacing: refined uniformly (fill = \"scattered\" refines locally)".into());
    }
    let hp_steps = target.degree == DegreeRule::Auto && smooth && refinement == Refinement::Uniform;
    // Whether the first step is the hp loop's coarse probe (about 1 000 nodes).
    let mut probed = false;
    if target.degree == DegreeRule::Auto && smooth {
        if let Some((raised, note)) = hp::raised_degree(&problem, target.tolerance) {
            problem = raised;
            notes.push(note);
        }
        if refinement == Refinement::Uniform {
            if let Some((coarse, note)) = hp::probe(&problem, nodes) {
                problem = coarse;
                notes.push(note);
                probed = true;
            }
        }
    }
    let formal = if hp_steps { hp::uniform_order(&problem.navier.approximation) } else { problem.navier.approximation.formal_order() };
    let mut history: Vec<Step> = Vec::new();
    let mut solution = navier::solve(&problem.case, &problem.navier, progress)?;
    let target = &aimed(target, &problem, &solution, &mut notes);
    // The best step so far (smallest estimate): its index, problem and solution.
    let mut best: Option<(usize, Problem, navier::Solution)> = None;
    let stop = loop {
        let step_seconds = t0.elapsed().as_secs_f64() - history.iter().map(|s| s.seconds).sum::<f64>();
        let Some(estimate) = solution.estimate.done() else {
            let reason = match &solution.estimate {
                navier::Estimate::Unavailable(_, why) => why.clone(),
                _ => "no estimate".into(),
            };
            match best {
                None => return Err(RunError::Estimate { reason }),
                Some(_) => break Stop::Failed { reason: format!("no estimate: {reason}") },
            }
        };
        let Some(value) = target.norm.of(&estimate.norms) else {
            return Err(RunError::Estimate { reason: format!("the estimate has no {}", target.norm.name()) });
        };
        let step = Step::of(&solution, estimate.norms, value, target.norm, step_seconds);
        on_step(&step);
        history.push(step);
        let k = history.len() - 1;
        // The probe's estimate on about 1 000 nodes may read the true error low (an
        // effectivity of 0.59 measured on Lame at degree 6): the probe alone is accepted
        // only with a margin of two, else the next step aims at half the target.
        let margin = if k == 0 && probed { PROBE_MARGIN } else { 1.0 };
        let aim = Target { tolerance: target.tolerance / margin, ..*target };
        let target = &aim;
        let next = if value <= target.tolerance {
            Err(Stop::Reached)
        } else if history.len() >= target.max_steps {
            Err(Stop::Steps { made: history.len() })
        } else if stalled(&history) {
            Err(Stop::Stalled)
        } else {
            let shown: Vec<(f64, f64)> = history.iter().map(|s| (s.spacing_max, s.estimate)).collect();
            let order = hp::observed_order(&shown, formal, refinement == Refinement::Uniform);
            next_problem(&problem, &solution, estimate, target, refinement, order)
                .map_err(|reason| Stop::Memory { reason })
                .and_then(|(next, nodes)| within_budget(target.budget, t0.elapsed().as_secs_f64(), &history[k], nodes).map(|()| next))
        };
        if best.as_ref().is_none_or(|(b, _, _)| value < history[*b].estimate) {
            best = Some((k, problem, solution));
        }
        let next = match next {
            Ok(next) => next,
            Err(stop) => break stop,
        };
        match navier::solve(&next.case, &next.navier, progress) {
            Ok(s) => {
                solution = s;
                problem = next;
            }
            Err(e @ RunError::Interrupted { .. }) => return Err(e),
            Err(e) => break Stop::Failed { reason: e.to_string() },
        }
    };
    let (best, problem, solution) = best.expect("the first step is solved and estimated");
    if best + 1 < history.len() {
        notes.push(format!(
            "the estimate of step {} ({:.2e}) is the smallest; later steps rose, and step {} is the result written",
            best + 1,
            history[best].estimate,
            best + 1
        ));
    }
    Ok(Outcome { history, stop, best, problem, solution, notes, refinement })
}

/// How far below the target the hp loop's first (probe) step must be estimated to be
/// accepted alone: the degree-6 estimate's effectivity on about 1 000 nodes was
/// measured down to 0.59 (Lame), so an estimate of E / 2 bounds the true error by
/// about 0.85 E (docs/guide/tradeoff.md).
pub const PROBE_MARGIN: f64 = 2.0;

/// `Err(Stop::Budget)` when the next step, of about `nodes` nodes, is predicted to take
/// longer than what is left of `budget` after `elapsed` seconds (the last step's seconds
/// times the node ratio, at least 1, to the power [`TIME_EXPONENT`]), or when nothing is
/// left. The caller reads the clock: the decision itself is tested with the seconds a
/// test sets (module `tests`).
fn within_budget(budget: Option<Duration>, elapsed: f64, last: &Step, nodes: f64) -> Result<(), Stop> {
    let Some(budget) = budget else { return Ok(()) };
    let predicted_s = last.seconds * (nodes / last.nodes as f64).max(1.0).powf(TIME_EXPONENT);
    let left_s = (budget.as_secs_f64() - elapsed).max(0.0);
    if left_s <= 0.0 || predicted_s > left_s {
        Err(Stop::Budget { predicted_s, left_s })
    } else {
        Ok(())
    }
}

/// Two steps running whose estimate fell by less than [`STALL_FALL`].
fn stalled(history: &[Step]) -> bool {
    let n = history.len();
    n >= 3 && (n - 2..n).all(|k| history[k].estimate > (1.0 - STALL_FALL) * history[k - 1].estimate)
}

/// The problem of the next step: the spacing refined by the indicator of `estimate`
/// (module docs), checked for node count and memory; with its expected node count.
fn next_problem(
    p: &Problem,
    sol: &navier::Solution,
    estimate: &ErrorEstimate,
    target: &Target,
    refinement: Refinement,
    order: f64,
) -> Result<(Problem, f64), String> {
    let (indicator, e_inf) = if target.norm.of_stress() {
        (estimate.per_node_sigma.as_deref().expect("stress computed (refusal)"), estimate.norms.e_inf_sigma.expect("stress"))
    } else {
        (estimate.per_node_u.as_slice(), estimate.norms.e_inf_u)
    };
    let value = target.norm.of(&estimate.norms).expect("norm present");
    // A relative-L2 target as a per-node tolerance (module docs).
    let tau = if value > 0.0 { target.tolerance * e_inf / value } else { target.tolerance };
    let fill = match refinement {
        Refinement::Uniform | Refinement::Auto => {
            let factor = indicator.iter().map(|&eta| adapt::refinement_factor(eta, tau, order)).fold(1.0, f64::min);
            p.navier.fill.scaled(factor)
        }
        Refinement::Local => {
            let pinned = singular_nodes(p, sol);
            let samples: SpacingSamples =
                adapt::adapted_spacing(&sol.nodes.positions, &sol.nodes.local_spacing, indicator, (tau, order, GROWTH), &pinned);
            let mut fill = p.navier.fill.clone();
            fill.adapted = Some(Arc::new(samples));
            fill
        }
    };
    let next = p.with_fill(fill).map_err(|e| e.reason)?;
    let memory = crate::models::resources::check(&next).map_err(|e| e.reason)?;
    Ok((next, memory.nodes))
}

/// The nodes within [`PINNED_SPACINGS`] local spacings of a singular corner of `p`.
fn singular_nodes(p: &Problem, sol: &navier::Solution) -> Vec<usize> {
    let corners = crate::quality::warnings::singular_corners(&p.case, &sol.nodes);
    let nodes = &sol.nodes;
    (0..nodes.len())
        .filter(|&i| {
            let x = nodes.positions[i];
            corners.iter().any(|c| (x[0] - c.at[0]).hypot(x[1] - c.at[1]) <= PINNED_SPACINGS * nodes.local_spacing[i])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step of `nodes` nodes that took `seconds`.
    fn step(nodes: usize, seconds: f64) -> Step {
        let norms = ErrorNorms { e_inf_u: 1e-2, e_inf_sigma: None, rel_l2_u: 1e-2, rel_l2_sigma: None };
        Step { nodes, spacing_min: 1.0, spacing_max: 1.0, seconds, estimate: 1e-2, error: None, estimated: norms, errors: None }
    }

    fn budget(seconds: f64) -> Option<Duration> {
        Some(Duration::from_secs_f64(seconds))
    }

    /// The budget's decision with the seconds the test sets: a step of 3 s on 1 000
    /// nodes, a next step of 4 000 nodes, predicted at 3 x 4^1.2 = 15.8 s.
    #[test]
    fn the_budget_stops_a_step_predicted_past_what_is_left() {
        let predicted = 3.0 * 4f64.powf(TIME_EXPONENT);
        assert!((predicted - 15.834).abs() < 1e-3, "{predicted}");
        // 20 s budget, 15 s spent: 5 s left, too few.
        match within_budget(budget(20.0), 15.0, &step(1000, 3.0), 4000.0) {
            Err(Stop::Budget { predicted_s, left_s }) => {
                assert!((predicted_s - predicted).abs() < 1e-12 && (left_s - 5.0).abs() < 1e-12, "{predicted_s} {left_s}");
                let said = Stop::Budget { predicted_s, left_s }.describe();
                assert_eq!(said, "the budget ends: the next step would take about 15.8 s, 5.0 s are left");
            }
            other => panic!("{other:?}"),
        }
        // 20 s left: the step fits; so does one just within (15.84 s left).
        assert!(within_budget(budget(30.0), 10.0, &step(1000, 3.0), 4000.0).is_ok());
        assert!(within_budget(budget(20.0), 20.0 - predicted - 1e-9, &step(1000, 3.0), 4000.0).is_ok());
        // No budget: never stopped by time.
        assert!(within_budget(None, 1e9, &step(1000, 3.0), 4000.0).is_ok());
    }

    /// A next step with fewer nodes is priced as the last one (the ratio is at least
    /// 1), and a budget already spent stops the loop whatever the prediction, with
    /// nothing (not a negative time) left: the smallest `--budget` (1 ns) ends every
    /// loop after its first step, on any machine.
    #[test]
    fn a_spent_budget_stops_with_nothing_left() {
        match within_budget(budget(10.0), 8.0, &step(1000, 3.0), 500.0) {
            Err(Stop::Budget { predicted_s, left_s }) => assert_eq!((predicted_s, left_s), (3.0, 2.0)),
            other => panic!("{other:?}"),
        }
        for elapsed in [1e-9, 0.5, 1e3] {
            match within_budget(budget(1e-9), elapsed, &step(10, 0.0), 10.0) {
                Err(Stop::Budget { predicted_s, left_s }) => assert_eq!((predicted_s, left_s), (0.0, 0.0)),
                other => panic!("{other:?}"),
            }
        }
    }
}
