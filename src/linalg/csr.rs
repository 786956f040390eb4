//! Compressed sparse rows with 32-bit column indices: the form GMRES and the
//! multigrid work on.
//!
//! Why not nalgebra-sparse's `CsrMatrix`: its `usize` column indices make a stored
//! entry 16 bytes; here it is 12: less memory at the solve's peak and a quarter less
//! memory traffic in every product and smoothing sweep, which bound the iteration's
//! time (docs/notebook/round2-target-error.md, "32-bit column indices"). faer's
//! `SparseRowMat<u32, _>` would also do, but its row pointers would be 32-bit too and
//! its API is built around views; the few operations the multigrid needs are written
//! here.

use super::SparseMatrix;
use rayon::prelude::*;

/// A value a [`Csr`] stores: `f64`, or `f32` where half the precision does (the
/// multigrid's transfers, [`Csr::into_single`]); arithmetic is in `f64` either way.
pub trait Value: Copy + Send + Sync + Default + std::fmt::Debug + PartialEq + 'static {
    /// The value in double precision (exact).
    fn to_f64(self) -> f64;
    /// A double rounded to this type.
    fn from_f64(x: f64) -> Self;
}

impl Value for f64 {
    fn to_f64(self) -> f64 {
        self
    }
    fn from_f64(x: f64) -> Self {
        x
    }
}

impl Value for f32 {
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    fn from_f64(x: f64) -> Self {
        x as f32
    }
}

/// A sparse matrix in compressed rows: row `i` holds the columns
/// `col_indices[offsets[i]..offsets[i + 1]]` (sorted, no duplicates) and their values.
#[derive(Clone, Debug, PartialEq)]
pub struct Csr<V: Value = f64> {
    nrows: usize,
    ncols: usize,
    offsets: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<V>,
}

/// One row of a [`Csr`].
#[derive(Clone, Copy, Debug)]
pub struct Row<'a, V = f64> {
    cols: &'a [u32],
    vals: &'a [V],
}

impl<'a, V> Row<'a, V> {
    /// Columns of the stored entries, sorted.
    pub fn col_indices(&self) -> &'a [u32] {
        self.cols
    }

    /// Values of the stored entries.
    pub fn values(&self) -> &'a [V] {
        self.vals
    }
}

impl<V: Value> Csr<V> {
    /// The matrix of the given compressed rows. Panics on inconsistent parts (the
    /// callers build them; a violation is a bug): `offsets` of length `nrows + 1`,
    /// non-decreasing, ending at the number of entries; columns below `ncols` (which
    /// must fit in 32 bits), sorted within each row.
    pub fn from_parts(nrows: usize, ncols: usize, offsets: Vec<usize>, cols: Vec<u32>, vals: Vec<V>) -> Self {
        assert!(ncols <= u32::MAX as usize + 1, "{ncols} columns do not fit 32-bit indices");
        assert_eq!(offsets.len(), nrows + 1, "row offsets");
        assert_eq!(offsets[nrows], cols.len(), "row offsets end at the number of entries");
        assert_eq!(cols.len(), vals.len(), "one value per column index");
        debug_assert!((0..nrows).all(|i| offsets[i] <= offsets[i + 1]));
        debug_assert!((0..nrows).all(|i| cols[offsets[i]..offsets[i + 1]].windows(2).all(|w| w[0] < w[1])));
        debug_assert!(cols.iter().all(|&c| (c as usize) < ncols));
        Csr { nrows, ncols, offsets, cols, vals }
    }

    /// Rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.vals.len()
    }

    /// Row offsets (`nrows + 1`).
    pub fn row_offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// Column indices of all rows.
    pub fn col_indices(&self) -> &[u32] {
        &self.cols
    }

    /// Values of all rows.
    pub fn values(&self) -> &[V] {
        &self.vals
    }

    /// Row `i`.
    pub fn row(&self, i: usize) -> Row<'_, V> {
        let range = self.offsets[i]..self.offsets[i + 1];
        Row { cols: &self.cols[range.clone()], vals: &self.vals[range] }
    }
}

