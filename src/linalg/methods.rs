//! The solve methods behind [`super::solve_with_memory`], each on the solved
//! (row-equilibrated) operator: sparse LU, BiCGSTAB, GMRES with a one-level
//! preconditioner or with the multigrid, and what a failed GMRES leaves for `auto`'s
//! fallback. The original system's residual is measured from the solved one
//! ([`Rhs::residuals`]), so the assembled matrix need not be kept.

use std::sync::OnceLock;
use std::borrow::Cow;
use std::cell::RefCell;
use std::time::Instant;

use super::csr::Csr;
use super::gmres::GmresSettings;
use super::inverse::Inverse;
use super::report::IN_PROCESS_HINT;
use super::retained::{Inverse as Kept, Retained};
use super::{
    amg, bicgstab, border, csr, gmres, lu, norm2, precond, relative, residual, solver_error, subtract_column_product,
};
use super::{scaling, NodeLayout, Preconditioner, SolveError, SolveReport, SparseMatrix};

/// The right-hand side as solved, and how the residual of the original system
/// `A x = b` is measured from that of the solved one `D A x = D b` (`D` the row
/// scales of the equilibration, the identity without it): `b − A x = D⁻¹ (D b − D A x)`,
/// so the original matrix need not be kept.
pub(super) struct Rhs<'a> {
    /// `b`.
    pub(super) original: &'a [f64],
    /// `D b`.
    pub(super) solved: Cow<'a, [f64]>,
    /// `D`, when the rows are equilibrated.
    pub(super) scales: Option<Vec<f64>>,
}

impl<'a> Rhs<'a> {
    /// `b` as the rows of `a` solve it: with `equilibrate`, scaled by `a`'s row scales
    /// ([`scaling::row_scales`]). Checks that every entry of `a` is finite and no row is
    /// zero.
    pub(super) fn of(a: &Csr, b: &'a [f64], equilibrate: bool) -> Result<Self, SolveError> {
        let row_max = scaling::row_max_abs(a)?;
        let scales = equilibrate.then(|| scaling::row_scales(a, &row_max));
        let solved = match &scales {
            Some(d) => Cow::Owned(scaling::scale_rhs(b, d)),
            None => Cow::Borrowed(b),
        };
        Ok(Rhs { original: b, solved, scales })
    }

    /// Relative residuals `(‖D b − D A x‖ / ‖D b‖, ‖b − A x‖ / ‖b‖)` from the residual
    /// `r = D b − D A x` of the solved system.
    pub(super) fn residuals(&self, r: &[f64]) -> (f64, f64) {
        let unscaled = match &self.scales {
            Some(d) => r.iter().zip(d).map(|(r, d)| (r / d) * (r / d)).sum::<f64>().sqrt(),
            None => norm2(r),
        };
        (relative(norm2(r), norm2(&self.solved)), relative(unscaled, norm2(self.original)))
    }
}

/// What every report of one solve shares: the method's label, `auto`'s reason, and
/// when the setup started.
pub(super) struct Start<'w> {
    pub(super) method: String,
    pub(super) choice: Option<String>,
    pub(super) setup: Instant,
    pub(super) equilibrated: bool,
    /// Told the residual after each iteration.
    pub(super) watch: &'w dyn super::watch::Watch,
    /// Where a solver that succeeded leaves itself when the caller keeps it
    /// ([`super::solve_nodal_retained`]).
    pub(super) keep: Option<&'w RefCell<Option<Retained>>>,
}

impl Start<'_> {
    /// Leave the solver made by `make` for the caller, when it keeps one.
    pub(super) fn retain(&self, make: impl FnOnce() -> Retained) {
        if let Some(slot) = self.keep {
            *slot.borrow_mut() = Some(make());
        }
    }

    /// The report of a finished solve, before its iteration counts are filled in;
    /// the method's name carries what the preconditioner says of itself (AMG: its
    /// levels).
    pub(super) fn report(&self, pc: Option<&precond::BuiltPreconditioner>, (setup_seconds, solve_seconds): (f64, f64)) -> SolveReport {
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
            solver_error: None,
            ranks: None,
            petsc: None,
        }
    }

    /// The report of a converged Krylov solve with `pc`: its `(iterations, restarts,
    /// relative residual, original relative residual)`.
    pub(super) fn converged(
        &self,
        pc: &precond::BuiltPreconditioner,
        seconds: (f64, f64),
        counts: (usize, usize, f64, f64),
    ) -> SolveReport {
        let (iterations, restarts, relative_residual, original_relative_residual) = counts;
        SolveReport { iterations, restarts, relative_residual, original_relative_residual, ..self.report(Some(pc), seconds) }
    }
}

