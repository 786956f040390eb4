//! Supports: the `n` nearest nodes of every node (the node itself first), from a
//! k-d tree (kiddo), stored in compressed rows.
//!
//! The choice is deterministic, symmetric where the nodes are, and free of the unit
//! system. On grids, and wherever nodes sit symmetrically, several candidates lie at
//! the same distance, and floating-point round-off alone used to decide which of them
//! entered the support (the cantilever in metres and in micrometres gave e_inf(u)
//! 1.3e-4 and 1.4e-5). Now the candidates are sorted by distance, distances that agree
//! to [`TIE`] relative to the node's local spacing (its nearest neighbour) count as
//! equal, and a group of equal distances is taken whole: the support is the nearest
//! `n` nodes plus the rest of the group at the cut, so `n` is a minimum. (Breaking
//! the tie by node index instead gave lopsided stencils: e_inf(u) 2.9e-4 on the
//! cantilever, 1.3e-4 with whole groups.)

use super::Point;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZeroUsize;

/// Distances equal to this fraction of the local spacing are ties.
pub const TIE: f64 = 1e-9;

/// The supports of every node, nearest first; `of(i)[0] == i`; each holds at least
/// the requested number of nodes (more where a group of ties was completed).
#[derive(Debug, Clone)]
pub struct Supports {
    requested: usize,
    offsets: Vec<usize>,
    indices: Vec<u32>,
}

/// The support of node `i` from the candidates `found` (squared distance, index): the
/// nearest `size` and the rest of the group of ties at the cut, nearest first, ties
/// by index, node `i` first; `None` when that group may continue beyond `found`
/// (more candidates are needed).
fn choose(i: usize, mut found: Vec<(f64, u32)>, size: usize, complete: bool) -> Option<Vec<u32>> {
    found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    // Local spacing: the nearest other node (distances are squared here).
    let spacing = found.iter().map(|f| f.0).find(|&d| d > 0.0).unwrap_or(1.0).sqrt();
    let tie = |a: f64, b: f64| (a.sqrt() - b.sqrt()).abs() <= TIE * spacing;
    // Groups of consecutive ties, each ordered by index; stop after the group at the cut.
    let (mut start, mut end) = (0, found.len());
    for k in 1..=found.len() {
        if k == found.len() || !tie(found[k - 1].0, found[k].0) {
            found[start..k].sort_by_key(|f| f.1);
            if k >= size {
                if k == found.len() && !complete {
                    return None;
                }
                end = k;
                break;
            }
            start = k;
        }
    }
    let mut row: Vec<u32> = found[..end].iter().map(|f| f.1).collect();
    // The node itself is at distance zero, alone in its group.
    if row[0] as usize != i {
        let pos = row.iter().position(|&j| j as usize == i).expect("node in its own support");
        row.remove(pos);
        row.insert(0, i as u32);
    }
    Some(row)
}

/// The support of node `i` of at least `size` nodes (module docs).
fn support_of(tree: &ImmutableKdTree<f64, 2>, positions: &[Point], i: usize, size: usize) -> Vec<u32> {
    // A few more than `size`, so that a group of ties at the cut is usually complete.
    let mut fetch = (size + 8).min(positions.len());
    loop {
        let k = NonZeroUsize::new(fetch).expect("at least one node");
        let query = tree.query(&positions[i]).nearest_n::<SquaredEuclidean<f64>>(k).execute();
        let found = query.iter().map(|f| (f.distance, f.item)).collect();
        if let Some(chosen) = choose(i, found, size, fetch == positions.len()) {
            return chosen;
        }
        fetch = (2 * fetch).min(positions.len());
    }
}

impl Supports {
    /// Find the supports of every node (module docs): at least `size` nodes each.
    /// `size` must not exceed the node count.
    pub fn nearest(positions: &[Point], size: usize) -> Supports {
        Supports::nearest_where(positions, size, |_| true)
    }

    /// The supports of the nodes `wanted` picks, among all of `positions` (the same
    /// as [`Supports::nearest`] gives them); the other nodes get an empty support.
    /// A rank of a distributed run finds only its own nodes' supports, which reach
    /// into the halo of nodes it does not own.
    pub fn nearest_where(positions: &[Point], size: usize, wanted: impl Fn(usize) -> bool + Sync) -> Supports {
        assert!(size >= 1 && size <= positions.len(), "support size {size} for {} nodes", positions.len());
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(positions).expect("k-d tree of finite node positions");
        let rows: Vec<Vec<u32>> = (0..positions.len())
            .into_par_iter()
            .map(|i| if wanted(i) { support_of(&tree, positions, i, size) } else { Vec::new() })
            .collect();
        Supports::from_rows(size, rows)
    }

