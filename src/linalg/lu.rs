//! Sparse direct LU (faer) with a-posteriori checks of the solution.

use super::{norm2, SolveError, SparseMatrix, LU_RESIDUAL_LIMIT};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::Lu;
use faer::sparse::linalg::LuError;

/// If `‖A‖_∞ ‖x‖_∞ / ‖b‖_∞` — a lower bound on the condition number
/// `κ_∞(A)`, since `‖b‖ = ‖A x‖ ≥ ‖x‖ / ‖A⁻¹‖` — exceeds this, the matrix is
/// treated as numerically singular: at `κ ≳ 1e14` double precision leaves at
/// most ~2 correct digits, and such an `x` is typically a consistent solution
/// polluted by a huge null-space (e.g. rigid-body) component.
pub const CONDITION_LIMIT: f64 = 1e14;

/// Sparse LU factorisation `P A Q = L U` with partial (row) pivoting and a
/// fill-reducing COLAMD column ordering, from `faer::sparse::linalg::solvers`
/// (supernodal or simplicial, chosen by faer). Uses faer's global parallelism.
pub struct SparseLu {
    lu: Lu<usize, f64>,
    n: usize,
}

impl SparseLu {
    /// Symbolic + numeric factorisation of `a`.
    ///
    /// A structurally singular matrix (no nonzero pivot candidate at some
    /// step) is [`SolveError::Singular`]. A *numerically* zero pivot is not
    /// detected here; it shows up as a non-finite or inaccurate solution in
    /// [`check_solution`].
    pub fn factor(a: &SparseMatrix) -> Result<Self, SolveError> {
        let lu = a.as_ref().sp_lu().map_err(|e| match e {
            LuError::SymbolicSingular { index } => SolveError::Singular {
                detail: format!(
                    "sparse LU found no usable pivot at elimination step {index} (structurally \
                     singular matrix). Check the boundary conditions: every unknown needs an \
                     equation, and a pure-traction problem has rigid-body modes unless \
                     displacements are fixed somewhere"
                ),
            },
            LuError::Generic(e) => SolveError::Dimension {
                detail: format!("sparse LU could not run ({e:?}); the problem is too large"),
            },
        })?;
        Ok(SparseLu { lu, n: a.nrows() })
    }

    /// `x = A⁻¹ b` by forward/backward substitution. No checks; see
    /// [`check_solution`].
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        assert_eq!(b.len(), self.n, "right-hand side length");
        let mut x = faer::Col::<f64>::from_fn(self.n, |i| b[i]);
        self.lu.solve_in_place(x.as_mat_mut());
        x.iter().copied().collect()
    }
}

/// Reject an LU "solution" that is not trustworthy.
///
/// * any NaN/inf in `x` (a zero pivot was divided by),
/// * `relres` (the true relative residual of the *original* system) above
///   [`LU_RESIDUAL_LIMIT`] — a backward-stable LU gives `~ε κ`, so this means
///   `κ ≳ 1e10`-ish garbage,
/// * `‖A‖_∞ ‖x‖_∞ / ‖b‖_∞ > ` [`CONDITION_LIMIT`] on the system that was
///   factorised (`a`, `b`, possibly row-scaled).
///
/// Each failure is [`SolveError::Singular`] with the numbers and a hint about
/// boundary conditions.
pub fn check_solution(a: &SparseMatrix, x: &[f64], b: &[f64], relres: f64) -> Result<(), SolveError> {
    const HINT: &str = "check the boundary conditions (a pure-traction problem has rigid-body \
                        modes; every node needs exactly one equation per displacement component)";
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(SolveError::Singular {
            detail: format!(
                "sparse LU produced a non-finite solution (entry {i} = {}), i.e. a zero pivot; {HINT}",
                x[i]
            ),
        });
    }
    if relres.is_nan() || relres > LU_RESIDUAL_LIMIT {
        return Err(SolveError::Singular {
            detail: format!(
                "sparse LU solution has true relative residual {relres:.2e} (limit \
                 {LU_RESIDUAL_LIMIT:e}), so the matrix is numerically singular; {HINT}"
            ),
        });
    }
    let b_inf = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if b_inf > 0.0 {
        let mut row_sum = vec![0.0f64; a.nrows()];
        for j in 0..a.ncols() {
            for (&i, &v) in a.symbolic().row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                row_sum[i] += v.abs();
            }
        }
        let a_inf = row_sum.iter().fold(0.0f64, |m, v| m.max(*v));
        let x_inf = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let kappa_lower = a_inf * x_inf / b_inf;
        if kappa_lower > CONDITION_LIMIT {
            return Err(SolveError::Singular {
                detail: format!(
                    "condition number is at least {kappa_lower:.1e} (‖A‖‖x‖/‖b‖), so the \
                     solution (‖x‖₂ = {:.1e}) is dominated by round-off; {HINT}",
                    norm2(x)
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::{assemble, relative_residual, Triplets};
    use super::*;

    #[test]
    fn small_nonsymmetric_system_is_solved_exactly() {
        // [[4, 1, 0], [2, 5, -1], [0, -3, 6]] x = b with x = (1, -2, 3).
        let mut t = Triplets::new(3);
        for &(i, j, v) in &[
            (0, 0, 4.0),
            (0, 1, 1.0),
            (1, 0, 2.0),
            (1, 1, 5.0),
            (1, 2, -1.0),
            (2, 1, -3.0),
            (2, 2, 6.0),
        ] {
            t.push(i, j, v);
        }
        let a = assemble(&t).unwrap();
        let b = [2.0, -11.0, 24.0];
        let lu = SparseLu::factor(&a).unwrap();
        let x = lu.solve(&b);
        // 3x3 well-conditioned (κ ~ 5): a few ulps.
        for (xi, ei) in x.iter().zip([1.0, -2.0, 3.0]) {
            assert!((xi - ei).abs() < 1e-14, "{x:?}");
        }
        let r = relative_residual(&a, &x, &b);
        assert!(r < 1e-15);
        check_solution(&a, &x, &b, r).unwrap();
    }
}
