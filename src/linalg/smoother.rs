//! The smoother of the multigrid ([`super::amg`]): block Gauss–Seidel on the nodal
//! blocks of a level, with the (pseudo-)inverses of its diagonal blocks.

use super::aggregation::Blocks;
use super::blocks::BlockRows;
use super::csr::{row_dot, Csr, RowsRef, Value};
use nalgebra::DMatrix;
use rayon::prelude::*;

/// Pseudo-inverses of the diagonal blocks of `a` (row-major, `block²` per node):
/// a ghost's block can be singular, and a coarse node whose near-null vectors were
/// dependent has zero rows; the pseudo-inverse leaves those directions to the other
/// levels instead of dividing by zero.
pub(super) fn inverse_diagonal_blocks(a: &Csr, blocks: Blocks) -> Vec<f64> {
    let b = blocks.block;
    let (ptr, idx, val) = (a.row_offsets(), a.col_indices(), a.values());
    let mut out = vec![0.0; blocks.nodes * b * b];
    out.par_chunks_mut(b * b).enumerate().for_each(|(node, inv)| {
        let mut d = DMatrix::<f64>::zeros(b, b);
        for r in 0..b {
            let row = node * b + r;
            for k in ptr[row]..ptr[row + 1] {
                let c = idx[k] as usize;
                if c / b == node {
                    d[(r, c % b)] = val[k];
                }
            }
        }
        let largest = d.amax();
        if largest == 0.0 {
            return;
        }
        let p = pseudo_inverse(&d);
        for r in 0..b {
            for c in 0..b {
                inv[r * b + c] = p[(r, c)];
            }
        }
    });
    out
}

/// Largest condition number of a diagonal block inverted as it stands; beyond it the
/// block's small singular values are dropped (pseudo-inverse).
const BLOCK_CONDITION: f64 = 1e10;

/// `d⁻¹` by LU when `d` is well conditioned, else the pseudo-inverse from faer's SVD
/// with singular values below `‖d‖ / BLOCK_CONDITION` dropped (nalgebra's SVD is not
/// used: it fails silently on some well-posed problems, `../shared/docs/crates.md`).
fn pseudo_inverse(d: &DMatrix<f64>) -> DMatrix<f64> {
    let b = d.nrows();
    if let Some(inv) = d.clone().try_inverse() {
        let (n, ni) = (d.abs().row_sum().max(), inv.abs().row_sum().max());
        if n * ni < BLOCK_CONDITION && inv.iter().all(|v| v.is_finite()) {
            return inv;
        }
    }
    let m = faer::Mat::<f64>::from_fn(b, b, |i, j| d[(i, j)]);
    let svd = m.svd();
    super::vector_state::clear_upper_halves();
    let Ok(svd) = svd else { return DMatrix::zeros(b, b) };
    let (u, s, v) = (svd.U(), svd.S(), svd.V());
    let largest = (0..b).map(|i| s[i]).fold(0.0f64, f64::max);
    let mut out = DMatrix::<f64>::zeros(b, b);
    for k in 0..b {
        if s[k] > largest / BLOCK_CONDITION {
            for i in 0..b {
                for j in 0..b {
                    out[(i, j)] += v[(i, k)] * u[(j, k)] / s[k];
                }
            }
        }
    }
    out
}

/// The order of a Gauss–Seidel sweep, and whether the iterate is zero before it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Sweep {
    /// Nodes in increasing order.
    Forward,
    /// Nodes in decreasing order.
    Backward,
    /// Nodes in increasing order from `z = 0` (a V-cycle's first sweep): a row then
    /// meets nonzero values only in the columns of the nodes before its own, so it
    /// reads only those entries (sorted columns: a binary search finds where they
    /// end), half of the matrix.
    ForwardFromZero,
}

