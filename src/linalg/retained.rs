//! A solver kept past its solve: the solved rows `D A` and what inverted them (LU
//! factors, or a Krylov method with its built preconditioner), for a second
//! right-hand side on the same matrix at the cost of a back-substitution or a few
//! preconditioned iterations instead of a second factorisation or multigrid setup
//! (the `defect` error estimate's correction, `models::navier::defect`).

use std::sync::OnceLock;

use super::gmres::GmresSettings;
use super::inverse::Inverse as _;
use super::report::IN_PROCESS_HINT;
use super::watch::Watch;
use super::{binary_exponent, times_power_of_two};
use super::{bicgstab, csr, gmres, lu, norm2, precond, relative, residual, row_residual, Csr, SolveError, SparseMatrix};

/// `c` scaled by a power of two to a largest entry in [1, 2), with the exponent;
/// `None` for a zero `c`, an error for a non-finite one.
fn scaled(c: &[f64]) -> Result<Option<(i32, Vec<f64>)>, SolveError> {
    let largest = c.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if !largest.is_finite() {
        return Err(SolveError::Dimension { detail: "the second right-hand side is not finite".into() });
    }
    if largest == 0.0 {
        return Ok(None);
    }
    let exponent = binary_exponent(largest);
    Ok(Some((exponent, c.iter().map(|v| times_power_of_two(*v, -exponent)).collect())))
}

/// The solution of the [`scaled`] right-hand side scaled back, or the first unknown
/// beyond the double range.
fn unscaled(y: Vec<f64>, exponent: i32) -> Result<Vec<f64>, SolveError> {
    if let Some(i) = y.iter().position(|v| !times_power_of_two(*v, exponent).is_finite()) {
        return Err(SolveError::Overflow { detail: format!("unknown {i} of the second solve is beyond the double range") });
    }
    Ok(y.into_iter().map(|v| times_power_of_two(v, exponent)).collect())
}

/// Iteration limit of [`Retained::solve_replaced`] preconditioned by LU factors (a
/// perturbation of a few hundred rows converges in tens).
const REPLACED_LU_ITERATIONS: usize = 500;

/// What inverts the kept rows.
pub(super) enum Inverse {
    /// The LU factors of the solved rows.
    Lu(lu::SparseLu),
    /// GMRES(restart) with its preconditioner.
    Gmres(precond::BuiltPreconditioner, GmresSettings),
    /// BiCGSTAB with its preconditioner and iteration limit.
    Bicgstab(precond::BuiltPreconditioner, usize),
}

/// A solver kept after its solve ([`super::solve_nodal_retained`]): the rows it solved,
/// `D A` (row-equilibrated when the scene asks, multipliers of a bordered system
/// last), and their inverse.
pub struct Retained {
    /// The solver's label, for the note of a second solve.
    pub(super) method: String,
    /// The solved rows, unless the preconditioner holds them (the multigrid's finest
    /// level); made once from `columns` when the solver kept them in columns and a
    /// second solve reads them.
    pub(super) rows: OnceLock<Csr>,
    /// The solved operator in columns (LU, BiCGSTAB).
    pub(super) columns: Option<SparseMatrix>,
    pub(super) inverse: Inverse,
}

impl Retained {
    /// The solved rows `D A`: those the solver holds, or made from its columns.
    pub fn rows(&self) -> &Csr {
        if let Some(rows) = self.rows.get() {
            return rows;
        }
        if let Inverse::Gmres(pc, _) | Inverse::Bicgstab(pc, _) = &self.inverse {
            if let Some(rows) = pc.fine_operator() {
                return rows;
            }
        }
        self.rows.get_or_init(|| csr::to_csr(self.columns.as_ref().expect("a retained solver keeps its operator in rows or in columns")))
    }

    /// Solve `D A y = c` (`c` in the solved rows' scale, of any magnitude: it is
    /// scaled by a power of two first, as [`super::solve_nodal`] scales the loads) to a
    /// relative residual `tolerance` (LU: as exact as its factors), from `y = 0`;
    /// returns `y` and a note of what the solve did. `watch` is told the residual of each
    /// iteration.
    pub fn solve(&self, c: &[f64], tolerance: f64, watch: &dyn Watch) -> Result<(Vec<f64>, String), SolveError> {
        let Some((exponent, b)) = scaled(c)? else {
            return Ok((vec![0.0; c.len()], format!("{}: a zero right-hand side", self.method)));
        };
        let rows = || self.rows();
        let (y, iterations, relres) = match &self.inverse {
            Inverse::Lu(lu) => {
                let y = lu.solve(&b);
                let r = match &self.columns {
                    Some(a) => residual(a, &y, &b),
                    None => row_residual(&rows(), &y, &b),
                };
                (y, 1, relative(norm2(&r), norm2(&b)))
            }
            Inverse::Gmres(pc, settings) => {
                let ops = rows();
                let apply = |x: &[f64], y: &mut [f64]| csr::product(ops, x, y);
                let limits = (tolerance, settings.max_iterations, settings.restart, settings.stall);
                let out = gmres::solve_gmres_with(apply, &b, |v, z| pc.solve_into(v, z), limits, watch);
                if !matches!(out.status, gmres::Status::Converged) {
                    return Err(self.not_converged(out.iterations, out.relative_residual, tolerance));
                }
                (out.x, out.iterations, out.relative_residual)
            }
            Inverse::Bicgstab(pc, max_iterations) => {
                let a = self.columns.as_ref().expect("BiCGSTAB keeps its operator in columns");
                let out = bicgstab::solve_bicgstab(a, &b, pc, tolerance, *max_iterations, |y| {
                    let reached = relative(norm2(&residual(a, y, &b)), norm2(&b));
                    watch.residual(reached, tolerance);
                    reached
                });
                if !matches!(out.status, bicgstab::Status::Converged) {
                    return Err(self.not_converged(out.iterations, out.relative_residual, tolerance));
                }
                (out.x, out.iterations, out.relative_residual)
            }
        };
        let y = unscaled(y, exponent)?;
        let note = match self.inverse {
            Inverse::Lu(_) => format!("{} factors reused, relative residual {relres:.1e}", self.method),
            _ => format!("{} reused: {iterations} iterations, relative residual {relres:.1e}", self.method),
        };
        Ok((y, note))
    }

