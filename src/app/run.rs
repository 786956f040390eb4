//! `mlsm run`: solve a scene with its model (or `--model`), write `solution.vtu` and
//! `summary.json` (and the series of a time-dependent run), print a short result.

use super::extremes::Extremes;
use super::fields::{navier_fields, pd_fields, write_points_vtu};
use super::preset_trial::{self, TrialReport};
use super::report::{print_dynamic, print_estimate, print_navier, print_pd};
use super::request::RunRequest;
use super::series::Series;
use super::summary::{navier_extremes, pd_extremes, Dynamic, DynamicSummary, NavierDynamicPart, NavierSummary, PdDynamicPart, PdSummary};
use super::target::{self, TargetReport};
use super::terminal::Terminal;
use super::{default_out, export, AppError};
use crate::scene::choice::Choice;
use crate::models::dispatch::{self, Outcome};
use crate::models::navier::estimate::ESTIMATE;
use crate::models::navier::Estimate;
use crate::output::{self, StagedDir};
use crate::models::peridynamics::PdParams;
use crate::parallel::petsc;
use crate::stages::{RunError, OUTPUT};
use crate::scene::problem::preset::Preset;
use crate::scene::problem::{Model, ModelParams, Problem};
use crate::quality::warnings::{self, Checks};
use serde::Serialize;
use std::ffi::OsStr;
use std::path::PathBuf;
use std::time::Instant;

/// The scene with the command line's overrides applied and checked.
fn prepare(req: &RunRequest) -> Result<Problem, AppError> {
    let preset = match &req.preset {
        Some(w) => Some(Preset::parse(w).map_err(|e| AppError::Usage(format!("--preset: {e}")))?),
        None => None,
    };
    if preset.is_some() && req.spacing.is_some() {
        return Err(AppError::Usage("--preset sets the spacing; give --preset or --spacing, not both".into()));
    }
    if preset.is_some() && req.model == Some(Model::Peridynamics) {
        return Err(AppError::Usage("--preset chooses the MLSM nodes and approximation; the peridynamic model takes --horizon".into()));
    }
    let mut p = Problem::from_file_with_preset(&req.scene, preset)?;
    if let Some(d) = p.case.dynamics.as_mut() {
        d.allow_long = req.allow_long;
    }
    if let Some(m) = req.model {
        p.model = p.model.running(m).ok_or_else(|| {
            AppError::Usage(format!("{}: the peridynamic model needs a [peridynamics] table", req.scene.display()))
        })?;
        if let Some(why) = (m == Model::Peridynamics).then(|| crate::scene::problem::validate::peridynamic_material_refusal(&p.case.material)).flatten() {
            return Err(AppError::Usage(format!("--model peridynamics: {}: material.nu: {why}", req.scene.display())));
        }
        if m == Model::Navier && p.model.has_fracture() {
            return Err(AppError::Usage(format!(
                "--model navier: {}: peridynamics.fracture: the pre-cracks and breaking bonds belong to the peridynamic model; the \
                 Navier model has no crack (remove [peridynamics.fracture] to solve the uncracked solid)",
                req.scene.display()
            )));
        }
        if let Some(why) = crate::scene::problem::estimate_mismatch(m, p.case.dynamics.is_some(), p.navier.estimate.method) {
            return Err(AppError::Usage(format!("--model {}: {}: estimate.method: {why}", m.name(), req.scene.display())));
        }
    }
    match p.model {
        ModelParams::Peridynamics(params) => {
            if req.spacing.is_some() {
                return Err(AppError::Usage("--spacing sets the MLSM node spacing; for peridynamics use --horizon (h = delta / m)".into()));
            }
            if let Some(d) = req.horizon {
                p = p.with_peridynamics(PdParams { horizon: d, ..params })?;
            }
        }
        ModelParams::Navier { .. } => {
            if req.horizon.is_some() {
                return Err(AppError::Usage("--horizon belongs to the peridynamic model (--model peridynamics)".into()));
            }
            if let Some(h) = req.spacing {
                p = p.with_spacing(h)?;
            }
        }
    }
    if req.export_system.is_some() {
        if p.model.kind() != Model::Navier || p.case.dynamics.is_some() {
            return Err(AppError::Usage(
                "--export-system writes the system of a static Navier run; this run is dynamic or peridynamic".into(),
            ));
        }
        p.navier.keep_system = true;
    }
    if let Some(t) = &req.target {
        if p.model.kind() != Model::Navier {
            return Err(AppError::Usage(
                "--target-error refines the MLSM nodes of a Navier run; the peridynamic model takes --horizon".into(),
            ));
        }
        if let Some(why) = crate::tradeoff::target::refusal(&p, t) {
            return Err(AppError::Usage(format!("{}: {why}", req.scene.display())));
        }
    }
    super::ranks::start_petsc(&mut p, req)?;
    crate::models::resources::check(&p)?;
    Ok(p)
}

