//! How `mlsm run` starts PETSc and MPI: when the scene or the command line asks for it,
//! or when `mpirun` launched several ranks; the solver each rank then uses, what over
//! several ranks is refused, and the silence of the ranks above 0.

use super::request::RunRequest;
use super::AppError;
use crate::choice::Choice;
use crate::linalg::{Krylov, Preconditioner, SolverKind, SolverParams, GMRES_RESTART};
use crate::petsc;
use crate::problem::{Model, Problem};

/// The solver of the model `p` runs.
fn active_solver(p: &mut Problem) -> &mut SolverParams {
    match (p.model, p.peridynamics.as_mut()) {
        (Model::Peridynamics, Some(pd)) => &mut pd.solver,
        _ => &mut p.navier.solver,
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
            silence_this_rank();
        }
        let (kind, note) = match active_solver(p).kind {
            SolverKind::Lu => {
                let (tolerance, max_iterations) = (1e-10, 500);
                let kind = SolverKind::Petsc { krylov: Krylov { preconditioner: Preconditioner::Amg, tolerance, max_iterations }, restart: GMRES_RESTART, direct: true };
                (kind, "solver.kind = \"lu\": MUMPS's distributed sparse LU in PETSc".to_string())
            }
            SolverKind::Auto(Krylov { preconditioner, tolerance, max_iterations }) if preconditioner.petsc_name().is_some() => {
                // LU while its factors fit (memory only: no fallback follows a failed
                // PETSc iteration, so the in-process choice by time does not apply).
                let estimate = crate::resources::of(p);
                let available = crate::output::available_memory_bytes();
                let direct = matches!(active_solver(p).kind.resolve(estimate.unknowns, estimate.nonzeros, available).0, SolverKind::Lu);
                let kind = SolverKind::Petsc { krylov: Krylov { preconditioner, tolerance, max_iterations }, restart: GMRES_RESTART, direct };
                let what = if direct { "the LU factors fit: MUMPS's distributed sparse LU" } else { "the LU factors do not fit: GMRES" };
                (kind, format!("auto: {what} ({})", kind.label()))
            }
            kind @ SolverKind::Petsc { .. } => (kind, String::new()),
            SolverKind::Bicgstab(Krylov { preconditioner, tolerance, max_iterations })
            | SolverKind::Gmres { krylov: Krylov { preconditioner, tolerance, max_iterations }, .. }
                if preconditioner.petsc_name().is_some() =>
            {
                let kind = SolverKind::Petsc { krylov: Krylov { preconditioner, tolerance, max_iterations }, restart: GMRES_RESTART, direct: false };
                (kind, format!("PETSc's KSP ({}) in place of the in-process Krylov solver", kind.label()))
            }
            other => {
                return Err(AppError::Usage(format!(
                    "{why}: solver {} has no PETSc counterpart (PETSc has no ILUT); over MPI ranks use \
                     preconditioner amg, ilu0 or jacobi, or solver.kind = \"lu\"",
                    other.label()
                )))
            }
        };
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

/// Send this process's stdout and stderr to /dev/null (the ranks above 0 of an MPI
/// run: rank 0 reports for all).
fn silence_this_rank() {
    #[cfg(unix)]
    if let Ok(null) = std::fs::OpenOptions::new().write(true).open("/dev/null") {
        use std::os::unix::io::AsRawFd;
        // SAFETY: dup2 onto the standard descriptors of this process; `null` stays
        // open until the duplicates exist.
        unsafe {
            libc::dup2(null.as_raw_fd(), 1);
            libc::dup2(null.as_raw_fd(), 2);
        }
    }
}