    /// Solve `M y = c` to a relative residual `tolerance`, `M` the solved rows `D A`
    /// with the rows of `replaced` (`(row, [(column, value)])`, in the solved rows'
    /// scale) in place of their own: GMRES on `M`, preconditioned by what inverted `D A`
    /// (its LU factors or its preconditioner). A few hundred rows replaced are a
    /// perturbation of low rank, which costs a few iterations more than a solve with
    /// `D A`. No rows replaced: [`Retained::solve`].
    pub fn solve_replaced(
        &self,
        c: &[f64],
        replaced: &[(usize, Vec<(u32, f64)>)],
        tolerance: f64,
        watch: &dyn Watch,
    ) -> Result<(Vec<f64>, String), SolveError> {
        if replaced.is_empty() {
            return self.solve(c, tolerance, watch);
        }
        let Some((exponent, b)) = scaled(c)? else {
            return Ok((vec![0.0; c.len()], format!("{}: a zero right-hand side", self.method)));
        };
        let ops = self.rows();
        let apply = |x: &[f64], y: &mut [f64]| {
            csr::product(ops, x, y);
            for (r, entries) in replaced {
                y[*r] = entries.iter().map(|&(col, v)| v * x[col as usize]).sum();
            }
        };
        let (max_iterations, restart) = match &self.inverse {
            Inverse::Gmres(_, settings) => (settings.max_iterations, settings.restart),
            Inverse::Bicgstab(_, max_iterations) => (*max_iterations, super::params::GMRES_RESTART),
            Inverse::Lu(_) => (REPLACED_LU_ITERATIONS, super::params::GMRES_RESTART),
        };
        let limits = (tolerance, max_iterations, restart, gmres::STAGNATION);
        let block = ReplacedBlock::new(replaced);
        let precondition = |v: &[f64], z: &mut [f64]| {
            match &self.inverse {
                Inverse::Lu(lu) => z.copy_from_slice(&lu.solve(v)),
                Inverse::Gmres(pc, _) | Inverse::Bicgstab(pc, _) => pc.solve_into(v, z),
            }
            if let Some(block) = &block {
                block.correct(replaced, v, z);
            }
        };
        let out = gmres::solve_gmres_with(apply, &b, precondition, limits, watch);
        if !matches!(out.status, gmres::Status::Converged) {
            return Err(self.not_converged(out.iterations, out.relative_residual, tolerance));
        }
        let y = unscaled(out.x, exponent)?;
        let note = format!(
            "gmres preconditioned by {} with {} rows replaced: {} iterations, relative residual {:.1e}",
            self.method,
            replaced.len(),
            out.iterations,
            out.relative_residual
        );
        Ok((y, note))
    }

    fn not_converged(&self, iterations: usize, relative_residual: f64, tolerance: f64) -> SolveError {
        SolveError::NoConvergence {
            hint: IN_PROCESS_HINT,
            limit: "the iteration limit or stagnation".into(),
            restarts: 0,
            iterations,
            relative_residual,
            method: format!("{} (reused)", self.method),
            tolerance,
        }
    }
}

/// The square block `M_CC` of replaced rows `C` (their columns among the same
/// indices), factorised: after the kept inverse `z = (D A)^-1 v`, the replaced rows'
/// residual is solved on their own unknowns, `z_C += M_CC^-1 (v - M z)_C` (one block
/// Gauss-Seidel step). The kept inverse knows nothing of the replaced rows; without
/// this step GMRES took 18 iterations where `D A` takes 4, with it 2 (the steel
/// plate's 400 corner rows, `models::navier::corner_defect`).
struct ReplacedBlock {
    lu: lu::SparseLu,
}

impl ReplacedBlock {
    /// The factorised block, or `None` when it is singular.
    fn new(replaced: &[(usize, Vec<(u32, f64)>)]) -> Option<Self> {
        let index: std::collections::HashMap<usize, usize> = replaced.iter().enumerate().map(|(a, (r, _))| (*r, a)).collect();
        let mut t = super::Triplets::new(replaced.len());
        for (a, (_, entries)) in replaced.iter().enumerate() {
            for &(col, v) in entries {
                if let Some(&b) = index.get(&(col as usize)) {
                    t.push(a, b, v);
                }
            }
        }
        let lu = lu::SparseLu::factor(&super::assemble(&t).ok()?).ok()?;
        Some(ReplacedBlock { lu })
    }

    /// `z_C += M_CC^-1 (v - M z)_C`.
    fn correct(&self, replaced: &[(usize, Vec<(u32, f64)>)], v: &[f64], z: &mut [f64]) {
        let residual: Vec<f64> =
            replaced.iter().map(|(r, entries)| v[*r] - entries.iter().map(|&(col, a)| a * z[col as usize]).sum::<f64>()).collect();
        for ((r, _), d) in replaced.iter().zip(self.lu.solve(&residual)) {
            z[*r] += d;
        }
    }
}

#[cfg(test)]
#[path = "retained_tests.rs"]
mod tests;