    fn from_rows(requested: usize, rows: Vec<Vec<u32>>) -> Supports {
        let mut offsets = Vec::with_capacity(rows.len() + 1);
        offsets.push(0);
        for r in &rows {
            offsets.push(offsets.last().unwrap() + r.len());
        }
        Supports { requested, offsets, indices: rows.into_iter().flatten().collect() }
    }

    /// The same supports with those of `nodes` widened to at least `size` nodes
    /// (capped at the node count).
    pub fn widened(&self, positions: &[Point], nodes: &[usize], size: usize) -> Supports {
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(positions).expect("k-d tree of finite node positions");
        let size = size.min(positions.len());
        let mut rows: Vec<Vec<u32>> = (0..self.len()).map(|i| self.of(i).to_vec()).collect();
        for &i in nodes {
            rows[i] = support_of(&tree, positions, i, size);
        }
        Supports::from_rows(self.requested, rows)
    }

    /// The requested support size `n` (every support holds at least this many nodes).
    pub fn requested(&self) -> usize {
        self.requested
    }

    /// The largest support.
    pub fn largest(&self) -> usize {
        self.offsets.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0)
    }

    /// Number of nodes with a support.
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Whether there are no supports.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Where the support of node `i` starts in the flat index array (shapes are stored
    /// in the same order).
    pub fn offset(&self, i: usize) -> usize {
        self.offsets[i]
    }

    /// Total number of (node, support node) pairs.
    pub fn total(&self) -> usize {
        self.indices.len()
    }

    /// Support of node `i` (node indices, `i` first; empty for a node
    /// [`Supports::nearest_where`] left out).
    pub fn of(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i]..self.offsets[i + 1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a 6 x 6 lattice: the corner node 0 has 1 and 6 at h and 7 at sqrt(2) h; the
    /// interior node 14 has four ties at h, which are taken whole, whatever the unit
    /// of length.
    #[test]
    fn groups_of_ties_are_taken_whole_in_any_unit() {
        for scale in [1.0, 1e-6, 1e4, 0.1] {
            let h = 0.1 * scale;
            let positions: Vec<Point> = (0..36).map(|k| [h * (k % 6) as f64, h * (k / 6) as f64]).collect();
            assert_eq!(Supports::nearest(&positions, 4).of(0), &[0, 1, 6, 7], "scale {scale}");
            assert_eq!(Supports::nearest(&positions, 3).of(0), &[0, 1, 6], "scale {scale}");
            // Interior node 14 (2, 2): 4 neighbours at h, 4 at sqrt(2) h.
            for n in [2, 3, 5] {
                assert_eq!(Supports::nearest(&positions, n).of(14), &[14, 8, 13, 15, 20], "n {n}, scale {scale}");
            }
            let s = Supports::nearest(&positions, 6);
            assert_eq!(s.of(14), &[14, 8, 13, 15, 20, 7, 9, 19, 21], "scale {scale}");
            assert!(s.requested() == 6 && s.largest() >= 9 && (0..36).all(|i| s.of(i).len() >= 6));
        }
    }

    /// The supports of picked nodes are those of the whole search; the others are empty.
    #[test]
    fn picked_supports_equal_the_whole_search() {
        let positions: Vec<Point> = (0..300).map(|k| [((k * 37) % 101) as f64 * 0.013, ((k * 53) % 97) as f64 * 0.011]).collect();
        let whole = Supports::nearest(&positions, 9);
        let picked = Supports::nearest_where(&positions, 9, |i| i % 3 == 1);
        for i in 0..positions.len() {
            let expected: &[u32] = if i % 3 == 1 { whole.of(i) } else { &[] };
            assert_eq!(picked.of(i), expected, "node {i}");
        }
        assert_eq!(picked.total(), (0..300).filter(|i| i % 3 == 1).map(|i| whole.of(i).len()).sum::<usize>());
    }

    /// Whole supports agree between unit systems on a rotated, shifted lattice whose
    /// coordinates carry round-off (ties are then not exact in floating point).
    #[test]
    fn supports_do_not_depend_on_the_unit_of_length() {
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let lattice = |scale: f64| -> Vec<Point> {
            (0..400)
                .map(|k| {
                    let (x, y) = ((k % 20) as f64 * 0.037, (k / 20) as f64 * 0.037);
                    [scale * (1.7 + c * x - s * y), scale * (-0.4 + s * x + c * y)]
                })
                .collect()
        };
        for n in [6, 9, 12, 13, 20] {
            let reference = Supports::nearest(&lattice(1.0), n);
            for scale in [1e-6, 1e-3, 1e4] {
                let other = Supports::nearest(&lattice(scale), n);
                assert_eq!((&reference.offsets, &reference.indices), (&other.offsets, &other.indices), "support {n}, scale {scale}");
            }
        }
    }
}
