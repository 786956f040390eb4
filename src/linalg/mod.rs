//! Sparse linear solvers for the collocation systems `A x = b`.
//!
//! Strong-form (collocation) discretisations of elasticity give square,
//! nonsymmetric, indefinite sparse matrices whose rows have wildly different
//! scales: an interior row carries second derivatives (`~1/h²`), a traction
//! row first derivatives (`~1/h`) and a Dirichlet row is an identity row
//! (`~1`). This module offers
//!
//! * [`Triplets`] + [`assemble`]: COO accumulation and CSC assembly
//!   (duplicates summed),
//! * [`solve`]: optional row equilibration ([`scaling`]) followed by either the
//!   sparse direct LU of `faer` ([`lu`]) or right-preconditioned BiCGSTAB
//!   ([`bicgstab`]) with Jacobi, ILU(0) or ILUT ([`precond`]).
//!
//! Whatever the path, the returned [`SolveReport::relative_residual`] is the
//! *true* residual `‖b − A x‖₂ / ‖b‖₂` recomputed from the **original**
//! (unscaled) `A` and `b` — never a solver's internal estimate. A result that
//! is not finite, or (for LU) whose residual exceeds [`LU_RESIDUAL_LIMIT`], is
//! an error, never silently returned.

pub mod aggregation;
pub mod amg;
pub mod bicgstab;
pub mod csr;
pub mod distributed;
pub mod gmres;
pub mod ilut;
pub mod lu;
pub mod params;
pub mod partition;
pub mod precond;
pub mod report;
pub mod rowmat;
pub mod scaling;
pub mod smoother;
pub mod spgemm;
pub mod triplets;

#[cfg(test)]
mod tests;

use std::borrow::Cow;
use std::time::Instant;

pub use amg::NodeLayout;
pub use csr::Csr;
pub use params::{
    lu_factor_bytes, Preconditioner, PreconditionerKind, SolverKind, SolverMethod, SolverParams, AUTO_LU_SHARE, GMRES_RESTART,
};
pub use report::{SolveError, SolveReport};
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

/// The residual `b − A x`, `A` in columns.
fn residual(a: &SparseMatrix, x: &[f64], b: &[f64]) -> Vec<f64> {
    let mut r = b.to_vec();
    for (j, &xj) in x.iter().enumerate() {
        if xj == 0.0 {
            continue;
        }
        let rows = a.symbolic().row_idx_of_col_raw(j);
        let vals = a.val_of_col(j);
        for (&i, &v) in rows.iter().zip(vals) {
            r[i] -= v * xj;
        }
    }
    r
}

/// The residual `b − A x`, `A` in rows (in parallel).
fn row_residual(a: &Csr, x: &[f64], b: &[f64]) -> Vec<f64> {
    let mut r = vec![0.0; b.len()];
    amg::product(a, x, &mut r);
    r.iter_mut().zip(b).for_each(|(r, b)| *r = b - *r);
    r
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

/// Solve `A x = b` in the scale of the loads: `b` is multiplied by the power of two
/// `s = 2^-e` that brings `max |b_i|` into `[1, 2)` (exact in binary floating point),
/// `A x' = s b` is solved by [`solve_with_memory`], and `x = x' / s`. Loads from 1e-300 to
/// 1e300 then give the same digits (no overflow or underflow in the residual norms),
/// and a solution beyond the double range is reported as [`SolveError::Overflow`].
pub fn solve(a: &SparseMatrix, b: &[f64], params: &SolverParams) -> Result<(Vec<f64>, SolveReport), SolveError> {
    solve_nodal(Cow::Borrowed(a), b, params, None)
}

/// [`solve`] of a system whose unknowns belong to nodes (`layout`): the multigrid
/// preconditioner takes its near-null space (rigid-body modes) from their positions.
/// A matrix handed over (`Cow::Owned`) is freed as soon as the solver holds the form it
/// works on (the equilibrated copy, or GMRES+AMG's equilibrated rows): one copy of the
/// matrix fewer at the solve's peak (0.84 GB at 1e6 nodes, BENCHMARKS.md).
pub fn solve_nodal(
    a: Cow<'_, SparseMatrix>,
    b: &[f64],
    params: &SolverParams,
    layout: Option<NodeLayout>,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    if let Some((i, v)) = b.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SolveError::Dimension { detail: format!("right-hand side entry {i} is not finite ({v})") });
    }
    let b_max = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let exponent = if b_max > 0.0 { b_max.log2().floor() as i32 } else { 0 };
    let scale = |x: f64, e: i32| x * 2f64.powi(e / 2) * 2f64.powi(e - e / 2);
    let scaled: Vec<f64> = b.iter().map(|v| scale(*v, -exponent)).collect();
    let (x, report) = solve_with_memory(a, &scaled, params, layout, crate::output::available_memory_bytes())?;
    if let Some(i) = x.iter().position(|v| !scale(*v, exponent).is_finite()) {
        return Err(SolveError::Overflow {
            detail: format!(
                "unknown {i} is {:.3e} x 2^{exponent}, beyond the largest double (1.8e308): the loads are too \
                 large for the moduli in these units; rescale them",
                x[i].abs()
            ),
        });
    }
    let x: Vec<f64> = x.into_iter().map(|v| scale(v, exponent)).collect();
    // Entries below 1e-12 of the largest are round-off of a zero (a symmetry line);
    // only significant entries that lost digits count.
    let largest = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let subnormal_unknowns = x.iter().filter(|v| v.is_subnormal() && v.abs() > 1e-12 * largest).count();
    Ok((x, SolveReport { subnormal_unknowns, ..report }))
}

