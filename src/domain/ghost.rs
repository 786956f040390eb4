//! Ghost (fictitious) nodes outside the boundary.
//!
//! A boundary node `p` with outward normal `n` gets the ghost `p + h n`, `h` the
//! node's local spacing. A ghost extrapolates the solution across its own part of the
//! boundary only, so it is skipped where that extrapolation would be ambiguous or
//! degenerate:
//! * it lies less than `h/2` outside the solid (thin parts);
//! * it lies closer than `h/2` to a node or to an earlier ghost (at a concave
//!   corner the ghosts of the two edges' neighbouring nodes coincide, which made
//!   the system singular);
//! * a boundary node of another part lies within `1.2 h` of it (the wedge outside
//!   a concave corner, where the continuations of the two sides disagree; a convex
//!   corner keeps its ghosts, whose nearest foreign node is `sqrt(2) h` away);
//! * its owner lies within [`REENTRANT_GHOST_FREE`] local spacings of a re-entrant
//!   corner given as ghost-free, where the stress is singular: there the
//!   extrapolation across the boundary is wrong by O(1) however fine the nodes (the
//!   caller leaves out the corners whose spurious load the sector balance of
//!   `navier::sector` takes: there the ghost-free edges were worse than the ghosts,
//!   for RBF-FD and for least squares).
//!
//! The radius was chosen on the L bracket without holes (grid, tip deflection against
//! a P2 finite-element reference, `benches/fem_reference.py`): with ghosts up to the
//! corner the tip had the wrong sign; ghost-free within 10 or 16 spacings it did not
//! converge monotonically, within 24 it did (before the sector balance of
//! `navier::sector`; docs/limits.md, and the figures in
//! docs/notebook/2026-11-26-reentrant-sector-balance.md, "From the code comments").

use super::{Domain, NodeSet, Point};
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Radius, in local spacings, around a re-entrant corner inside which boundary nodes
/// get no ghost (module docs: the smallest radius at which the L bracket's tip
/// deflection converged monotonically).
pub const REENTRANT_GHOST_FREE: f64 = 24.0;

/// Ghosts for the boundary nodes `candidates`: `(boundary node, ghost position)`; none
/// within [`REENTRANT_GHOST_FREE`] local spacings of a corner in `ghost_free`.
pub fn place_ghosts(domain: &Domain, nodes: &NodeSet, candidates: &[usize], ghost_free: &[Point]) -> Vec<(usize, Point)> {
    let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&nodes.positions).expect("finite node positions");
    let mut placed: Vec<(usize, Point)> = Vec::with_capacity(candidates.len());
    // Ghosts lie in a band along the boundary: a hash of cells of half the smallest
    // spacing finds earlier ones.
    let cell_size = 0.5 * candidates.iter().map(|&i| nodes.local_spacing[i]).fold(f64::INFINITY, f64::min);
    let cell = |p: Point| ((p[0] / cell_size).floor() as i64, (p[1] / cell_size).floor() as i64);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = std::collections::HashMap::new();
    for &i in candidates {
        // The rules use the node's own (local) spacing h.
        let h = nodes.local_spacing[i];
        let min_gap = 0.5 * h;
        let (p, n) = (nodes.positions[i], nodes.normal(i));
        if ghost_free.iter().any(|c| (c[0] - p[0]).hypot(c[1] - p[1]) < REENTRANT_GHOST_FREE * h) {
            continue;
        }
        let g = [p[0] + h * n[0], p[1] + h * n[1]];
        if domain.signed_distance(g) < min_gap {
            continue;
        }
        let nearest = tree.query(&g).nearest_one::<SquaredEuclidean<f64>>().execute();
        if nearest.distance < min_gap * min_gap {
            continue;
        }
        let own = &nodes.boundary[i].touches;
        let near_foreign_part = tree.query(&g).within::<SquaredEuclidean<f64>>((1.2 * h).powi(2)).execute().iter().any(|q| {
            let j = q.item as usize;
            j < nodes.boundary.len() && nodes.boundary[j].touches.iter().any(|(part, _)| !own.iter().any(|(o, _)| o == part))
        });
        if near_foreign_part {
            continue;
        }
        let (cx, cy) = cell(g);
        let reach = (min_gap / cell_size).ceil() as i64 + 1;
        let clash = (-reach..=reach).any(|dx| {
            (-reach..=reach).any(|dy| {
                grid.get(&(cx + dx, cy + dy))
                    .is_some_and(|list| list.iter().any(|&k| (placed[k].1[0] - g[0]).hypot(placed[k].1[1] - g[1]) < min_gap))
            })
        });
        if clash {
            continue;
        }
        grid.entry((cx, cy)).or_default().push(placed.len());
        placed.push((i, g));
    }
    placed
}

