//! Compressed rows assembled fragment by fragment, in row order, without a triplet list
//! or a second copy of the matrix.
//!
//! A collocation system is written node by node, and a node's equations are the rows
//! of that node (and of its ghost). So the rows arrive in order when the nodes are
//! written in order: each fragment (the entries of a block of nodes, written in
//! parallel and sorted there) is appended to the growing row arrays and freed. The
//! peak of the assembly is then the matrix itself (12 bytes per entry) plus the
//! fragments in flight, where a triplet list compressed by a counting sort held the
//! triplets (16 bytes per entry) and the compressed copy together
//! (docs/notebook/round2-target-error.md, "Rows assembled in node order").

use super::csr::Csr;
use super::triplets::StoredEntry;
use super::SolveError;

/// Entries of some rows, sorted by `(row, column)` with duplicates summed (in the order
/// they were written): a piece of a [`Csr`] ready to be appended by [`RowAssembler`].
#[derive(Clone, Debug, Default)]
pub struct RowFragment {
    entries: Vec<StoredEntry>,
}

impl RowFragment {
    /// The fragment of `entries` `(row, column, value)` in any order: sorted (stably,
    /// so that duplicates are summed in the order written) and compacted.
    pub fn new(mut entries: Vec<StoredEntry>) -> Self {
        // By row first (linear when the rows come in order, as a node's do), then each
        // row's few entries by column.
        entries.sort_by_key(|e| e.0);
        for row in entries.chunk_by_mut(|a, b| a.0 == b.0) {
            row.sort_by_key(|e| e.1);
        }
        let mut kept = 0;
        for k in 0..entries.len() {
            if kept > 0 && (entries[kept - 1].0, entries[kept - 1].1) == (entries[k].0, entries[k].1) {
                entries[kept - 1].2 += entries[k].2;
            } else {
                entries[kept] = entries[k];
                kept += 1;
            }
        }
        entries.truncate(kept);
        RowFragment { entries }
    }

    /// The entries of rows `from_row` and after, taken out of this fragment (sorted,
    /// duplicates summed).
    pub fn split_off_rows(&mut self, from_row: usize) -> Vec<StoredEntry> {
        let at = self.entries.partition_point(|e| (e.0 as usize) < from_row);
        self.entries.split_off(at)
    }

    /// Stored entries (after duplicates were summed).
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// `true` without entries.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// The rows of an `nrows × ncols` matrix, appended fragment by fragment in increasing
/// row order; every row's entries come in one fragment. Rows that no fragment holds
/// are empty.
#[derive(Debug)]
pub struct RowAssembler {
    nrows: usize,
    ncols: usize,
    /// Start of each row begun so far.
    offsets: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

impl RowAssembler {
    /// No rows yet. Panics when `ncols` exceeds the 32-bit column indices (the callers'
    /// node limit keeps systems below it).
    pub fn new(nrows: usize, ncols: usize) -> Self {
        assert!(ncols <= u32::MAX as usize + 1, "{ncols} columns do not fit 32-bit indices");
        RowAssembler { nrows, ncols, offsets: Vec::new(), cols: Vec::new(), vals: Vec::new() }
    }

    /// Append `fragment`, whose rows must all follow the rows appended before.
    ///
    /// Errors: [`SolveError::Dimension`] for an index out of range or a row that comes
    /// after a later one (a row written in two fragments); [`SolveError::NotFinite`]
    /// for a non-finite value (two finite duplicates can overflow when summed). The
    /// assembler is unusable after an error.
    pub fn append(&mut self, fragment: RowFragment) -> Result<(), SolveError> {
        let Some(&(first, _, _)) = fragment.entries.first() else { return Ok(()) };
        if (first as usize) < self.offsets.len() {
            return Err(SolveError::Dimension {
                detail: format!("row {first} is appended after row {}: rows must arrive in order", self.offsets.len() - 1),
            });
        }
        self.cols.reserve(fragment.len());
        self.vals.reserve(fragment.len());
        for (row, col, value) in fragment.entries {
            let (row, col) = (row as usize, col as usize);
            if row >= self.nrows || col >= self.ncols {
                return Err(SolveError::Dimension {
                    detail: format!("entry ({row}, {col}) is out of range for a {}x{} matrix", self.nrows, self.ncols),
                });
            }
            if !value.is_finite() {
                return Err(SolveError::NotFinite { row, col, value });
            }
            while self.offsets.len() <= row {
                self.offsets.push(self.cols.len());
            }
            self.cols.push(col as u32);
            self.vals.push(value);
        }
        Ok(())
    }

    /// The matrix; the rows after the last appended one are empty.
    pub fn finish(mut self) -> Csr {
        while self.offsets.len() <= self.nrows {
            self.offsets.push(self.cols.len());
        }
        self.cols.shrink_to_fit();
        self.vals.shrink_to_fit();
        Csr::from_parts(self.nrows, self.ncols, self.offsets, self.cols, self.vals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fragments in row order give the matrix of all their entries, duplicates summed
    /// in the order written (exact: small binary fractions), empty rows included.
    #[test]
    fn fragments_in_row_order_make_the_matrix() {
        let mut rows = RowAssembler::new(5, 4);
        rows.append(RowFragment::new(vec![(1, 3, 1.0), (0, 2, 0.5), (1, 0, 2.0), (1, 3, 0.25)])).unwrap();
        rows.append(RowFragment::new(Vec::new())).unwrap();
        let mut tail = RowFragment::new(vec![(4, 0, 3.0), (3, 1, -1.0), (4, 0, 1.0)]);
        let last = tail.split_off_rows(4);
        assert_eq!((tail.len(), last), (1, vec![(4, 0, 4.0)]));
        rows.append(tail).unwrap();
        let a = rows.finish();
        let expected = Csr::from_triplets(5, 4, &[(0, 2, 0.5), (1, 0, 2.0), (1, 3, 1.25), (3, 1, -1.0)]);
        assert_eq!(a, expected);
    }

    #[test]
    fn a_row_out_of_order_or_range_and_a_non_finite_value_are_errors() {
        let mut rows = RowAssembler::new(3, 3);
        rows.append(RowFragment::new(vec![(1, 1, 1.0)])).unwrap();
        let e = rows.append(RowFragment::new(vec![(1, 2, 1.0)])).unwrap_err();
        assert!(e.to_string().contains("row 1 is appended after row 1"), "{e}");
        let mut rows = RowAssembler::new(3, 3);
        assert!(matches!(rows.append(RowFragment::new(vec![(0, 3, 1.0)])), Err(SolveError::Dimension { .. })));
        let mut rows = RowAssembler::new(3, 3);
        let overflow = RowFragment::new(vec![(2, 0, f64::MAX), (2, 0, f64::MAX)]);
        assert!(matches!(rows.append(overflow), Err(SolveError::NotFinite { row: 2, col: 0, .. })));
    }
}
