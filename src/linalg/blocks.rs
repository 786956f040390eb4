//! Sparse matrices stored by dense blocks of `rows x cols` entries, one column index
//! per block (block compressed rows): the multigrid's transfers, whose entries come
//! in whole aggregates. A row of the prolongation `P` holds all `k` near-null
//! columns of each aggregate it touches (`1 x k` blocks), and the `k` rows of one
//! aggregate in the restriction `R` share their columns (`k x 1` blocks). With `k = 3`
//! an entry takes 4 + 4/3 bytes instead of 8: at 1e6 nodes the two transfers take
//! 0.25 GB instead of 0.38 GB.

use super::csr::Csr;
use rayon::prelude::*;

/// One task's block rows: blocks per block row, block columns, values.
type Part = (Vec<usize>, Vec<u32>, Vec<f32>);

/// A matrix of dense `shape.0 x shape.1` blocks in compressed block rows; the values
/// of a block are row-major and in single precision (the cycle applies the transfers
/// as a fixed linear map, [`super::amg`]).
#[derive(Clone, Debug, PartialEq)]
pub struct BlockRows {
    /// Rows and columns of one block.
    shape: (usize, usize),
    /// Block columns of block row `i`: `cols[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<usize>,
    cols: Vec<u32>,
    /// `shape.0 * shape.1` values per block.
    vals: Vec<f32>,
    /// Rows and columns of the matrix.
    nrows: usize,
    ncols: usize,
}

impl BlockRows {
    /// `a` in blocks of `shape`, if every stored entry lies in a block whose entries
    /// are all stored: `None` otherwise (a pattern that does not come in whole blocks,
    /// or dimensions that are not multiples of the block).
    pub fn from_csr(a: &Csr<f32>, shape: (usize, usize)) -> Option<Self> {
        let (br, bc) = shape;
        if br == 0 || bc == 0 || !a.nrows().is_multiple_of(br) || !a.ncols().is_multiple_of(bc) {
            return None;
        }
        let block_rows = a.nrows() / br;
        // Ranges of block rows in parallel, each into its own part, the parts then
        // concatenated (serially the conversion took 0.77 s of the 1e6-node setup).
        let per_task = block_rows.div_ceil(4 * rayon::current_num_threads().max(1)).max(1024);
        let parts: Option<Vec<Part>> = (0..block_rows.div_ceil(per_task))
            .into_par_iter()
            .map(|task| {
                let rows = task * per_task..block_rows.min((task + 1) * per_task);
                let (mut counts, mut cols, mut vals) = (Vec::with_capacity(rows.len()), Vec::new(), Vec::new());
                for bi in rows {
                    let first = a.row(bi * br).col_indices();
                    // Every row of the block row has the pattern of the first, in whole
                    // blocks of consecutive columns.
                    if !first.len().is_multiple_of(bc) || (1..br).any(|m| a.row(bi * br + m).col_indices() != first) {
                        return None;
                    }
                    for (t, group) in first.chunks_exact(bc).enumerate() {
                        if !(group[0] as usize).is_multiple_of(bc) || group.iter().enumerate().any(|(c, &j)| j != group[0] + c as u32) {
                            return None;
                        }
                        cols.push(group[0] / bc as u32);
                        for m in 0..br {
                            vals.extend_from_slice(&a.row(bi * br + m).values()[t * bc..(t + 1) * bc]);
                        }
                    }
                    counts.push(first.len() / bc);
                }
                Some((counts, cols, vals))
            })
            .collect();
        let parts = parts?;
        let mut offsets = Vec::with_capacity(block_rows + 1);
        offsets.push(0);
        let (mut cols, mut vals) = (Vec::with_capacity(a.nnz() / (br * bc)), Vec::with_capacity(a.nnz()));
        for (counts, c, v) in parts {
            for count in counts {
                offsets.push(offsets.last().expect("starts at 0") + count);
            }
            cols.extend_from_slice(&c);
            vals.extend_from_slice(&v);
        }
        Some(BlockRows { shape, offsets, cols, vals, nrows: a.nrows(), ncols: a.ncols() })
    }

    /// Stored entries (values, counting every entry of every block).
    pub fn nnz(&self) -> usize {
        self.vals.len()
    }

    /// Rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// `y = A x`, block rows in parallel, in double precision.
    pub fn product(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!((x.len(), y.len()), (self.ncols, self.nrows), "dimensions of y = A x");
        // The transfers' shapes with the block size known to the compiler (the generic
        // loop took twice as long at 1e6 nodes).
        match self.shape {
            (1, 3) => self.product_with::<1, 3>(x, y),
            (3, 1) => self.product_with::<3, 1>(x, y),
            (1, 2) => self.product_with::<1, 2>(x, y),
            (2, 1) => self.product_with::<2, 1>(x, y),
            _ => self.product_generic(x, y),
        }
    }