impl Csr {
    /// The same matrix with the rows in `replaced` (row -> entries `(column, value)`,
    /// sorted by column) instead of its own; the others copied (the matrix is held
    /// twice while they are).
    pub fn with_rows_replaced(self, replaced: &std::collections::BTreeMap<usize, Vec<(usize, f64)>>) -> Csr {
        let extra: usize = replaced.iter().map(|(&i, r)| r.len().saturating_sub(self.offsets[i + 1] - self.offsets[i])).sum();
        let (mut offsets, mut cols, mut vals) =
            (Vec::with_capacity(self.nrows + 1), Vec::with_capacity(self.nnz() + extra), Vec::with_capacity(self.nnz() + extra));
        offsets.push(0);
        for i in 0..self.nrows {
            match replaced.get(&i) {
                Some(r) => {
                    cols.extend(r.iter().map(|&(c, _)| u32::try_from(c).expect("columns fit in 32 bits")));
                    vals.extend(r.iter().map(|&(_, v)| v));
                }
                None => {
                    let range = self.offsets[i]..self.offsets[i + 1];
                    cols.extend_from_slice(&self.cols[range.clone()]);
                    vals.extend_from_slice(&self.vals[range]);
                }
            }
            offsets.push(cols.len());
        }
        let (nrows, ncols) = (self.nrows, self.ncols);
        drop(self);
        Csr::from_parts(nrows, ncols, offsets, cols, vals)
    }

    /// The same matrix with its values rounded to single precision (values in half
    /// the memory, an entry in two thirds): for operators whose application need only
    /// be a fixed linear map, not the exact one (the multigrid's transfers).
    pub fn into_single(self) -> Csr<f32> {
        let vals = self.vals.iter().map(|&v| v as f32).collect();
        Csr { nrows: self.nrows, ncols: self.ncols, offsets: self.offsets, cols: self.cols, vals }
    }

    /// The `nrows x ncols` matrix of the entries `(row, column, value)`, duplicates
    /// summed (tests and small matrices).
    pub fn from_triplets(nrows: usize, ncols: usize, entries: &[(usize, usize, f64)]) -> Self {
        let mut sorted = entries.to_vec();
        sorted.sort_by_key(|e| (e.0, e.1));
        let mut offsets = vec![0usize; nrows + 1];
        let (mut cols, mut vals): (Vec<u32>, Vec<f64>) = (Vec::new(), Vec::new());
        let mut last: Option<(usize, usize)> = None;
        for (r, c, v) in sorted {
            assert!(r < nrows && c < ncols, "entry ({r}, {c}) outside a {nrows} x {ncols} matrix");
            if last == Some((r, c)) {
                *vals.last_mut().expect("a previous entry") += v;
            } else {
                cols.push(c as u32);
                vals.push(v);
                offsets[r + 1] += 1;
                last = Some((r, c));
            }
        }
        for i in 0..nrows {
            offsets[i + 1] += offsets[i];
        }
        Csr::from_parts(nrows, ncols, offsets, cols, vals)
    }

    /// Every stored entry `(row, column, value)`, row by row.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, f64)> + Clone + '_ {
        (0..self.nrows).flat_map(move |i| {
            let row = self.row(i);
            row.cols.iter().zip(row.vals).map(move |(&c, &v)| (i, c as usize, v))
        })
    }

    /// The stored entry `(i, i)`, zero when there is none.
    pub fn diagonal(&self, i: usize) -> f64 {
        let row = self.row(i);
        row.cols.binary_search(&(i as u32)).map_or(0.0, |k| row.vals[k])
    }

    /// `A ← D A`, `D = diag(scales)`, in place (groups of rows in parallel).
    pub fn scale_rows(&mut self, scales: &[f64]) {
        const GROUP: usize = 4096;
        assert_eq!(scales.len(), self.nrows, "one scale per row");
        let offsets = &self.offsets;
        let mut rest: &mut [f64] = &mut self.vals;
        let mut groups = Vec::with_capacity(self.nrows.div_ceil(GROUP));
        for first in (0..self.nrows).step_by(GROUP) {
            let last = self.nrows.min(first + GROUP);
            let (group, tail) = std::mem::take(&mut rest).split_at_mut(offsets[last] - offsets[first]);
            groups.push((first, last, group));
            rest = tail;
        }
        groups.into_par_iter().for_each(|(first, last, group)| {
            for i in first..last {
                let d = scales[i];
                group[offsets[i] - offsets[first]..offsets[i + 1] - offsets[first]].iter_mut().for_each(|v| *v *= d);
            }
        });
    }

    /// The parts: offsets, column indices, values.
    pub fn disassemble(self) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
        (self.offsets, self.cols, self.vals)
    }

    /// `Aᵀ`, by a counting sort on the column (the rows of the result come out sorted).
    pub fn transpose(&self) -> Csr {
        let (mut cols, mut vals) = (vec![0u32; self.nnz()], vec![0.0; self.nnz()]);
        let offsets = transposed(self.ncols, &self.offsets, &self.cols, |i, k, slot| {
            cols[slot] = i as u32;
            vals[slot] = self.vals[k];
        });
        Csr::from_parts(self.ncols, self.nrows, offsets, cols, vals)
    }

    /// `self - omega other` (the same shape), on the union of the two patterns.
    pub fn minus_scaled(&self, omega: f64, other: &Csr) -> Csr {
        assert_eq!((self.nrows, self.ncols), (other.nrows, other.ncols), "difference of matrices of different shapes");
        let mut offsets = Vec::with_capacity(self.nrows + 1);
        offsets.push(0usize);
        let (mut cols, mut vals) = (Vec::with_capacity(self.nnz().max(other.nnz())), Vec::with_capacity(self.nnz().max(other.nnz())));
        for i in 0..self.nrows {
            let (a, b) = (self.row(i), other.row(i));
            let (mut p, mut q) = (0, 0);
            while p < a.cols.len() || q < b.cols.len() {
                let (ca, cb) = (a.cols.get(p).copied().unwrap_or(u32::MAX), b.cols.get(q).copied().unwrap_or(u32::MAX));
                if ca == cb {
                    cols.push(ca);
                    vals.push(a.vals[p] - omega * b.vals[q]);
                    p += 1;
                    q += 1;
                } else if ca < cb {
                    cols.push(ca);
                    vals.push(a.vals[p]);
                    p += 1;
                } else {
                    cols.push(cb);
                    vals.push(-omega * b.vals[q]);
                    q += 1;
                }
            }
            offsets.push(cols.len());
        }
        Csr::from_parts(self.nrows, self.ncols, offsets, cols, vals)
    }
}