/// One block Gauss–Seidel sweep for `A z = f`, nodes in the order of `direction`:
/// `z_I += D_I⁺ (f − A z)_I`. With several threads the nodes are
/// split into one contiguous range per thread, each swept in order with the values
/// of the other ranges from before the sweep ("hybrid" Gauss–Seidel, Baker, Falgout,
/// Kolev & Yang, *SIAM J. Sci. Comput.* 33 (2011) 2864–2887): ranges of thousands of
/// nodes couple only through their edges, so the sweep stays a Gauss–Seidel sweep
/// almost everywhere.
///
/// Each range but the first is swept in a private copy of the whole iterate (`copies`,
/// kept by the caller between sweeps), which holds the values of the other ranges from
/// before the sweep and its own as they are updated, so that the inner loop reads one
/// array without testing where a column lies (the test was 40 % of the sweep's
/// samples); the first range is swept in the iterate itself, which no other range
/// writes, and the other ranges are then copied back.
pub(super) fn gauss_seidel<A: NodeResidual>(
    a: A,
    blocks: Blocks,
    inv_diag: &[f64],
    f: &[f64],
    z: &mut [f64],
    direction: Sweep,
    copies: &mut Vec<Vec<f64>>,
) {
    let nodes = blocks.nodes;
    let parts = if nodes >= PARALLEL_SWEEP_NODES { rayon::current_num_threads().max(1) } else { 1 };
    if parts == 1 {
        sweep(a, blocks, inv_diag, f, z, 0..nodes, direction);
        return;
    }
    let (b, per_part) = (blocks.block, nodes.div_ceil(parts));
    let range_of = |part: usize| part * per_part..nodes.min((part + 1) * per_part);
    // The first range is swept in `z` itself: the others write only their copies.
    copies.resize_with(parts - 1, Vec::new);
    copies.par_iter_mut().for_each(|copy| {
        copy.clear();
        copy.extend_from_slice(z);
    });
    let own: Vec<&mut Vec<f64>> = copies.iter_mut().collect();
    rayon::scope(|s| {
        for (part, copy) in own.into_iter().enumerate() {
            s.spawn(move |_| sweep(a, blocks, inv_diag, f, copy, range_of(part + 1), direction));
        }
        sweep(a, blocks, inv_diag, f, z, range_of(0), direction);
    });
    z.par_chunks_mut(per_part * b).enumerate().skip(1).for_each(|(part, own)| {
        let first = range_of(part).start * b;
        own.copy_from_slice(&copies[part - 1][first..first + own.len()]);
    });
}

/// What a Gauss–Seidel sweep reads of an operator: the residual of one node's rows.
pub(super) trait NodeResidual: Copy + Send + Sync {
    /// `s_m = f_{bI+m} − (A x)_{bI+m}` for the `b` unknowns of node `I`; with
    /// `lower`, only the columns of the nodes before `I` count (a forward sweep from a
    /// zero iterate reads the others as zeros).
    fn node_residual(&self, node: usize, b: usize, f: &[f64], x: &[f64], lower: bool, s: &mut [f64]);
}

impl<V: Value> NodeResidual for RowsRef<'_, V> {
    fn node_residual(&self, node: usize, b: usize, f: &[f64], x: &[f64], lower: bool, s: &mut [f64]) {
        let (ptr, idx, val) = self.parts();
        for (m, sm) in s.iter_mut().enumerate().take(b) {
            let row = node * b + m;
            let mut entries = ptr[row]..ptr[row + 1];
            if lower {
                entries.end = entries.start + idx[entries.clone()].partition_point(|&c| (c as usize) < node * b);
            }
            *sm = f[row] - row_dot(&idx[entries.clone()], &val[entries], x);
        }
    }
}

impl<V: Value> NodeResidual for &Csr<V> {
    fn node_residual(&self, node: usize, b: usize, f: &[f64], x: &[f64], lower: bool, s: &mut [f64]) {
        RowsRef::from(*self).node_residual(node, b, f, x, lower, s);
    }
}

/// Square node blocks ([`BlockRows::square`]); the 2 x 2 blocks of a displacement
/// system with the block size known to the compiler.
impl NodeResidual for &BlockRows {
    fn node_residual(&self, node: usize, b: usize, f: &[f64], x: &[f64], lower: bool, s: &mut [f64]) {
        match b {
            2 => BlockRows::node_residual::<2>(self, node, f, x, lower, s),
            _ => unreachable!("the multigrid makes node blocks of two unknowns only (LevelOperator::new)"),
        }
    }
}

/// One Gauss–Seidel sweep over the nodes of `range` of the iterate `x`, in the order
/// of `direction`: `x_I += D_I⁺ (f − A x)_I`.
fn sweep<A: NodeResidual>(
    a: A,
    blocks: Blocks,
    inv_diag: &[f64],
    f: &[f64],
    x: &mut [f64],
    range: std::ops::Range<usize>,
    direction: Sweep,
) {
    let b = blocks.block;
    let lower = direction == Sweep::ForwardFromZero;
    let mut s = [0.0f64; MAX_BLOCK];
    let mut update = |node: usize| {
        a.node_residual(node, b, f, x, lower, &mut s);
        let inv = &inv_diag[node * b * b..(node + 1) * b * b];
        for m in 0..b {
            x[node * b + m] += (0..b).map(|c| inv[m * b + c] * s[c]).sum::<f64>();
        }
    };
    if direction == Sweep::Backward {
        range.rev().for_each(&mut update);
    } else {
        range.for_each(&mut update);
    }
}

