//! The smoother of the multigrid ([`super::amg`]): block Gauss–Seidel on the nodal
//! blocks of a level, with the (pseudo-)inverses of its diagonal blocks.

use super::aggregation::Blocks;
use super::csr::Csr;
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
    let Ok(svd) = m.svd() else { return DMatrix::zeros(b, b) };
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

/// One block Gauss–Seidel sweep for `A z = f`, nodes in increasing (`forward`) or
/// decreasing order: `z_I += D_I⁺ (f − A z)_I`. With several threads the nodes are
/// split into one contiguous range per thread, each swept in order with the values
/// of the other ranges from before the sweep ("hybrid" Gauss–Seidel, Baker, Falgout,
/// Kolev & Yang, *SIAM J. Sci. Comput.* 33 (2011) 2864–2887): ranges of thousands of
/// nodes couple only through their edges, so the sweep stays a Gauss–Seidel sweep
/// almost everywhere.
///
/// `before` is the buffer the iterate is copied into when the sweep runs in parallel
/// (kept by the caller between sweeps).
pub(super) fn gauss_seidel(a: &Csr, blocks: Blocks, inv_diag: &[f64], f: &[f64], z: &mut [f64], forward: bool, before: &mut Vec<f64>) {
    let b = blocks.block;
    let nodes = blocks.nodes;
    let parts = if nodes >= PARALLEL_SWEEP_NODES { rayon::current_num_threads().max(1) } else { 1 };
    let per_part = nodes.div_ceil(parts);
    if parts > 1 {
        before.clear();
        before.extend_from_slice(z);
    }
    let before: Option<&[f64]> = (parts > 1).then_some(&before[..]);
    let (ptr, idx, val) = (a.row_offsets(), a.col_indices(), a.values());
    z.par_chunks_mut(per_part * b).enumerate().for_each(|(part, own)| {
        let first = part * per_part;
        let start = first * b;
        let end = start + own.len();
        let range = first..first + own.len() / b;
        let mut s = [0.0f64; MAX_BLOCK];
        let mut sweep = |node: usize| {
            for (m, sm) in s.iter_mut().enumerate().take(b) {
                let row = node * b + m;
                let mut sum = 0.0;
                let entries = ptr[row]..ptr[row + 1];
                for (&c, &v) in idx[entries.clone()].iter().zip(&val[entries]) {
                    let c = c as usize;
                    let zc = if (start..end).contains(&c) { own[c - start] } else { before.map_or(0.0, |z| z[c]) };
                    sum += v * zc;
                }
                *sm = f[row] - sum;
            }
            let inv = &inv_diag[node * b * b..(node + 1) * b * b];
            for m in 0..b {
                own[(node - first) * b + m] += (0..b).map(|c| inv[m * b + c] * s[c]).sum::<f64>();
            }
        };
        if forward {
            range.for_each(&mut sweep);
        } else {
            range.rev().for_each(&mut sweep);
        }
    });
}

/// Below this many nodes a level is swept by one thread (the copy of the iterate
/// costs more than the second thread gains).
const PARALLEL_SWEEP_NODES: usize = 20_000;

/// Largest block (unknowns per node or near-null vectors) the smoother handles.
const MAX_BLOCK: usize = 8;
