//! Supports: the `n` nearest nodes of every node (the node itself first), from a
//! k-d tree (kiddo). Stored as one flat `N x n` index array.

use super::Point;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZeroUsize;

/// The `n` nearest nodes of every node, nearest first; `of(i)[0] == i`.
#[derive(Debug, Clone)]
pub struct Supports {
    size: usize,
    indices: Vec<u32>,
}

impl Supports {
    /// Find the `size` nearest nodes of every node. `size` must not exceed the node count.
    pub fn nearest(positions: &[Point], size: usize) -> Supports {
        assert!(size >= 1 && size <= positions.len(), "support size {size} for {} nodes", positions.len());
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(positions).expect("k-d tree of finite node positions");
        let k = NonZeroUsize::new(size).unwrap();
        let mut indices = vec![0u32; positions.len() * size];
        indices.par_chunks_mut(size).enumerate().for_each(|(i, row)| {
            let found = tree.query(&positions[i]).nearest_n::<SquaredEuclidean<f64>>(k).execute();
            for (slot, item) in row.iter_mut().zip(&found) {
                *slot = item.item;
            }
            // Ties at distance zero cannot happen (nodes are distinct), but equal
            // distances can reorder: make sure the node itself comes first.
            if row[0] as usize != i {
                let pos = row.iter().position(|&j| j as usize == i).expect("node in its own support");
                row.swap(0, pos);
            }
        });
        Supports { size, indices }
    }

    /// Support size `n`.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Support of node `i` (node indices, `i` first).
    pub fn of(&self, i: usize) -> &[u32] {
        &self.indices[i * self.size..(i + 1) * self.size]
    }
}
