//! Corners and holes of a node set. Corners: boundary nodes where two parts meet (a kink inside one named
//! part is not a corner here), and whether the solid's
//! interior angle there exceeds 180 degrees (a re-entrant corner, where the elastic
//! stress is singular whatever the boundary conditions).
//!
//! With `n1`, `n2` the outward normals of the two parts at the corner `p`, the interior
//! near a convex corner is `{x.n1 < 0 and x.n2 < 0}`, near a re-entrant one
//! `{x.n1 < 0 or x.n2 < 0}`. The direction `d = n1 - n2` has `d.n1 > 0` and
//! `d.n2 < 0`, so `p + eps d` lies inside exactly when the corner is re-entrant.
//!
//! Holes: the boundary's loops are its parts joined wherever a node touches two; a
//! loop is a hole when its outward normals point towards its own mean position,
//! `sum_i n_i . (x_i - x_mean) < 0` (the outer loop's point away from it).

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

/// The holes of `nodes`: for each, the indices of its boundary nodes (module docs).
pub fn holes(nodes: &NodeSet) -> Vec<Vec<usize>> {
    let parts = nodes.boundary.iter().flat_map(|b| b.touches.iter().map(|&(p, _)| p + 1)).max().unwrap_or(0);
    // Union-find over parts.
    let mut root: Vec<usize> = (0..parts).collect();
    fn find(root: &mut [usize], mut p: usize) -> usize {
        while root[p] != p {
            root[p] = root[root[p]];
            p = root[p];
        }
        p
    }
    for b in &nodes.boundary {
        for w in b.touches.windows(2) {
            let (a, c) = (find(&mut root, w[0].0), find(&mut root, w[1].0));
            root[a] = c;
        }
    }
    let mut loops: std::collections::BTreeMap<usize, Vec<usize>> = std::collections::BTreeMap::new();
    for (i, b) in nodes.boundary.iter().enumerate() {
        if let Some(&(p, _)) = b.touches.first() {
            loops.entry(find(&mut root, p)).or_default().push(i);
        }
    }
    loops
        .into_values()
        .filter(|l| {
            let mean = mean_position(nodes, l);
            let outward: f64 = l
                .iter()
                .map(|&i| {
                    let n = nodes.normal(i);
                    n[0] * (nodes.positions[i][0] - mean[0]) + n[1] * (nodes.positions[i][1] - mean[1])
                })
                .sum();
            outward < 0.0
        })
        .collect()
}

/// The mean position of the boundary nodes `indices`, each weighted by the length of
/// boundary it stands for (graded nodes crowd one side of a hole; the plain mean
/// leaned towards it): `sum l_i x_i / sum l_i`.
pub fn mean_position(nodes: &NodeSet, indices: &[usize]) -> Point {
    let length = |i: usize| nodes.boundary[i].lengths.iter().sum::<f64>();
    let total: f64 = indices.iter().map(|&i| length(i)).sum();
    indices.iter().fold([0.0, 0.0], |m, &i| {
        let w = length(i) / total;
        [m[0] + w * nodes.positions[i][0], m[1] + w * nodes.positions[i][1]]
    })
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

    /// A square with a hole has one hole (the disc's nodes); a disc that cuts the
    /// outer edge (a notch) joins the outer loop and is not a hole.
    #[test]
    fn a_hole_is_an_inner_loop_and_a_notch_is_not() {
        let with_disc = |center: Point| Domain {
            regions: vec![
                Region {
                    primitive: Primitive::Rectangle { min: [0.0, 0.0], max: [2.0, 2.0] },
                    op: CsgOp::Union,
                    edge_parts: vec![0, 1, 2, 3],
                },
                Region { primitive: Primitive::Disc { center, radius: 0.4 }, op: CsgOp::Subtract, edge_parts: vec![4] },
            ],
            parts: (0..5).map(|k| format!("edge{k}")).collect(),
        };
        let fill = FillParams { spacing: 0.1, refine: None, adapted: None, kind: FillKind::Scattered, seed: 1, relax_iterations: 0 };
        let domain = with_disc([1.0, 1.0]);
        let nodes = generate(&domain, &fill);
        let found = holes(&nodes);
        assert_eq!(found.len(), 1);
        assert!(found[0].iter().all(|&i| nodes.boundary[i].touches.iter().all(|&(p, _)| p == 4)));
        assert_eq!(found[0].len(), nodes.boundary.iter().filter(|b| b.touches[0].0 == 4).count());
        let notched = with_disc([2.0, 1.0]);
        assert!(holes(&generate(&notched, &fill)).is_empty());
    }
}
