//! Compressed-row matrices for parallel products `y += A x`, one task per row (the
//! explicit time loops apply their operators this way).

use super::SolveError;
use faer::sparse::{SparseRowMat, Triplet};
use rayon::prelude::*;

/// A sparse matrix in compressed sparse row (CSR) form.
pub type RowMatrix = SparseRowMat<usize, f64>;

/// The `nrows x ncols` matrix with `entries` `(row, column, value)`; duplicates are summed.
pub fn row_matrix(nrows: usize, ncols: usize, entries: &[(usize, usize, f64)]) -> Result<RowMatrix, SolveError> {
    let t: Vec<Triplet<usize, usize, f64>> = entries.iter().map(|&(r, c, v)| Triplet::new(r, c, v)).collect();
    RowMatrix::try_new_from_triplets(nrows, ncols, &t)
        .map_err(|e| SolveError::Dimension { detail: format!("{nrows} x {ncols} matrix: {e:?}") })
}

/// `y += A x`, each row summed in column order.
pub fn mul_add(a: &RowMatrix, x: &[f64], y: &mut [f64]) {
    let (ptr, idx, val) = (a.symbolic().row_ptr(), a.symbolic().col_idx(), a.val());
    y.par_iter_mut().enumerate().for_each(|(r, y)| {
        *y += (ptr[r]..ptr[r + 1]).map(|k| val[k] * x[idx[k]]).sum::<f64>();
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_sums_duplicates_and_adds_to_y() {
        let a = row_matrix(2, 3, &[(0, 2, 1.0), (0, 0, 2.0), (1, 1, 3.0), (0, 2, 0.5)]).unwrap();
        let mut y = vec![1.0, 1.0];
        mul_add(&a, &[1.0, 2.0, 4.0], &mut y);
        assert_eq!(y, vec![1.0 + 2.0 + 6.0, 1.0 + 6.0]);
    }
}
