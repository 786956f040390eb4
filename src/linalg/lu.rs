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
/// (supernodal or simplicial, chosen by faer). Runs sequentially: results then do
/// not depend on the thread count, and two threads gave no gain here
/// (`../shared/docs/crates.md`).
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
        faer::set_global_parallelism(faer::Par::Seq);
        let lu = a.as_ref().sp_lu().map_err(|e| match e {
            LuError::SymbolicSingular { index } => SolveError::Singular {
                detail: format!(
                    "sparse LU found no usable pivot at elimination step {index} (structurally \
                     singular matrix). Check the boundary conditions: every unknown needs an \
                     equation, and a pure-traction problem has rigid-body modes unless \
                     displacements are fixed somewhere"
                ),
            },
            LuError::Generic(e) => SolveError::Dimension { detail: format!("sparse LU could not run ({e:?}); the problem is too large") },
        })?;
        super::vector_state::clear_upper_halves_everywhere();
        Ok(SparseLu { lu, n: a.nrows() })
    }

    /// `x = A⁻¹ b` by forward/backward substitution. No checks; see
    /// [`check_solution`].
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        self.solve_impl(b, false)
    }

    /// `x = A⁻ᵀ b`.
    pub fn solve_transpose(&self, b: &[f64]) -> Vec<f64> {
        self.solve_impl(b, true)
    }

    fn solve_impl(&self, b: &[f64], transpose: bool) -> Vec<f64> {
        assert_eq!(b.len(), self.n, "right-hand side length");
        let mut x = faer::Col::<f64>::from_fn(self.n, |i| b[i]);
        if transpose {
            self.lu.solve_transpose_in_place(x.as_mat_mut());
        } else {
            self.lu.solve_in_place(x.as_mat_mut());
        }
        super::vector_state::clear_upper_halves();
        x.iter().copied().collect()
    }

    /// Estimate of `κ₁(A) = ‖A‖₁ ‖A⁻¹‖₁` for the factorised `a`, by Hager's
    /// method as refined by Higham (N. J. Higham, *ACM TOMS* 14 (1988)
    /// 381–396, Alg. 4.1 = LAPACK `xLACON`): at most 5 power-like steps with
    /// `A⁻¹` and `A⁻ᵀ` plus the alternating-sign test vector. Each step is one
    /// LU solve. The `‖A⁻¹‖₁` part is a lower bound, almost always within a
    /// factor 3 of the truth. Returns `inf` if a solve produces NaN/inf.
    pub fn condition_estimate_1(&self, a: &SparseMatrix) -> f64 {
        let n = self.n;
        if n == 0 {
            return 0.0;
        }
        let a_norm1 = (0..n).map(|j| a.val_of_col(j).iter().map(|v| v.abs()).sum::<f64>()).fold(0.0f64, f64::max);
        let norm1 = |v: &[f64]| v.iter().map(|x| x.abs()).sum::<f64>();
        let sign = |v: &[f64]| -> Vec<f64> { v.iter().map(|&x| if x >= 0.0 { 1.0 } else { -1.0 }).collect() };
        let mut y = self.solve(&vec![1.0 / n as f64; n]);
        let mut est = norm1(&y);
        if n > 1 {
            let mut xi = sign(&y);
            let mut z = self.solve_transpose(&xi);
            let mut j_prev = None;
            for _ in 0..5 {
                if !est.is_finite() || z.iter().any(|v| !v.is_finite()) {
                    return f64::INFINITY;
                }
                let j = (0..n).max_by(|&p, &q| z[p].abs().total_cmp(&z[q].abs())).unwrap_or(0);
                if j_prev == Some(j) {
                    break;
                }
                j_prev = Some(j);
                let mut e = vec![0.0; n];
                e[j] = 1.0;
                y = self.solve(&e);
                let new_est = norm1(&y);
                let new_xi = sign(&y);
                if new_xi == xi || new_est <= est {
                    est = est.max(new_est);
                    break;
                }
                est = new_est;
                xi = new_xi;
                z = self.solve_transpose(&xi);
            }
            // Alternating-sign vector guards against the power steps missing
            // the dominant direction.
            let alt: Vec<f64> = (0..n)
                .map(|i| {
                    let s = if i % 2 == 0 { 1.0 } else { -1.0 };
                    s * (1.0 + i as f64 / (n - 1) as f64)
                })
                .collect();
            est = est.max(2.0 * norm1(&self.solve(&alt)) / (3.0 * n as f64));
        }
        if est.is_finite() {
            a_norm1 * est
        } else {
            f64::INFINITY
        }
    }
}

