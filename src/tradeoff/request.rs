//! What `mlsm run --target-error E` asks for: the tolerance, the norm it is set on,
//! how the loop refines, which degree it solves with, its budget; and the targets the
//! loop refuses ([`refusal`]). The loop itself: [`super::target`].

use crate::quality::post::ErrorNorms;
use crate::scene::problem::Problem;
use serde::Serialize;
use std::time::Duration;

/// The norm a target is set on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TargetNorm {
    /// Relative max-norm error of the displacement.
    EInfU,
    /// Relative max-norm error of the stress.
    EInfSigma,
    /// Relative L2 error of the displacement.
    RelL2U,
    /// Relative L2 error of the stress.
    RelL2Sigma,
}

impl TargetNorm {
    /// The name used in `summary.json` (`e_inf_u`, ...).
    pub fn name(self) -> &'static str {
        match self {
            TargetNorm::EInfU => "e_inf_u",
            TargetNorm::EInfSigma => "e_inf_sigma",
            TargetNorm::RelL2U => "rel_l2_u",
            TargetNorm::RelL2Sigma => "rel_l2_sigma",
        }
    }

    /// Whether the norm is of the stress.
    pub fn of_stress(self) -> bool {
        matches!(self, TargetNorm::EInfSigma | TargetNorm::RelL2Sigma)
    }

    /// This norm of `n` (None when `n` has no stress part).
    pub fn of(self, n: &ErrorNorms) -> Option<f64> {
        match self {
            TargetNorm::EInfU => Some(n.e_inf_u),
            TargetNorm::EInfSigma => n.e_inf_sigma,
            TargetNorm::RelL2U => Some(n.rel_l2_u),
            TargetNorm::RelL2Sigma => n.rel_l2_sigma,
        }
    }
}

/// How the nodes are refined between steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Refinement {
    /// Uniform where the solution is smooth ([`super::hp::is_smooth`]), local where it is not.
    Auto,
    /// Graded, where the indicator asks for it.
    Local,
    /// The whole spacing function scaled by one factor.
    Uniform,
}

impl Refinement {
    /// The word of the command line (`auto`, `local`, `uniform`).
    pub fn name(self) -> &'static str {
        match self {
            Refinement::Auto => "auto",
            Refinement::Local => "local",
            Refinement::Uniform => "uniform",
        }
    }
}

/// Which degree the loop solves with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DegreeRule {
    /// The scene's, raised by [`super::hp::raised_degree`] where the solution is smooth.
    Auto,
    /// The scene's own.
    Scene,
}

/// What `--target-error` asks for.
#[derive(Debug, Clone, Copy)]
pub struct Target {
    /// The error to reach (relative), positive.
    pub tolerance: f64,
    /// The norm it is set on.
    pub norm: TargetNorm,
    /// How nodes are refined.
    pub refinement: Refinement,
    /// Which degree the loop solves with.
    pub degree: DegreeRule,
    /// Wall-clock limit of the whole loop.
    pub budget: Option<Duration>,
    /// Solves at most ([`super::target::MAX_STEPS`] from the command line; a test sets fewer to bound
    /// its cost by steps, not by the clock).
    pub max_steps: usize,
}

/// Why `target` cannot be pursued on `p`, if it cannot.
pub fn refusal(p: &Problem, target: &Target) -> Option<String> {
    if !(target.tolerance > 0.0 && target.tolerance < 1.0) {
        return Some(format!("--target-error must lie in (0, 1) (a relative error), got {}", target.tolerance));
    }
    if target.budget.is_some_and(|b| b.is_zero()) {
        return Some("--budget must be positive".into());
    }
    if p.case.dynamics.is_some() {
        return Some("--target-error refines a static Navier run; this scene is dynamic".into());
    }
    if target.norm.of_stress() && !p.case.outputs.needs_gradient() {
        return Some(format!("--target-norm {} needs the stress, which this scene does not compute (outputs)", target.norm.name()));
    }
    None
}
