//! Families: the bonds of every free node, from a k-d tree radius query, stored
//! compactly as one flat neighbour array with row offsets (CSR), 4 bytes per bond.

use crate::domain::Point;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Neighbours within the search radius of each free node (the node itself excluded),
/// in increasing index order.
#[derive(Debug, Clone)]
pub struct Families {
    offsets: Vec<usize>,
    neighbours: Vec<u32>,
}

impl Families {
    /// Bonds of free nodes `0..free` to every node within `radius`; callers pad the
    /// radius by a relative `1e-9` so that lattice points at exactly the horizon count.
    pub fn within(positions: &[Point], free: usize, radius: f64) -> Families {
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(positions).expect("finite node positions");
        let r2 = radius * radius;
        let lists: Vec<Vec<u32>> = (0..free)
            .into_par_iter()
            .map(|i| {
                let found = tree.query(&positions[i]).within::<SquaredEuclidean<f64>>(r2).execute();
                let mut js: Vec<u32> = found.iter().map(|n| n.item).filter(|&j| j as usize != i).collect();
                js.sort_unstable();
                js
            })
            .collect();
        let mut offsets = Vec::with_capacity(free + 1);
        offsets.push(0);
        for l in &lists {
            offsets.push(offsets.last().unwrap() + l.len());
        }
        let neighbours = lists.into_iter().flatten().collect();
        Families { offsets, neighbours }
    }

    /// Number of free nodes (rows).
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Total number of bonds (each direction counted).
    pub fn bonds(&self) -> usize {
        self.neighbours.len()
    }

    /// Neighbours of free node `i`.
    pub fn of(&self, i: usize) -> &[u32] {
        &self.neighbours[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Bond index range of free node `i` (into per-bond arrays).
    pub fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i]..self.offsets[i + 1]
    }
}