/// The counting sort behind every transpose of compressed rows: for the rows
/// `offsets` (`nrows + 1`) with columns `cols` (below `ncols`), returns the offsets of
/// the transposed rows (`ncols + 1`) and calls `place(i, k, slot)` for every entry `k`
/// of row `i`, rows in increasing order, with its position `slot` in the transposed
/// arrays (so each transposed row lists its entries by increasing `i`).
pub fn transposed(ncols: usize, offsets: &[usize], cols: &[u32], mut place: impl FnMut(usize, usize, usize)) -> Vec<usize> {
    let mut out = vec![0usize; ncols + 1];
    for &c in cols {
        out[c as usize + 1] += 1;
    }
    for j in 0..ncols {
        out[j + 1] += out[j];
    }
    let mut next = out[..ncols].to_vec();
    for i in 0..offsets.len() - 1 {
        for (k, &c) in cols.iter().enumerate().take(offsets[i + 1]).skip(offsets[i]) {
            let j = c as usize;
            place(i, k, next[j]);
            next[j] += 1;
        }
    }
    out
}

/// Compressed rows by reference: the structure of a [`Csr`] with values of any
/// precision, so that the multigrid's finest level can apply the system's rows with
/// their values rounded to single precision without a second copy of the structure.
#[derive(Clone, Copy, Debug)]
pub struct RowsRef<'a, V = f64> {
    offsets: &'a [usize],
    cols: &'a [u32],
    vals: &'a [V],
}

impl<'a, V: Value> RowsRef<'a, V> {
    /// Rows.
    pub fn nrows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Row offsets, column indices and values of all rows.
    pub fn parts(&self) -> (&'a [usize], &'a [u32], &'a [V]) {
        (self.offsets, self.cols, self.vals)
    }
}

impl<'a, V: Value> From<&'a Csr<V>> for RowsRef<'a, V> {
    fn from(a: &'a Csr<V>) -> Self {
        RowsRef { offsets: &a.offsets, cols: &a.cols, vals: &a.vals }
    }
}

impl<V: Value> Csr<V> {
    /// This matrix's rows with `vals` in place of its values (one per stored entry).
    pub fn with_values<'a, W: Value>(&'a self, vals: &'a [W]) -> RowsRef<'a, W> {
        assert_eq!(vals.len(), self.nnz(), "one value per stored entry");
        RowsRef { offsets: &self.offsets, cols: &self.cols, vals }
    }
}

/// `y = A x`, rows in parallel, in double precision whatever `A` stores.
pub fn product<'a, V: Value>(a: impl Into<RowsRef<'a, V>>, x: &[f64], y: &mut [f64]) {
    let (ptr, idx, val) = a.into().parts();
    y.par_iter_mut().enumerate().with_min_len(256).for_each(|(r, y)| {
        let entries = ptr[r]..ptr[r + 1];
        *y = row_dot(&idx[entries.clone()], &val[entries], x);
    });
}

/// `sum_k vals[k] x[cols[k]]`, one row of `A x`, in double precision, in four
/// independent partial sums (entries `k mod 4`): a single running sum makes every
/// addition wait for the previous one, and the matrix-vector products and the
/// Gauss-Seidel sweeps are made of these rows.
pub fn row_dot<V: Value>(cols: &[u32], vals: &[V], x: &[f64]) -> f64 {
    let mut sums = [0.0f64; 4];
    let (cols4, vals4) = (cols.chunks_exact(4), vals.chunks_exact(4));
    let tail: f64 = cols4.remainder().iter().zip(vals4.remainder()).map(|(&c, v)| v.to_f64() * x[c as usize]).sum();
    for (c, v) in cols4.zip(vals4) {
        for m in 0..4 {
            sums[m] += v[m].to_f64() * x[c[m] as usize];
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3]) + tail
}