/// The entries of a result folder that `run` writes: a re-run replaces those of the
/// earlier run (and the staging folder of older versions); anything else in the
/// folder (`compare/`, `convergence.csv`, the user's files) is kept.
const RUN_ENTRIES: [&str; 7] =
    ["solution.vtu", "summary.json", "target.csv", "snapshots", "series.pvd", "energies.csv", ".snapshots.partial"];

/// Whether `name` is one of [`RUN_ENTRIES`].
fn run_owns(name: &OsStr) -> bool {
    RUN_ENTRIES.iter().any(|e| name == *e)
}

/// Solve, write and report one scene. Everything is written into a staged folder
/// that replaces the result folder only when all files are written.
pub(super) fn run(mut req: RunRequest, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    let p = prepare(&req)?;
    let world = petsc::world();
    if world.rank > 0 {
        // Rank 0 writes the results; the others write theirs (the same) aside and drop them.
        let aside = std::env::temp_dir().join(format!("mlsm-rank{}-{}", world.rank, std::process::id()));
        req.out = Some(aside.clone());
        let done = run_prepared(p, req, term, true);
        let _ = std::fs::remove_dir_all(&aside);
        return done;
    }
    run_prepared(p, req, term, quiet)
}

/// [`run`] of a prepared problem.
fn run_prepared(p: Problem, req: RunRequest, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    let staged = StagedDir::create(&req.out.clone().unwrap_or_else(|| default_out(&p)), run_owns);
    // Over MPI ranks, a rank that cannot write stops them all before the first collective.
    if petsc::any_rank(staged.is_err()) && staged.is_ok() {
        return Err(AppError::Run(RunError::Solve(crate::parallel::distributed::other_rank_failed())));
    }
    let staged = staged?;
    let dir = staged.path().to_path_buf();
    if !quiet {
        eprintln!("{}", dispatch::announce(&p));
        for n in &p.notes {
            eprintln!("note: {n}");
        }
    }
    let t0 = Instant::now();
    if let Some(t) = &req.target {
        let (outcome, report) = target::pursue(&p, t, quiet)?;
        target::write_csv(&dir, &report)?;
        let before = Before { target: Some(&report), trial: None };
        return write_navier_static(&outcome.problem, outcome.solution, staged, t0, &req, before, term, quiet);
    }
    let mut trial_report = None;
    if let Some(trial) = preset_trial::trial_problem(&p, &req)? {
        if !quiet {
            let name = trial.preset.map_or("?", |t| t.name());
            eprintln!("note: the \"{name}\" preset is tried first, with its error estimate (a preset's trial)");
        }
        let (kept, report) = preset_trial::attempt(&p, trial, term)?;
        if let Some(k) = kept {
            let before = Before { target: None, trial: Some(&report) };
            return write_navier_static(&k.problem, k.solution, staged, t0, &req, before, term, quiet);
        }
        trial_report = Some(report);
    }
    let fracture = p.model.has_fracture();
    let mut series = Series::new(&dir, &p.case, fracture);
    let outcome = dispatch::solve(&p, term, |s| series.snapshot(s).map_err(RunError::Snapshot)).map_err(|e| AppError::of_scene(&p, e))?;
    // Each branch starts the output stage where its output begins (after the
    // estimate of a peridynamic run, which is timed as its own stage).
    match outcome {
        Outcome::NavierStatic(sol) => {
            let before = Before { target: None, trial: trial_report.as_ref() };
            write_navier_static(&p, sol, staged, t0, &req, before, term, quiet)?
        }
        Outcome::PdStatic(sol) => write_pd_static(&p, sol, staged, t0, &req, term, quiet)?,
        Outcome::NavierDynamic(mut sim) => {
            let output = OutputStage::start();
            series.finish(&sim.energies, &sim.positions, (&sim.u, &sim.v), &sim.estimate)?;
            output.record(&mut sim.timings);
            write_dynamic(&p, staged, navier_dynamic(&sim), (NavierDynamicPart::of(&p, &sim), None), t0, &req, quiet)?;
        }
        Outcome::PdDynamic(mut sim) => {
            let nodes = &sim.discretisation.nodes;
            let run = ((sim.u.as_slice(), None), sim.history.as_slice());
            let estimate = peridynamics_estimate(&p, &nodes.positions[..nodes.free], run, &mut sim.timings, term);
            let discretisation = p.navier.estimate.method.peridynamics_estimates().then(|| {
                if p.model.has_fracture() {
                    return (Err(FRACTURE_UNESTIMATED.to_string()), 0.0);
                }
                let t = Instant::now();
                let params = *p.model.peridynamics().expect("a peridynamic scene has [peridynamics]");
                let dynamics = p.case.dynamics.as_ref().expect("a dynamic run has [dynamics]");
                let d = crate::models::peridynamics::discretisation::estimate_dynamic(&p.case, &params, dynamics, &sim);
                let seconds = t.elapsed().as_secs_f64();
                term.line(ESTIMATE, seconds, &discretisation_note(&d));
                (d, seconds)
            });
            let discretisation = discretisation.map(|(d, seconds)| {
                sim.timings.record(ESTIMATE, seconds);
                d
            });
            let nodes = &sim.discretisation.nodes;
            let output = OutputStage::start();
            series.finish(&sim.energies, &nodes.positions[..nodes.free], (&sim.u, &sim.v), &estimate)?;
            output.record(&mut sim.timings);
            if !quiet {
                println!("throughput {:.2e} bond updates per second per thread", sim.bond_updates_per_second_per_thread);
                if let Some(f) = &sim.fracture {
                    let s0 = f.critical_stretch.map_or("no breaking (pre-cracks only)".into(), |s| format!("critical stretch {s:.3e}"));
                    println!(
                        "fracture: {s0}; {} bonds broke ({:.3e} J released), {} across the pre-cracks; {} nodes damaged, largest damage {:.2}",
                        f.broken_bonds, f.released_energy, f.precracked_bonds, f.damaged_nodes, f.largest_damage
                    );
                }
            }
            let dynamic = Dynamic {
                nodes: nodes.free,
                report: &sim.report,
                energies: &sim.energies,
                timings: &sim.timings,
                estimate: &estimate,
                unbalanced: &[],
                extremes: final_extremes(&nodes.positions[..nodes.free], &sim.u, &sim.energies),
            };
            write_dynamic(&p, staged, dynamic, (PdDynamicPart::of(&p, &sim, discretisation.as_ref()), discretisation.as_ref()), t0, &req, quiet)?;
        }
    }
    Ok(())
}

