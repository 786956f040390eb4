//! Sparse linear solvers for the collocation systems `A x = b`.
//!
//! Strong-form (collocation) discretisations of elasticity give square,
//! nonsymmetric, indefinite sparse matrices whose rows have wildly different
//! scales: an interior row carries second derivatives (`~1/h²`), a traction
//! row first derivatives (`~1/h`) and a Dirichlet row is an identity row
//! (`~1`). This module offers
//!
//! * [`row_assembly`]: compressed rows ([`Csr`]) assembled fragment by fragment in
//!   row order, the form the solvers take; [`Triplets`] + [`assemble`]: COO
//!   accumulation and CSC assembly (duplicates summed),
//! * [`solve`]: optional row equilibration ([`scaling`]) followed by either the
//!   sparse direct LU of `faer` ([`lu`]) or right-preconditioned BiCGSTAB
//!   ([`bicgstab`]) with Jacobi, ILU(0) or ILUT ([`precond`]),
//! * [`border`]: constraints with multipliers, `[A G; C 0]`, and the block
//!   preconditioner that lets the Krylov solvers take them.
//!
//! Whatever the path, the returned [`SolveReport::relative_residual`] is the
//! *true* residual `‖b − A x‖₂ / ‖b‖₂` recomputed from the solved system (the
//! row-equilibrated `D A x = D b` when equilibration is on: unit-free, and what
//! bounds the error through the condition of `D A`) — never a solver's internal
//! estimate. A result that
//! is not finite, or (for LU) whose residual exceeds [`LU_RESIDUAL_LIMIT`], is
//! an error, never silently returned.

pub mod addition;
pub mod aggregation;
pub mod amg;
pub mod bicgstab;
pub mod blocks;
pub mod border;
pub mod csr;
pub mod gmres;
pub mod ilut;
pub mod inverse;
pub mod layout;
mod level_operator;
pub mod lu;
mod methods;
pub mod near_null;
pub mod orthogonal;
pub mod params;
pub mod precond;
pub mod report;
pub mod retained;
pub mod row_assembly;
pub mod rowmat;
pub mod saddle;
pub mod scaling;
pub mod smoother;
pub mod solver_error;
pub mod spgemm;
pub mod triplets;
pub mod vector_state;
pub mod watch;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod auto_tests;

use std::borrow::Cow;
use std::time::Instant;

use gmres::GmresSettings;
use methods::{
    solve_gmres_multigrid, solve_gmres_saddle_point, solve_krylov_bicgstab, solve_krylov_gmres, solve_lu, solved_rows, working, Leftover,
    Rhs, Start,
};

pub use addition::{solve_nodal_with_addition, takes_addition, Addition};
pub use csr::Csr;
pub use layout::NodeLayout;
pub use params::{
    lu_factor_bytes, Krylov, Preconditioner, PreconditionerKind, SolverChoice, SolverKind, SolverMethod, SolverParams, AUTO_KRYLOV_BYTES,
    AUTO_KRYLOV_PACE, AUTO_LU_SHARE, GMRES_RESTART, SADDLE_POINT_ITERATIONS, SADDLE_POINT_RESTART,
};
pub use report::{SolveError, SolveReport};
pub use retained::Retained;
pub use rowmat::{mul_add, row_matrix, RowMatrix};
pub use triplets::{assemble, Triplets};

/// Square sparse matrix in compressed sparse column (CSC) form, `usize`
/// indices, `f64` values, as produced by [`assemble`].
pub type SparseMatrix = faer::sparse::SparseColMat<usize, f64>;

/// Largest true relative residual `‖b − A x‖₂/‖b‖₂` accepted from the direct
/// LU solve. A backward-stable LU gives `~ ε·κ(A)`; anything above `1e-6`
/// means the matrix is numerically singular (or nearly so) and the "solution"
/// is garbage, so [`solve`] reports [`SolveError::Singular`] instead.
pub const LU_RESIDUAL_LIMIT: f64 = 1e-6;

