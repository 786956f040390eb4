//! A node spacing adapted to a per-node error indicator (`mlsm run --target-error`).
//!
//! Node `i` with spacing `h_i` and indicator `eta_i` (its estimated error, relative,
//! in the norm of the target) asks for the spacing that would bring its error to a
//! fraction [`SAFETY`] of the tolerance `tau`, if the error falls like `h^q`:
//!
//! ```text
//! h_i' = h_i * clamp((SAFETY tau / eta_i)^(1/q), MIN_FACTOR, 1)
//! ```
//!
//! (never coarser than before: the loop starts coarse and only refines). The wishes are
//! then graded so that the spacing grows by at most `g` per unit of distance,
//!
//! ```text
//! h'(x_i) = min_j (h_j' + g |x_i - x_j|),
//! ```
//!
//! computed by a shortest-path sweep over the graph of each node's [`GRAPH_NEIGHBOURS`]
//! nearest nodes (a path is never shorter than the straight line, so the result is at
//! least the exact envelope and differs from it by the detour of the graph). The
//! grading keeps the density free of jumps and widens a refined spot to the support
//! around it, where the error is made as much as where it shows.

use super::density::SpacingSamples;
use super::shape::Point;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::num::NonZeroUsize;

/// Fraction of the tolerance a refined node aims at (indicators are estimates, and
/// the order is a guess: aiming at the tolerance itself takes an extra step half of
/// the time).
pub const SAFETY: f64 = 0.5;

/// Smallest factor a spacing is multiplied by in one step (at most 16x the nodes
/// locally, so that a wrong order guess cannot explode the node count).
pub const MIN_FACTOR: f64 = 0.25;

/// Spacing gained per unit of distance from a refined node (as `[nodes.refine]`
/// `growth`; below 1/2, the largest the scene accepts).
pub const GROWTH: f64 = 0.1;

/// Power of the step's smallest factor that the nodes next to a singular corner take.
/// The error a corner makes falls like `h_c^lambda` with its corner spacing `h_c`,
/// `lambda` about 0.54 at a re-entrant corner of 270 degrees and about 0.7 where a
/// clamped edge meets a free one, where the rest of the solid's error falls like
/// `h^q`, `q >= 1`: to keep pace, a corner's spacing must shrink by the bulk's factor
/// to the power `q / lambda`, 1.4 to 1.9 for the loop's `q = 1` of degree 2. The square
/// is the round value. On the bracket it kept the estimate close to the true error,
/// where the plain factor, with fewer nodes, let it fall well below
/// (docs/notebook/2026-11-27-bracket-to-error-target.md; docs/verification.md,
/// "Refining to an error target: measured").
pub const CORNER_POWER: i32 = 2;

/// Finest spacing a node next to a singular corner is refined to, as a fraction of
/// the largest spacing of the step. Without it the square of [`CORNER_POWER`]
/// compounds (the nodes graded around a corner ask for refinement too): on the
/// bracket it took one node seed's corner far below the other seeds' in three steps,
/// and the fourth solve took minutes instead of seconds
/// (docs/notebook/2026-11-27-bracket-to-error-target.md).
pub const CORNER_FLOOR: f64 = MIN_FACTOR * MIN_FACTOR * MIN_FACTOR * MIN_FACTOR;

/// Neighbours of a node in the grading graph.
pub const GRAPH_NEIGHBOURS: usize = 8;

/// The factor node spacing is multiplied by for indicator `eta`, tolerance `tau` and
/// order `q` (module docs).
pub fn refinement_factor(eta: f64, tau: f64, order: f64) -> f64 {
    if eta.is_nan() {
        return MIN_FACTOR;
    }
    if eta <= 0.0 {
        return 1.0;
    }
    (SAFETY * tau / eta).powf(1.0 / order).clamp(MIN_FACTOR, 1.0)
}

/// The adapted spacing of nodes at `positions` with spacing `spacing` and
/// `indicator`, graded with growth `g` (module docs). The nodes in `pinned` (those
/// next to singular corners, where the indicator cannot see the error) are refined
/// by the smallest factor of any node to the power [`CORNER_POWER`], down to
/// [`CORNER_FLOOR`] times the largest spacing.
pub fn adapted_spacing(
    positions: &[Point],
    spacing: &[f64],
    indicator: &[f64],
    (tau, order, g): (f64, f64, f64),
    pinned: &[usize],
) -> SpacingSamples {
    let factor: Vec<f64> = indicator.iter().map(|eta| refinement_factor(*eta, tau, order)).collect();
    let smallest = factor.iter().copied().fold(1.0, f64::min);
    let mut wish: Vec<f64> = spacing.iter().zip(&factor).map(|(h, f)| h * f).collect();
    let corner_factor = smallest.powi(CORNER_POWER);
    let floor = CORNER_FLOOR * spacing.iter().copied().fold(0.0, f64::max);
    for &i in pinned {
        wish[i] = wish[i].min((spacing[i] * corner_factor).max(floor));
    }
    SpacingSamples { points: positions.to_vec(), spacing: graded_envelope(positions, &wish, g) }
}

