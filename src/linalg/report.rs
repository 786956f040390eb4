//! What a solve reports: [`SolveReport`] on success, [`SolveError`] on failure.

#[cfg(doc)]
use super::{assemble, solve};

/// What to try when an in-process Krylov solver does not converge.
pub const IN_PROCESS_HINT: &str = "try lu, a stronger preconditioner (ilut with smaller drop / larger fill) or more iterations";

/// What a successful [`solve`] did and how well.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SolveReport {
    /// e.g. `"lu"`, `"bicgstab+ilut(drop=1e-5,fill=20)"`.
    pub method: String,
    /// Why `kind = "auto"` chose `method` (`None` for an explicit kind).
    pub choice: Option<String>,
    /// Krylov iterations (BiCGSTAB, summed over restarts); 1 for LU.
    pub iterations: usize,
    /// True `‖b − A x‖₂ / ‖b‖₂` of the system actually solved: the
    /// row-equilibrated `D A x = D b` when equilibration is on (row scaling does
    /// not change `x`, and this measure does not depend on the units of each
    /// equation), else the original one. Convergence and singularity checks use it.
    pub relative_residual: f64,
    /// The same on the original, unscaled system (for information: rows of very
    /// different scales, e.g. Navier rows `~ E/h^2` next to displacement rows `~ 1`,
    /// make it reflect the largest rows only).
    pub original_relative_residual: f64,
    /// Equilibration + factorisation / preconditioner construction, in seconds.
    pub setup_seconds: f64,
    /// Triangular solves or Krylov iterations, including the true-residual
    /// checks, in seconds.
    pub solve_seconds: f64,
    /// Whether row equilibration was applied.
    pub equilibrated: bool,
    /// Stored entries of the preconditioner (L + U + diagonal); `None` for LU.
    pub preconditioner_nonzeros: Option<usize>,
    /// Number of BiCGSTAB restarts triggered because the true residual was
    /// above the tolerance when the recursive one claimed convergence.
    pub restarts: usize,
    /// Unknowns whose value fell below the smallest normal double (2.2e-308) when
    /// scaled back to the loads' units, while above 1e-12 of the largest: they keep
    /// fewer than 15 digits.
    pub subnormal_unknowns: usize,
    /// Hager–Higham estimate of `κ₁` of the solved (equilibrated) matrix, LU only:
    /// the solution keeps about `-log10(κ₁ ε)` correct digits.
    pub condition_estimate: Option<f64>,
    /// The Krylov solvers' estimate of their own error, `max |δ_u| / max |u|` with
    /// `δ ≈ A⁻¹ r` ([`super::solver_error`]): what the stopped iteration may still be
    /// off, in the units of `e_inf(u)`. `None` for LU (see `condition_estimate`).
    pub solver_error: Option<f64>,
    /// Rows, entries, halo and stage times of each MPI rank (PETSc runs only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranks: Option<RankReport>,
    /// What PETSc's KSP ran with, after its options database (PETSc runs only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub petsc: Option<KspSettings>,
}

/// The Krylov method and preconditioner PETSc ran, with the settings in force once
/// the options database (`-ksp_type`, `-pc_type`, `-ksp_rtol`, `-ksp_max_it`,
/// `PETSC_OPTIONS`) overrode the scene's, and why it stopped (in `summary.json`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct KspSettings {
    /// `KSPGetType`, e.g. `gmres`.
    pub ksp_type: String,
    /// `PCGetType`, e.g. `gamg`.
    pub pc_type: String,
    /// The relative tolerance in force.
    pub rtol: f64,
    /// The iteration limit in force.
    pub max_it: usize,
    /// `KSPConvergedReason`'s name, e.g. `CONVERGED_RTOL`.
    pub converged_reason: String,
}

