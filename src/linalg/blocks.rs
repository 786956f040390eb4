//! Sparse matrices stored by dense blocks of `rows x cols` entries, one column index
//! per block (block compressed rows): the multigrid's transfers, whose entries come
//! in whole aggregates. A row of the prolongation `P` holds all `k` near-null
//! columns of each aggregate it touches (`1 x k` blocks), and the `k` rows of one
//! aggregate in the restriction `R` share their columns (`k x 1` blocks). With `k = 3`
//! an entry takes 4 + 4/3 bytes instead of 8
//! (docs/notebook/2026-11-26-up-form-iterative-solvers.md, "Single-precision cycle,
//! block-stored transfers").

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
        // concatenated (serially the conversion was a noticeable part of the 1e6-node
        // setup: docs/notebook/2026-11-26-up-form-iterative-solvers.md).
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

    /// `a` in square `b x b` node blocks (rows and columns `b J .. b J + b` of node
    /// `J`), in single precision, the entries a block lacks stored as zeros: the
    /// finest operator as the multigrid's cycle applies it, whose `b` rows of a node
    /// reach the unknowns of the same support nodes. One column index per block: an
    /// entry of a 2 x 2 block takes 5 bytes instead of 8, and a row of blocks reads
    /// `x` in pairs. `None` when the dimensions are not multiples of `b` or the
    /// stored zeros would exceed [`MAX_FILL`] of the entries.
    pub fn square(a: &Csr, b: usize) -> Option<Self> {
        if b == 0 || b > MAX_SQUARE || !a.nrows().is_multiple_of(b) || !a.ncols().is_multiple_of(b) {
            return None;
        }
        let block_rows = a.nrows() / b;
        // Two passes over the rows, each in parallel: the block columns of each block
        // row, then the blocks written in place (one pass into parts and a
        // concatenation was slower: docs/notebook/2026-11-27-node-blocks-in-the-cycle.md).
        let counts: Vec<usize> = (0..block_rows)
            .into_par_iter()
            .with_min_len(4096)
            .map(|bi| {
                let mut n = 0;
                block_columns(a, bi, b, |_| n += 1);
                n
            })
            .collect();
        let mut offsets = Vec::with_capacity(block_rows + 1);
        offsets.push(0);
        for c in &counts {
            offsets.push(offsets.last().expect("starts at 0") + c);
        }
        drop(counts);
        let blocks = offsets[block_rows];
        if (blocks * b * b) as f64 > MAX_FILL * a.nnz() as f64 {
            return None;
        }
        let (mut cols, mut vals) = (vec![0u32; blocks], vec![0.0f32; blocks * b * b]);
        // Disjoint slices of `cols` and `vals` for ranges of block rows.
        let per_task = block_rows.div_ceil(8 * rayon::current_num_threads().max(1)).max(1024);
        let mut tasks = Vec::new();
        let (mut c_rest, mut v_rest) = (cols.as_mut_slice(), vals.as_mut_slice());
        for start in (0..block_rows).step_by(per_task) {
            let end = block_rows.min(start + per_task);
            let n = offsets[end] - offsets[start];
            let (c, c_next) = c_rest.split_at_mut(n);
            let (v, v_next) = v_rest.split_at_mut(n * b * b);
            tasks.push((start..end, c, v));
            (c_rest, v_rest) = (c_next, v_next);
        }
        tasks.into_par_iter().for_each(|(rows, c, v)| {
            let first = offsets[rows.start];
            for bi in rows {
                let (start, end) = (offsets[bi] - first, offsets[bi + 1] - first);
                let mut t = start;
                block_columns(a, bi, b, |node| {
                    c[t] = node;
                    t += 1;
                });
                let nodes = &c[start..end];
                for m in 0..b {
                    let row = a.row(bi * b + m);
                    // Both lists are sorted: each entry's block is found by a pointer
                    // that only moves forward.
                    let mut t = 0;
                    for (&col, &value) in row.col_indices().iter().zip(row.values()) {
                        let node = col / b as u32;
                        while nodes[t] != node {
                            t += 1;
                        }
                        v[(start + t) * b * b + m * b + col as usize % b] = value as f32;
                    }
                }
            }
        });
        Some(BlockRows { shape: (b, b), offsets, cols, vals, nrows: a.nrows(), ncols: a.ncols() })
    }

    /// `(A x)_I = Σ_J A_IJ x_J` for the `B` unknowns of node `I` (square `B x B`
    /// blocks), over the block columns `J < I` only when `lower` (a forward sweep from
    /// a zero iterate: the columns are sorted). One partial sum per entry of the block,
    /// so that consecutive multiply-adds do not wait on each other.
    #[inline]
    fn node_sums<const B: usize>(&self, node: usize, x: &[f64], lower: bool) -> [f64; B] {
        debug_assert_eq!(self.shape, (B, B));
        let mut range = self.offsets[node]..self.offsets[node + 1];
        if lower {
            range.end = range.start + self.cols[range.clone()].partition_point(|&c| (c as usize) < node);
        }
        let mut sums = [[0.0f64; B]; B];
        let vals = &self.vals[range.start * B * B..range.end * B * B];
        for (&j, block) in self.cols[range].iter().zip(vals.chunks_exact(B * B)) {
            let x = &x[j as usize * B..][..B];
            for (m, row) in sums.iter_mut().enumerate() {
                for (c, sum) in row.iter_mut().enumerate() {
                    *sum += f64::from(block[m * B + c]) * x[c];
                }
            }
        }
        sums.map(|row| row.iter().sum())
    }

    /// `s = f_I − (A x)_I` for the `B` unknowns of node `I`, only the columns of the
    /// nodes before `I` when `lower` ([`BlockRows::node_sums`]): a Gauss–Seidel
    /// sweep's residual.
    #[inline]
    pub fn node_residual<const B: usize>(&self, node: usize, f: &[f64], x: &[f64], lower: bool, s: &mut [f64]) {
        for (m, ax) in self.node_sums::<B>(node, x, lower).iter().enumerate() {
            s[m] = f[node * B + m] - ax;
        }
    }

    /// Square blocks: the size of one side, if the blocks are square.
    pub fn square_block(&self) -> Option<usize> {
        (self.shape.0 == self.shape.1).then_some(self.shape.0)
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
            (2, 2) => y
                .par_chunks_mut(2)
                .enumerate()
                .with_min_len(256)
                .for_each(|(node, y)| y.copy_from_slice(&self.node_sums::<2>(node, x, false))),
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

/// Largest side of the square blocks of [`BlockRows::square`].
const MAX_SQUARE: usize = 4;

/// The block columns of block row `bi` of `a` (rows `b bi .. b bi + b`) in
/// increasing order, each once: a merge of the `b` sorted rows.
fn block_columns(a: &Csr, bi: usize, b: usize, mut visit: impl FnMut(u32)) {
    let rows: [&[u32]; MAX_SQUARE] = std::array::from_fn(|m| a.row(bi * b + m.min(b - 1)).col_indices());
    let mut pos = [0usize; MAX_SQUARE];
    let node_of = |c: u32| c / b as u32;
    while let Some(node) = (0..b).filter_map(|m| rows[m].get(pos[m]).map(|&c| node_of(c))).min() {
        visit(node);
        for m in 0..b {
            while rows[m].get(pos[m]).is_some_and(|&c| node_of(c) == node) {
                pos[m] += 1;
            }
        }
    }
}

/// The largest share of stored entries over the matrix's own in [`BlockRows::square`]:
/// the zeros of a Dirichlet row's block (one entry of four) are a few per cent of a
/// Navier system; a pattern far from whole blocks stays in compressed rows.
pub const MAX_FILL: f64 = 1.25;

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

    /// Square node blocks multiply as the rows they were made of (rounded to single
    /// precision, as the blocks store them), with the zeros a block lacks (a row of
    /// one entry); a pattern that would be mostly zeros is refused.
    #[test]
    fn square_blocks_multiply_as_their_rows_and_refuse_mostly_zeros() {
        let n = 12;
        let mut e = Vec::new();
        for node in 0..n / 2 {
            for other in [node, (node + 1) % (n / 2), (node + 3) % (n / 2)] {
                for (r, c) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    if node == 2 && (other != node || r != c) {
                        continue;
                    }
                    e.push((2 * node + r, 2 * other + c, 1.0 / (1.0 + (3 * node + 2 * other + r + c) as f64)));
                }
            }
        }
        let a = Csr::from_triplets(n, n, &e);
        let blocks = BlockRows::square(&a, 2).expect("few zeros");
        assert_eq!(blocks.square_block(), Some(2));
        assert!(blocks.nnz() > a.nnz() && (blocks.nnz() as f64) <= MAX_FILL * a.nnz() as f64);
        let x: Vec<f64> = (0..n).map(|j| 0.5 + j as f64).collect();
        let (mut want, mut got) = (vec![0.0; n], vec![1.0; n]);
        product(&a.clone().into_single(), &x, &mut want);
        blocks.product(&x, &mut got);
        let worst = want.iter().zip(&got).map(|(w, g)| (w - g).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-14 * want.iter().fold(0.0f64, |m, w| m.max(w.abs())), "{worst:e}");
        let diagonal = Csr::from_triplets(n, n, &(0..n).map(|i| (i, i, 1.0)).collect::<Vec<_>>());
        assert!(BlockRows::square(&diagonal, 2).is_none(), "2x2 blocks of a diagonal are half zeros");
        assert!(BlockRows::square(&a, 5).is_none(), "12 rows are not whole blocks of 5");
    }
}
