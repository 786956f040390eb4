//! Row equilibration (diagonal row scaling) of `A x = b`.
//!
//! Collocation rows mix second-derivative (`~1/h²`), first-derivative
//! (`~1/h`) and identity (`~1`) equations. Scaling row `i` by
//! `d_i = 1 / max_j |a_ij|` (the row-scaling half of the equilibration in
//! LAPACK `xGEEQU`; Golub & Van Loan, *Matrix Computations*, 4th ed., §3.5.2)
//! makes every row's largest entry `±1`. The sign of `d_i` makes the diagonal entry
//! `a_ii` positive (a Navier row's own coefficient is negative, a displacement row's
//! positive): pivoting and ILU do not care, but smoothed aggregation sums rows over
//! an aggregate, and rows of opposite signs there cancel into coarse operators that
//! Gauss–Seidel cannot smooth (it diverged by 1e38 in one sweep on the cantilever).
//! The solution is unchanged (`D A x = D b ⇔ A x = b` for nonsingular diagonal `D`),
//! but pivoting in LU, ILU drop tolerances and the Krylov residual all see
//! comparable rows.

use super::csr::Csr;
use super::SolveError;

/// `max_j |a_ij|` for every row `i`, validating the matrix on the way.
///
/// Errors: [`SolveError::NotFinite`] for a NaN/inf entry,
/// [`SolveError::Singular`] for a row or column whose stored entries are all
/// zero (an equation constraining nothing, or an unknown appearing in no
/// equation — the matrix is singular either way).
pub fn row_max_abs(a: &Csr) -> Result<Vec<f64>, SolveError> {
    let mut row_max = vec![0.0f64; a.nrows()];
    let mut col_max = vec![0.0f64; a.ncols()];
    for (i, m) in row_max.iter_mut().enumerate() {
        let row = a.row(i);
        for (&j, &v) in row.col_indices().iter().zip(row.values()) {
            let j = j as usize;
            if !v.is_finite() {
                return Err(SolveError::NotFinite { row: i, col: j, value: v });
            }
            *m = m.max(v.abs());
            col_max[j] = col_max[j].max(v.abs());
        }
    }
    if let Some(j) = col_max.iter().position(|&m| m == 0.0) {
        return Err(SolveError::Singular {
            detail: format!(
                "column {j} of the matrix is entirely zero: unknown {j} appears in no \
                 equation; check that every node's displacement enters some stencil"
            ),
        });
    }
    if let Some(i) = row_max.iter().position(|&m| m == 0.0) {
        return Err(SolveError::Singular {
            detail: format!(
                "row {i} of the matrix is entirely zero: equation {i} constrains nothing; \
                 check that every node received a collocation or boundary-condition equation"
            ),
        });
    }
    Ok(row_max)
}

/// Row-equilibrate `A`: returns `(D A, d)` with `d_i = ±1 / max_j |a_ij|`, the sign
/// that of `a_ii` (`+` when `a_ii = 0`).
/// Scale the right-hand side with [`scale_rhs`]. Errors as [`row_max_abs`].
pub fn equilibrate_rows(a: &Csr) -> Result<(Csr, Vec<f64>), SolveError> {
    let row_max = row_max_abs(a)?;
    let d = row_scales(a, &row_max);
    let mut s = a.clone();
    s.scale_rows(&d);
    Ok((s, d))
}

/// The row scales `d_i = ±1 / max_j |a_ij|` of [`equilibrate_rows`], from the row
/// maxima of [`row_max_abs`].
pub fn row_scales(a: &Csr, row_max: &[f64]) -> Vec<f64> {
    (0..a.nrows()).map(|i| row_scale(row_max[i], a.diagonal(i))).collect()
}

/// The scale `d_i = ±1 / max_j |a_ij|` of a row, its sign that of the diagonal entry
/// (module docs).
pub fn row_scale(row_max: f64, diagonal: f64) -> f64 {
    if diagonal < 0.0 {
        -1.0 / row_max
    } else {
        1.0 / row_max
    }
}

/// `D b`, i.e. `b_i · d_i`.
pub fn scale_rhs(b: &[f64], d: &[f64]) -> Vec<f64> {
    b.iter().zip(d).map(|(bi, di)| bi * di).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_get_unit_max_and_zero_rows_are_singular() {
        let a = Csr::from_triplets(3, 3, &[(0, 0, -4e12), (0, 1, 1e12), (1, 1, 2e-12), (2, 2, 3.0), (2, 0, -6.0)]);
        let (s, d) = equilibrate_rows(&a).unwrap();
        // Division by a power of two or a single rounding: 1 ulp-level.
        assert!((d[0] + 0.25e-12).abs() < 1e-27, "a_00 < 0 flips the row: {}", d[0]);
        for i in 0..3 {
            assert!(s.diagonal(i) > 0.0, "diagonal {i} of D A is positive");
            let m = s.row(i).values().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!((m - 1.0).abs() < 1e-15, "row max {m}");
        }

        let a = Csr::from_triplets(2, 2, &[(0, 0, 1.0), (0, 1, 1.0), (1, 1, 0.0)]); // (1, 1) stored, but zero
        match equilibrate_rows(&a) {
            Err(SolveError::Singular { detail }) => assert!(detail.contains("row 1"), "{detail}"),
            other => panic!("expected Singular, got {other:?}"),
        }
    }
}
