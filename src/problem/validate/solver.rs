//! `[solver]` (and `[peridynamics.solver]`): sparse LU, or BiCGSTAB with its
//! preconditioner, tolerance and iteration limit.

use super::Ctx;
use crate::choice::Choice;
use crate::linalg::{Preconditioner, PreconditionerKind, SolverKind, SolverMethod, SolverParams};
use crate::problem::spec::SolverSpec;
use crate::problem::ProblemError;

/// The BiCGSTAB settings of `s` (also those of `auto`'s iterative choice), defaults
/// from [`SolverKind::default_bicgstab`].
fn bicgstab(c: &Ctx, s: &SolverSpec) -> Result<SolverKind, ProblemError> {
    let SolverKind::Bicgstab { preconditioner: default_p, tolerance: default_t, max_iterations: default_m } =
        SolverKind::default_bicgstab()
    else {
        unreachable!("default_bicgstab is a BiCGSTAB configuration")
    };
    let (default_drop, default_fill) = match default_p {
        Preconditioner::Ilut { drop, fill } => (drop, fill),
        _ => (1e-5, 20),
    };
    let kind: PreconditionerKind = c.choose("solver.preconditioner", s.preconditioner.as_deref())?;
    let preconditioner = match kind {
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
        PreconditionerKind::Ilu0 | PreconditionerKind::Jacobi => {
            if s.drop.is_some() || s.fill.is_some() {
                return c.err("solver.drop", format!("drop and fill belong to preconditioner = \"ilut\", not \"{}\"", kind.name()));
            }
            if kind == PreconditionerKind::Ilu0 {
                Preconditioner::Ilu0
            } else {
                Preconditioner::Jacobi
            }
        }
    };
    let tolerance = s.tolerance.unwrap_or(default_t);
    if !(tolerance > 0.0 && tolerance < 1.0) {
        return c.err("solver.tolerance", format!("must lie in (0, 1), got {tolerance}"));
    }
    let max_iterations = s.max_iterations.unwrap_or(default_m);
    if max_iterations == 0 {
        return c.err("solver.max_iterations", "must be at least 1");
    }
    Ok(SolverKind::Bicgstab { preconditioner, tolerance, max_iterations })
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
            ];
            if let Some((k, _)) = iterative_only.iter().find(|(_, p)| *p) {
                return c.err(format!("solver.{k}"), "only used by kind = \"bicgstab\" or \"auto\"");
            }
            SolverKind::Lu
        }
        SolverMethod::Bicgstab => bicgstab(c, s)?,
        SolverMethod::Auto => match bicgstab(c, s)? {
            SolverKind::Bicgstab { preconditioner, tolerance, max_iterations } => {
                SolverKind::Auto { preconditioner, tolerance, max_iterations }
            }
            other => other,
        },
    };
    Ok(SolverParams { kind, equilibrate })
}
