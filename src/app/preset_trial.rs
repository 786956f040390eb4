//! The trial run of a `balanced` or `accurate` preset: the scene is first solved with
//! the `fast` preset and its error estimate. When that estimate is already below the
//! requested preset's floor (`Preset::band`) and the run raised no warning, the basis
//! reproduces the solution (a polynomial of at most its degree, as in the cantilevers),
//! more nodes would add only round-off, and the trial is the result written. Otherwise
//! the preset's own run follows, and the trial's cost is part of the run's total.
//!
//! Measured on the shipped cantilevers (README, "Presets"): `accurate` took 60-76x the
//! time of the cheapest run as accurate and was less accurate than `fast` (round-off
//! grows with the node count); on scenes with non-polynomial solutions the trial adds
//! the `fast` run and its estimate to the preset's time.

use super::request::RunRequest;
use super::AppError;
use crate::scene::choice::Choice;
use crate::models::navier::{self, EstimateMethod};
use crate::stages::Progress;
use crate::scene::problem::preset::Preset;
use crate::scene::problem::{Model, Problem};
use serde::Serialize;
use std::time::Instant;

/// `summary.json`'s `preset_trial`: what was tried and whether it was kept.
#[derive(Debug, Clone, Serialize)]
pub(super) struct TrialReport {
    /// The preset asked for.
    preset: &'static str,
    /// The preset of the trial.
    trial: &'static str,
    nodes: usize,
    /// Seconds of the trial: its solve and its estimate.
    seconds: f64,
    /// `e_inf_sigma`, or `e_inf_u` when the scene computes no stress.
    norm: &'static str,
    /// The trial's estimate in `norm` (none when the estimate failed).
    estimate: Option<f64>,
    /// The requested preset's floor of `norm`.
    floor: f64,
    /// The trial is the result written.
    pub(super) kept: bool,
    /// Why it was kept or not, as the note on the terminal says.
    pub(super) reason: String,
}

/// A trial that was kept: its problem and its solution.
pub(super) struct Kept {
    pub(super) problem: Problem,
    pub(super) solution: navier::Solution,
}

/// The trial problem of `p` when its preset has one: the scene read again with the
/// trial's preset and the error estimate on. None for a scene without a preset or
/// with `fast`, and for a run that sets its own spacing (`--spacing` on a scene whose
/// file names a preset), exports its system, pursues an error target (the loop
/// refines from the preset's nodes) or solves with PETSc.
pub(super) fn trial_problem(p: &Problem, req: &RunRequest) -> Result<Option<Problem>, AppError> {
    let Some(trial) = p.preset.and_then(Preset::trial) else { return Ok(None) };
    let asked_otherwise = req.spacing.is_some() || req.export_system.is_some() || req.target.is_some();
    let petsc = p.navier.solver.kind.method() == crate::linalg::SolverMethod::Petsc;
    if p.model.kind() != Model::Navier || p.case.dynamics.is_some() || asked_otherwise || petsc {
        return Ok(None);
    }
    let mut t = Problem::from_file_with_preset(&req.scene, Some(trial))?;
    t.model = t.model.running(Model::Navier).expect("the Navier model always runs");
    if !t.navier.estimate.method.static_navier_estimates() {
        t.navier.estimate.method = EstimateMethod::Auto;
    }
    crate::models::resources::check(&t)?;
    Ok(Some(t))
}

/// Solve and estimate `trial`; keep it when its estimate is at most the floor of
/// `p`'s preset and it raised no warning.
pub(super) fn attempt(p: &Problem, trial: Problem, progress: &dyn Progress) -> Result<(Option<Kept>, TrialReport), AppError> {
    let preset = p.preset.expect("a trial is made for a preset");
    let (floor, _) = preset.band();
    let t = Instant::now();
    let solution = navier::solve(&trial.case, &trial.navier, progress).map_err(|e| AppError::of_scene(&trial, e))?;
    let seconds = t.elapsed().as_secs_f64();
    let norms = solution.estimate.done().map(|e| e.norms);
    // A displacement estimate counts as the `estimate` check counts it: double at
    // singular corners, where its reference is about as wrong as the run.
    let corners = || crate::quality::warnings::displacement_estimate_factor(&crate::quality::warnings::singular_corners(&trial.case, &solution.nodes));
    let (norm, estimate) = match norms {
        Some(n) => match n.e_inf_sigma {
            Some(s) => ("e_inf_sigma", Some(s)),
            None => ("e_inf_u", Some(n.e_inf_u * corners())),
        },
        None => (if trial.case.outputs.stress { "e_inf_sigma" } else { "e_inf_u" }, None),
    };
    let warned: Vec<&str> =
        crate::quality::warnings::navier_static(&solution, &trial.navier, &trial.case).warnings.iter().map(|w| w.check).collect();
    let kept = warned.is_empty() && estimate.is_some_and(|e| e <= floor);
    let trial_name = trial.preset.map_or("?", |t| t.name());
    let reason = match (kept, estimate) {
        (true, Some(e)) => format!(
            "preset \"{}\": the \"{trial_name}\" trial ({} nodes) estimates {norm} {e:.1e}, below the preset's floor {floor:.0e}: \
             the basis reproduces the solution, and its result is the one written",
            preset.name(),
            solution.nodes.len()
        ),
        (false, Some(e)) if warned.is_empty() => format!(
            "preset \"{}\": the \"{trial_name}\" trial estimates {norm} {e:.1e}, above the preset's floor {floor:.0e} \
             ({seconds:.2} s, counted in the total)",
            preset.name()
        ),
        (false, Some(_)) => format!(
            "preset \"{}\": the \"{trial_name}\" trial was warned ({}) and is not kept ({seconds:.2} s, counted in the total)",
            preset.name(),
            warned.join(", ")
        ),
        (_, None) => format!(
            "preset \"{}\": the \"{trial_name}\" trial has no estimate and is not kept ({seconds:.2} s, counted in the total)",
            preset.name()
        ),
    };
    let report =
        TrialReport { preset: preset.name(), trial: trial_name, nodes: solution.nodes.len(), seconds, norm, estimate, floor, kept, reason };
    Ok((kept.then_some(Kept { problem: trial, solution }), report))
}