/// The right-hand side as solved, and how the residual of the original system
/// `A x = b` is measured from that of the solved one `D A x = D b` (`D` the row
/// scales of the equilibration, the identity without it): `b − A x = D⁻¹ (D b − D A x)`,
/// so the original matrix need not be kept.
struct Rhs<'a> {
    /// `b`.
    original: &'a [f64],
    /// `D b`.
    solved: Cow<'a, [f64]>,
    /// `D`, when the rows are equilibrated.
    scales: Option<Vec<f64>>,
}

impl Rhs<'_> {
    /// Relative residuals `(‖D b − D A x‖ / ‖D b‖, ‖b − A x‖ / ‖b‖)` from the residual
    /// `r = D b − D A x` of the solved system.
    fn residuals(&self, r: &[f64]) -> (f64, f64) {
        let unscaled = match &self.scales {
            Some(d) => r.iter().zip(d).map(|(r, d)| (r / d) * (r / d)).sum::<f64>().sqrt(),
            None => norm2(r),
        };
        (relative(norm2(r), norm2(&self.solved)), relative(unscaled, norm2(self.original)))
    }
}

/// What every report of one solve shares: the method's label, `auto`'s reason, and
/// when the setup started.
struct Start {
    method: String,
    choice: Option<String>,
    setup: Instant,
    equilibrated: bool,
}

impl Start {
    /// The report of a finished solve, before its iteration counts are filled in;
    /// the method's name carries what the preconditioner says of itself (AMG: its
    /// levels).
    fn report(&self, pc: Option<&precond::BuiltPreconditioner>, (setup_seconds, solve_seconds): (f64, f64)) -> SolveReport {
        SolveReport {
            method: format!("{}{}", self.method, pc.map(|p| p.describe()).unwrap_or_default()),
            choice: self.choice.clone(),
            iterations: 0,
            relative_residual: f64::NAN,
            original_relative_residual: f64::NAN,
            setup_seconds,
            solve_seconds,
            equilibrated: self.equilibrated,
            preconditioner_nonzeros: pc.map(|p| p.nonzeros()),
            restarts: 0,
            subnormal_unknowns: 0,
            condition_estimate: None,
            ranks: None,
        }
    }
}

impl Start {
    /// The report of a converged Krylov solve with `pc`: its `(iterations, restarts,
    /// relative residual, original relative residual)`.
    fn converged(&self, pc: &precond::BuiltPreconditioner, seconds: (f64, f64), counts: (usize, usize, f64, f64)) -> SolveReport {
        let (iterations, restarts, relative_residual, original_relative_residual) = counts;
        SolveReport { iterations, restarts, relative_residual, original_relative_residual, ..self.report(Some(pc), seconds) }
    }
}

/// What to try when an in-process Krylov solver does not converge.
const IN_PROCESS_HINT: &str = "try lu, a stronger preconditioner (ilut with smaller drop / larger fill) or more iterations";

