//! Right-preconditioned BiCGSTAB with true-residual verification.
//!
//! The Krylov iteration itself is `faer::matrix_free::bicgstab::bicgstab`
//! (H. A. van der Vorst, "Bi-CGSTAB: a fast and smoothly converging variant of
//! Bi-CG for the solution of nonsymmetric linear systems", *SIAM J. Sci. Stat.
//! Comput.* 13 (1992) 631–644), called with the identity as left and our
//! [`BuiltPreconditioner`] as right preconditioner, i.e. it solves
//! `A M⁻¹ y = b`, `x = M⁻¹ y`, so its residual is that of the unpreconditioned
//! system. This module wraps it because faer 0.24.4 on its own:
//!
//! * stops on the *recursively updated* residual, which drifts away from the
//!   true `b − A x` (it under-reports, badly at large `n`);
//! * on `NoConvergence` reports the *initial* residual and no iteration
//!   count;
//! * produces NaN with `InitialGuessStatus::Zero` (uninitialised residual), so
//!   we always pass an explicitly zeroed `x` with `MaybeNonZero`.
//!
//! The wrapper: run faer's BiCGSTAB; whenever it claims convergence, compute
//! the true residual (`accept`, supplied by the caller: `linalg::solve` passes
//! that of the equilibrated system it iterates on). If it is above the tolerance, restart from the current `x` with a
//! tightened inner tolerance (restarting also replaces the drifted recursive
//! residual by the true one, cf. van der Vorst & Ye, *SIAM J. Sci. Comput.* 22
//! (2000) 1035–1062), until the iteration budget or [`MAX_RESTARTS`] is spent.
//! A NaN/inf iterate is reported as [`Status::Breakdown`] (faer does not stop
//! on NaN, so this is only detected after its inner run ends).

use super::precond::BuiltPreconditioner;
use super::{relative_residual, SparseMatrix};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::matrix_free::bicgstab::{bicgstab, bicgstab_scratch, BicgParams};
use faer::matrix_free::{IdentityPrecond, InitialGuessStatus};
use faer::{Mat, MatRef, Par};

/// Upper bound on verification restarts (each costs a true-residual check
/// and loses the Krylov space); reached only when the tolerance is near
/// round-off level.
pub const MAX_RESTARTS: usize = 30;

/// How a BiCGSTAB run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// True relative residual of the original system `≤ tolerance`.
    Converged,
    /// Budget (iterations or restarts) exhausted above the tolerance.
    NotConverged,
    /// The iterate became NaN/inf.
    Breakdown,
}

/// Result of [`solve_bicgstab`]: always the last iterate and its verified
/// residual, whatever the status.
#[derive(Clone, Debug)]
pub struct BicgstabOutcome {
    /// Last iterate (zeros if no iteration ran).
    pub x: Vec<f64>,
    /// How the run ended.
    pub status: Status,
    /// Total BiCGSTAB iterations over all restarts.
    pub iterations: usize,
    /// `accept(x)`: the true relative residual the caller measures by.
    pub relative_residual: f64,
    /// Restarts caused by recursive-vs-true residual disagreement.
    pub restarts: usize,
}

/// Solve `a x = b` by right-preconditioned BiCGSTAB from `x₀ = 0`.
///
/// `a`, `b` are the system actually iterated on (possibly row-equilibrated);
/// `accept(x)` returns a true relative residual (of this system, or of the
/// original one), and convergence means `accept(x) ≤ tolerance`; its last call is
/// on the iterate returned (unless the iteration broke down). The inner faer
/// tolerance starts at `tolerance` and, after a false convergence claim, is
/// tightened to `½ · tolerance · (scaled residual / original residual)`
/// (floored at machine ε) so that the target is met even when `accept`
/// measures a differently scaled system.
pub fn solve_bicgstab(
    a: &SparseMatrix,
    b: &[f64],
    pc: &BuiltPreconditioner,
    tolerance: f64,
    max_iterations: usize,
    mut accept: impl FnMut(&[f64]) -> f64,
) -> BicgstabOutcome {
    let n = b.len();
    let mut x = Mat::<f64>::zeros(n, 1);
    let rhs = MatRef::from_column_major_slice(b, n, 1);
    let id = IdentityPrecond { dim: n };
    let par = Par::Seq;
    let mut mem = MemBuffer::new(bicgstab_scratch(id, pc, a.as_ref(), 1, par));
    let xs = |x: &Mat<f64>| -> Vec<f64> { x.col(0).iter().copied().collect() };

    let mut out = BicgstabOutcome {
        x: vec![0.0; n],
        status: Status::NotConverged,
        iterations: 0,
        relative_residual: accept(&vec![0.0; n]),
        restarts: 0,
    };
    if out.relative_residual <= tolerance {
        out.status = Status::Converged; // b = 0
        return out;
    }
    let mut inner_tol = tolerance;
    loop {
        let budget = max_iterations - out.iterations;
        if budget == 0 {
            return out;
        }
        let params = BicgParams {
            initial_guess: InitialGuessStatus::MaybeNonZero,
            abs_tolerance: 0.0,
            rel_tolerance: inner_tol,
            max_iters: budget,
            ..Default::default()
        };
        let result = bicgstab(x.as_mut(), id, pc, a.as_ref(), rhs, params, |_| {}, par, MemStack::new(&mut mem));
        super::vector_state::clear_upper_halves_everywhere();
        let claimed = match result {
            Ok(info) => {
                out.iterations += info.iter_count;
                true
            }
            Err(_) => {
                out.iterations = max_iterations;
                false
            }
        };
        out.x = xs(&x);
        if out.x.iter().any(|v| !v.is_finite()) {
            out.relative_residual = f64::NAN;
            out.status = Status::Breakdown;
            return out;
        }
        out.relative_residual = accept(&out.x);
        if out.relative_residual <= tolerance {
            out.status = Status::Converged;
            return out;
        }
        if !claimed || out.restarts == MAX_RESTARTS {
            return out;
        }
        out.restarts += 1;
        let inner = relative_residual(a, &out.x, b);
        inner_tol = inner_tol.min(0.5 * tolerance * inner / out.relative_residual).max(f64::EPSILON);
    }
}