/// Reject an LU "solution" that is not trustworthy. `a`, `b` are the system
/// that was factorised (possibly row-scaled), `relres` the true relative
/// residual of the *original* system. Failures, each
/// [`SolveError::Singular`] with the numbers and a boundary-condition hint:
///
/// * any NaN/inf in `x` (a zero pivot was divided by);
/// * `relres` above [`LU_RESIDUAL_LIMIT`] (backward-stable LU gives `~ε κ`,
///   so this means a numerically singular matrix and an inconsistent `b`);
/// * `‖A‖_∞ ‖x‖_∞ / ‖b‖_∞` (a lower bound on `κ_∞`) or the Hager–Higham
///   estimate of `κ₁` ([`SparseLu::condition_estimate_1`]) above
///   [`CONDITION_LIMIT`]. This catches a singular but *consistent* system
///   (e.g. a pure-traction problem with self-equilibrated loads), for which LU
///   returns a small residual but an arbitrary rigid-body component.
///
/// Returns the κ₁ estimate of an accepted solution.
pub fn check_solution(lu: &SparseLu, a: &SparseMatrix, x: &[f64], b: &[f64], relres: f64) -> Result<f64, SolveError> {
    const HINT: &str = "check the boundary conditions (a pure-traction problem has rigid-body \
                        modes; every node needs exactly one equation per displacement component)";
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(SolveError::Singular {
            detail: format!("sparse LU produced a non-finite solution (entry {i} = {}), i.e. a zero pivot; {HINT}", x[i]),
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
    let too_ill = |kappa: f64, how: &str| SolveError::Singular {
        detail: format!(
            "{how} {kappa:.1e} exceeds {CONDITION_LIMIT:e}: the matrix is singular to working \
             precision and the solution (‖x‖₂ = {:.1e}) is not determined by the data; {HINT}. \
             If equilibration is off and the rows have very different scales, turn it on",
            norm2(x)
        ),
    };
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
            return Err(too_ill(kappa_lower, "condition number is at least ‖A‖‖x‖/‖b‖ ="));
        }
    }
    let kappa = lu.condition_estimate_1(a);
    if kappa.is_nan() || kappa > CONDITION_LIMIT {
        return Err(too_ill(kappa, "estimated condition number κ₁(A) ≈"));
    }
    Ok(kappa)
}

#[cfg(test)]
mod tests {
    use super::super::{assemble, relative_residual, Triplets};
    use super::*;

    #[test]
    fn small_nonsymmetric_system_is_solved_exactly() {
        // [[4, 1, 0], [2, 5, -1], [0, -3, 6]] x = b with x = (1, -2, 3).
        let mut t = Triplets::new(3);
        for &(i, j, v) in &[(0, 0, 4.0), (0, 1, 1.0), (1, 0, 2.0), (1, 1, 5.0), (1, 2, -1.0), (2, 1, -3.0), (2, 2, 6.0)] {
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
        check_solution(&lu, &a, &x, &b, r).unwrap();
        // Exact κ₁ = ‖A‖₁ ‖A⁻¹‖₁ = 9 · 45/96 = 4.21875 (det A = 96, by hand).
        // The estimate is a lower bound (up to rounding), in practice within a
        // factor 3 (Higham 1988).
        let k = lu.condition_estimate_1(&a);
        assert!((4.21875 / 3.0..=4.21875 * (1.0 + 1e-12)).contains(&k), "κ₁ estimate {k}");
    }
}
