//! Sparse matrix-matrix product `C = A B` of compressed-row matrices, rows in
//! parallel (Gustavson's row-by-row algorithm): row `i` of `C` is
//! `sum_k a_ik (row k of B)`, accumulated in a dense row with a marker per column.
//!
//! Why written here: the multigrid setup forms six products per level (`A T`,
//! `D (A T)`, `Tᵀ A`, `(Tᵀ A) D`, `R A`, `(R A) P`); nalgebra-sparse's product is
//! serial and was most of the 10 s setup at 1e6 nodes. sprs has a parallel product,
//! but every operand would have to be copied into its format and back.

use nalgebra_sparse::CsrMatrix;
use rayon::prelude::*;

/// Rows handed to one task: large enough to amortise the task, small enough to
/// balance two to a few dozen threads.
const ROWS_PER_TASK: usize = 2048;

/// `A B` (dimensions must agree: `a.ncols() == b.nrows()`, checked). Columns come out
/// sorted within each row; products that cancel to zero are kept as stored zeros.
/// Two passes over the rows: the pattern's row lengths, then the entries written in
/// place, so that the result is held once (a single pass collecting per-task parts
/// held it twice: +0.4 GB at 1e6 nodes).
pub fn product(a: &CsrMatrix<f64>, b: &CsrMatrix<f64>) -> CsrMatrix<f64> {
    assert_eq!(a.ncols(), b.nrows(), "sparse product of a {}x{} and a {}x{} matrix", a.nrows(), a.ncols(), b.nrows(), b.ncols());
    let (n, m) = (a.nrows(), b.ncols());
    let tasks = n.div_ceil(ROWS_PER_TASK);
    let rows_of = |task: usize| task * ROWS_PER_TASK..n.min((task + 1) * ROWS_PER_TASK);
    // Pass 1: the number of distinct columns of each row.
    let lengths: Vec<Vec<usize>> = (0..tasks)
        .into_par_iter()
        .map_init(
            || vec![usize::MAX; m],
            |mark, task| {
                rows_of(task)
                    .map(|i| {
                        let mut count = 0;
                        for &k in a.row(i).col_indices() {
                            for &j in b.row(k).col_indices() {
                                if mark[j] != i {
                                    mark[j] = i;
                                    count += 1;
                                }
                            }
                        }
                        count
                    })
                    .collect()
            },
        )
        .collect();
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0usize);
    for len in lengths.iter().flatten() {
        offsets.push(offsets[offsets.len() - 1] + len);
    }
    drop(lengths);
    let nnz = offsets[n];
    let (mut cols, mut vals) = (vec![0usize; nnz], vec![0.0f64; nnz]);
    // Each task's slice of the result.
    let mut slices = Vec::with_capacity(tasks);
    let (mut rest_c, mut rest_v) = (cols.as_mut_slice(), vals.as_mut_slice());
    for task in 0..tasks {
        let rows = rows_of(task);
        let len = offsets[rows.end] - offsets[rows.start];
        let (c, rc) = rest_c.split_at_mut(len);
        let (v, rv) = rest_v.split_at_mut(len);
        slices.push((rows, c, v));
        (rest_c, rest_v) = (rc, rv);
    }
    // Pass 2: accumulate each row densely, write its sorted columns and values.
    slices.into_par_iter().for_each_init(
        || (vec![usize::MAX; m], vec![0.0f64; m]),
        |(mark, dense), (rows, c, v)| {
            let base = offsets[rows.start];
            for i in rows {
                let (start, end) = (offsets[i] - base, offsets[i + 1] - base);
                let mut next = start;
                let row = a.row(i);
                for (&k, &aik) in row.col_indices().iter().zip(row.values()) {
                    let brow = b.row(k);
                    for (&j, &bkj) in brow.col_indices().iter().zip(brow.values()) {
                        if mark[j] != i {
                            mark[j] = i;
                            dense[j] = aik * bkj;
                            c[next] = j;
                            next += 1;
                        } else {
                            dense[j] += aik * bkj;
                        }
                    }
                }
                debug_assert_eq!(next, end);
                c[start..end].sort_unstable();
                for k in start..end {
                    v[k] = dense[c[k]];
                }
            }
        },
    );
    CsrMatrix::try_from_csr_data(n, m, offsets, cols, vals).expect("rows built sorted and without duplicates")
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::CooMatrix;

    /// A pseudo-random `n x m` sparse matrix with about `per_row` entries per row
    /// (duplicates summed, some rows empty).
    fn random(n: usize, m: usize, per_row: usize, seed: u64) -> CsrMatrix<f64> {
        let mut state = seed;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        let mut coo = CooMatrix::new(n, m);
        for i in 0..n {
            if i % 7 == 3 {
                continue;
            }
            for _ in 0..per_row {
                coo.push(i, next() % m, (next() % 2000) as f64 / 1000.0 - 1.0);
            }
        }
        CsrMatrix::from(&coo)
    }

    /// Against nalgebra-sparse's serial product, on shapes that span several tasks
    /// (5000 rows: three tasks) and rectangular factors: the same pattern, the same
    /// values to round-off (1e-14; both sum each entry's products in column order of
    /// A's row, but nalgebra may fuse differently).
    #[test]
    fn matches_the_serial_product() {
        for (n, k, m) in [(5000, 3000, 4000), (7, 5, 3), (1, 1, 1), (2100, 700, 40)] {
            let (a, b) = (random(n, k, 6, 1 + n as u64), random(k, m, 5, 7 + m as u64));
            let (fast, slow) = (product(&a, &b), &a * &b);
            assert_eq!(fast.row_offsets(), slow.row_offsets(), "{n}x{k}x{m}: pattern");
            assert_eq!(fast.col_indices(), slow.col_indices(), "{n}x{k}x{m}: columns");
            let worst = fast.values().iter().zip(slow.values()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-14, "{n}x{k}x{m}: values differ by {worst:e}");
        }
    }
}