/// Estimate, write and report a static peridynamic run (its estimate is timed as its
/// own stage, before the output stage).
fn write_pd_static(
    p: &Problem,
    mut sol: crate::models::peridynamics::PdSolution,
    staged: StagedDir,
    t0: Instant,
    req: &RunRequest,
    term: &Terminal,
    quiet: bool,
) -> Result<(), AppError> {
    let n = sol.nodes.free;
    let free = &sol.nodes.positions[..n];
    let fields = (&sol.displacement[..n], sol.stress.as_ref());
    let estimate = peridynamics_estimate(p, free, (fields, &[]), &mut sol.timings, term);
    if p.navier.estimate.method.peridynamics_estimates() {
        let t = Instant::now();
        let params = *p.model.peridynamics().expect("a peridynamic scene has [peridynamics]");
        let d = crate::models::peridynamics::discretisation::estimate(&p.case, &params, &sol);
        let seconds = t.elapsed().as_secs_f64();
        sol.timings.record(ESTIMATE, seconds);
        term.line(ESTIMATE, seconds, &discretisation_note(&d));
        sol.discretisation = Some(d);
    }
    let output = OutputStage::start();
    let mut checks = warnings::peridynamics_static(&sol, &estimate, p.navier.estimate.threshold);
    checks.warnings.extend(warnings::pd_near_incompressible(&p.case.material));
    checks.warnings.extend(warnings::memory(p));
    write_points_vtu(&staged.path().join("solution.vtu"), free, &p.case.domain, pd_fields(&p.case, &sol, &estimate))?;
    output.record(&mut sol.timings);
    let target = publish(staged, &PdSummary::new(p, &sol, &estimate, &checks, t0))?;
    term.line(OUTPUT, output.seconds(), &target.display().to_string());
    if !quiet {
        print_pd(&sol, pd_extremes(&sol).as_ref());
        print_estimate(&estimate);
    }
    report_checks(&checks, req.strict, quiet)
}

