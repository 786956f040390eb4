//! Sparse matrix-matrix product `C = A B` of compressed-row matrices, rows in
//! parallel (Gustavson's row-by-row algorithm): row `i` of `C` is
//! `sum_k a_ik (row k of B)`, accumulated in a dense row with a marker per column.
//!
//! Why written here: the multigrid setup forms six products per level (`A T`,
//! `D (A T)`, `Tᵀ A`, `(Tᵀ A) D`, and `R A P` fused); nalgebra-sparse's product is
//! serial and was most of the setup at 1e6 nodes (docs/notebook/round2-gmres-amg-against-lu.md,
//! "Parallel sparse products in the multigrid setup"). sprs has a parallel product,
//! but every operand would have to be copied into its format and back.

use super::csr::{Csr, Value};
use rayon::prelude::*;

/// Rows handed to one task: large enough to amortise the task, small enough to
/// balance two to a few dozen threads.
const ROWS_PER_TASK: usize = 2048;

/// A row accumulator over `m` columns: a dense row with a marker per column (the
/// row that last touched it) and the list of the columns touched.
struct Accumulator {
    mark: Vec<usize>,
    dense: Vec<f64>,
    touched: Vec<usize>,
}

impl Accumulator {
    fn new(m: usize) -> Self {
        Accumulator { mark: vec![usize::MAX; m], dense: vec![0.0; m], touched: Vec::new() }
    }

    /// Start row `i`.
    fn start(&mut self) {
        self.touched.clear();
    }

    /// Add `value` at column `j` of row `i`.
    fn add(&mut self, i: usize, j: usize, value: f64) {
        if self.mark[j] != i {
            self.mark[j] = i;
            self.dense[j] = value;
            self.touched.push(j);
        } else {
            self.dense[j] += value;
        }
    }

    /// Accumulate `sum_k x_k (row k of b)` for the entries `(k, x_k)` of `row` into row
    /// `i`, in double precision whatever the operands store.
    fn add_rows<X: Value, B: Value>(&mut self, i: usize, cols: &[u32], vals: &[X], b: &Csr<B>) {
        for (&k, &x) in cols.iter().zip(vals) {
            let brow = b.row(k as usize);
            for (&j, &bkj) in brow.col_indices().iter().zip(brow.values()) {
                self.add(i, j as usize, x.to_f64() * bkj.to_f64());
            }
        }
    }

    /// The touched columns sorted, and their values.
    fn sorted(&mut self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.touched.sort_unstable();
        self.touched.iter().map(|&j| (j, self.dense[j]))
    }
}

/// The `n x m` matrix whose row `i` the accumulators `row(i, scratch)` build, rows in
/// parallel: every row formed once into its task's part, the parts then concatenated,
/// so the result is held twice while they are copied. Forming every row twice instead
/// (its length, then its entries in place) held it once, but made the multigrid setup
/// slower for the same peak of the run: the transfers are not its peak
/// (docs/notebook/2026-11-26-up-form-iterative-solvers.md, "Sparse products formed in
/// one pass").
fn rows_of_products<S: Send, V: Value>(
    n: usize,
    m: usize,
    scratch: impl Fn() -> S + Sync + Send,
    row: impl Fn(usize, &mut S) -> &mut Accumulator + Sync + Send,
) -> Csr<V> {
    let tasks = n.div_ceil(ROWS_PER_TASK);
    let parts: Vec<(Vec<usize>, Vec<u32>, Vec<V>)> = (0..tasks)
        .into_par_iter()
        .map_init(&scratch, |s, task| {
            let rows = task * ROWS_PER_TASK..n.min((task + 1) * ROWS_PER_TASK);
            let (mut lengths, mut cols, mut vals) = (Vec::with_capacity(rows.len()), Vec::new(), Vec::new());
            for i in rows {
                let before = cols.len();
                for (j, x) in row(i, s).sorted() {
                    cols.push(j as u32);
                    vals.push(V::from_f64(x));
                }
                lengths.push(cols.len() - before);
            }
            (lengths, cols, vals)
        })
        .collect();
    let nnz = parts.iter().map(|p| p.1.len()).sum();
    let (mut offsets, mut cols, mut vals) = (Vec::with_capacity(n + 1), Vec::with_capacity(nnz), Vec::with_capacity(nnz));
    offsets.push(0usize);
    for (lengths, c, v) in parts {
        for len in lengths {
            offsets.push(offsets[offsets.len() - 1] + len);
        }
        cols.extend(c);
        vals.extend(v);
    }
    // Rows built sorted and without duplicates.
    Csr::from_parts(n, m, offsets, cols, vals)
}

