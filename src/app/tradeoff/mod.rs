//! `mlsm tradeoff`: the designed sweep of [`crate::tradeoff`] over spacing, basis and
//! degree, stencil size and solver, cheapest predicted run first, until the time budget
//! ends; each configuration is a scene file run as its own process. Writes
//! `tradeoff.csv`, `tradeoff.json`, the front plot (`tradeoff.svg`, `tradeoff.png`),
//! the configuration files (`configs/`) and each run's `summary.json` (`runs/`), and
//! prints the table and the cheapest configuration per accuracy decade.
//!
//! For tests only, `MLSM_TRADEOFF_MAX_RUNS=N` ends the sweep once N runs were started:
//! a count a test sets where a budget would make it depend on the machine's speed.

mod child;
mod report;

use super::AppError;
use crate::output::{self, StagedDir};
use crate::scene::problem::{Model, Problem, ProblemError, ProblemErrorKind};
use crate::models::resources::{self, MemoryEstimate};
use crate::tradeoff::design::{self, Budget, Measured, Sweep, LADDER_LEVELS};
use crate::tradeoff::variant::{Edits, Setting};
use crate::quality::warnings::singular_estimate_note;
use child::{Ending, Norms};
use serde::Serialize;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What `tradeoff` was asked for.
pub(super) struct TradeoffRequest {
    pub scene: PathBuf,
    pub budget: Duration,
    pub out: Option<PathBuf>,
}

/// For tests only (module docs): the number of runs after which the sweep ends.
const MAX_RUNS_VARIABLE: &str = "MLSM_TRADEOFF_MAX_RUNS";

/// `MLSM_TRADEOFF_MAX_RUNS`, when set: a positive whole number.
fn max_runs() -> Result<Option<usize>, AppError> {
    let Ok(text) = std::env::var(MAX_RUNS_VARIABLE) else { return Ok(None) };
    match text.trim().parse::<usize>() {
        Ok(n) if n > 0 => Ok(Some(n)),
        _ => Err(AppError::Usage(format!("{MAX_RUNS_VARIABLE}={text:?} must be a positive whole number (runs; for tests)"))),
    }
}

/// Warnings that make a run's errors untrustworthy (the solve itself is in doubt).
/// `solver-error` is not one of them: a converged solve whose own error is above a
/// tenth of the discretisation's is reproducible, and its exact or estimated errors
/// are of the solution it returned, solver's error included; the sweep reports what
/// the configuration delivers.
const DOUBTFUL_SOLVE: [&str; 3] = ["residual", "conditioning", "underflow"];

/// How a configuration ended.
#[derive(Serialize, Clone, Copy, PartialEq, Eq, Debug, Default)]
#[serde(rename_all = "kebab-case")]
enum Status {
    /// Ran and reported.
    #[default]
    Ok,
    /// Not started: its memory estimate exceeds the available memory.
    Refused,
    /// Not started: its predicted time exceeds what is left of the budget.
    Skipped,
    /// Ran and failed (exit code and reason).
    Failed,
    /// Stopped at the end of the budget.
    Stopped,
}

/// One configuration of the sweep and what became of it.
#[derive(Serialize, Clone, Debug, Default)]
struct Row {
    id: String,
    family: String,
    level: usize,
    /// Far-field spacing (a graded spacing function scaled with it).
    spacing: f64,
    status: Status,
    #[serde(skip_serializing_if = "Option::is_none")]
    reason: Option<String>,
    estimated_nodes: f64,
    estimated_peak_memory_bytes: f64,
    nodes: Option<u64>,
    /// Seconds of the run as a user runs it, its error estimate included.
    seconds: Option<f64>,
    /// Seconds of its error estimate (part of `seconds`).
    estimate_seconds: Option<f64>,
    /// Wall-clock seconds of the whole process (estimate and output included).
    wall_seconds: Option<f64>,
    peak_memory_bytes: Option<f64>,
    /// Errors against the scene's exact solution.
    exact: Option<Norms>,
    /// The run's error estimate.
    estimated: Option<Norms>,
    /// The checks that warned; a run whose linear solve is doubtful (`residual`,
    /// `conditioning`, `underflow`) is listed but never on a front or in the advice.
    warnings: Vec<String>,
    on_front_sigma: bool,
    on_front_u: bool,
    /// The scene snippet of this configuration.
    snippet: String,
}

/// Which error a front is drawn on.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Field {
    Sigma,
    U,
}

impl Row {
    /// e_inf of `field`: exact when the run has it, else estimated; with `true` for exact.
    fn error(&self, field: Field) -> Option<(f64, bool)> {
        let pick = |n: &Option<Norms>| n.and_then(|n| n.e_inf(field));
        pick(&self.exact).map(|e| (e, true)).or_else(|| pick(&self.estimated).map(|e| (e, false)))
    }

    /// A finished run whose solve is trustworthy (see `warnings`): one that may be on a
    /// front or recommended.
    fn trusted(&self) -> bool {
        self.status == Status::Ok && !self.warnings.iter().any(|w| DOUBTFUL_SOLVE.contains(&w.as_str()))
    }

