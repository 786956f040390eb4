//! `mlsm run --target-error E`: the refinement loop of [`crate::tradeoff::target`],
//! one terminal line per step, and its history in `target.csv` and in `summary.json`
//! (`target`).

use super::AppError;
use crate::app::cli::{RefinementArg, TargetDegreeArg, TargetNormArg};
use crate::output;
use crate::stages::Silent;
use crate::scene::problem::Problem;
use crate::tradeoff::target::{self, DegreeRule, Outcome, Refinement, Step, Stop, Target, TargetNorm, MAX_STEPS};
use crate::quality::warnings::Warning;
use serde::Serialize;
use std::path::Path;
use std::time::Duration;

/// The target of the command line.
pub(super) fn request(
    tolerance: f64,
    norm: TargetNormArg,
    refinement: RefinementArg,
    degree: TargetDegreeArg,
    budget: Option<Duration>,
) -> Target {
    let norm = match norm {
        TargetNormArg::EInfU => TargetNorm::EInfU,
        TargetNormArg::EInfSigma => TargetNorm::EInfSigma,
        TargetNormArg::RelL2U => TargetNorm::RelL2U,
        TargetNormArg::RelL2Sigma => TargetNorm::RelL2Sigma,
    };
    let refinement = match refinement {
        RefinementArg::Auto => Refinement::Auto,
        RefinementArg::Local => Refinement::Local,
        RefinementArg::Uniform => Refinement::Uniform,
    };
    let degree = match degree {
        TargetDegreeArg::Auto => DegreeRule::Auto,
        TargetDegreeArg::Scene => DegreeRule::Scene,
    };
    Target { tolerance, norm, refinement, degree, budget, max_steps: MAX_STEPS }
}

/// `summary.json`'s `target`: what was asked, how it ended, and every step.
#[derive(Serialize)]
pub(super) struct TargetReport {
    tolerance: f64,
    norm: TargetNorm,
    /// How the loop refined (`auto` resolved: uniform or local).
    refinement: Refinement,
    budget_s: Option<f64>,
    reached: bool,
    /// Why the loop ended (`stop`), with its numbers.
    #[serde(flatten)]
    stop: Stop,
    message: String,
    /// What the loop changed or assumed (the estimate switched on, a grid refined
    /// uniformly, an estimate counted double at singular corners), as on the terminal.
    notes: Vec<String>,
    /// The step written (the smallest estimate), counted from 1.
    best_step: usize,
    steps: Vec<Step>,
}

impl TargetReport {
    /// The warning of a target that was not reached (the best estimate and why).
    pub(super) fn warning(&self) -> Option<Warning> {
        let best = self.steps.get(self.best_step.checked_sub(1)?)?;
        (!self.reached).then(|| Warning {
            check: "target",
            message: format!(
                "--target-error {:e} ({}) not reached: the best estimate is {:.2e} at {} nodes; {}",
                self.tolerance,
                self.norm.name(),
                best.estimate,
                best.nodes,
                self.message
            ),
        })
    }
}

/// Run the loop for `target` on `p`, printing a line per step unless `quiet`.
pub(super) fn pursue(p: &Problem, target: &Target, quiet: bool) -> Result<(Outcome, TargetReport), AppError> {
    if !quiet {
        eprintln!(
            "target: {} <= {:e}, {} refinement{}",
            target.norm.name(),
            target.tolerance,
            target.refinement.name(),
            target.budget.map_or(String::new(), |b| format!(", budget {:.0} s", b.as_secs_f64()))
        );
    }
    let mut k = 0;
    let outcome = target::pursue(p, target, &Silent, |s| {
        k += 1;
        if !quiet {
            let error = s.error.map_or(String::new(), |e| format!(" (true {e:.2e})"));
            eprintln!(
                "step {k}: {:>8} nodes, spacing {:.3e}..{:.3e}, estimate {:.2e}{error}, {:.2} s",
                s.nodes, s.spacing_min, s.spacing_max, s.estimate, s.seconds
            );
        }
    })
    .map_err(|e| AppError::of_scene(p, e))?;
    if !quiet {
        for n in &outcome.notes {
            eprintln!("note: {n}");
        }
        eprintln!("target: {} ({} refinement)", outcome.stop.describe(), outcome.refinement.name());
    }
    let report = TargetReport {
        tolerance: target.tolerance,
        norm: target.norm,
        refinement: outcome.refinement,
        budget_s: target.budget.map(|b| b.as_secs_f64()),
        reached: matches!(outcome.stop, Stop::Reached),
        stop: outcome.stop.clone(),
        message: outcome.stop.describe(),
        notes: outcome.notes.clone(),
        best_step: outcome.best + 1,
        steps: outcome.history.clone(),
    };
    Ok((outcome, report))
}

/// `target.csv`: one row per step.
pub(super) fn write_csv(dir: &Path, report: &TargetReport) -> Result<(), AppError> {
    let nan = |o: Option<f64>| o.unwrap_or(f64::NAN);
    let rows: Vec<Vec<f64>> = report
        .steps
        .iter()
        .enumerate()
        .map(|(k, s)| {
            vec![
                (k + 1) as f64,
                s.nodes as f64,
                s.spacing_min,
                s.spacing_max,
                s.seconds,
                s.estimate,
                nan(s.error),
                s.estimated.e_inf_u,
                nan(s.estimated.e_inf_sigma),
                nan(s.errors.map(|e| e.e_inf_u)),
                nan(s.errors.and_then(|e| e.e_inf_sigma)),
            ]
        })
        .collect();
    output::write_csv(
        &dir.join("target.csv"),
        &[
            "step",
            "nodes",
            "spacing_min",
            "spacing_max",
            "seconds",
            "estimate",
            "error",
            "estimated_e_inf_u",
            "estimated_e_inf_sigma",
            "e_inf_u",
            "e_inf_sigma",
        ],
        &rows,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quality::post::ErrorNorms;

    fn step(nodes: usize, estimate: f64) -> Step {
        let norms = ErrorNorms { e_inf_u: estimate, e_inf_sigma: None, rel_l2_u: estimate, rel_l2_sigma: None };
        Step { nodes, spacing_min: 1.0, spacing_max: 1.0, seconds: 1.0, estimate, error: None, estimated: norms, errors: None }
    }

    /// A target not reached names the step that was written (the smallest estimate),
    /// not the last one: on the bracket's local loop the second step rose to 3.5e-1
    /// after 1.5e-1, and the warning named the 3.5e-1.
    #[test]
    fn the_warning_names_the_best_step_not_the_last() {
        let report = TargetReport {
            tolerance: 1e-2,
            norm: TargetNorm::EInfU,
            refinement: Refinement::Local,
            budget_s: None,
            reached: false,
            stop: Stop::Stalled,
            message: Stop::Stalled.describe(),
            notes: Vec::new(),
            best_step: 1,
            steps: vec![step(1161, 0.147), step(15511, 0.346)],
        };
        let w = report.warning().expect("not reached");
        assert!(w.message.contains("the best estimate is 1.47e-1 at 1161 nodes"), "{}", w.message);
    }
}