/// `report` of a converged Krylov solve with its own error ([`solver_error`]) from the
/// final residual `r` of the iterate `x`, `A` given by its product `apply`; the
/// estimate's time is added to the solve's.
fn with_own_error(
    report: SolveReport,
    apply: impl Fn(&[f64], &mut [f64]),
    r: &[f64],
    pc: &precond::BuiltPreconditioner,
    x: &[f64],
    layout: Option<&NodeLayout>,
) -> SolveReport {
    let t_error = Instant::now();
    let delta = solver_error::correction(apply, r, |v, z| pc.solve_into(v, z));
    let own = solver_error::relative_to_displacement(&delta, x, layout);
    SolveReport { solver_error: Some(own), solve_seconds: report.solve_seconds + t_error.elapsed().as_secs_f64(), ..report }
}

/// What stopped a Krylov method that ran out of iterations.
pub(super) fn iteration_limit(max_iterations: usize) -> String {
    format!("the iteration limit (solver.max_iterations = {max_iterations})")
}

/// The operator as solved in rows, `D A`: a matrix handed over is scaled in place (no
/// second copy), a borrowed one copied first.
pub(super) fn solved_rows(a: Cow<'_, Csr>, rhs: &Rhs) -> Csr {
    let mut rows = a.into_owned();
    if let Some(d) = &rhs.scales {
        // An auxiliary operator of a bordered system has the leading rows only.
        rows.scale_rows(&d[..rows.nrows()]);
    }
    rows
}

/// [`solved_rows`] in columns, for the solvers that work on columns (LU, the one-level
/// preconditioners); the rows are freed once converted.
pub(super) fn working(a: Cow<'_, Csr>, rhs: &Rhs) -> SparseMatrix {
    csr::columns_of(solved_rows(a, rhs))
}

/// A solution and its report.
pub(super) type Solved = (Vec<f64>, SolveReport);

/// Why a GMRES attempt failed, and the operator it leaves for `auto`'s fallback.
pub(super) type Failed = (SolveError, Leftover);

/// The solved operator a failed GMRES leaves for `auto`'s fallback.
pub(super) enum Leftover {
    /// In columns, as the other preconditioners needed it.
    Columns(SparseMatrix),
    /// In rows, as the multigrid held it.
    Rows(Csr),
}

impl Leftover {
    pub(super) fn into_columns(self) -> SparseMatrix {
        match self {
            Leftover::Columns(c) => c,
            Leftover::Rows(r) => csr::columns_of(r),
        }
    }
}

/// Sparse LU of the solved operator `a` (`D A`).
pub(super) fn solve_lu(a: SparseMatrix, rhs: &Rhs, start: &Start) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let lu = lu::SparseLu::factor(&a)?;
    let setup_seconds = start.setup.elapsed().as_secs_f64();
    let t_solve = Instant::now();
    let x = lu.solve(&rhs.solved);
    let (relres, original_relative_residual) = rhs.residuals(&residual(&a, &x, &rhs.solved));
    let kappa = lu::check_solution(&lu, &a, &x, &rhs.solved, relres)?;
    let solve_seconds = t_solve.elapsed().as_secs_f64();
    let report = SolveReport {
        iterations: 1,
        relative_residual: relres,
        original_relative_residual,
        condition_estimate: Some(kappa),
        ..start.report(None, (setup_seconds, solve_seconds))
    };
    start.retain(|| Retained { method: start.method.clone(), rows: OnceLock::new(), columns: Some(a), inverse: Kept::Lu(lu) });
    Ok((x, report))
}