    /// The error that steers the sweep: sigma where computed, else u.
    fn measure(&self) -> Option<f64> {
        self.error(Field::Sigma).or_else(|| self.error(Field::U)).map(|e| e.0)
    }
}

/// A configuration ready to run.
struct Plan {
    edits: Edits,
    text: String,
    estimate: MemoryEstimate,
    /// `resources::check`'s refusal when the estimate exceeds the available memory.
    refused: Option<String>,
    spacing: f64,
}

/// The family's configuration at `level` of the ladder.
fn plan(p: &Problem, text: &str, setting: Option<&Setting>, level: usize) -> Result<Plan, ProblemError> {
    let spacing = design::spacing(p.navier.fill.spacing, level);
    let edits = Edits::of(p, setting, spacing)?;
    let text = edits.apply(text, &p.source)?;
    let variant = Problem::from_str(&text, &p.source)?;
    let refused = resources::check(&variant).err().map(|e| format!("{}: {}", e.field, e.reason));
    Ok(Plan { edits, estimate: resources::of(&variant), refused, text, spacing })
}

/// The families of the sweep with their settings: those of [`design::families`] that
/// the scene accepts, without repeats of the scene's own setting.
fn families(p: &Problem, text: &str) -> (Vec<(String, Option<Setting>)>, Vec<String>) {
    let mut notes = Vec::new();
    let at_scene = |s: Option<&Setting>| -> Result<Problem, ProblemError> {
        let edits = Edits::of(p, s, p.navier.fill.spacing)?;
        Problem::from_str(&edits.apply(text, &p.source)?, &p.source)
    };
    let phs4 = Setting { basis: "phs", degree: 4, support: None, solver: None };
    let phs4_support = at_scene(Some(&phs4)).map(|v| v.navier.approximation.support).unwrap_or(30);
    let signature =
        |v: &Problem| format!("{:?}|{}|{:?}", v.navier.approximation.basis, v.navier.approximation.support, v.navier.solver.kind);
    let mut kept: Vec<(String, Option<Setting>, String)> = Vec::new();
    for (name, setting) in design::families(phs4_support) {
        match at_scene(setting.as_ref()) {
            Ok(v) => {
                let sig = signature(&v);
                if let Some(shipped) = kept.iter_mut().find(|k| k.2 == sig) {
                    shipped.0 = format!("{} = {name}", shipped.0);
                } else {
                    kept.push((name, setting, sig));
                }
            }
            Err(e) => notes.push(format!("family \"{name}\" left out: {}: {}", e.field, e.reason)),
        }
    }
    (kept.into_iter().map(|(n, s, _)| (n, s)).collect(), notes)
}

/// Refuse scenes the sweep cannot study.
fn check_scene(p: &Problem) -> Result<(), AppError> {
    let file = p.source.display();
    if p.case.dynamics.is_some() {
        return Err(AppError::Usage(format!("{file}: tradeoff sweeps the static solve; remove the [dynamics] table")));
    }
    if p.model.kind() == Model::Peridynamics {
        return Err(AppError::Usage(format!(
            "{file}: tradeoff sweeps the Navier model; for peridynamics `mlsm compare` prints each horizon's cost next to its error"
        )));
    }
    if p.case.exact.is_none() && !p.navier.estimate.method.static_navier_estimates() {
        return Err(AppError::Usage(format!(
            "{file}: the scene has no [exact] solution and estimate.method = \"none\": a sweep without any error measures nothing"
        )));
    }
    Ok(())
}

/// The scene of `req`, as text (the sweep edits it) and validated; refused when the
/// sweep cannot study it or the memory limit is malformed (an error of the command,
/// not of every configuration).
fn read_scene(req: &TradeoffRequest) -> Result<(String, Problem), AppError> {
    let text = std::fs::read_to_string(&req.scene).map_err(|e| ProblemError {
        file: req.scene.clone(),
        field: "(file)".into(),
        reason: format!("cannot read the scene file: {e}"),
        kind: ProblemErrorKind::Invalid,
    })?;
    let p = Problem::from_str(&text, &req.scene)?;
    check_scene(&p)?;
    match resources::check(&p) {
        Err(e) if e.field == "MLSM_MEMORY_LIMIT" => Err(e.into()),
        _ => Ok((text, p)),
    }
}

/// A configuration for every running family that has none: levels too coarse for its
/// stencil are passed over; any other refusal stops the family.
fn plan_next_runs((p, text): (&Problem, &str), families: &[(String, Option<Setting>)], sweep: &mut Sweep, plans: &mut [Option<Plan>]) {
    for (f, (_, setting)) in families.iter().enumerate() {
        while sweep.families[f].stopped.is_none() && plans[f].is_none() {
            let level = sweep.families[f].next_level;
            match plan(p, text, setting.as_ref(), level) {
                Ok(pl) => plans[f] = Some(pl),
                Err(e) if e.kind == ProblemErrorKind::TooFewNodes && level + 1 < LADDER_LEVELS => sweep.families[f].next_level += 1,
                Err(e) => sweep.stop(f, format!("{}: {}", e.field, e.reason)),
            }
        }
    }
}

