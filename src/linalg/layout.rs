//! Where the unknowns of a system live: per node and after the nodes (the
//! multipliers of a bordered system), for the multigrid's near-null space and the
//! preconditioners that split a system by blocks.

/// Where the unknowns of a system live, for the near-null space: `per_node`
/// interleaved unknowns per node (`u, v[, p]`), node `i` at `positions[i]`.
#[derive(Clone, Copy, Debug)]
pub struct NodeLayout<'a> {
    /// Unknowns per node; the first two are the displacement.
    pub per_node: usize,
    /// Position of each node (ghosts included).
    pub positions: &'a [[f64; 2]],
    /// Unknowns after the nodes' that belong to no node: the multipliers of a
    /// bordered system ([`super::border`]), 0 for none.
    pub multipliers: usize,
}

impl NodeLayout<'_> {
    /// The layout of the nodes' unknowns alone (a bordered system's leading block).
    pub fn nodes_only(self) -> Self {
        NodeLayout { multipliers: 0, ..self }
    }

    /// Whether each node's third unknown is a pressure (the displacement-pressure form).
    pub fn has_pressure(&self) -> bool {
        self.per_node == 3
    }
}