/// `min_j (wish_j + g d(i, j))` over paths of the nearest-neighbour graph (Dijkstra
/// from every node at once, each starting at its own wish).
pub fn graded_envelope(positions: &[Point], wish: &[f64], g: f64) -> Vec<f64> {
    let n = positions.len();
    if n < 2 {
        return wish.to_vec();
    }
    let tree = ImmutableKdTree::<f64, 2>::new_from_slice(positions).expect("finite node positions");
    let k = NonZeroUsize::new((GRAPH_NEIGHBOURS + 1).min(n)).expect("two nodes");
    let mut h = wish.to_vec();
    // Keys are spacings, positive and finite: their bit patterns order like the values.
    let mut heap: BinaryHeap<Reverse<(u64, usize)>> = (0..n).map(|i| Reverse((h[i].to_bits(), i))).collect();
    let mut done = vec![false; n];
    while let Some(Reverse((bits, i))) = heap.pop() {
        if done[i] || bits != h[i].to_bits() {
            continue;
        }
        done[i] = true;
        for nb in tree.query(&positions[i]).nearest_n::<SquaredEuclidean<f64>>(k).execute() {
            let j = nb.item as usize;
            let candidate = h[i] + g * nb.distance.sqrt();
            if !done[j] && candidate < h[j] {
                h[j] = candidate;
                heap.push(Reverse((candidate.to_bits(), j)));
            }
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The factor follows `(SAFETY tau / eta)^(1/q)` inside its clamp.
    #[test]
    fn factor_from_indicator() {
        assert_eq!(refinement_factor(1e-5, 1e-3, 2.0), 1.0, "well below the tolerance: kept");
        assert!((refinement_factor(2e-3, 1e-3, 2.0) - 0.5).abs() < 1e-15, "4x the aim at order 2: halved");
        assert_eq!(refinement_factor(1.0, 1e-3, 2.0), MIN_FACTOR, "far above: clamped");
        assert_eq!(refinement_factor(f64::NAN, 1e-3, 2.0), MIN_FACTOR, "a NaN indicator refines");
        assert_eq!(refinement_factor(0.0, 1e-3, 2.0), 1.0);
    }

    /// A pinned node with a small indicator is refined by the square of the factor of
    /// the node whose indicator asks the most; the others keep their own factors.
    #[test]
    fn a_pinned_node_takes_the_square_of_the_smallest_factor() {
        let positions: Vec<Point> = (0..3).map(|i| [10.0 * i as f64, 0.0]).collect();
        let spacing = [0.1; 3];
        // Order 1, tolerance 1e-3: node 1 asks for (0.5e-3 / 1e-3) = 0.5, the others keep
        // theirs; nodes 10 apart at growth 1 do not grade into each other.
        let indicator = [1e-5, 1e-3, 1e-5];
        let h = adapted_spacing(&positions, &spacing, &indicator, (1e-3, 1.0, 1.0), &[2]).spacing;
        assert_eq!(h, vec![0.1, 0.05, 0.025]);
    }

    /// A pinned node stops at `CORNER_FLOOR` times the largest spacing (1/256 of 0.1
    /// here), and one already finer is not coarsened.
    #[test]
    fn a_pinned_node_stops_at_the_floor() {
        let positions: Vec<Point> = (0..3).map(|i| [10.0 * i as f64, 0.0]).collect();
        // Node 1 asks for the clamp (factor 1/4): the pinned node's square is 1/16.
        let h = adapted_spacing(&positions, &[0.1, 0.1, 0.004], &[1e-5, 1.0, 1e-5], (1e-3, 1.0, 1.0), &[2]).spacing;
        assert_eq!(h, vec![0.1, 0.025, 0.1 / 256.0], "0.004 / 16 = 2.5e-4 is below the floor");
        let h = adapted_spacing(&positions, &[0.1, 0.1, 1e-4], &[1e-5, 1.0, 1e-5], (1e-3, 1.0, 1.0), &[2]).spacing;
        assert_eq!(h, vec![0.1, 0.025, 1e-4], "already below the floor: kept");
    }

    /// On a line of nodes 0.1 apart with one small wish, the envelope rises by g per
    /// unit of distance from it, and never above the wishes.
    #[test]
    fn envelope_grows_linearly_from_a_refined_node() {
        let positions: Vec<Point> = (0..21).map(|i| [0.1 * i as f64, 0.0]).collect();
        let mut wish = vec![0.1; 21];
        wish[10] = 0.01;
        let h = graded_envelope(&positions, &wish, 0.3);
        for (i, hi) in h.iter().enumerate() {
            let expected = (0.01 + 0.3 * 0.1 * (i as f64 - 10.0).abs()).min(0.1);
            assert!((hi - expected).abs() < 1e-12, "node {i}: {hi} vs {expected}");
        }
    }
}