#[cfg(test)]
mod tests {
    use super::super::{generate, FillKind, FillParams};
    use super::*;
    use crate::domain::{CsgOp, Primitive, Region};

    fn nodes(domain: &Domain, h: f64) -> NodeSet {
        generate(domain, &FillParams { spacing: h, refine: None, adapted: None, kind: FillKind::Grid, seed: 0, relax_iterations: 0 })
    }

    /// On a rectangle every boundary node gets its ghost at `p + h n`, outside the
    /// solid, and no two points (nodes or ghosts) are closer than h/2.
    #[test]
    fn rectangle_ghosts_lie_one_spacing_outside_along_the_normal() {
        let h = 0.1;
        let domain = Domain::rectangle([0.0, 0.0], [1.0, 0.5]);
        let n = nodes(&domain, h);
        let all: Vec<usize> = (0..n.boundary.len()).collect();
        let ghosts = place_ghosts(&domain, &n, &all, &crate::domain::corner::reentrant_corners(&domain, &n));
        assert_eq!(ghosts.len(), n.boundary.len(), "every boundary node of a convex solid has a ghost");
        let mut points = n.positions.clone();
        for &(i, g) in &ghosts {
            let (p, normal) = (n.positions[i], n.normal(i));
            assert!((g[0] - p[0] - h * normal[0]).abs() < 1e-12 && (g[1] - p[1] - h * normal[1]).abs() < 1e-12);
            assert!(domain.signed_distance(g) >= 0.5 * h, "ghost of node {i} at {g:?} is not outside");
            points.push(g);
        }
        for (a, p) in points.iter().enumerate() {
            for q in &points[a + 1..] {
                assert!((p[0] - q[0]).hypot(p[1] - q[1]) >= 0.5 * h - 1e-12, "{p:?} and {q:?} too close");
            }
        }
        // Only the candidates get ghosts.
        assert_eq!(place_ghosts(&domain, &n, &all[..3], &[]).len(), 3);
    }

    /// An L-shaped solid: no boundary node within [`REENTRANT_GHOST_FREE`] spacings of
    /// the concave corner (0.5, 0.5) gets a ghost, and no ghost lies in the wedge
    /// outside it, near the other part's nodes.
    #[test]
    fn concave_corner_has_no_ghost() {
        let h = 0.01;
        let vertices = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.5, 0.5], [0.5, 1.0], [0.0, 1.0]];
        let domain = Domain {
            regions: vec![Region { primitive: Primitive::Polygon { vertices }, op: CsgOp::Union, edge_parts: (0..6).collect() }],
            parts: (0..6).map(|k| format!("edge{k}")).collect(),
        };
        let n = nodes(&domain, h);
        let all: Vec<usize> = (0..n.boundary.len()).collect();
        let ghosts = place_ghosts(&domain, &n, &all, &crate::domain::corner::reentrant_corners(&domain, &n));
        let corner = n.positions.iter().position(|p| (p[0] - 0.5).hypot(p[1] - 0.5) < 1e-12).expect("a node at the concave corner");
        assert!(!ghosts.iter().any(|&(i, _)| i == corner), "the concave corner got a ghost");
        for &(i, g) in &ghosts {
            assert!((g[0] - 0.5).hypot(g[1] - 0.5) > 1.2 * h - 1e-12, "ghost {g:?} in the wedge of the concave corner");
            let p = n.positions[i];
            assert!((p[0] - 0.5).hypot(p[1] - 0.5) >= REENTRANT_GHOST_FREE * h, "node {p:?} near the concave corner has a ghost");
        }
        assert!(ghosts.len() > n.boundary.len() / 2, "the straight edges keep their ghosts");
    }
}