/// What stopped a Krylov method that ran out of iterations.
fn iteration_limit(max_iterations: usize) -> String {
    format!("the iteration limit (solver.max_iterations = {max_iterations})")
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
/// or breaks down, it tries BiCGSTAB with ILU(0) on the same equilibrated operator
/// before giving up (on the cantilever grid ILUT diverges where ILU(0) converges;
/// BENCHMARKS.md), and says so in `choice`.
///
/// Only LU can *prove* trouble: a Krylov method on a singular but consistent system
/// (e.g. pure traction with self-equilibrated loads) may converge to one of
/// the infinitely many solutions, rigid-body component included.
///
/// An empty system (`n = 0`) returns an empty solution.
pub(crate) fn solve_with_memory(
    a: Cow<'_, SparseMatrix>,
    b: &[f64],
    params: &SolverParams,
    layout: Option<NodeLayout>,
    available: Option<f64>,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let (kind, choice) = params.kind.resolve(a.nrows() as f64, a.compute_nnz() as f64, available);
    let fallback = match (params.kind, kind) {
        (SolverKind::Auto { tolerance, max_iterations, .. }, SolverKind::Gmres { .. }) => Some((tolerance, max_iterations)),
        _ => None,
    };
    if let SolverKind::Petsc { .. } = kind {
        let (per_point, owner, points) = match layout {
            Some(l) => (l.per_node, partition::morton_owners(l.positions, crate::petsc::world().size), l.positions.to_vec()),
            None => (1, partition::block_owners(a.nrows(), crate::petsc::world().size), Vec::new()),
        };
        return distributed::solve_replicated(&a, b, owner, per_point, &points, params);
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
    if let SolverKind::Bicgstab { tolerance, .. } | SolverKind::Gmres { tolerance, .. } = kind {
        if !(tolerance > 0.0 && tolerance.is_finite()) {
            return Err(SolveError::Dimension { detail: format!("the Krylov tolerance must be positive and finite, got {tolerance}") });
        }
    }

    let start = Start { method: kind.label(), choice, setup: Instant::now(), equilibrated: params.equilibrate };
    if n == 0 {
        let report =
            SolveReport { iterations: 0, relative_residual: 0.0, original_relative_residual: 0.0, ..start.report(None, (0.0, 0.0)) };
        return Ok((Vec::new(), report));
    }

    // Validates finiteness / zero rows in every case.
    let row_max = scaling::row_max_abs(&a)?;
    let scales = params.equilibrate.then(|| scaling::row_scales(&a, &row_max));
    let rhs = Rhs {
        original: b,
        solved: match &scales {
            Some(d) => Cow::Owned(scaling::scale_rhs(b, d)),
            None => Cow::Borrowed(b),
        },
        scales,
    };
    match kind {
        SolverKind::Auto { .. } | SolverKind::Petsc { .. } => unreachable!("resolved and returned above"),
        SolverKind::Lu => solve_lu(&working(a, &rhs, &row_max), &rhs, &start),
        SolverKind::Bicgstab { preconditioner, tolerance, max_iterations } => {
            solve_krylov_bicgstab(&working(a, &rhs, &row_max), &rhs, &start, (preconditioner, tolerance, max_iterations), layout)
        }
        SolverKind::Gmres { preconditioner, tolerance, max_iterations, restart } => {
            let settings = GmresSettings { preconditioner, tolerance, max_iterations, restart };
            let attempt = if preconditioner == Preconditioner::Amg {
                let rows = amg::scaled_rows(&a, rhs.scales.as_deref());
                drop(a);
                solve_gmres_multigrid(rows, &rhs, &start, settings, layout)
            } else {
                let a_work = working(a, &rhs, &row_max);
                match solve_krylov_gmres(&a_work, &rhs, &start, settings, layout) {
                    Ok(done) => Ok(done),
                    Err(e) => Err(Box::new((e, Leftover::Columns(a_work)))),
                }
            };
            match (attempt.map_err(|failed| *failed), fallback) {
                (Ok(done), _) => Ok(done),
                (
                    Err((e @ (SolveError::NoConvergence { .. } | SolveError::Singular { .. }), leftover)),
                    Some((tolerance, max_iterations)),
                ) => {
                    let why = format!("{}; {e}; retried with BiCGSTAB+ILU(0)", start.choice.clone().unwrap_or_default());
                    let columns = leftover.into_columns();
                    let retry = Start {
                        method: SolverKind::Bicgstab { preconditioner: Preconditioner::Ilu0, tolerance, max_iterations }.label(),
                        choice: Some(why),
                        setup: Instant::now(),
                        ..start
                    };
                    solve_krylov_bicgstab(&columns, &rhs, &retry, (Preconditioner::Ilu0, tolerance, max_iterations), layout)
                }
                (Err((e, _)), _) => Err(e),
            }
        }
    }
}

/// The operator as solved, in columns (`D A` with the row maxima `row_max`); a matrix
/// handed over is freed once scaled. (The multigrid makes its own copy in rows instead.)
fn working<'a>(a: Cow<'a, SparseMatrix>, rhs: &Rhs, row_max: &[f64]) -> Cow<'a, SparseMatrix> {
    match &rhs.scales {
        Some(_) => Cow::Owned(scaling::equilibrate_rows_with(&a, row_max).0),
        None => a,
    }
}

