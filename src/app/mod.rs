//! The commands; the only module that prints. Each command is one file: [`check`],
//! [`run`](mod@run), [`convergence`], [`compare`], [`tradeoff`] (and `run --target-error`, [`target`]); they share the terminal progress
//! ([`terminal`]), the point fields of `solution.vtu` ([`fields`]), the series writer
//! of time-dependent runs ([`series`]), the summary header ([`summary`]), a run's
//! terminal summary ([`report`]) with its largest values ([`extremes`]), and the
//! plain numbers of the terminal ([`number`]).

pub mod cli;
mod check;
mod compare;
mod convergence;
mod export;
mod extremes;
mod fields;
mod number;
mod preset_trial;
mod ranks;
mod report;
mod request;
mod run;
mod series;
mod summary;
mod target;
mod terminal;
mod tradeoff;

use crate::app::cli::{Cli, Command, ModelArg};
use crate::output::OutputError;
use crate::stages::RunError;
use crate::scene::problem::{Model, Problem, ProblemError};
use std::path::{Path, PathBuf};
use terminal::Terminal;

/// Any failure of a command, with its exit code.
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// Invalid scene (exit 2).
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// Numerical failure (exit 3).
    #[error(transparent)]
    Run(RunError),
    /// Writing results failed (exit 1).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Invalid command-line use (exit 2).
    #[error("{0}")]
    Usage(String),
    /// `--strict` and the run ended with warnings (exit 4); the results were written.
    #[error("--strict: the run ended with {0} warning(s) (listed above and in summary.json)")]
    Strict(usize),
}

impl AppError {
    /// A run failure caused by the scene file (a fixed time step above the stability
    /// limit, a formula that is not finite at a node) as an error of that file and
    /// field; any other failure as it is.
    pub(crate) fn of_scene(p: &Problem, e: RunError) -> Self {
        let field = match &e {
            RunError::UnstableTimeStep { .. } => "dynamics.time_step".to_string(),
            RunError::BadFormula { field, .. } => field.clone(),
            RunError::Formula { field, reason } => {
                return AppError::Problem(ProblemError { file: p.source.clone(), field: field.clone(), reason: reason.clone(), kind: crate::scene::problem::ProblemErrorKind::Invalid })
            }
            _ => return e.into(),
        };
        AppError::Problem(ProblemError { file: p.source.clone(), field, reason: e.to_string(), kind: crate::scene::problem::ProblemErrorKind::Invalid })
    }
}

impl From<RunError> for AppError {
    /// A snapshot that could not be written is an output failure, not a numerical one.
    fn from(e: RunError) -> Self {
        match e {
            RunError::Snapshot(o) => AppError::Output(o),
            e => AppError::Run(e),
        }
    }
}

impl AppError {
    /// Process exit code: 2 invalid input (a fixed time step above the stability limit
    /// included), 3 solver failure, 4 warnings under `--strict`, 1 anything else.
    pub fn exit_code(&self) -> u8 {
        match self {
            AppError::Problem(_)
            | AppError::Usage(_)
            | AppError::Run(RunError::UnstableTimeStep { .. })
            | AppError::Run(RunError::TooManySteps { .. })
            | AppError::Run(RunError::BadFormula { .. })
            | AppError::Run(RunError::Formula { .. }) => 2,
            AppError::Run(RunError::Interrupted { .. }) => 130,
            AppError::Run(_) => 3,
            AppError::Output(_) => 1,
            AppError::Strict(_) => 4,
        }
    }
}

/// Run the command of `cli`.
pub fn run(cli: &Cli) -> Result<(), AppError> {
    let term = Terminal::new(cli.quiet);
    let launched = crate::parallel::petsc::launched_ranks();
    if launched > 1 && !matches!(cli.command, Command::Run { .. }) {
        return Err(AppError::Usage(format!("mpirun started {launched} ranks: only `mlsm run` runs over MPI")));
    }
    match &cli.command {
        Command::Check { scene } => check::run(scene, cli.quiet),
        Command::Options => {
            print!("{}", crate::scene::problem::reference::markdown());
            Ok(())
        }
        Command::Run {
            scene,
            out,
            spacing,
            model,
            horizon,
            strict,
            preset,
            allow_long,
            export_system,
            target_error,
            target_norm,
            refinement,
            target_degree,
            budget,
            petsc_options,
        } => {
            let model = model.map(|m| match m {
                ModelArg::Navier => Model::Navier,
                ModelArg::Peridynamics => Model::Peridynamics,
            });
            let req = request::RunRequest {
                scene: scene.clone(),
                out: out.clone(),
                spacing: *spacing,
                model,
                horizon: *horizon,
                strict: *strict,
                preset: preset.clone(),
                allow_long: *allow_long,
                export_system: export_system.clone(),
                target: target_error.map(|tolerance| target::request(tolerance, *target_norm, *refinement, *target_degree, *budget)),
                petsc_options: petsc_options.clone(),
            };
            run::run(req, &term, cli.quiet)
        }
        Command::Compare { scene, m, deltas, levels, quadratures, reference_spacing, out } => {
            let p = Problem::from_file(scene)?;
            let dir = out.clone().unwrap_or_else(|| default_out(&p).join("compare"));
            let req = compare::CompareRequest {
                m: *m,
                deltas: deltas.clone(),
                levels: *levels,
                quadratures: quadratures.clone(),
                reference_spacing: *reference_spacing,
            };
            compare::compare(&p, req, &dir, &term, cli.quiet)
        }
        Command::Tradeoff { scene, budget, out } => {
            tradeoff::run(tradeoff::TradeoffRequest { scene: scene.clone(), budget: *budget, out: out.clone() }, cli.quiet)
        }
        Command::Convergence { scene, levels, out } => {
            let p = Problem::from_file(scene)?;
            let dir = out.clone().unwrap_or_else(|| default_out(&p));
            convergence::run(&p, *levels, &dir, &term, cli.quiet)
        }
    }
}

/// `output/<scene name>`.
fn default_out(p: &Problem) -> PathBuf {
    Path::new("output").join(&p.name)
}

/// Create `dir` (and parents) for a command's results.
fn create_dir(dir: &Path) -> Result<(), AppError> {
    std::fs::create_dir_all(dir).map_err(|e| AppError::Output(OutputError::Io { path: dir.to_path_buf(), source: e }))
}
