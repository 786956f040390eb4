//! Corners of a node set: boundary nodes where two parts meet (a kink inside one named
//! part is not a corner here), and whether the solid's
//! interior angle there exceeds 180 degrees (a re-entrant corner, where the elastic
//! stress is singular whatever the boundary conditions).
//!
//! With `n1`, `n2` the outward normals of the two parts at the corner `p`, the interior
//! near a convex corner is `{x.n1 < 0 and x.n2 < 0}`, near a re-entrant one
//! `{x.n1 < 0 or x.n2 < 0}`. The direction `d = n1 - n2` has `d.n1 > 0` and
//! `d.n2 < 0`, so `p + eps d` lies inside exactly when the corner is re-entrant.

use super::{Domain, NodeSet, Point};

/// A boundary node touching two or more parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corner {
    /// Index of the node.
    pub node: usize,
    /// Its position.
    pub position: Point,
    /// The first two parts it touches.
    pub parts: [usize; 2],
    /// Interior angle above 180 degrees.
    pub reentrant: bool,
}

/// The corners of `nodes` in `domain`.
pub fn corners(domain: &Domain, nodes: &NodeSet) -> Vec<Corner> {
    nodes
        .boundary
        .iter()
        .enumerate()
        .filter(|(_, b)| b.touches.len() >= 2)
        .map(|(node, b)| {
            let ((a, n1), (c, n2)) = (b.touches[0], b.touches[1]);
            let eps = 1e-3 * nodes.local_spacing[node];
            let probe = [b.position[0] + eps * (n1[0] - n2[0]), b.position[1] + eps * (n1[1] - n2[1])];
            Corner { node, position: b.position, parts: [a, c], reentrant: domain.contains(probe) }
        })
        .collect()
}

/// The positions of the re-entrant corners of `nodes` in `domain` (by default the
/// ghost-free corners of `ghost::place_ghosts`).
pub fn reentrant_corners(domain: &Domain, nodes: &NodeSet) -> Vec<Point> {
    corners(domain, nodes).into_iter().filter(|c| c.reentrant).map(|c| c.position).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::{generate, CsgOp, FillKind, FillParams, Primitive, Region};

    /// The L-shaped solid `[0, 2]^2` minus `[1, 3]^2`, one part per edge, has five
    /// convex corners and one re-entrant corner at (1, 1).
    #[test]
    fn the_inner_corner_of_an_l_is_reentrant() {
        let domain = Domain {
            regions: vec![
                Region {
                    primitive: Primitive::Rectangle { min: [0.0, 0.0], max: [2.0, 2.0] },
                    op: CsgOp::Union,
                    edge_parts: vec![0, 1, 2, 3],
                },
                Region {
                    primitive: Primitive::Rectangle { min: [1.0, 1.0], max: [3.0, 3.0] },
                    op: CsgOp::Subtract,
                    edge_parts: vec![4, 5, 6, 7],
                },
            ],
            parts: (0..8).map(|k| format!("edge{k}")).collect(),
        };
        let nodes = generate(
            &domain,
            &FillParams { spacing: 0.1, refine: None, adapted: None, kind: FillKind::Scattered, seed: 1, relax_iterations: 0 },
        );
        let c = corners(&domain, &nodes);
        let reentrant: Vec<Point> = c.iter().filter(|c| c.reentrant).map(|c| c.position).collect();
        assert_eq!(reentrant.len(), 1, "{c:?}");
        assert!((reentrant[0][0] - 1.0).abs() < 1e-9 && (reentrant[0][1] - 1.0).abs() < 1e-9);
        assert_eq!(c.len(), 6, "{c:?}");
    }
}
