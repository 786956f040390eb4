//! COO (triplet) accumulation and assembly into CSC.
//!
//! The entries are kept in the blocks they were written in (one per node of a
//! discretisation, written in parallel), so that no flat copy is made, and compressed
//! by a counting sort on the column: `O(nnz)` time, and besides the blocks only the
//! compressed arrays themselves (16 bytes per entry) in memory. faer's
//! `try_new_from_triplets` sorts a flat triplet list instead, which needed about
//! three times the memory of the entries at 1e6 nodes.

use super::{SolveError, SparseMatrix};
use faer::sparse::SymbolicSparseColMat;

/// One entry `(row, column, value)`.
pub type Entry = (usize, usize, f64);

/// One entry as stored, `(row, column, value)` with 32-bit indices: 16 bytes instead
/// of 24, a lower assembly peak (docs/notebook/round2-target-error.md, "32-bit column
/// indices"). Systems of more than `u32::MAX` unknowns are refused by [`Triplets::new`].
pub type StoredEntry = (u32, u32, f64);

/// `(row, column, value)` in the stored form.
pub fn stored(row: usize, col: usize, value: f64) -> StoredEntry {
    (row as u32, col as u32, value)
}

/// COO entries `(row, col, value)` of a square `n × n` sparse matrix.
///
/// Entries may repeat; [`assemble`] sums duplicates (`a_ij = Σ value` over all
/// triplets with that `(i, j)`), which is how per-node stencil contributions
/// are accumulated.
#[derive(Clone, Debug, Default)]
pub struct Triplets {
    n: usize,
    blocks: Vec<Vec<StoredEntry>>,
}

impl Triplets {
    /// Empty triplet list for an `n × n` matrix.
    pub fn new(n: usize) -> Self {
        Self::with_capacity(n, 0)
    }

    /// Empty triplet list for an `n × n` matrix with room for `cap` entries.
    pub fn with_capacity(n: usize, cap: usize) -> Self {
        Self::from_blocks(n, vec![Vec::with_capacity(cap)])
    }

    /// The triplets `entries` `(row, column, value)` of an `n × n` matrix.
    pub fn from_entries(n: usize, entries: &[Entry]) -> Self {
        Self::from_blocks(n, vec![entries.iter().map(|&(r, c, v)| stored(r, c, v)).collect()])
    }

    /// The entries of an `n × n` matrix as written, block by block (no copy). Panics
    /// when `n` exceeds the 32-bit indices ([`StoredEntry`]): unreachable from a scene,
    /// whose node limit (`problem::validate::MAX_NODES`) is checked against them at
    /// compile time.
    pub fn from_blocks(n: usize, blocks: Vec<Vec<StoredEntry>>) -> Self {
        assert!(n <= u32::MAX as usize, "a system of {n} unknowns exceeds the 32-bit indices of the triplets");
        Triplets { n, blocks }
    }

    /// Add `value` at `(row, col)`. Debug builds assert that the indices are
    /// in range and the value is finite; release builds defer both checks to
    /// [`assemble`], which returns an error instead of panicking.
    pub fn push(&mut self, row: usize, col: usize, value: f64) {
        debug_assert!(row < self.n && col < self.n, "triplet ({row}, {col}) out of range for a {0}x{0} matrix", self.n);
        debug_assert!(value.is_finite(), "triplet ({row}, {col}) has non-finite value {value}");
        self.push_unchecked(row, col, value);
    }

    fn push_unchecked(&mut self, row: usize, col: usize, value: f64) {
        if self.blocks.is_empty() {
            self.blocks.push(Vec::new());
        }
        self.blocks.last_mut().expect("a block").push(stored(row, col, value));
    }

    /// Move all entries of `other` into `self`, leaving `other` empty (for
    /// merging per-thread accumulators). Dimensions must agree
    /// (debug-asserted; [`assemble`] re-checks the indices).
    pub fn append(&mut self, other: &mut Triplets) {
        debug_assert_eq!(self.n, other.n, "appending triplets of a different dimension");
        self.blocks.append(&mut other.blocks);
    }

