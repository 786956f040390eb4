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
    /// Rows that [`Families::retain`] took bonds from (empty: none).
    cut: Vec<bool>,
}

/// A layer of [`Families::around`] that the layers did not reach.
pub const UNREACHED: u8 = u8::MAX;

/// Neighbours of node `i` within `sqrt(r2)`, itself excluded, in increasing order.
fn family_of(tree: &ImmutableKdTree<f64, 2>, positions: &[Point], i: usize, r2: f64) -> Vec<u32> {
    let found = tree.query(&positions[i]).within::<SquaredEuclidean<f64>>(r2).execute();
    let mut js: Vec<u32> = found.iter().map(|n| n.item).filter(|&j| j as usize != i).collect();
    js.sort_unstable();
    js
}

impl Families {
    /// Bonds of free nodes `0..free` to every node within `radius`; callers pad the
    /// radius by a relative `1e-9` so that lattice points at exactly the horizon count.
    pub fn within(positions: &[Point], free: usize, radius: f64) -> Families {
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(positions).expect("finite node positions");
        let lists: Vec<Vec<u32>> = (0..free).into_par_iter().map(|i| family_of(&tree, positions, i, radius * radius)).collect();
        Families::from_lists(lists)
    }

    /// The families of the free nodes `own` picks and of `layers` layers of free
    /// nodes around them (layer `l + 1`: the free neighbours of layer `l` not in an
    /// earlier one), each equal to its family in [`Families::within`]; the other
    /// free nodes get an empty family. Returns the layer of every free node (0: own,
    /// [`UNREACHED`]: none). A rank of a distributed run builds only these: its rows
    /// read the bonds of the halo around its own nodes.
    pub fn around(positions: &[Point], free: usize, radius: f64, own: impl Fn(usize) -> bool, layers: u8) -> (Families, Vec<u8>) {
        assert!(layers < UNREACHED, "at most {} layers", UNREACHED - 1);
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(positions).expect("finite node positions");
        let mut layer: Vec<u8> = (0..free).map(|i| if own(i) { 0 } else { UNREACHED }).collect();
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); free];
        let mut front: Vec<usize> = (0..free).filter(|&i| layer[i] == 0).collect();
        for l in 0..=layers {
            let found: Vec<Vec<u32>> = front.par_iter().map(|&i| family_of(&tree, positions, i, radius * radius)).collect();
            for (&i, f) in front.iter().zip(found) {
                lists[i] = f;
            }
            if l == layers {
                break;
            }
            let mut next = Vec::new();
            for &i in &front {
                for &j in &lists[i] {
                    let j = j as usize;
                    if j < free && layer[j] == UNREACHED {
                        layer[j] = l + 1;
                        next.push(j);
                    }
                }
            }
            front = next;
        }
        (Families::from_lists(lists), layer)
    }

    /// The same families without the bonds `(i, j)` that `keep` rejects, and how many
    /// were removed.
    pub fn retain(&self, keep: impl Fn(usize, usize) -> bool + Sync) -> (Families, usize) {
        let lists: Vec<Vec<u32>> = (0..self.len()).into_par_iter().map(|i| self.of(i).iter().copied().filter(|&j| keep(i, j as usize)).collect()).collect();
        let cut: Vec<bool> = lists.iter().enumerate().map(|(i, l)| l.len() < self.of(i).len()).collect();
        let kept: usize = lists.iter().map(Vec::len).sum();
        let mut f = Families::from_lists(lists);
        if cut.iter().any(|&c| c) {
            f.cut = cut;
        }
        (f, self.bonds() - kept)
    }

    /// Whether row `i` lost bonds to [`Families::retain`] (its family is cut, not
    /// truncated by the body's edge).
    pub fn is_cut(&self, i: usize) -> bool {
        self.cut.get(i).copied().unwrap_or(false)
    }

    fn from_lists(lists: Vec<Vec<u32>>) -> Families {
        let mut offsets = Vec::with_capacity(lists.len() + 1);
        offsets.push(0);
        for l in &lists {
            offsets.push(offsets.last().unwrap() + l.len());
        }
        let neighbours = lists.into_iter().flatten().collect();
        Families { offsets, neighbours, cut: Vec::new() }
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

    /// The node bond `b` reads.
    pub fn neighbour(&self, b: usize) -> u32 {
        self.neighbours[b]
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

    /// `n` points drawn uniformly in the unit square with seed `seed`.
    fn random_points(seed: u64, n: usize) -> Vec<Point> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(|_| [rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)]).collect()
    }

    /// The k-d tree query finds exactly the brute-force neighbours, sorted, without
    /// the node itself; bonds between free nodes come in pairs.
    #[test]
    fn families_are_the_brute_force_neighbourhoods() {
        let points = random_points(5, 400);
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

    /// The families around a set of own nodes are those of the whole search, on
    /// exactly the own nodes and the layers of neighbours around them.
    #[test]
    fn families_around_own_nodes_are_the_whole_search_in_layers() {
        let points = random_points(7, 600);
        let (free, radius) = (500, 0.08);
        let whole = Families::within(&points, free, radius);
        let own = |i: usize| points[i][0] < 0.3;
        for layers in [0u8, 1, 2] {
            let (f, layer) = Families::around(&points, free, radius, own, layers);
            for i in 0..free {
                // The layer is the bond distance from the own nodes, up to `layers`.
                let expected = if own(i) {
                    0
                } else {
                    (1..=layers)
                        .find(|&l| whole.of(i).iter().any(|&j| (j as usize) < free && layer[j as usize] == l - 1))
                        .unwrap_or(UNREACHED)
                };
                assert_eq!(layer[i], expected, "layer of node {i}, {layers} layers");
                let family: &[u32] = if layer[i] == UNREACHED { &[] } else { whole.of(i) };
                assert_eq!(f.of(i), family, "family of node {i}, {layers} layers");
            }
            assert!(layer.iter().filter(|&&l| l == layers).count() > 0, "layer {layers} is not empty");
        }
    }
}