/// Right-preconditioned BiCGSTAB on the solved operator `a` (`D A`) with
/// `(preconditioner, tolerance, max_iterations)`.
pub(super) fn solve_krylov_bicgstab(
    a: SparseMatrix,
    rhs: &Rhs,
    start: &Start,
    (preconditioner, tolerance, max_iterations): (Preconditioner, f64, usize),
    layout: Option<NodeLayout>,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let pc = precond::BuiltPreconditioner::build(&a, preconditioner, layout)?;
    let setup_seconds = start.setup.elapsed().as_secs_f64();
    let t_solve = Instant::now();
    // Converged means the true residual of the solved (equilibrated) system is
    // within the tolerance, the same measure LU's checks use: the original
    // system's residual is dominated by its largest rows (LU's accepted
    // solutions of the shipped scenes leave 3e-14 to 7e-9 there).
    // The residual of the last check is kept: BiCGSTAB returns the iterate it checked
    // last, whose residual also gives the original system's.
    let mut last_residual = Vec::new();
    let out = bicgstab::solve_bicgstab(&a, &rhs.solved, &pc, tolerance, max_iterations, |x| {
        last_residual = residual(&a, x, &rhs.solved);
        let reached = relative(norm2(&last_residual), norm2(&rhs.solved));
        start.watch.residual(reached, tolerance);
        reached
    });
    let solve_seconds = t_solve.elapsed().as_secs_f64();
    let name = format!("BiCGSTAB+{}", preconditioner.display_name());
    match out.status {
        bicgstab::Status::Converged => {
            let (_, original_relative_residual) = rhs.residuals(&last_residual);
            // `y = A x` as `−(0 − A x)`, without a vector allocated per product.
            let product = |x: &[f64], y: &mut [f64]| {
                y.fill(0.0);
                subtract_column_product(&a, x, y);
                y.iter_mut().for_each(|v| *v = -*v);
            };
            let counts = (out.iterations, out.restarts, out.relative_residual, original_relative_residual);
            let report = start.converged(&pc, (setup_seconds, solve_seconds), counts);
            let report = with_own_error(report, product, &last_residual, &pc, &out.x, layout.as_ref());
            start.retain(|| Retained { method: name, rows: OnceLock::new(), columns: Some(a), inverse: Kept::Bicgstab(pc, max_iterations) });
            Ok((out.x, report))
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

/// GMRES with the multigrid built on the solved operator in rows (`D A`, kept as its
/// finest level), or on `auxiliary` (`D A_aux`, a low-order operator on the same
/// unknowns, [`super::Auxiliary`]) when given; on failure the rows come back for
/// `auto`'s fallback.
pub(super) fn solve_gmres_multigrid(
    rows: Csr,
    auxiliary: Option<Csr>,
    rhs: &Rhs,
    start: &Start,
    settings: GmresSettings,
    layout: Option<NodeLayout>,
) -> Result<Solved, Box<Failed>> {
    // The system's rows are the multigrid's finest level unless it is built on `auxiliary`.
    let method = match auxiliary {
        Some(_) => format!("{} on the low-order operator", start.method),
        None => start.method.clone(),
    };
    let start = Start { method, choice: start.choice.clone(), ..*start };
    // A bordered system's multigrid is built on its leading block (border module).
    let multipliers = layout.map_or(0, |l| l.multipliers);
    let (finest, system) = match auxiliary {
        Some(aux) => (aux, Some(rows)),
        None if multipliers > 0 => (border::leading_block(&rows, multipliers), Some(rows)),
        None => (rows, None),
    };
    let keep = if system.is_some() { amg::Finest::PreconditionerOnly } else { amg::Finest::System };
    let amg = Box::new(amg::Amg::build_from_rows(finest, layout.map(NodeLayout::nodes_only), amg::AmgParams::default(), keep));
    let pc = match system.as_ref().filter(|_| multipliers > 0) {
        None => precond::BuiltPreconditioner::Amg(amg),
        Some(rows) => match border::Bordered::build(rows, multipliers, Box::new(precond::BuiltPreconditioner::Amg(amg))) {
            Ok(b) => precond::BuiltPreconditioner::Bordered(Box::new(b)),
            Err(e) => return Err(Box::new((e, Leftover::Rows(system.expect("a bordered system is kept"))))),
        },
    };
    let rows = system.as_ref().or(pc.fine_operator()).expect("the multigrid keeps its finest operator");
    match run_gmres(&Operator::rows(rows), &pc, rhs, &start, settings, layout.as_ref()) {
        Ok(done) => {
            start.retain(|| Retained { method: start.method.clone(), rows: system.map_or_else(OnceLock::new, OnceLock::from), columns: None, inverse: Kept::Gmres(pc, settings) });
            Ok(done)
        }
        Err(e) => {
            let e = e.with_cycle_growth(pc.multigrid());
            let rows = system.unwrap_or_else(|| {
                let precond::BuiltPreconditioner::Amg(amg) = pc else { unreachable!("built as the multigrid above") };
                amg.into_fine_operator().expect("kept as the system")
            });
            Err(Box::new((e, Leftover::Rows(rows))))
        }
    }
}

/// GMRES on the solved rows of a displacement-pressure system with the block-triangular
/// preconditioner of [`super::saddle`], its multigrid on the displacement block of
/// `auxiliary` when given (a low-order operator on the same unknowns), else of the
/// system. There is no fallback to try after it (ILU(0) and ILUT diverge or overflow on
/// these rows near nu = 1/2), so a failure is reported as it stands.
pub(super) fn solve_gmres_saddle_point(
    rows: Csr,
    auxiliary: Option<Csr>,
    rhs: &Rhs,
    start: &Start,
    settings: GmresSettings,
    layout: NodeLayout,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let method = match auxiliary {
        Some(_) => format!("{} (low-order operator)", start.method),
        None => start.method.clone(),
    };
    let start = Start { method, choice: start.choice.clone(), ..*start };
    // A bordered system's saddle point is its leading block (border module).
    let lead = (layout.multipliers > 0).then(|| border::leading_block(&rows, layout.multipliers));
    let built = super::saddle::SaddlePoint::build(lead.as_ref().unwrap_or(&rows), auxiliary.as_ref(), layout.nodes_only())
        .ok_or_else(|| SolveError::Dimension { detail: "the displacement-pressure preconditioner needs three unknowns per node".into() })?;
    drop((auxiliary, lead));
    let mut pc = precond::BuiltPreconditioner::SaddlePoint(Box::new(built));
    if layout.multipliers > 0 {
        pc = precond::BuiltPreconditioner::Bordered(Box::new(border::Bordered::build(&rows, layout.multipliers, Box::new(pc))?));
    }
    let done = run_gmres(&Operator::rows(&rows), &pc, rhs, &start, settings, Some(&layout))?;
    start.retain(|| Retained { method: start.method.clone(), rows: OnceLock::from(rows), columns: None, inverse: Kept::Gmres(pc, settings) });
    Ok(done)
}

/// GMRES with a one-level preconditioner built on the solved operator `a` (`D A`).
pub(super) fn solve_krylov_gmres(
    a: &SparseMatrix,
    rhs: &Rhs,
    start: &Start,
    settings: GmresSettings,
    layout: Option<NodeLayout>,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let pc = precond::BuiltPreconditioner::build(a, settings.preconditioner, layout)?;
    let rows = csr::to_csr(a);
    let done = run_gmres(&Operator::rows(&rows), &pc, rhs, start, settings, layout.as_ref())?;
    start.retain(|| Retained { method: start.method.clone(), rows: OnceLock::from(rows), columns: None, inverse: Kept::Gmres(pc, settings) });
    Ok(done)
}

/// The solved operator `D (A + E)` as GMRES applies it: the rows `D A`, and when the
/// operator has a part applied without its matrix ([`super::Addition`]), that part
/// and the row scales `D` it is multiplied by (none: unscaled).
pub(super) struct Operator<'a> {
    pub(super) rows: &'a Csr,
    pub(super) addition: Option<(super::Addition<'a>, Option<&'a [f64]>)>,
}

impl<'a> Operator<'a> {
    /// The rows alone.
    pub(super) fn rows(rows: &'a Csr) -> Self {
        Operator { rows, addition: None }
    }

    /// `y ← D (A + E) x`.
    pub(super) fn apply(&self, x: &[f64], y: &mut [f64]) {
        csr::product(self.rows, x, y);
        if let Some((addition, scales)) = self.addition {
            let mut e = vec![0.0; y.len()];
            addition(x, &mut e);
            match scales {
                Some(d) => y.iter_mut().zip(&e).zip(d).for_each(|((y, e), d)| *y += d * e),
                None => y.iter_mut().zip(&e).for_each(|(y, e)| *y += e),
            }
        }
    }

    /// `b − D (A + E) x`.
    fn residual(&self, x: &[f64], b: &[f64]) -> Vec<f64> {
        let mut r = vec![0.0; b.len()];
        self.apply(x, &mut r);
        r.iter_mut().zip(b).for_each(|(r, b)| *r = b - *r);
        r
    }
}

/// GMRES(restart) on `op` (the solved operator) with the preconditioner `pc`.
pub(super) fn run_gmres(
    op: &Operator,
    pc: &precond::BuiltPreconditioner,
    rhs: &Rhs,
    start: &Start,
    GmresSettings { preconditioner, tolerance, max_iterations, restart, stall }: GmresSettings,
    layout: Option<&NodeLayout>,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let setup_seconds = start.setup.elapsed().as_secs_f64();
    let t_solve = Instant::now();
    let apply = |x: &[f64], y: &mut [f64]| op.apply(x, y);
    let out =
        gmres::solve_gmres_with(apply, &rhs.solved, |v, z| pc.solve_into(v, z), (tolerance, max_iterations, restart, stall), start.watch);
    let solve_seconds = t_solve.elapsed().as_secs_f64();
    let name = format!("GMRES({restart})+{}", preconditioner.display_name());
    let r = op.residual(&out.x, &rhs.solved);
    let (_, original_relative_residual) = rhs.residuals(&r);
    match out.status {
        gmres::Status::Converged => {
            let counts = (out.iterations, out.restarts, out.relative_residual, original_relative_residual);
            let report = start.converged(pc, (setup_seconds, solve_seconds), counts);
            let report = with_own_error(report, apply, &r, pc, &out.x, layout);
            Ok((out.x, report))
        }
        gmres::Status::IterationLimit | gmres::Status::Stalled => Err(SolveError::NoConvergence {
            hint: IN_PROCESS_HINT,
            limit: if out.status == gmres::Status::IterationLimit {
                iteration_limit(max_iterations)
            } else {
                format!("stagnation (a restart cycle reduced the residual by less than {:.0} %)", 100.0 * (1.0 - stall))
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