/// `a` (CSC) as a CSR matrix, transposed straight from faer's columns by a counting
/// sort on the row (columns come out sorted).
pub fn to_csr(a: &SparseMatrix) -> Csr {
    let (n, m) = (a.nrows(), a.ncols());
    let mut offsets = vec![0usize; n + 1];
    for j in 0..m {
        for &i in a.symbolic().row_idx_of_col_raw(j) {
            offsets[i + 1] += 1;
        }
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    let mut next = offsets[..n].to_vec();
    let (mut cols, mut vals) = (vec![0u32; offsets[n]], vec![0.0f64; offsets[n]]);
    for j in 0..m {
        for (&i, &v) in a.symbolic().row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            cols[next[i]] = j as u32;
            vals[next[i]] = v;
            next[i] += 1;
        }
    }
    Csr::from_parts(n, m, offsets, cols, vals)
}

/// `a` (CSR) in compressed columns, by the counting sort of [`transposed`]
/// (rows come out sorted); `a` is consumed and freed once converted.
pub fn columns_of(a: Csr) -> SparseMatrix {
    let (n, m) = (a.nrows(), a.ncols());
    let (mut rows, mut values) = (vec![0usize; a.nnz()], vec![0.0f64; a.nnz()]);
    let col_ptr = transposed(m, a.row_offsets(), a.col_indices(), |i, k, slot| {
        rows[slot] = i;
        values[slot] = a.values()[k];
    });
    drop(a);
    let symbolic = faer::sparse::SymbolicSparseColMat::new_checked(n, m, col_ptr, None, rows);
    SparseMatrix::new(symbolic, values)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Duplicates are summed, the transpose swaps every entry, and `A - w B` is the
    /// entrywise difference on the union of the patterns (exact: binary fractions).
    #[test]
    fn transpose_and_difference_are_entrywise() {
        let a = Csr::from_triplets(3, 4, &[(0, 3, 1.0), (0, 0, 2.0), (2, 1, 0.5), (0, 3, 0.25), (1, 2, -1.0)]);
        assert_eq!(a.nnz(), 4);
        assert_eq!(a.row(0).col_indices(), &[0, 3]);
        assert_eq!(a.row(0).values(), &[2.0, 1.25]);
        let t = a.transpose();
        assert_eq!((t.nrows(), t.ncols()), (4, 3));
        assert_eq!(t, Csr::from_triplets(4, 3, &[(3, 0, 1.25), (0, 0, 2.0), (1, 2, 0.5), (2, 1, -1.0)]));
        let b = Csr::from_triplets(3, 4, &[(0, 3, 1.0), (1, 1, 4.0), (2, 1, 1.0)]);
        let d = a.minus_scaled(0.5, &b);
        assert_eq!(d, Csr::from_triplets(3, 4, &[(0, 0, 2.0), (0, 3, 0.75), (1, 1, -2.0), (1, 2, -1.0), (2, 1, 0.0)]));
        let mut y = vec![0.0; 3];
        product(&a, &[1.0, 2.0, 4.0, 8.0], &mut y);
        assert_eq!(y, vec![2.0 + 10.0, -4.0, 1.0]);
    }

    /// Single precision keeps the pattern and rounds each value once (relative error
    /// at most 2^-24); scaling multiplies each row by its own scale (exact here: powers
    /// of two); the diagonal reads the stored entry or zero.
    #[test]
    fn single_precision_scaling_and_diagonal() {
        let a = Csr::from_triplets(3, 3, &[(0, 0, 0.1), (0, 2, 1.0 / 3.0), (1, 0, -7.25), (2, 2, 1e-3)]);
        let s = a.clone().into_single();
        assert_eq!((s.row_offsets(), s.col_indices()), (a.row_offsets(), a.col_indices()));
        for (&v, &w) in a.values().iter().zip(s.values()) {
            assert!((f64::from(w) - v).abs() <= v.abs() * 2f64.powi(-24), "{v} -> {w}");
        }
        let mut scaled = a.clone();
        scaled.scale_rows(&[2.0, 0.5, -4.0]);
        assert_eq!(scaled, Csr::from_triplets(3, 3, &[(0, 0, 0.2), (0, 2, 2.0 / 3.0), (1, 0, -3.625), (2, 2, -4e-3)]));
        assert_eq!([a.diagonal(0), a.diagonal(1), a.diagonal(2)], [0.1, 0.0, 1e-3]);
    }
}