/// `A B` (dimensions must agree: `a.ncols() == b.nrows()`, checked). Columns come out
/// sorted within each row; products that cancel to zero are kept as stored zeros.
pub fn product(a: &Csr, b: &Csr) -> Csr {
    assert_eq!(a.ncols(), b.nrows(), "sparse product of a {}x{} and a {}x{} matrix", a.nrows(), a.ncols(), b.nrows(), b.ncols());
    rows_of_products(
        a.nrows(),
        b.ncols(),
        || Accumulator::new(b.ncols()),
        |i, acc| {
            acc.start();
            let row = a.row(i);
            acc.add_rows(i, row.col_indices(), row.values(), b);
            acc
        },
    )
}

/// `base + scale (A B) C` (no base: `scale (A B) C`), rows in parallel, each row of
/// `A B` formed in one accumulator and at once multiplied into `C`, the sums in double
/// and stored as `V`.
fn plus_triple<V: Value, VB: Value, VA: Value, VC: Value>(
    (base, scale): (Option<&Csr<VB>>, f64),
    a: &Csr<VA>,
    b: &Csr,
    c: &Csr<VC>,
) -> Csr<V> {
    assert_eq!(a.ncols(), b.nrows(), "sparse product of a {}x{} and a {}x{} matrix", a.nrows(), a.ncols(), b.nrows(), b.ncols());
    assert_eq!(b.ncols(), c.nrows(), "sparse product of a {}x{} and a {}x{} matrix", b.nrows(), b.ncols(), c.nrows(), c.ncols());
    if let Some(base) = base {
        assert_eq!((base.nrows(), base.ncols()), (a.nrows(), c.ncols()), "the base must have the shape of the product");
    }
    rows_of_products(
        a.nrows(),
        c.ncols(),
        || (Accumulator::new(b.ncols()), Accumulator::new(c.ncols()), Vec::new(), Vec::new()),
        |i, (ab, abc, cols, vals)| {
            abc.start();
            if let Some(base) = base {
                let own = base.row(i);
                for (&j, &x) in own.col_indices().iter().zip(own.values()) {
                    abc.add(i, j as usize, x.to_f64());
                }
            }
            ab.start();
            let row = a.row(i);
            ab.add_rows(i, row.col_indices(), row.values(), b);
            cols.clear();
            vals.clear();
            for (j, x) in ab.sorted() {
                cols.push(j as u32);
                vals.push(scale * x);
            }
            abc.add_rows(i, cols, vals, c);
            abc
        },
    )
}

/// `(A B) C` without holding `A B`: each row of `A B` is formed in one accumulator and
/// at once multiplied into the next. The multigrid's coarse operator `R A P` this way
/// never holds `R A`, whose rows reach two stencils around an aggregate: it was the
/// peak of the whole run (docs/notebook/round2-target-error.md, "One copy of the
/// matrix in the solve"). `A` and `C` may be
/// stored in single precision (the multigrid's transfers); the sums are in double.
pub fn triple_product<VA: Value, VC: Value>(a: &Csr<VA>, b: &Csr, c: &Csr<VC>) -> Csr {
    plus_triple((None::<&Csr>, 1.0), a, b, c)
}

