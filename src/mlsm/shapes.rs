//! Shape functions of all nodes, computed in parallel (rayon) for exactly the
//! operators each node needs, and stored node by node.

use super::basis::{Basis, LocalBasis};
use super::ops::{Op, OpSet};
use super::fit::shape_functions;
use super::frame::{monomial_matrix_into, LocalFrame};
use super::wls::{rank_ratio_in, RANK_TOLERANCE};
use super::Approximation;
use crate::domain::neighbors::Supports;
use crate::domain::Point;
use rayon::prelude::*;

/// A support whose local least-squares matrix is rank deficient.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "degenerate support at node {node} ({x:.6e}, {y:.6e}): the weighted basis matrix has rank < {basis_size} \
     (smallest relative QR pivot {ratio:.1e}); the {support} nearest nodes are too close to collinear or too few \
     for the basis. Use a larger support, a lower degree, or a finer/more regular node fill"
)]
pub struct ShapeError {
    /// Node index.
    pub node: usize,
    /// Node position x.
    pub x: f64,
    /// Node position y.
    pub y: f64,
    /// Basis size m.
    pub basis_size: usize,
    /// Support size n.
    pub support: usize,
    /// Smallest `|R_kk| / max |R_kk|`.
    pub ratio: f64,
}

/// Shape functions per node and operator, stored node by node in the order of the
/// supports: node `i` holds one block of `len(support i)` values per stored operator.
#[derive(Debug, Clone)]
pub struct Shapes {
    /// Start of each node's support in the flat support array (`N + 1` entries).
    offsets: Vec<usize>,
    /// Operators stored for every node (slots), and per node which of them were computed.
    stored: OpSet,
    slot: [usize; 6],
    computed: Vec<OpSet>,
    data: Vec<f64>,
}

impl Shapes {
    /// Union of the operators computed at any node.
    pub fn operators(&self) -> OpSet {
        self.stored
    }

    /// Operators computed at node `i`.
    pub fn computed_at(&self, i: usize) -> OpSet {
        self.computed[i]
    }

    /// Shape function of `op` at node `i`, aligned with `supports.of(i)`.
    pub fn get(&self, i: usize, op: Op) -> &[f64] {
        debug_assert!(self.computed[i].contains(op), "shape {op:?} not computed at node {i}");
        let len = self.offsets[i + 1] - self.offsets[i];
        let start = self.stored.len() * self.offsets[i] + self.slot[op as usize] * len;
        &self.data[start..start + len]
    }

    /// Number of (node, operator) shape functions actually computed.
    pub fn count(&self) -> usize {
        self.computed.iter().map(|s| s.len()).sum()
    }

    /// Keep the operators in `keep` only and give the memory of the others back (the
    /// second derivatives are needed for assembly, the gradients after the solve): at
    /// 1e6 nodes with 13-node supports, 0.53 GB of shapes become 0.21 GB. Each node's
    /// kept blocks move towards the front, in place.
    pub fn retain(&mut self, keep: OpSet) {
        let kept = self.stored & keep;
        if kept == self.stored {
            return;
        }
        let (old_k, new_k) = (self.stored.len(), kept.len());
        let mut new_slot = [0; 6];
        for (k, op) in kept.iter().enumerate() {
            new_slot[op as usize] = k;
        }
        for i in 0..self.offsets.len() - 1 {
            let (offset, len) = (self.offsets[i], self.offsets[i + 1] - self.offsets[i]);
            for op in kept.iter() {
                // The target never lies after the source, and the sources still to be
                // read lie after every target written so far.
                let from = old_k * offset + self.slot[op as usize] * len;
                let to = new_k * offset + new_slot[op as usize] * len;
                self.data.copy_within(from..from + len, to);
            }
        }
        self.data.truncate(new_k * self.offsets[self.offsets.len() - 1]);
        self.data.shrink_to_fit();
        self.stored = kept;
        self.slot = new_slot;
        self.computed.iter_mut().for_each(|c| *c = *c & keep);
    }
}

/// The nodes that need shapes (`needs[i]` not empty) and whose support cannot
/// determine the polynomial part of `basis`, each with the smallest relative QR pivot
/// of its monomials at the support nodes in local coordinates (numerical rank below
/// their count: a one-sided lattice stencil spanning fewer than `p + 1` rows, for
/// instance; 0 for a support with fewer nodes than monomials). For RBF-FD this is the
/// only rank test: the discretisation runs it on every support before the shapes.
pub fn degenerate_supports(positions: &[Point], supports: &Supports, basis: &Basis, needs: &[OpSet]) -> Vec<(usize, f64)> {
    let local = LocalBasis::new(basis);
    // Buffers per rayon task, not per node (six allocations a node were 3 % of a
    // degree-6 run: docs/notebook/2026-11-29-stencil-weights-null-space.md).
    (0..supports.len())
        .into_par_iter()
        .map_init(RankScratch::default, |scratch, i| {
            if needs[i].is_empty() {
                return None;
            }
            let support = supports.of(i);
            if support.len() < local.len() {
                return Some((i, 0.0));
            }
            let RankScratch { points, frame, p, diag, beta } = scratch;
            points.clear();
            points.extend(support.iter().map(|&j| positions[j as usize]));
            frame.fill(positions[i], points);
            monomial_matrix_into(&local, &frame.z, p);
            let ratio = rank_ratio_in(p, support.len(), local.len(), (diag, beta));
            (ratio.is_nan() || ratio <= RANK_TOLERANCE).then_some((i, ratio))
        })
        .flatten()
        .collect()
}

