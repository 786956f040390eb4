//! COO (triplet) accumulation and assembly into CSC.

use super::{SolveError, SparseMatrix};
use faer::sparse::Triplet;

/// COO entries `(row, col, value)` of a square `n × n` sparse matrix.
///
/// Entries may repeat; [`assemble`] sums duplicates (`a_ij = Σ value` over all
/// triplets with that `(i, j)`), which is how per-node stencil contributions
/// are accumulated.
#[derive(Clone, Debug, Default)]
pub struct Triplets {
    n: usize,
    entries: Vec<Triplet<usize, usize, f64>>,
}

impl Triplets {
    /// Empty triplet list for an `n × n` matrix.
    pub fn new(n: usize) -> Self {
        Self::with_capacity(n, 0)
    }

    /// Empty triplet list for an `n × n` matrix with room for `cap` entries.
    pub fn with_capacity(n: usize, cap: usize) -> Self {
        Triplets { n, entries: Vec::with_capacity(cap) }
    }

    /// The triplets `entries` `(row, column, value)` of an `n × n` matrix.
    pub fn from_entries(n: usize, entries: &[(usize, usize, f64)]) -> Self {
        let mut t = Triplets::with_capacity(n, entries.len());
        for &(r, c, v) in entries {
            t.push(r, c, v);
        }
        t
    }

    /// Add `value` at `(row, col)`. Debug builds assert that the indices are
    /// in range and the value is finite; release builds defer both checks to
    /// [`assemble`], which returns an error instead of panicking.
    pub fn push(&mut self, row: usize, col: usize, value: f64) {
        debug_assert!(row < self.n && col < self.n, "triplet ({row}, {col}) out of range for a {0}x{0} matrix", self.n);
        debug_assert!(value.is_finite(), "triplet ({row}, {col}) has non-finite value {value}");
        self.entries.push(Triplet::new(row, col, value));
    }

    /// Move all entries of `other` into `self`, leaving `other` empty (for
    /// merging per-thread accumulators). Dimensions must agree
    /// (debug-asserted; [`assemble`] re-checks the indices).
    pub fn append(&mut self, other: &mut Triplets) {
        debug_assert_eq!(self.n, other.n, "appending triplets of a different dimension");
        self.entries.append(&mut other.entries);
    }

    /// Number of stored entries (duplicates counted separately).
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// `true` if no entry is stored.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Matrix dimension `n`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// The raw entries, in insertion order.
    pub fn entries(&self) -> &[Triplet<usize, usize, f64>] {
        &self.entries
    }
}

/// Assemble the `n × n` CSC matrix, summing duplicate `(row, col)` entries
/// (`faer::sparse::SparseColMat::try_new_from_triplets`). Row indices within
/// each column come out sorted; structural entries whose sum is zero are kept.
///
/// Errors: [`SolveError::NotFinite`] for the first non-finite value (naming its
/// row and column), [`SolveError::Dimension`] for an index `≥ n`.
pub fn assemble(t: &Triplets) -> Result<SparseMatrix, SolveError> {
    let n = t.n;
    for e in &t.entries {
        if e.row >= n || e.col >= n {
            return Err(SolveError::Dimension { detail: format!("triplet ({}, {}) is out of range for a {n}x{n} matrix", e.row, e.col) });
        }
        if !e.val.is_finite() {
            return Err(SolveError::NotFinite { row: e.row, col: e.col, value: e.val });
        }
    }
    let m = SparseMatrix::try_new_from_triplets(n, n, &t.entries)
        .map_err(|e| SolveError::Dimension { detail: format!("could not build the sparse matrix: {e:?}") })?;
    // Two finite values can still overflow to ±inf when summed.
    for j in 0..n {
        let rows = m.symbolic().row_idx_of_col_raw(j);
        for (&i, &v) in rows.iter().zip(m.val_of_col(j)) {
            if !v.is_finite() {
                return Err(SolveError::NotFinite { row: i, col: j, value: v });
            }
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn duplicates_are_summed() {
        let mut t = Triplets::new(2);
        t.push(0, 0, 1.0);
        t.push(1, 0, -2.0);
        t.push(0, 0, 2.5);
        let mut u = Triplets::new(2);
        u.push(1, 1, 4.0);
        u.push(1, 0, 0.5);
        t.append(&mut u);
        assert_eq!((t.len(), u.len(), t.dim()), (5, 0, 2));
        let a = assemble(&t).unwrap();
        // Exact: sums of a few small binary fractions.
        assert_eq!(a.val_of_col(0), &[3.5, -1.5]);
        assert_eq!(a.val_of_col(1), &[4.0]);
        assert_eq!(a.compute_nnz(), 3);
    }

    #[test]
    fn nan_is_reported_with_its_position() {
        // Bypass `push` (it debug-asserts finiteness) to emulate a release
        // build where a NaN slipped through.
        let mut t = Triplets::new(3);
        t.push(0, 0, 1.0);
        t.entries.push(Triplet::new(2, 1, f64::NAN));
        match assemble(&t) {
            Err(SolveError::NotFinite { row: 2, col: 1, value }) => assert!(value.is_nan()),
            other => panic!("expected NotFinite at (2, 1), got {other:?}"),
        }
        let msg = assemble(&t).unwrap_err().to_string();
        assert!(msg.contains("(2, 1)"), "{msg}");
    }

    #[test]
    fn overflowing_sum_and_out_of_range_are_errors() {
        let mut t = Triplets::new(2);
        t.push(1, 1, f64::MAX);
        t.push(1, 1, f64::MAX);
        assert!(matches!(assemble(&t), Err(SolveError::NotFinite { row: 1, col: 1, .. })));
        let mut t = Triplets::new(2);
        t.entries.push(Triplet::new(0, 2, 1.0));
        assert!(matches!(assemble(&t), Err(SolveError::Dimension { .. })));
    }
}