/// `y ← y − A x`, `A` in columns (each column scattered into the rows it touches).
fn subtract_column_product(a: &SparseMatrix, x: &[f64], y: &mut [f64]) {
    for (j, &xj) in x.iter().enumerate() {
        if xj == 0.0 {
            continue;
        }
        let rows = a.symbolic().row_idx_of_col_raw(j);
        let vals = a.val_of_col(j);
        for (&i, &v) in rows.iter().zip(vals) {
            y[i] -= v * xj;
        }
    }
}

/// The residual `b − A x`, `A` in columns.
fn residual(a: &SparseMatrix, x: &[f64], b: &[f64]) -> Vec<f64> {
    let mut r = b.to_vec();
    subtract_column_product(a, x, &mut r);
    r
}

/// The residual `b − A x`, `A` in rows (in parallel).
fn row_residual(a: &Csr, x: &[f64], b: &[f64]) -> Vec<f64> {
    let mut r = vec![0.0; b.len()];
    csr::product(a, x, &mut r);
    r.iter_mut().zip(b).for_each(|(r, b)| *r = b - *r);
    r
}

/// `floor(log2 m)` of the largest magnitude `m` of a right-hand side (0 for `m = 0`):
/// the loads are solved as `b / 2^e`, so that any representable answer is computed.
fn binary_exponent(m: f64) -> i32 {
    if m > 0.0 {
        m.log2().floor() as i32
    } else {
        0
    }
}

/// `max_i |b_i| / max_j |a_ij|` when the rows are equilibrated (the largest entry of
/// the right-hand side the solver sees, `D b`), else `max_i |b_i|`. Scaling by this
/// and not by `max |b|` keeps the solved right-hand side near 1 whatever the moduli:
/// with `E = 1e200` the equilibrated loads are ~1e-194 and their squared norm
/// underflows to zero (the solver would return `x = 0`), with `E = 1e-200` it
/// overflows. Rows with no stored entry are skipped (the solver refuses them).
fn solved_rhs_max(a: &Csr, b: &[f64], equilibrate: bool) -> f64 {
    if !equilibrate || a.nrows() != b.len() {
        return b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    }
    (0..a.nrows())
        .filter(|&i| b[i] != 0.0)
        .map(|i| {
            let row_max = a.row(i).values().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if row_max > 0.0 && row_max.is_finite() {
                b[i].abs() / row_max
            } else {
                b[i].abs()
            }
        })
        .fold(0.0f64, f64::max)
        .min(f64::MAX)
}

/// `x 2^e`, in two factors so that neither overflows for `|e|` up to 2 x 1023.
fn times_power_of_two(x: f64, e: i32) -> f64 {
    x * 2f64.powi(e / 2) * 2f64.powi(e - e / 2)
}

/// `‖r‖ / ‖b‖`, or `‖r‖` when `b = 0`.
fn relative(r: f64, b: f64) -> f64 {
    if b > 0.0 {
        r / b
    } else {
        r
    }
}

/// True relative residual `‖b − A x‖₂ / ‖b‖₂` (plain 2-norms, computed by a
/// CSC sweep). If `b = 0` the absolute residual `‖A x‖₂` is returned. NaN in
/// `x` propagates to a NaN result.
pub fn relative_residual(a: &SparseMatrix, x: &[f64], b: &[f64]) -> f64 {
    relative(norm2(&residual(a, x, b)), norm2(b))
}

/// Euclidean norm.
pub(crate) fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Euclidean norm of entries of any magnitude: `m sqrt(sum (v_i / m)^2)` with
/// `m = max |v_i|`, so that entries of 1e-200 or 1e200 (rows of a matrix in the units of
/// extreme moduli) neither underflow nor overflow when squared. Two passes: for
/// setup, not for the inner loops of a solver.
pub fn scaled_norm<'a>(v: impl IntoIterator<Item = &'a f64> + Clone) -> f64 {
    let m = v.clone().into_iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    m * v.into_iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt()
}

/// Solve `A x = b` in the scale of the loads: `b` is multiplied by the power of two
/// `s = 2^-e` that brings the largest entry of the right-hand side the solver sees
/// (`D b` of the equilibrated rows, [`solved_rhs_max`]) into `[1, 2)` (exact in binary
/// floating point), `A x' = s b` is solved by [`solve_with_memory`], and `x = x' / s`.
/// Loads from 1e-300 to 1e300 and moduli from 1e-250 to 1e250 then give the same digits
/// (no overflow or underflow in the residual norms), and a solution beyond the double
/// range is reported as [`SolveError::Overflow`].
pub fn solve(a: &SparseMatrix, b: &[f64], params: &SolverParams) -> Result<(Vec<f64>, SolveReport), SolveError> {
    solve_nodal(Cow::Owned(csr::to_csr(a)), b, params, None, None, &())
}

