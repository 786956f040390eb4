//! Systems `(A + E) x = b` whose operator is kept in two parts: the matrix `A`, and a
//! part `E` applied by its product only ([`Addition`]), never assembled, where
//! assembling it would cost more than the rest of the run (the dilatation of the linear
//! peridynamic solid, `E = beta D^T V D`: its rows read the nodes within twice the
//! horizon, 3.6x the bonds' nonzeros).
//!
//! They are solved by GMRES preconditioned with the multigrid of `A` alone, which works
//! when `A` is spectrally close to `A + E`: for the peridynamic solid the bond part is
//! the Navier operator of `(mu, lambda = mu)` and the whole the one of `(mu, lambda)`,
//! so the preconditioned operator's spectrum lies between 1 and
//! `(lambda + 2 mu) / (3 mu)` (shear and dilatational waves), 1.17 at nu = 0.3 in plane
//! strain. The rows are equilibrated by `A`'s row scales (the same `D` multiplies `E`),
//! and the loads solved in the scale of [`super::solve`]. Only a solver that runs
//! GMRES with the multigrid in this process takes such a system ([`takes_addition`]);
//! nothing falls back to LU here, as there is no matrix to factor: the caller assembles
//! `A + E` and solves that when this fails.

use std::borrow::Cow;
use std::time::Instant;

use super::gmres::{self, GmresSettings};
use super::inverse::Inverse;
use super::methods::{run_gmres, solved_rows, Operator, Rhs, Start};
use super::{
    amg, in_load_scale, precond, solved_rhs_max, watch, Csr, Krylov, NodeLayout, Preconditioner, SolveError, SolveReport,
};
use super::{SolverKind, SolverParams, AUTO_KRYLOV_PACE};

/// `y ← E x`: the part of an operator applied without its matrix.
pub type Addition<'a> = &'a (dyn Fn(&[f64], &mut [f64]) + Sync);

/// The GMRES settings `params` runs on a system of `unknowns` rows with `nonzeros`
/// entries once assembled, when that is GMRES with the multigrid in this process
/// (`auto` gone iterative, or asked for), and `auto`'s reason; `None` otherwise (LU,
/// BiCGSTAB, a one-level preconditioner, PETSc).
pub fn takes_addition(params: &SolverParams, unknowns: usize, nonzeros: f64) -> Option<(GmresSettings, Option<String>)> {
    let choice = params.kind.choose(unknowns as f64, nonzeros, false, crate::output::available_memory_bytes());
    match choice.primary {
        SolverKind::Gmres { krylov: Krylov { preconditioner: Preconditioner::Amg, tolerance, max_iterations }, restart } => {
            // Chosen for time with LU behind it: a cycle must show the pace, as in `solve`.
            let stall = if choice.fallback == Some(SolverKind::Lu) { AUTO_KRYLOV_PACE } else { gmres::STAGNATION };
            Some((GmresSettings { preconditioner: Preconditioner::Amg, tolerance, max_iterations, restart, stall }, choice.reason))
        }
        _ => None,
    }
}

/// Solve `(A + E) x = b` (module docs) with `settings` from [`takes_addition`]: `a` the
/// assembled part (the multigrid's operator), `addition` the product of the rest,
/// `layout` the unknowns' nodes (the multigrid's rigid-body modes), `choice` what the
/// report says of the choice. Errors as [`super::solve_nodal`]'s GMRES.
pub fn solve_nodal_with_addition(
    a: Csr,
    addition: Addition<'_>,
    b: &[f64],
    (settings, choice): (GmresSettings, Option<String>),
    equilibrate: bool,
    layout: NodeLayout,
    watch: &dyn watch::Watch,
) -> Result<(Vec<f64>, SolveReport), SolveError> {
    let n = a.nrows();
    if a.ncols() != n || b.len() != n {
        return Err(SolveError::Dimension { detail: format!("matrix is {}x{}, right-hand side {} long", n, a.ncols(), b.len()) });
    }
    let note = "the dilatation applied without its matrix, the multigrid on the bond part";
    let choice = Some(choice.map_or_else(|| note.to_string(), |c| format!("{c}; {note}")));
    in_load_scale(solved_rhs_max(&a, b, equilibrate), b, |scaled| {
        let start = Start {
            method: format!("GMRES({})+AMG", settings.restart),
            choice,
            setup: Instant::now(),
            equilibrated: equilibrate,
            watch,
            keep: None,
        };
        if n == 0 {
            return Ok((
                Vec::new(),
                SolveReport { relative_residual: 0.0, original_relative_residual: 0.0, ..start.report(None, (0.0, 0.0)) },
            ));
        }
        let rhs = Rhs::of(&a, scaled, equilibrate)?;
        let amg = amg::Amg::build_from_rows(solved_rows(Cow::Owned(a), &rhs), Some(layout), amg::AmgParams::default(), amg::Finest::System);
        let pc = precond::BuiltPreconditioner::Amg(Box::new(amg));
        let rows = pc.fine_operator().expect("the multigrid keeps its finest operator");
        let op = Operator { rows, addition: Some((addition, rhs.scales.as_deref())) };
        run_gmres(&op, &pc, &rhs, &start, settings, Some(&layout)).map_err(|e| e.with_cycle_growth(pc.multigrid()))
    })
}