/// `base − ω (A B C)` in single precision, without holding `A B`, `A B C` or any
/// double-precision copy: each row is `base`'s row plus `−ω` times the row of `A B`
/// (formed in one accumulator) multiplied into `C`, summed in double and rounded
/// once. The multigrid's smoothed transfers are of this form:
/// `P = T − ω (D⁻¹ A) T` and `R = Tᵀ − ω (Tᵀ A) D⁻¹`; formed by separate products
/// they held `A T`, `D⁻¹ A T` and `P` in double at once, the peak of the run
/// (docs/notebook/2026-11-26-up-form-iterative-solvers.md, "The smoothed transfers in
/// one fused product").
pub fn smoothed<VB: Value>(base: &Csr<VB>, omega: f64, a: &Csr, b: &Csr, c: &Csr) -> Csr<f32> {
    plus_triple((Some(base), -omega), a, b, c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra_sparse::{CooMatrix, CsrMatrix};

    /// A pseudo-random `n x m` sparse matrix with about `per_row` entries per row
    /// (duplicates summed, some rows empty), as nalgebra's and as ours.
    fn random(n: usize, m: usize, per_row: usize, seed: u64) -> (CsrMatrix<f64>, Csr) {
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
        let theirs = CsrMatrix::from(&coo);
        let (offsets, cols, vals) = theirs.clone().disassemble();
        (theirs, Csr::from_parts(n, m, offsets, cols.into_iter().map(|c| c as u32).collect(), vals))
    }

    /// Against nalgebra-sparse's serial product, on shapes that span several tasks
    /// (5000 rows: three tasks) and rectangular factors: the same pattern, the same
    /// values to round-off (1e-14; both sum each entry's products in column order of
    /// A's row, but nalgebra may fuse differently).
    #[test]
    fn matches_the_serial_product() {
        for (n, k, m) in [(5000, 3000, 4000), (7, 5, 3), (1, 1, 1), (2100, 700, 40)] {
            let ((na, a), (nb, b)) = (random(n, k, 6, 1 + n as u64), random(k, m, 5, 7 + m as u64));
            let (fast, slow) = (product(&a, &b), &na * &nb);
            assert_eq!(fast.row_offsets(), slow.row_offsets(), "{n}x{k}x{m}: pattern");
            assert!(fast.col_indices().iter().zip(slow.col_indices()).all(|(&x, &y)| x as usize == y), "{n}x{k}x{m}: columns");
            let worst = fast.values().iter().zip(slow.values()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-14, "{n}x{k}x{m}: values differ by {worst:e}");
        }
    }

    /// The fused triple product has the pattern of the two products in turn and their
    /// values to round-off (the same sums in the same order: 1e-14 is generous).
    #[test]
    fn triple_product_matches_two_products() {
        for (n, k, l, m) in [(3000, 5000, 2500, 400), (7, 5, 4, 3), (1, 1, 1, 1)] {
            let (a, b, c) = (random(n, k, 6, 3 + n as u64).1, random(k, l, 5, 5 + l as u64).1, random(l, m, 4, 11 + m as u64).1);
            let (fused, staged) = (triple_product(&a, &b, &c), product(&product(&a, &b), &c));
            assert_eq!(fused.row_offsets(), staged.row_offsets(), "{n}x{k}x{l}x{m}: pattern");
            assert_eq!(fused.col_indices(), staged.col_indices(), "{n}x{k}x{l}x{m}: columns");
            let worst = fused.values().iter().zip(staged.values()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-14, "{n}x{k}x{l}x{m}: values differ by {worst:e}");
        }
    }

    /// `base − ω A B C` fused equals the staged products and difference, rounded once
    /// to single precision (relative 2^-24 of each entry's size, plus the round-off of
    /// sums that cancel: 1e-6 of the largest entry), on the union of the patterns.
    #[test]
    fn smoothed_matches_the_staged_difference() {
        for (n, k, l, m) in [(3000, 5000, 2500, 400), (7, 5, 4, 3)] {
            let (a, b, c) = (random(n, k, 6, 3 + n as u64).1, random(k, l, 5, 5 + l as u64).1, random(l, m, 4, 11 + m as u64).1);
            let base = random(n, m, 3, 17 + n as u64).1;
            let omega = 0.37;
            let fused = smoothed(&base, omega, &a, &b, &c);
            let staged = base.minus_scaled(omega, &triple_product(&a, &b, &c));
            assert_eq!(fused.row_offsets(), staged.row_offsets(), "{n}x{k}x{l}x{m}: pattern");
            assert_eq!(fused.col_indices(), staged.col_indices(), "{n}x{k}x{l}x{m}: columns");
            let largest = staged.values().iter().fold(0.0f64, |x, v| x.max(v.abs()));
            let worst = fused.values().iter().zip(staged.values()).map(|(x, y)| (f64::from(*x) - y).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-6 * largest, "{n}x{k}x{l}x{m}: values differ by {worst:e} of {largest:e}");
        }
    }
}