/// Below this many nodes a level is swept by one thread (the copy of the iterate
/// costs more than the second thread gains).
const PARALLEL_SWEEP_NODES: usize = 20_000;

/// Largest block (unknowns per node or near-null vectors) the smoother handles.
pub(super) const MAX_BLOCK: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;

    /// A block-banded matrix of `nodes` 2x2-block nodes coupled to their neighbours up to
    /// three nodes away, unsymmetric, diagonally dominant.
    fn banded(nodes: usize) -> Csr {
        let mut t = Vec::new();
        for i in 0..nodes {
            for j in i.saturating_sub(3)..(i + 4).min(nodes) {
                for (r, c) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    let v = if i == j {
                        if r == c {
                            8.0
                        } else {
                            0.5
                        }
                    } else {
                        -0.3 - 0.1 * ((i + 2 * j + r + c) % 5) as f64
                    };
                    t.push((2 * i + r, 2 * j + c, v));
                }
            }
        }
        Csr::from_triplets(2 * nodes, 2 * nodes, &t)
    }

    /// From `z = 0`, the sweep that reads only the columns before each node's own gives
    /// the forward sweep's result (to round-off: the skipped terms are zeros, the sums'
    /// grouping differs), on one range and on one range per thread.
    #[test]
    fn a_forward_sweep_from_zero_reads_the_lower_part_only_and_agrees() {
        for nodes in [50, 2 * PARALLEL_SWEEP_NODES] {
            let (a, blocks) = (banded(nodes), Blocks { block: 2, nodes });
            let inv = inverse_diagonal_blocks(&a, blocks);
            let f: Vec<f64> = (0..2 * nodes).map(|k| ((k * 7919) % 13) as f64 - 6.0).collect();
            let mut copies = Vec::new();
            let (mut full, mut lower) = (vec![0.0; 2 * nodes], vec![0.0; 2 * nodes]);
            gauss_seidel(&a, blocks, &inv, &f, &mut full, Sweep::Forward, &mut copies);
            gauss_seidel(&a, blocks, &inv, &f, &mut lower, Sweep::ForwardFromZero, &mut copies);
            let worst = full.iter().zip(&lower).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(worst <= 1e-14 * full.iter().fold(0.0f64, |m, x| m.max(x.abs())), "{nodes} nodes: {worst:e}");
            assert!(full.iter().any(|&x| x != 0.0));
        }
    }

    /// The sweeps read node blocks ([`BlockRows::square`]) as they read rows: the same
    /// iterate to round-off (the sums are grouped differently) in each direction, on
    /// one range and on one range per thread, with some nodes' rows reduced to their
    /// diagonal (Dirichlet rows: their blocks store zeros).
    #[test]
    fn sweeps_on_node_blocks_equal_sweeps_on_rows() {
        for nodes in [50, 2 * PARALLEL_SWEEP_NODES] {
            let entries: Vec<_> = banded(nodes).entries().filter(|&(i, j, _)| (i / 2) % 7 != 3 || i == j).collect();
            let a = Csr::from_triplets(2 * nodes, 2 * nodes, &entries);
            let blocks = Blocks { block: 2, nodes };
            let inv = inverse_diagonal_blocks(&a, blocks);
            let square = BlockRows::square(&a, 2).expect("few zeros");
            let single = a.clone().into_single();
            let f: Vec<f64> = (0..2 * nodes).map(|k| ((k * 7919) % 13) as f64 - 6.0).collect();
            let mut copies = Vec::new();
            let (mut rows, mut by_blocks) = (vec![0.0; 2 * nodes], vec![0.0; 2 * nodes]);
            for direction in [Sweep::ForwardFromZero, Sweep::Backward, Sweep::Forward] {
                gauss_seidel(RowsRef::from(&single), blocks, &inv, &f, &mut rows, direction, &mut copies);
                gauss_seidel(&square, blocks, &inv, &f, &mut by_blocks, direction, &mut copies);
                let worst = rows.iter().zip(&by_blocks).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                let scale = rows.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                assert!(worst <= 1e-13 * scale && scale > 0.0, "{nodes} nodes, {direction:?}: {worst:e} of {scale:e}");
            }
        }
    }
}