/// A solution and its report.
type Solved = (Vec<f64>, SolveReport);

/// Why a GMRES attempt failed, and the operator it leaves for `auto`'s fallback.
type Failed<'a> = (SolveError, Leftover<'a>);

/// The solved operator a failed GMRES leaves for `auto`'s fallback.
enum Leftover<'a> {
    /// In columns, as the other preconditioners needed it.
    Columns(Cow<'a, SparseMatrix>),
    /// In rows, as the multigrid held it.
    Rows(Csr),
}

impl<'a> Leftover<'a> {
    fn into_columns(self) -> Cow<'a, SparseMatrix> {
        match self {
            Leftover::Columns(c) => c,
            Leftover::Rows(r) => Cow::Owned(amg::columns_of(r)),
        }
    }
}

/// Sparse LU of the solved operator `a` (`D A`).
fn solve_lu(a: &SparseMatrix, rhs: &Rhs, start: &Start) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let lu = lu::SparseLu::factor(a)?;
    let setup_seconds = start.setup.elapsed().as_secs_f64();
    let t_solve = Instant::now();
    let x = lu.solve(&rhs.solved);
    let (relres, original_relative_residual) = rhs.residuals(&residual(a, &x, &rhs.solved));
    let kappa = lu::check_solution(&lu, a, &x, &rhs.solved, relres)?;
    let solve_seconds = t_solve.elapsed().as_secs_f64();
    let report = SolveReport {
        iterations: 1,
        relative_residual: relres,
        original_relative_residual,
        condition_estimate: Some(kappa),
        ..start.report(None, (setup_seconds, solve_seconds))
    };
    Ok((x, report))
}

/// Right-preconditioned BiCGSTAB on the solved operator `a` (`D A`) with
/// `(preconditioner, tolerance, max_iterations)`.
fn solve_krylov_bicgstab(
    a: &SparseMatrix,
    rhs: &Rhs,
    start: &Start,
    (preconditioner, tolerance, max_iterations): (Preconditioner, f64, usize),
    layout: Option<NodeLayout>,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let pc = precond::BuiltPreconditioner::build(a, preconditioner, layout)?;
    let setup_seconds = start.setup.elapsed().as_secs_f64();
    let t_solve = Instant::now();
    // Converged means the true residual of the solved (equilibrated) system is
    // within the tolerance, the same measure LU's checks use: the original
    // system's residual is dominated by its largest rows (LU's accepted
    // solutions of the shipped scenes leave 3e-14 to 7e-9 there).
    let out = bicgstab::solve_bicgstab(a, &rhs.solved, &pc, tolerance, max_iterations, |x| relative_residual(a, x, &rhs.solved));
    let solve_seconds = t_solve.elapsed().as_secs_f64();
    let name = format!("BiCGSTAB+{}", preconditioner.display_name());
    let (_, original_relative_residual) = rhs.residuals(&residual(a, &out.x, &rhs.solved));
    match out.status {
        bicgstab::Status::Converged => {
            let counts = (out.iterations, out.restarts, out.relative_residual, original_relative_residual);
            Ok((out.x, start.converged(&pc, (setup_seconds, solve_seconds), counts)))
        }
        bicgstab::Status::NotConverged => Err(SolveError::NoConvergence {
            hint: IN_PROCESS_HINT,
            limit: if out.iterations >= max_iterations {
                iteration_limit(max_iterations)
            } else {
                format!(
                    "the restart limit ({} verification restarts: the recursive residual claimed \
                     convergence each time, the true residual did not follow)",
                    bicgstab::MAX_RESTARTS
                )
            },
            restarts: out.restarts,
            iterations: out.iterations,
            relative_residual: out.relative_residual,
            method: name,
            tolerance,
        }),
        bicgstab::Status::Breakdown => Err(SolveError::Singular {
            detail: format!(
                "{name} broke down after {} iterations (the iterate became NaN or \
                 infinite); the matrix or the preconditioner is (nearly) singular. Try lu, \
                 and check the boundary conditions (a pure-traction problem has \
                 rigid-body modes)",
                out.iterations
            ),
        }),
    }
}

