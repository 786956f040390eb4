//! The layout of the unknowns: two displacement components per node, interleaved
//! (`u_0, v_0, u_1, v_1, ...`) so that a node's unknowns sit next to each other.
//! Only this type knows the layout.

/// Maps (node, component) to the global unknown index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DofMap {
    nodes: usize,
}

impl DofMap {
    /// Layout for `nodes` nodes.
    pub fn new(nodes: usize) -> Self {
        DofMap { nodes }
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        2 * self.nodes
    }

    /// Whether there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.nodes == 0
    }

    /// Unknown of component `c` (0 = x, 1 = y) of node `i`.
    #[inline]
    pub fn dof(&self, node: usize, c: usize) -> usize {
        2 * node + c
    }

    /// Displacement of node `i` from the global solution vector.
    #[inline]
    pub fn displacement(&self, x: &[f64], node: usize) -> [f64; 2] {
        [x[2 * node], x[2 * node + 1]]
    }
}