/// What a run of family `f` (its planned work, `wall` seconds) ended with, in its row
/// and in the sweep: measured, failed (the family stops), or stopped by the budget
/// (every family stops). Returns whether the run met singular corners.
fn record(row: &mut Row, ending: Ending, (f, work, wall): (usize, f64, f64), sweep: &mut Sweep) -> bool {
    row.wall_seconds = Some(wall);
    match ending {
        Ending::Finished(r) => {
            (row.nodes, row.seconds, row.estimate_seconds) = (Some(r.nodes), Some(r.seconds), Some(r.estimate_seconds));
            (row.peak_memory_bytes, row.warnings) = (r.peak_memory_bytes, r.warnings);
            (row.exact, row.estimated) = (r.exact, r.estimated);
            let error = if row.trusted() { row.measure() } else { None };
            sweep.record(f, Measured { work, seconds: wall, error });
            r.singular_corners
        }
        Ending::Failed(why) => {
            sweep.stop(f, format!("a run failed ({why})"));
            (row.status, row.reason) = (Status::Failed, Some(why));
            false
        }
        Ending::Stopped => {
            (row.status, row.reason) = (Status::Stopped, Some("the budget ended during the run".into()));
            for g in 0..sweep.families.len() {
                sweep.stop(g, "the budget ended".into());
            }
            false
        }
    }
}

/// Run the sweep of `req` (module docs).
pub(super) fn run(req: TradeoffRequest, quiet: bool) -> Result<(), AppError> {
    let (text, p) = read_scene(&req)?;
    let max_runs = max_runs()?;
    let start = Instant::now();
    let budget = Budget { seconds: req.budget.as_secs_f64() };
    let elapsed = || start.elapsed().as_secs_f64();
    let target = req.out.clone().unwrap_or_else(|| super::default_out(&p).join("tradeoff"));
    let staged = StagedDir::create(&target, |_| true)?;
    let dir = staged.path().to_path_buf();
    for sub in ["configs", "runs"] {
        super::create_dir(&dir.join(sub))?;
    }
    let (families, mut notes) = families(&p, &text);
    if !quiet {
        let names: Vec<&str> = families.iter().map(|f| f.0.as_str()).collect();
        eprintln!("tradeoff of {} within {:.0} s: {} families ({})", p.name, req.budget.as_secs_f64(), names.len(), names.join("; "));
        notes.iter().for_each(|n| eprintln!("note: {n}"));
    }
    let singular_note = singular_estimate_note("the estimated e_inf(u) and rel_l2(u) count");
    let mut sweep = Sweep::new(families.iter().map(|f| f.0.clone()).collect());
    let mut plans: Vec<Option<Plan>> = families.iter().map(|_| None).collect();
    let mut rows: Vec<Row> = Vec::new();
    let mut started = 0;
    loop {
        plan_next_runs((&p, &text), &families, &mut sweep, &mut plans);
        let work = |f: usize, _level: usize| plans[f].as_ref().map_or(f64::INFINITY, |pl| pl.estimate.nonzeros);
        let Some((f, predicted)) = sweep.next(work) else { break };
        if max_runs == Some(started) {
            for g in 0..families.len() {
                sweep.stop(g, format!("{started} runs were made ({MAX_RUNS_VARIABLE}, for tests)"));
            }
            break;
        }
        let pl = plans[f].take().expect("planned above");
        let mut row = Row {
            id: format!("r{:02}", rows.len() + 1),
            family: families[f].0.clone(),
            level: sweep.families[f].next_level,
            spacing: pl.spacing,
            estimated_nodes: pl.estimate.nodes,
            estimated_peak_memory_bytes: pl.estimate.peak_bytes,
            snippet: pl.edits.snippet(),
            ..Row::default()
        };
        if let Some(why) = pl.refused {
            sweep.stop(f, format!("its next run was refused ({why})"));
            (row.status, row.reason) = (Status::Refused, Some(why));
        } else if let Some(why) = budget.skip(predicted, elapsed()) {
            sweep.stop(f, format!("its next run is {why}"));
            (row.status, row.reason) = (Status::Skipped, Some(why));
        } else {
            let config = dir.join("configs").join(format!("{}.toml", row.id));
            output::write_atomic(&config, pl.text.as_bytes())?;
            started += 1;
            let launched = Instant::now();
            let ending = child::run(&config, &dir.join("runs").join(&row.id), || budget.ended(elapsed()))?;
            let wall = launched.elapsed().as_secs_f64();
            let singular = record(&mut row, ending, (f, pl.estimate.nonzeros, wall), &mut sweep);
            if singular && !notes.contains(&singular_note) {
                notes.push(singular_note.clone());
            }
        }
        if !quiet {
            eprintln!("{}", report::progress_line(&row, elapsed()));
        }
        rows.push(row);
    }
    let mut summary = report::Summary::new(&p, req.budget, rows, &families, &sweep, notes, start);
    summary.write(&dir)?;
    let target = staged.target().to_path_buf();
    staged.commit()?;
    if !quiet {
        summary.print(&target);
    }
    Ok(())
}