/// The terminal's line of a peridynamic run's discretisation estimate.
fn discretisation_note(d: &Result<crate::models::peridynamics::solve::DiscretisationEstimate, String>) -> String {
    match d {
        Ok(d) => format!("discretisation at this horizon: e_inf(u) ~ {:.1e} ({})", d.e_inf_u, d.reference),
        Err(why) => format!("no discretisation estimate: {why}"),
    }
}

/// What a dynamic Navier run reports.
fn navier_dynamic(sim: &crate::models::navier::Simulation) -> Dynamic<'_> {
    Dynamic {
        nodes: sim.positions.len(),
        report: &sim.report,
        energies: &sim.energies,
        timings: &sim.timings,
        estimate: &sim.estimate,
        unbalanced: &sim.unbalanced,
        extremes: final_extremes(&sim.positions, &sim.u, &sim.energies),
    }
}

/// The extremes of a dynamic run's final state (the time of the last energy row).
fn final_extremes(positions: &[[f64; 2]], u: &[[f64; 2]], energies: &[crate::models::dynamics::driver::EnergyRow]) -> Option<Extremes> {
    let t = energies.last().map_or(0.0, |e| e[0]);
    Extremes::of(positions, u, None).map(|e| e.at_time(t))
}

/// The output stage of a run: its seconds and its peak memory from [`OutputStage::start`].
struct OutputStage {
    start: Instant,
    mark: crate::output::PeakMark,
}

impl OutputStage {
    fn start() -> Self {
        OutputStage { start: Instant::now(), mark: crate::output::restart_peak() }
    }

    fn seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Record the seconds and the peak so far as the output stage's.
    fn record(&self, timings: &mut crate::stages::StageTimings) {
        timings.record(OUTPUT, self.seconds());
        if let Some(bytes) = crate::output::peak_since(self.mark) {
            timings.record_peak(OUTPUT, bytes);
        }
    }
}

/// What ran before the solve that is written: the steps of `--target-error`, or a
/// preset's trial.
#[derive(Clone, Copy)]
struct Before<'a> {
    target: Option<&'a TargetReport>,
    trial: Option<&'a TrialReport>,
}

/// Write `solution.vtu` and `summary.json` of a static Navier run (with the history of
/// `--target-error` or the preset's trial), export its system if asked, print its
/// result and checks.
#[allow(clippy::too_many_arguments)]
fn write_navier_static(
    p: &Problem,
    mut sol: crate::models::navier::Solution,
    staged: StagedDir,
    t0: Instant,
    req: &RunRequest,
    Before { target, trial }: Before,
    term: &Terminal,
    quiet: bool,
) -> Result<(), AppError> {
    let output = OutputStage::start();
    let dir = staged.path().to_path_buf();
    let mut checks = warnings::navier_static(&sol, &p.navier, &p.case);
    checks.warnings.extend(warnings::memory(p));
    checks.warnings.extend(target.and_then(TargetReport::warning));
    checks.notes.extend(trial.map(|t| t.reason.clone()));
    write_points_vtu(&dir.join("solution.vtu"), &sol.nodes.positions, &p.case.domain, navier_fields(&p.case, &sol))?;
    output.record(&mut sol.timings);
    let mut summary = NavierSummary::new(p, &sol, &checks, t0);
    summary.target = target;
    summary.preset_trial = trial;
    let written = publish(staged, &summary)?;
    term.line(OUTPUT, output.seconds(), &written.display().to_string());
    if let (Some(to), Some(system)) = (&req.export_system, &sol.system) {
        export::write(to, system, &sol.solver)?;
        if !quiet {
            println!("system written: {}", to.display());
        }
    }
    if !quiet {
        print_navier(&sol, navier_extremes(&sol).as_ref());
    }
    report_checks(&checks, req.strict, quiet)
}

/// Write `summary.json` (the last file) into `staged` and replace the result folder
/// with it; returns the result folder.
fn publish(staged: StagedDir, summary: &impl Serialize) -> Result<PathBuf, AppError> {
    output::write_json(&staged.path().join("summary.json"), summary)?;
    let target = staged.target().to_path_buf();
    staged.commit()?;
    Ok(target)
}