    /// Number of stored entries (duplicates counted separately).
    pub fn len(&self) -> usize {
        self.blocks.iter().map(Vec::len).sum()
    }

    /// `true` if no entry is stored.
    pub fn is_empty(&self) -> bool {
        self.blocks.iter().all(Vec::is_empty)
    }

    /// Matrix dimension `n`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// The entries, in insertion order.
    pub fn entries(&self) -> impl Iterator<Item = Entry> + Clone + '_ {
        self.blocks.iter().flatten().map(|&(r, c, v)| (r as usize, c as usize, v))
    }
}

/// Assemble the `n × n` CSC matrix, summing duplicate `(row, col)` entries, by a
/// counting sort on the column (module docs). Row indices within each column come
/// out sorted; structural entries whose sum is zero are kept.
///
/// Errors: [`SolveError::NotFinite`] for the first non-finite value (naming its
/// row and column), [`SolveError::Dimension`] for an index `≥ n`.
pub fn assemble(t: &Triplets) -> Result<SparseMatrix, SolveError> {
    let n = t.n;
    for (row, col, val) in t.entries() {
        if row >= n || col >= n {
            return Err(SolveError::Dimension { detail: format!("triplet ({row}, {col}) is out of range for a {n}x{n} matrix") });
        }
        if !val.is_finite() {
            return Err(SolveError::NotFinite { row, col, value: val });
        }
    }
    let (col_ptr, rows, vals) = compress(n, t.entries().map(|(row, col, val)| (col, row, val)));
    // Two finite values can still overflow to ±inf when summed.
    if let Some(k) = vals.iter().position(|v| !v.is_finite()) {
        let col = col_ptr.partition_point(|&p| p <= k) - 1;
        return Err(SolveError::NotFinite { row: rows[k], col, value: vals[k] });
    }
    let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
    Ok(SparseMatrix::new(symbolic, vals))
}

/// Entries `(segment, index, value)` compressed by a counting sort on the segment (a
/// column of CSC, a row of CSR): two passes over `entries`, each segment then sorted
/// by index (stable: duplicates summed in the order they were written) and compacted
/// in place. Returns the segment pointers, indices and values; segments must be
/// `< segments`.
pub(crate) fn compress<I: Ord + Copy + Default>(
    segments: usize,
    entries: impl Iterator<Item = (usize, I, f64)> + Clone,
) -> (Vec<usize>, Vec<I>, Vec<f64>) {
    let mut start = vec![0usize; segments + 1];
    for (s, _, _) in entries.clone() {
        start[s + 1] += 1;
    }
    for s in 0..segments {
        start[s + 1] += start[s];
    }
    let mut next = start.clone();
    let (mut idx, mut vals) = (vec![I::default(); start[segments]], vec![0.0f64; start[segments]]);
    for (s, i, v) in entries {
        idx[next[s]] = i;
        vals[next[s]] = v;
        next[s] += 1;
    }
    drop(next);
    let mut ptr = vec![0usize; segments + 1];
    let (mut segment, mut kept): (Vec<(I, f64)>, usize) = (Vec::new(), 0);
    for s in 0..segments {
        segment.clear();
        segment.extend(idx[start[s]..start[s + 1]].iter().copied().zip(vals[start[s]..start[s + 1]].iter().copied()));
        segment.sort_by_key(|e| e.0);
        for (k, &(i, v)) in segment.iter().enumerate() {
            if k > 0 && segment[k - 1].0 == i {
                vals[kept - 1] += v;
            } else {
                idx[kept] = i;
                vals[kept] = v;
                kept += 1;
            }
        }
        ptr[s + 1] = kept;
    }
    idx.truncate(kept);
    vals.truncate(kept);
    idx.shrink_to_fit();
    vals.shrink_to_fit();
    (ptr, idx, vals)
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
        t.push_unchecked(2, 1, f64::NAN);
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
        t.push_unchecked(0, 2, 1.0);
        assert!(matches!(assemble(&t), Err(SolveError::Dimension { .. })));
    }
}