/// Why [`solve`] or [`assemble`] failed. Messages are plain language and say
/// what to try next.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// A matrix entry is NaN or infinite.
    #[error(
        "matrix entry ({row}, {col}) is not finite ({value}); \
         check the node coordinates, support sizes and material constants that produced this row"
    )]
    NotFinite {
        /// Row of the offending entry.
        row: usize,
        /// Column of the offending entry.
        col: usize,
        /// The NaN or ±inf found there.
        value: f64,
    },
    /// The matrix (or the preconditioner built from it) is singular: LU
    /// failure, zero pivot in an incomplete factorisation, all-zero row, or a
    /// non-finite / inaccurate solution.
    #[error("the system matrix is singular or numerically singular: {detail}")]
    Singular {
        /// What was detected, with numbers and what to check.
        detail: String,
    },
    /// BiCGSTAB did not reach the tolerance; `relative_residual` is the TRUE
    /// relative residual of the solved (equilibrated) system at the last iterate.
    #[error(
        "{method} did not converge in {iterations} iterations ({restarts} restarts), stopped by {limit}: \
         true relative residual {relative_residual:.1e} (tolerance {tolerance:e}){}",
        hint_suffix(.hint)
    )]
    NoConvergence {
        /// What to try next (empty: nothing, `auto` tries it itself).
        hint: &'static str,
        /// Iterations performed (the budget, unless the restart limit was hit
        /// first).
        iterations: usize,
        /// Verification restarts performed.
        restarts: usize,
        /// The limit that stopped it: the iteration budget or the restart cap.
        limit: String,
        /// True `‖b − A x‖₂/‖b‖₂` of the solved system at the last iterate.
        relative_residual: f64,
        /// e.g. `BiCGSTAB+ILU(0)`.
        method: String,
        /// The requested tolerance.
        tolerance: f64,
    },
    /// A multigrid-preconditioned solve failed, and the multigrid's V-cycle, run as a
    /// stationary iteration, amplifies an error on this system (measured after the
    /// failure, [`super::amg::Amg::cycle_growth`]): the cause to report with it.
    #[error(
        "{failure}; the multigrid is unstable on this system: one V-cycle, as a stationary iteration, \
         amplifies an error {growth:.1e}-fold (it should shrink it; block Gauss-Seidel diverges next to \
         boundary nodes that carry only traction rows, such as the ghost-free boundary around a re-entrant \
         corner: docs/limits.md)"
    )]
    UnstableMultigrid {
        /// The solve's own failure.
        failure: Box<SolveError>,
        /// `‖e₃‖ / ‖e₂‖` over three cycles on `A e = 0` (> 1).
        growth: f64,
    },
    /// `auto`'s iterative method failed and so did its fallback.
    #[error("{first}; retried with {retry_method}, which failed too: {retry}")]
    FallbackFailed {
        /// Why the first method failed.
        first: Box<SolveError>,
        /// The fallback, e.g. `BiCGSTAB+ILU(0)`.
        retry_method: String,
        /// Why the fallback failed.
        retry: Box<SolveError>,
    },
    /// PETSc or MPI failed (not a convergence failure: those are
    /// [`SolveError::NoConvergence`] with PETSc's converged reason).
    #[error("PETSc: {detail}")]
    Petsc {
        /// What failed.
        detail: String,
    },
    /// The solution exceeds the double range (the loads are too large in these units).
    #[error("overflow: {detail}")]
    Overflow {
        /// Which unknown overflowed and what to do.
        detail: String,
    },
    /// Inconsistent sizes (non-square matrix, wrong right-hand-side length,
    /// triplet index out of range), other invalid input (non-finite
    /// right-hand side, non-positive tolerance) or a problem too large for the
    /// solver (index overflow / out of memory in faer).
    #[error("dimension error: {detail}")]
    Dimension {
        /// What was inconsistent or invalid.
        detail: String,
    },
}

/// `"; hint"`, or nothing for an empty hint.
fn hint_suffix(hint: &str) -> String {
    if hint.is_empty() {
        String::new()
    } else {
        format!("; {hint}")
    }
}

impl SolveError {
    /// This failure without its advice on what to try next: `auto`, which retries
    /// with another method itself, reports the first failure so (its advice, "try
    /// lu", would name the retry it already made).
    pub fn without_hint(self) -> SolveError {
        match self {
            SolveError::NoConvergence { iterations, restarts, limit, relative_residual, method, tolerance, .. } => {
                SolveError::NoConvergence { hint: "", iterations, restarts, limit, relative_residual, method, tolerance }
            }
            SolveError::UnstableMultigrid { failure, growth } => {
                SolveError::UnstableMultigrid { failure: Box::new(failure.without_hint()), growth }
            }
            other => other,
        }
    }

    /// This failure with the multigrid's measured instability as its cause
    /// ([`SolveError::UnstableMultigrid`]) when `multigrid`'s V-cycle amplifies an error
    /// ([`super::amg::Amg::cycle_growth`] above 1); as it stands when the cycle
    /// converges by itself (then the Krylov method's limits are the story) or there is
    /// no multigrid. Measured here, after the failure: a solve that succeeds pays nothing.
    pub(super) fn with_cycle_growth(self, multigrid: Option<&super::amg::Amg>) -> SolveError {
        match multigrid.and_then(super::amg::Amg::cycle_growth) {
            Some(growth) if growth > 1.0 => SolveError::UnstableMultigrid { failure: Box::new(self), growth },
            _ => self,
        }
    }
}

/// What each rank holds and sends, gathered on every rank (in `summary.json`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct RankReport {
    /// Number of ranks.
    pub ranks: usize,
    /// Rows owned by each rank.
    pub rows: Vec<usize>,
    /// Matrix entries of each rank's rows.
    pub nonzeros: Vec<usize>,
    /// Distinct unknowns of other ranks that each rank's rows read: the doubles it
    /// receives per matrix-vector product.
    pub halo_unknowns: Vec<usize>,
    /// Seconds per stage on each rank (filled in by the model at the end of the run).
    pub stage_seconds: Vec<Vec<(String, f64)>>,
}
