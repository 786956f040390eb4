//! How `mlsm run` starts PETSc and MPI: when the scene or the command line asks for it,
//! or when `mpirun` launched several ranks; the solver each rank then uses, what over
//! several ranks is refused, and the silence of the ranks above 0.

use super::request::RunRequest;
use super::AppError;
use crate::scene::choice::Choice;
use crate::linalg::{SolverKind, SolverParams};
use crate::parallel::{launch, petsc};
use crate::scene::problem::{ModelParams, Problem};

/// The solver of the model `p` runs.
fn active_solver(p: &mut Problem) -> &mut SolverParams {
    match &mut p.model {
        ModelParams::Peridynamics(pd) => &mut pd.solver,
        ModelParams::Navier { .. } => &mut p.navier.solver,
    }
}

/// Start PETSc when the run needs it: `solver.kind = "petsc"`, options after `--`, or
/// more than one MPI rank. Over several ranks `auto` becomes PETSc with its settings
/// (a note says so), and what cannot be distributed is refused. Ranks other than 0
/// print nothing (their stdout and stderr go to /dev/null).
pub(super) fn start_petsc(p: &mut Problem, req: &RunRequest) -> Result<(), AppError> {
    let launched = petsc::launched_ranks();
    let asks = matches!(active_solver(p).kind, SolverKind::Petsc { .. });
    if launched == 1 && !asks && req.petsc_options.is_empty() {
        return Ok(());
    }
    let why = if launched > 1 {
        format!("mpirun started {launched} ranks")
    } else if asks {
        "solver.kind = \"petsc\"".to_string()
    } else {
        "PETSc options were given after `--`".to_string()
    };
    let world = petsc::start(&req.petsc_options).map_err(|e| AppError::Usage(format!("{why}: {e}")))?;
    if world.size > 1 {
        if p.case.dynamics.is_some() {
            return Err(AppError::Usage(format!("{why}: a dynamic run is explicit and runs in one process; run it without mpirun")));
        }
        if req.target.is_some() || req.export_system.is_some() {
            return Err(AppError::Usage(format!("{why}: --target-error and --export-system run in one process; run them without mpirun")));
        }
        if world.rank > 0 {
            launch::silence_this_rank();
        }
        let kind = active_solver(p).kind;
        let (kind, note) = launch::solver_on_ranks(kind, || {
            let estimate = crate::models::resources::of(p);
            (estimate.unknowns, estimate.nonzeros)
        })
        .map_err(|e| AppError::Usage(format!("{why}: {e}")))?;
        active_solver(p).kind = kind;
        if !note.is_empty() {
            p.notes.push(format!("{} MPI ranks; {note}", world.size));
        }
    } else if req.export_system.is_some() {
        return Err(AppError::Usage(format!("{why}: --export-system writes the system of an in-process solve; PETSc's is not kept")));
    } else if !matches!(active_solver(p).kind, SolverKind::Petsc { .. }) {
        return Err(AppError::Usage(format!(
            "{why}, but the solver is \"{}\": set solver.kind = \"petsc\"",
            active_solver(p).kind.method().name()
        )));
    }
    Ok(())
}
