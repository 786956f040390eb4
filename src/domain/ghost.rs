//! Ghost (fictitious) nodes outside the boundary.
//!
//! A boundary node `p` with outward normal `n` gets the ghost `p + h n`. A ghost is
//! skipped when it would not be a clean extra point: when it lies less than `h/2`
//! outside the solid (thin parts, concave corners where the normals of two edges
//! cross) or closer than `h/2` to a node or to an earlier ghost (at a concave
//! corner the ghosts of the two edges' neighbouring nodes coincide, which would
//! make the system singular).

use super::{Domain, NodeSet, Point};
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// Ghosts for the boundary nodes `candidates`: `(boundary node, ghost position)`.
pub fn place_ghosts(domain: &Domain, nodes: &NodeSet, candidates: &[usize]) -> Vec<(usize, Point)> {
    let h = nodes.spacing;
    let min_gap = 0.5 * h;
    let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&nodes.positions).expect("finite node positions");
    let mut placed: Vec<(usize, Point)> = Vec::with_capacity(candidates.len());
    // Ghosts lie in a band along the boundary: a hash of cells of size h/2 finds earlier ones.
    let cell = |p: Point| ((p[0] / min_gap).floor() as i64, (p[1] / min_gap).floor() as i64);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = std::collections::HashMap::new();
    for &i in candidates {
        let (p, n) = (nodes.positions[i], nodes.normal(i));
        let g = [p[0] + h * n[0], p[1] + h * n[1]];
        if domain.signed_distance(g) < min_gap {
            continue;
        }
        let nearest = tree.query(&g).nearest_one::<SquaredEuclidean<f64>>().execute();
        if nearest.distance < min_gap * min_gap {
            continue;
        }
        let (cx, cy) = cell(g);
        let clash = (-2..=2).any(|dx| {
            (-2..=2).any(|dy| {
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
