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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The k-d tree query finds exactly the brute-force neighbours, sorted, without
    /// the node itself; bonds between free nodes come in pairs.
    #[test]
    fn families_are_the_brute_force_neighbourhoods() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let points: Vec<Point> = (0..400).map(|_| [rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)]).collect();
        let (free, radius) = (300, 0.12);
        let f = Families::within(&points, free, radius);
        assert_eq!(f.len(), free);
        let mut total = 0;
        for i in 0..free {
            let brute: Vec<u32> = (0..points.len())
                .filter(|&j| j != i && (points[i][0] - points[j][0]).hypot(points[i][1] - points[j][1]) <= radius)
                .map(|j| j as u32)
                .collect();
            assert_eq!(f.of(i), brute.as_slice(), "family of node {i}");
            assert_eq!(f.range(i).len(), brute.len());
            total += brute.len();
            for &j in f.of(i) {
                if (j as usize) < free {
                    assert!(f.of(j as usize).contains(&(i as u32)), "bond {i}-{j} has no partner");
                }
            }
        }
        assert_eq!(f.bonds(), total);
    }
}