/// The settings of a GMRES solve.
#[derive(Clone, Copy)]
struct GmresSettings {
    preconditioner: Preconditioner,
    tolerance: f64,
    max_iterations: usize,
    restart: usize,
}

/// GMRES with the multigrid built on the solved operator in rows (`D A`, kept as its
/// finest level); on failure the rows come back for `auto`'s fallback.
fn solve_gmres_multigrid<'a>(
    rows: Csr,
    rhs: &Rhs,
    start: &Start,
    settings: GmresSettings,
    layout: Option<NodeLayout>,
) -> Result<Solved, Box<Failed<'a>>> {
    let amg = amg::Amg::build_from_rows(rows, layout, amg::AmgParams::default());
    let pc = precond::BuiltPreconditioner::Amg(Box::new(amg));
    let rows = pc.fine_operator().expect("the multigrid keeps its finest operator");
    run_gmres(rows, &pc, rhs, start, settings).map_err(|e| {
        let precond::BuiltPreconditioner::Amg(amg) = pc else { unreachable!("built as the multigrid above") };
        Box::new((e, Leftover::Rows(amg.into_fine_operator())))
    })
}

/// GMRES with a one-level preconditioner built on the solved operator `a` (`D A`).
fn solve_krylov_gmres(
    a: &SparseMatrix,
    rhs: &Rhs,
    start: &Start,
    settings: GmresSettings,
    layout: Option<NodeLayout>,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let pc = precond::BuiltPreconditioner::build(a, settings.preconditioner, layout)?;
    let rows = amg::to_csr(a);
    run_gmres(&rows, &pc, rhs, start, settings)
}

/// GMRES(restart) on `rows` (the solved operator) with the preconditioner `pc`.
fn run_gmres(
    rows: &Csr,
    pc: &precond::BuiltPreconditioner,
    rhs: &Rhs,
    start: &Start,
    GmresSettings { preconditioner, tolerance, max_iterations, restart }: GmresSettings,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let setup_seconds = start.setup.elapsed().as_secs_f64();
    let t_solve = Instant::now();
    let out = gmres::solve_gmres(rows, &rhs.solved, |v| pc.solve_in_place(v), tolerance, max_iterations, restart);
    let solve_seconds = t_solve.elapsed().as_secs_f64();
    let name = format!("GMRES({restart})+{}", preconditioner.display_name());
    let (_, original_relative_residual) = rhs.residuals(&row_residual(rows, &out.x, &rhs.solved));
    match out.status {
        gmres::Status::Converged => {
            let counts = (out.iterations, out.restarts, out.relative_residual, original_relative_residual);
            Ok((out.x, start.converged(pc, (setup_seconds, solve_seconds), counts)))
        }
        gmres::Status::IterationLimit | gmres::Status::Stalled => Err(SolveError::NoConvergence {
            hint: IN_PROCESS_HINT,
            limit: if out.status == gmres::Status::IterationLimit {
                iteration_limit(max_iterations)
            } else {
                format!("stagnation (a restart cycle reduced the residual by less than {:.0} %)", 100.0 * (1.0 - gmres::STAGNATION))
            },
            restarts: out.restarts,
            iterations: out.iterations,
            relative_residual: out.relative_residual,
            method: name,
            tolerance,
        }),
        gmres::Status::Breakdown => Err(SolveError::Singular {
            detail: format!(
                "{name}: the iterate became NaN or infinite after {} iterations; the matrix or the \
                 preconditioner is (nearly) singular. Try lu, and check the boundary conditions",
                out.iterations
            ),
        }),
    }
}
