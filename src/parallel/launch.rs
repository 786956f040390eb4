//! What each MPI rank runs when `mpirun` starts several: the solver that takes the
//! place of the scene's (PETSc's counterpart of it), and the silence of the ranks
//! above 0.

use crate::linalg::{Krylov, Preconditioner, SolverKind, GMRES_RESTART};

/// The PETSc solver every rank uses in place of `kind`, with a note of the change
/// (empty when `kind` already is PETSc's): LU becomes MUMPS's distributed LU; `auto`
/// becomes MUMPS while its LU factors fit in memory (`estimate()`: unknowns and
/// nonzeros of the run; memory only, since no fallback follows a failed PETSc
/// iteration), else GMRES; BiCGSTAB and GMRES become PETSc's KSP with the same
/// preconditioner. A preconditioner PETSc lacks (ILUT) is refused, with what to use.
pub fn solver_on_ranks(kind: SolverKind, estimate: impl FnOnce() -> (f64, f64)) -> Result<(SolverKind, String), String> {
    let chosen = match kind {
        SolverKind::Lu => {
            let (tolerance, max_iterations) = (1e-10, 500);
            let kind = SolverKind::Petsc { krylov: Krylov { preconditioner: Preconditioner::Amg, tolerance, max_iterations }, restart: GMRES_RESTART, direct: true };
            (kind, "solver.kind = \"lu\": MUMPS's distributed sparse LU in PETSc".to_string())
        }
        SolverKind::Auto(Krylov { preconditioner, tolerance, max_iterations }) if preconditioner.petsc_name().is_some() => {
            // LU while its factors fit (memory only: no fallback follows a failed
            // PETSc iteration, so the in-process choice by time does not apply).
            let (unknowns, nonzeros) = estimate();
            let available = crate::output::available_memory_bytes();
            let direct = matches!(kind.resolve(unknowns, nonzeros, available).0, SolverKind::Lu);
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
            return Err(format!(
                "solver {} has no PETSc counterpart (PETSc has no ILUT); over MPI ranks use \
                 preconditioner amg, ilu0 or jacobi, or solver.kind = \"lu\"",
                other.label()
            ))
        }
    };
    Ok(chosen)
}

/// Send this process's stdout and stderr to /dev/null (the ranks above 0 of an MPI
/// run: rank 0 reports for all).
pub fn silence_this_rank() {
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