    fn product_with<const R: usize, const C: usize>(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(R).enumerate().with_min_len(256).for_each(|(bi, y)| {
            let mut sums = [0.0f64; R];
            for k in self.offsets[bi]..self.offsets[bi + 1] {
                let j = self.cols[k] as usize * C;
                let block = &self.vals[k * R * C..(k + 1) * R * C];
                for (m, sum) in sums.iter_mut().enumerate() {
                    for c in 0..C {
                        *sum += f64::from(block[m * C + c]) * x[j + c];
                    }
                }
            }
            y.copy_from_slice(&sums);
        });
    }

    fn product_generic(&self, x: &[f64], y: &mut [f64]) {
        let (br, bc) = self.shape;
        y.par_chunks_mut(br).enumerate().with_min_len(256).for_each(|(bi, y)| {
            y.fill(0.0);
            for k in self.offsets[bi]..self.offsets[bi + 1] {
                let x = &x[self.cols[k] as usize * bc..][..bc];
                let block = &self.vals[k * br * bc..][..br * bc];
                for (m, y) in y.iter_mut().enumerate() {
                    *y += block[m * bc..][..bc].iter().zip(x).map(|(&v, &x)| f64::from(v) * x).sum::<f64>();
                }
            }
        });
    }
}

/// A transfer of the multigrid: in blocks when its pattern comes in whole blocks of
/// the shape asked for (always, for the aggregates' transfers: the sparse products
/// keep every entry of the pattern), else in plain compressed rows.
#[derive(Debug)]
pub(super) enum Transfer {
    Blocks(BlockRows),
    Rows(Csr<f32>),
}

impl Transfer {
    /// `a` in blocks of `shape` if it can be stored so.
    pub(super) fn new(a: Csr<f32>, shape: (usize, usize)) -> Self {
        match BlockRows::from_csr(&a, shape) {
            Some(blocks) => Transfer::Blocks(blocks),
            None => Transfer::Rows(a),
        }
    }

    /// Stored entries.
    pub(super) fn nnz(&self) -> usize {
        match self {
            Transfer::Blocks(b) => b.nnz(),
            Transfer::Rows(a) => a.nnz(),
        }
    }

    /// Rows.
    pub(super) fn nrows(&self) -> usize {
        match self {
            Transfer::Blocks(b) => b.nrows(),
            Transfer::Rows(a) => a.nrows(),
        }
    }

    /// `y = A x`.
    pub(super) fn product(&self, x: &[f64], y: &mut [f64]) {
        match self {
            Transfer::Blocks(b) => b.product(x, y),
            Transfer::Rows(a) => super::csr::product(a, x, y),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::csr::product;

    /// A 6 x 9 matrix in whole 1 x 3 blocks (its transpose is in 3 x 1 blocks).
    fn aggregated() -> Csr {
        let mut e = Vec::new();
        for i in 0..6 {
            for agg in [i % 3, (i + 1) % 3] {
                for c in 0..3 {
                    e.push((i, 3 * agg + c, 1.0 + i as f64 * 0.25 - c as f64 * 0.5 + agg as f64 * 0.125));
                }
            }
        }
        Csr::from_triplets(6, 9, &e)
    }

    fn transpose(a: &Csr) -> Csr {
        Csr::from_triplets(a.ncols(), a.nrows(), &a.entries().map(|(i, j, v)| (j, i, v)).collect::<Vec<_>>())
    }

    /// The block product equals the entrywise product, for `1 x 3` and `3 x 1`
    /// blocks (exact: the values are binary fractions).
    #[test]
    fn block_products_equal_entrywise_products() {
        let p = aggregated();
        let r = transpose(&p).into_single();
        let p = p.into_single();
        for (a, shape) in [(&p, (1, 3)), (&r, (3, 1))] {
            let blocks = BlockRows::from_csr(a, shape).expect("whole blocks");
            assert_eq!(blocks.nnz(), a.nnz());
            let x: Vec<f64> = (0..a.ncols()).map(|j| 0.5 + j as f64).collect();
            let (mut want, mut got) = (vec![0.0; a.nrows()], vec![1.0; a.nrows()]);
            product(a, &x, &mut want);
            blocks.product(&x, &mut got);
            assert_eq!(got, want);
        }
    }

    /// A pattern that is not in whole blocks is refused, not stored wrongly.
    #[test]
    fn partial_blocks_are_refused() {
        let p = aggregated();
        let mut e: Vec<_> = p.entries().collect();
        e.retain(|&(i, j, _)| !(i == 4 && j % 3 == 2));
        let partial = Csr::from_triplets(6, 9, &e).into_single();
        assert!(BlockRows::from_csr(&partial, (1, 3)).is_none());
        // Rows of one 3 x 1 block with different patterns.
        let mut e: Vec<_> = transpose(&p).entries().collect();
        e.retain(|&(i, j, _)| !(i == 1 && j == 0));
        assert!(BlockRows::from_csr(&Csr::from_triplets(9, 6, &e).into_single(), (3, 1)).is_none());
        assert!(BlockRows::from_csr(&p.into_single(), (4, 1)).is_none(), "6 rows are not whole blocks of 4");
    }
}