/// A second operator on the same unknowns and rows for the multigrid preconditioner
/// to be built on instead of the system (a low-order discretisation of the same
/// equations on the same nodes, whose small stencils the block Gauss–Seidel smoother
/// and the aggregation handle where the system's large ones defeat them). It is made
/// only when the multigrid is built; no builder builds the multigrid on the system,
/// and so does a builder's failure, whose reason then goes into the report's `choice`.
pub type Auxiliary<'a> = Option<Box<dyn FnOnce() -> Result<Csr, String> + 'a>>;

/// [`solve`] of a system whose unknowns belong to nodes (`layout`): the multigrid
/// preconditioner takes its near-null space (rigid-body modes) from their positions.
/// A matrix handed over (`Cow::Owned`) is freed as soon as the solver holds the form it
/// works on (the equilibrated copy, or GMRES+AMG's equilibrated rows): one copy of the
/// matrix fewer at the solve's peak (docs/notebook/round2-target-error.md, "One copy
/// of the matrix in the solve").
pub fn solve_nodal(
    a: Cow<'_, Csr>,
    b: &[f64],
    params: &SolverParams,
    layout: Option<NodeLayout>,
    auxiliary: Auxiliary<'_>,
    watch: &dyn watch::Watch,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    solve_nodal_kept(a, b, params, layout, auxiliary, (watch, None))
}

/// [`solve_nodal`], the solver kept for further right-hand sides on the same matrix
/// ([`Retained`]: the solved rows and their factors or preconditioner; a run's peak
/// memory stays where the solve's was). `None` when the solve did not leave one (an
/// empty system).
pub fn solve_nodal_retained(
    a: Cow<'_, Csr>,
    b: &[f64],
    params: &SolverParams,
    layout: Option<NodeLayout>,
    auxiliary: Auxiliary<'_>,
    watch: &dyn watch::Watch,
) -> Result<(Vec<f64>, SolveReport, Option<Retained>), SolveError> {
    let slot = std::cell::RefCell::new(None);
    let (x, report) = solve_nodal_kept(a, b, params, layout, auxiliary, (watch, Some(&slot)))?;
    Ok((x, report, slot.into_inner()))
}

/// [`solve_nodal`] leaving its solver in `keep` when given.
fn solve_nodal_kept(
    a: Cow<'_, Csr>,
    b: &[f64],
    params: &SolverParams,
    layout: Option<NodeLayout>,
    auxiliary: Auxiliary<'_>,
    (watch, keep): (&dyn watch::Watch, Option<&std::cell::RefCell<Option<Retained>>>),
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    in_load_scale(solved_rhs_max(&a, b, params.equilibrate), b, |scaled| {
        solve_with_memory(a, scaled, params, layout, auxiliary, (crate::output::available_memory_bytes(), watch, keep))
    })
}

/// `solve(s b) / s` with the power of two `s = 2^-e` that brings `rhs_max`, the largest
/// entry of the right-hand side the solver sees (`D b` of the equilibrated rows,
/// [`solved_rhs_max`]), into `[1, 2)` ([`solve`]); a solution beyond the double range
/// is [`SolveError::Overflow`], and the report counts the unknowns that lost digits
/// to subnormal numbers.
fn in_load_scale(
    rhs_max: f64,
    b: &[f64],
    solve: impl FnOnce(&[f64]) -> Result<(Vec<f64>, SolveReport), SolveError>,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    if let Some((i, v)) = b.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SolveError::Dimension { detail: format!("right-hand side entry {i} is not finite ({v})") });
    }
    let exponent = binary_exponent(rhs_max);
    let scaled: Vec<f64> = b.iter().map(|v| times_power_of_two(*v, -exponent)).collect();
    let (x, report) = solve(&scaled)?;
    if let Some(i) = x.iter().position(|v| !times_power_of_two(*v, exponent).is_finite()) {
        return Err(SolveError::Overflow {
            detail: format!(
                "unknown {i} is {:.3e} x 2^{exponent}, beyond the largest double (1.8e308): the loads are too \
                 large for the moduli in these units; rescale them",
                x[i].abs()
            ),
        });
    }
    let x: Vec<f64> = x.into_iter().map(|v| times_power_of_two(v, exponent)).collect();
    // Entries below 1e-12 of the largest are round-off of a zero (a symmetry line);
    // only significant entries that lost digits count.
    let largest = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let subnormal_unknowns = x.iter().filter(|v| v.is_subnormal() && v.abs() > 1e-12 * largest).count();
    Ok((x, SolveReport { subnormal_unknowns, ..report }))
}