/// Print the notes and warnings of `checks` (warnings also under `--quiet`: a doubtful
/// result is never silent); with `strict`, any warning is an error (exit 4) after the
/// results were written.
fn report_checks(checks: &Checks, strict: bool, quiet: bool) -> Result<(), AppError> {
    if !quiet {
        for n in &checks.notes {
            eprintln!("note: {n}");
        }
    }
    for w in &checks.warnings {
        eprintln!("warning [{}]: {}", w.check, w.message);
    }
    if strict && !checks.warnings.is_empty() {
        return Err(AppError::Strict(checks.warnings.len()));
    }
    Ok(())
}

/// `summary.json` of a time-dependent run with its checks, the replacement of the
/// result folder, and its terminal lines.
/// `discretisation`: a peridynamic run's estimate at its horizon, warned above the
/// threshold like the static one's.
fn write_dynamic<M: Serialize>(
    p: &Problem,
    staged: StagedDir,
    d: Dynamic,
    (model, discretisation): (M, Option<&Result<crate::models::peridynamics::solve::DiscretisationEstimate, String>>),
    t0: Instant,
    req: &RunRequest,
    quiet: bool,
) -> Result<(), AppError> {
    let threshold = p.navier.estimate.threshold;
    // A peridynamic run's horizon (its estimate is a model difference) and node spacing.
    let peridynamics = match p.model {
        ModelParams::Peridynamics(pd) => Some(pd),
        ModelParams::Navier { .. } => None,
    };
    let horizon = peridynamics.map(|pd| pd.horizon);
    let mut checks = warnings::dynamic(d.energies, threshold, p.case.loads().depend_on_time(), d.estimate, (horizon, d.report.integrator));
    if let Some(dynamics) = &p.case.dynamics {
        let spacing = match peridynamics {
            Some(pd) => pd.horizon / pd.ratio,
            None => p.navier.fill.field(&p.case.domain).min(),
        };
        let resolution =
            warnings::load_time_resolution(&p.case, spacing, d.report.time_step, dynamics.end_time, dynamics.integrator, threshold);
        checks.warnings.extend(resolution);
    }
    if let Some(pd) = peridynamics {
        warnings::pd_discretisation(discretisation, (pd.horizon, pd.ratio), threshold, &mut checks);
        checks.warnings.extend(warnings::pd_near_incompressible(&p.case.material));
    }
    checks.warnings.extend(warnings::memory(p));
    checks.notes.extend(warnings::unbalanced_note(d.unbalanced));
    let dir = publish(staged, &DynamicSummary::new(p, &d, model, &checks, t0))?;
    if !quiet {
        print_dynamic(&d, p.case.loads().depend_on_time(), &dir);
    }
    report_checks(&checks, req.strict, quiet)
}

/// A peridynamic run's fields for its estimate: `((displacement, stress), history)`.
type PdFields<'a> = ((&'a [[f64; 2]], Option<&'a crate::physics::elasticity::stress::StressField>), &'a [(f64, Vec<[f64; 2]>)]);

/// The `local-model` estimate of a peridynamic run whose free nodes `positions` carry
/// `displacement` (and `stress`; a dynamic run's kept `history`), timed as the
/// estimate stage; off for `estimate.method = "none"`.
/// Why a peridynamic run with `[peridynamics.fracture]` has no error estimate.
const FRACTURE_UNESTIMATED: &str = "bonds break or the solid is pre-cracked: the local (Navier) model has no crack to compare with, \
     and a run at another m breaks other bonds (a crack path is not a converging field)";

fn peridynamics_estimate(
    p: &Problem,
    positions: &[crate::domain::Point],
    (fields, history): PdFields,
    timings: &mut crate::stages::StageTimings,
    term: &Terminal,
) -> Estimate {
    if !p.navier.estimate.method.peridynamics_estimates() {
        return Estimate::Off;
    }
    if p.model.has_fracture() {
        return Estimate::Unavailable("local-model", FRACTURE_UNESTIMATED.into());
    }
    let t = Instant::now();
    let estimate = crate::quality::compare::estimate::local_model(p, positions, fields, history);
    let seconds = t.elapsed().as_secs_f64();
    timings.record(ESTIMATE, seconds);
    term.line(ESTIMATE, seconds, &estimate.note());
    estimate
}