/// The buffers of [`degenerate_supports`]' rank tests, one set per rayon task.
#[derive(Default)]
struct RankScratch {
    points: Vec<[f64; 2]>,
    frame: LocalFrame,
    p: Vec<f64>,
    diag: Vec<f64>,
    beta: Vec<f64>,
}

/// Compute, for every node `i`, the shapes of the operators `needs[i]`.
pub fn compute_shapes(positions: &[Point], supports: &Supports, approx: &Approximation, needs: &[OpSet]) -> Result<Shapes, ShapeError> {
    let stored = needs.iter().fold(OpSet::EMPTY, |a, &b| a | b);
    // Storage slot of each operator (only the stored ones have one).
    let mut slot = [0; 6];
    for (k, op) in stored.iter().enumerate() {
        slot[op as usize] = k;
    }
    let k = stored.len();
    let offsets: Vec<usize> =
        (0..=supports.len()).map(|i| if i < supports.len() { supports.offset(i) } else { supports.total() }).collect();
    let mut data = vec![0.0; k * supports.total()];
    if k > 0 {
        // One mutable block per node, in node order.
        let mut blocks: Vec<&mut [f64]> = Vec::with_capacity(supports.len());
        let mut rest = data.as_mut_slice();
        for i in 0..supports.len() {
            let (block, tail) = rest.split_at_mut(k * (offsets[i + 1] - offsets[i]));
            blocks.push(block);
            rest = tail;
        }
        blocks.into_par_iter().enumerate().try_for_each_init(
            || (Vec::new(), Vec::new()),
            |(pts, buf): &mut (Vec<Point>, Vec<f64>), (i, record)| {
                // The node's operators, without an allocation per node.
                let mut list = [Op::Value; Op::ALL.len()];
                let count = needs[i].iter().zip(list.iter_mut()).map(|(op, slot)| *slot = op).count();
                let ops = &list[..count];
                if ops.is_empty() {
                    return Ok(());
                }
                let support = supports.of(i);
                let n = support.len();
                pts.clear();
                pts.extend(support.iter().map(|&j| positions[j as usize]));
                buf.clear();
                buf.resize(ops.len() * n, 0.0);
                shape_functions(&approx.basis, &approx.weight, positions[i], pts, ops, buf).map_err(|e| ShapeError {
                    node: i,
                    x: positions[i][0],
                    y: positions[i][1],
                    basis_size: e.basis_size,
                    support: n,
                    ratio: e.ratio,
                })?;
                for (c, op) in ops.iter().enumerate() {
                    let s = slot[*op as usize];
                    record[s * n..(s + 1) * n].copy_from_slice(&buf[c * n..(c + 1) * n]);
                }
                Ok(())
            },
        )?;
    }
    Ok(Shapes { offsets, stored, slot, computed: needs.to_vec(), data })
}

/// The least-squares approximation the unit tests use: monomials of degree 2, a
/// Gaussian weight of width 1 (in support radii), `support` nodes, no ghosts.
#[cfg(test)]
pub(crate) fn test_least_squares(support: usize) -> Approximation {
    Approximation { basis: Basis::Monomials { degree: 2 }, weight: super::Weight::Gaussian { sigma: 1.0 }, support, ghost_nodes: false }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::neighbors::Supports;

    /// Retaining the first derivatives keeps them bit for bit at every node (whatever
    /// else each node had), drops the second derivatives, and shrinks the storage to
    /// 2 of the 5 operators stored.
    #[test]
    fn retain_keeps_the_kept_operators_exactly() {
        let positions: Vec<[f64; 2]> = (0..64).map(|k| [0.1 * (k % 8) as f64 + 0.01 * (k / 8) as f64, 0.1 * (k / 8) as f64]).collect();
        let supports = Supports::nearest(&positions, 9);
        let approx = test_least_squares(9);
        let needs: Vec<OpSet> = (0..64).map(|i| [OpSet::D1 | OpSet::D2, OpSet::D1, OpSet::D2, OpSet::EMPTY][i % 4]).collect();
        let all = compute_shapes(&positions, &supports, &approx, &needs).unwrap();
        let mut kept = all.clone();
        kept.retain(OpSet::D1);
        assert_eq!(kept.operators(), OpSet::D1);
        assert_eq!(kept.data.len() * 5, all.data.len() * 2);
        for (i, need) in needs.iter().enumerate() {
            assert_eq!(kept.computed_at(i), *need & OpSet::D1);
            for op in (*need & OpSet::D1).iter() {
                assert_eq!(kept.get(i, op), all.get(i, op), "node {i}, {op:?}");
            }
        }
    }
}