/// Solve `A x = b` (the loads already scaled, [`solve`]) with `available` bytes of
/// memory for `auto`'s choice.
///
/// 1. Checks that `A` is square, `b` has length `n`, every stored entry is
///    finite and no row is entirely zero.
/// 2. With `params.equilibrate`, solves `D A x = D b` with
///    `D = diag(±1 / max_j |a_ij|)` ([`scaling::equilibrate_rows`]); `x` is
///    unchanged by row scaling.
/// 3. Runs [`lu::SparseLu`], [`bicgstab::solve_bicgstab`] or [`gmres::solve_gmres`].
/// 4. Recomputes the true residual of the solved (equilibrated, if asked)
///    system and reports it, with the residual of the original system beside it
///    ([`Rhs::residuals`]). For LU a non-finite solution or a
///    residual above [`LU_RESIDUAL_LIMIT`] or a condition estimate above
///    [`lu::CONDITION_LIMIT`] is [`SolveError::Singular`]; for the Krylov
///    methods a residual above the tolerance is [`SolveError::NoConvergence`]
///    and a NaN/inf iterate is [`SolveError::Singular`].
///
/// When `auto` goes iterative and its Krylov solver (or the multigrid's setup) stops
/// or breaks down, it tries [`SolverKind::auto_fallback`] on the same equilibrated
/// operator before giving up (LU where the factors fit, else BiCGSTAB with ILU(0)), and
/// says so in `choice`.
///
/// Only LU can *prove* trouble: a Krylov method on a singular but consistent system
/// (e.g. pure traction with self-equilibrated loads) may converge to one of
/// the infinitely many solutions, rigid-body component included.
///
/// An empty system (`n = 0`) returns an empty solution.
pub(crate) fn solve_with_memory(
    a: Cow<'_, Csr>,
    b: &[f64],
    params: &SolverParams,
    layout: Option<NodeLayout>,
    auxiliary: Auxiliary<'_>,
    (available, watch, keep): (Option<f64>, &dyn watch::Watch, Option<&std::cell::RefCell<Option<Retained>>>),
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let saddle_point = layout.filter(|l| l.has_pressure());
    let (unknowns, nonzeros) = (a.nrows() as f64, a.nnz() as f64);
    let SolverChoice { primary: kind, fallback, reason: choice } =
        params.kind.choose(unknowns, nonzeros, saddle_point.is_some(), available);
    if let SolverKind::Petsc { .. } = kind {
        return Err(SolveError::Petsc { detail: "PETSc solves the rows each MPI rank owns (`parallel::share::Share::solve`)".into() });
    }
    let n = a.nrows();
    if a.ncols() != n {
        return Err(SolveError::Dimension { detail: format!("matrix is {}x{}, expected square", n, a.ncols()) });
    }
    if b.len() != n {
        return Err(SolveError::Dimension { detail: format!("right-hand side has length {}, matrix has {n} rows", b.len()) });
    }
    if let Some((i, v)) = b.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SolveError::Dimension { detail: format!("right-hand side entry {i} is not finite ({v})") });
    }
    if let SolverKind::Bicgstab(Krylov { tolerance, .. }) | SolverKind::Gmres { krylov: Krylov { tolerance, .. }, .. } = kind {
        if !(tolerance > 0.0 && tolerance.is_finite()) {
            return Err(SolveError::Dimension { detail: format!("the Krylov tolerance must be positive and finite, got {tolerance}") });
        }
    }

    let start = Start { method: kind.label(), choice, setup: Instant::now(), equilibrated: params.equilibrate, watch, keep };
    if n == 0 {
        let report =
            SolveReport { iterations: 0, relative_residual: 0.0, original_relative_residual: 0.0, ..start.report(None, (0.0, 0.0)) };
        return Ok((Vec::new(), report));
    }

    // Validates finiteness / zero rows in every case.
    let rhs = Rhs::of(&a, b, params.equilibrate)?;
    match kind {
        SolverKind::Auto(..) | SolverKind::Petsc { .. } => unreachable!("resolved and returned above"),
        SolverKind::Lu => solve_lu(working(a, &rhs), &rhs, &start),
        SolverKind::Bicgstab(Krylov { preconditioner, tolerance, max_iterations }) => {
            solve_krylov_bicgstab(working(a, &rhs), &rhs, &start, (preconditioner, tolerance, max_iterations), layout)
        }
        SolverKind::Gmres { krylov: Krylov { preconditioner, tolerance, max_iterations }, restart } => {
            // GMRES chosen for time gives way to LU as soon as a cycle shows it is slow.
            let stall = if fallback == Some(SolverKind::Lu) { AUTO_KRYLOV_PACE } else { gmres::STAGNATION };
            let settings = GmresSettings { preconditioner, tolerance, max_iterations, restart, stall };
            let attempt = if preconditioner == Preconditioner::Amg {
                // The auxiliary operator in the system's row scale, so that its
                // multigrid approximates the inverse of the solved (equilibrated) rows.
                let (auxiliary, note) = match auxiliary.map(|build| build()) {
                    Some(Ok(aux)) => (Some(solved_rows(Cow::Owned(aux), &rhs)), None),
                    Some(Err(why)) => {
                        (None, Some(format!("the low-order operator for the multigrid could not be made ({why}): built on the system")))
                    }
                    None => (None, None),
                };
                let choice = match (&start.choice, note) {
                    (Some(c), Some(n)) => Some(format!("{c}; {n}")),
                    (c, n) => n.or_else(|| c.clone()),
                };
                let start = Start { method: start.method.clone(), choice, ..start };
                if let Some(layout) = saddle_point {
                    return solve_gmres_saddle_point(solved_rows(a, &rhs), auxiliary, &rhs, &start, settings, layout);
                }
                solve_gmres_multigrid(solved_rows(a, &rhs), auxiliary, &rhs, &start, settings, layout)
            } else {
                let a_work = working(a, &rhs);
                match solve_krylov_gmres(&a_work, &rhs, &start, settings, layout) {
                    Ok(done) => Ok(done),
                    Err(e) => Err(Box::new((e, Leftover::Columns(a_work)))),
                }
            };
            match (attempt.map_err(|failed| *failed), fallback) {
                (Ok(done), _) => Ok(done),
                (
                    Err((
                        e @ (SolveError::NoConvergence { .. } | SolveError::Singular { .. } | SolveError::UnstableMultigrid { .. }),
                        leftover,
                    )),
                    Some(retry_kind),
                ) => {
                    let retry_method = match retry_kind {
                        SolverKind::Bicgstab(Krylov { preconditioner, .. }) => format!("BiCGSTAB+{}", preconditioner.display_name()),
                        other => other.label(),
                    };
                    let e = e.without_hint();
                    let why = format!("{}; {e}; retried with {retry_method}", start.choice.clone().unwrap_or_default());
                    let columns = leftover.into_columns();
                    let retry = Start { method: retry_kind.label(), choice: Some(why), setup: Instant::now(), ..start };
                    // A failed fallback reports both failures: the first is the one
                    // that says what is wrong with the system.
                    let retried = match retry_kind {
                        SolverKind::Bicgstab(Krylov { preconditioner, tolerance, max_iterations }) => {
                            solve_krylov_bicgstab(columns, &rhs, &retry, (preconditioner, tolerance, max_iterations), layout)
                        }
                        _ => solve_lu(columns, &rhs, &retry),
                    };
                    retried.map_err(|retry| SolveError::FallbackFailed { first: Box::new(e), retry_method, retry: Box::new(retry) })
                }
                (Err((e, _)), _) => Err(e),
            }
        }
    }
}
