//! `[solver]` (and `[peridynamics.solver]`): sparse LU, or BiCGSTAB / GMRES with
//! their preconditioner, tolerance and iteration limit, or `auto`.

use super::Ctx;
use crate::scene::choice::Choice;
use crate::linalg::{Krylov, Preconditioner, PreconditionerKind, SolverKind, SolverMethod, SolverParams, GMRES_RESTART};
use crate::models::navier::low_order::MultigridOperator;
use crate::scene::problem::spec::SolverSpec;
use crate::scene::problem::ProblemError;

/// Largest GMRES restart length accepted: the basis then takes 8 kB per unknown.
const MAX_RESTART: usize = 1000;

/// `solver.preconditioner` with its `drop` and `fill` (ILUT only), `default` when the
/// scene names none.
fn preconditioner(c: &Ctx, s: &SolverSpec, default: Preconditioner) -> Result<Preconditioner, ProblemError> {
    let (default_drop, default_fill) = (1e-5, 20);
    let kind: PreconditionerKind = match s.preconditioner.as_deref() {
        None => default.kind(),
        named => c.choose("solver.preconditioner", named)?,
    };
    if kind != PreconditionerKind::Ilut && (s.drop.is_some() || s.fill.is_some()) {
        return c.err("solver.drop", format!("drop and fill belong to preconditioner = \"ilut\", not \"{}\"", kind.name()));
    }
    Ok(match kind {
        PreconditionerKind::Ilut => {
            let drop = s.drop.unwrap_or(default_drop);
            if !(drop.is_finite() && drop >= 0.0) {
                return c.err("solver.drop", format!("must be >= 0, got {drop}"));
            }
            let fill = s.fill.unwrap_or(default_fill);
            if fill == 0 {
                return c.err("solver.fill", "must be at least 1");
            }
            Preconditioner::Ilut { drop, fill }
        }
        PreconditionerKind::Ilu0 => Preconditioner::Ilu0,
        PreconditionerKind::Amg => Preconditioner::Amg,
        PreconditionerKind::Jacobi => Preconditioner::Jacobi,
    })
}

/// The Krylov settings of `s`: BiCGSTAB with defaults from [`Krylov::bicgstab`],
/// GMRES, PETSc and `auto`'s iterative choice from [`Krylov::default`]
/// (preconditioner `amg` unless another is named).
fn krylov(c: &Ctx, s: &SolverSpec, method: SolverMethod) -> Result<SolverKind, ProblemError> {
    let defaults = match method {
        SolverMethod::Bicgstab => Krylov::bicgstab(),
        SolverMethod::Gmres | SolverMethod::Petsc | SolverMethod::Auto | SolverMethod::Lu => Krylov::default(),
    };
    let (default_p, default_t, default_m) = (defaults.preconditioner, defaults.tolerance, defaults.max_iterations);
    let preconditioner = preconditioner(c, s, default_p)?;
    let tolerance = s.tolerance.unwrap_or(default_t);
    if !(tolerance > 0.0 && tolerance < 1.0) {
        return c.err("solver.tolerance", format!("must lie in (0, 1), got {tolerance}"));
    }
    let max_iterations = s.max_iterations.unwrap_or(default_m);
    if max_iterations == 0 {
        return c.err("solver.max_iterations", "must be at least 1");
    }
    let restart = s.restart.unwrap_or(GMRES_RESTART);
    if restart == 0 || restart > MAX_RESTART {
        return c.err("solver.restart", format!("must lie in 1..={MAX_RESTART} (each vector costs 8 bytes per unknown), got {restart}"));
    }
    Ok(match method {
        SolverMethod::Bicgstab => {
            if s.restart.is_some() {
                return c.err("solver.restart", "only used by kind = \"gmres\" (BiCGSTAB keeps no Krylov basis)");
            }
            SolverKind::Bicgstab(Krylov { preconditioner, tolerance, max_iterations })
        }
        SolverMethod::Auto => {
            if s.restart.is_some() {
                return c.err(
                    "solver.restart",
                    format!("auto's GMRES restarts every {GMRES_RESTART} iterations; set kind = \"gmres\" to change it"),
                );
            }
            SolverKind::Auto(Krylov { preconditioner, tolerance, max_iterations })
        }
        SolverMethod::Petsc => {
            if !crate::parallel::petsc::AVAILABLE {
                return c.err(
                    "solver.kind",
                    "\"petsc\" needs a build with the PETSc backend: scripts/install-petsc.sh, then \
                     cargo build --release --features petsc (docs/guide/petsc-mpi.md)",
                );
            }
            if preconditioner.petsc_name().is_none() {
                return c.err(
                    "solver.preconditioner",
                    "PETSc has no ILUT; use \"amg\" (GAMG), \"ilu0\" or \"jacobi\", or PETSc's own options \
                     (e.g. -pc_type hypre -pc_hypre_type euclid after `--`)",
                );
            }
            SolverKind::Petsc { krylov: Krylov { preconditioner, tolerance, max_iterations }, restart, direct: false }
        }
        SolverMethod::Gmres => SolverKind::Gmres { krylov: Krylov { preconditioner, tolerance, max_iterations }, restart },
        SolverMethod::Lu => unreachable!("LU has no Krylov settings: `solver` handles it"),
    })
}

/// `solver.multigrid` of the MLSM model's `[solver]`: which operator its multigrid
/// preconditioner is built on; only with `amg` in-process (gmres, auto).
pub(super) fn multigrid(c: &Ctx, s: &SolverSpec, params: &SolverParams) -> Result<MultigridOperator, ProblemError> {
    let chosen = c.choose("solver.multigrid", s.multigrid.as_deref())?;
    let in_process_amg = match params.kind {
        SolverKind::Gmres { krylov: Krylov { preconditioner, .. }, .. } | SolverKind::Auto(Krylov { preconditioner, .. }) => {
            preconditioner == Preconditioner::Amg
        }
        _ => false,
    };
    if s.multigrid.is_some() && !in_process_amg {
        return c
            .err("solver.multigrid", "only used by the in-process multigrid: kind = \"gmres\" or \"auto\" with preconditioner = \"amg\"");
    }
    Ok(chosen)
}

/// `[solver]`; the fields of errors start with `solver.` (the caller renames them
/// for `[peridynamics.solver]`).
pub(super) fn solver(c: &Ctx, s: &SolverSpec) -> Result<SolverParams, ProblemError> {
    let equilibrate = s.equilibrate.unwrap_or(true);
    let kind = match c.choose("solver.kind", s.kind.as_deref())? {
        SolverMethod::Lu => {
            let iterative_only = [
                ("preconditioner", s.preconditioner.is_some()),
                ("drop", s.drop.is_some()),
                ("fill", s.fill.is_some()),
                ("tolerance", s.tolerance.is_some()),
                ("max_iterations", s.max_iterations.is_some()),
                ("restart", s.restart.is_some()),
                ("multigrid", s.multigrid.is_some()),
            ];
            if let Some((k, _)) = iterative_only.iter().find(|(_, p)| *p) {
                return c.err(format!("solver.{k}"), "only used by kind = \"bicgstab\", \"gmres\", \"petsc\" or \"auto\"");
            }
            SolverKind::Lu
        }
        method => krylov(c, s, method)?,
    };
    Ok(SolverParams { kind, equilibrate })
}
