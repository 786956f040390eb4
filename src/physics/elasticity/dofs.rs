//! The layout of the unknowns. Only this type knows it: `k` unknowns per node,
//! interleaved node by node (`u_0, v_0, [p_0,] u_1, v_1, [p_1,] ...`), so that a node's
//! unknowns sit next to each other in the matrix. `k = 2` (displacement) for both
//! models today; `k = 3` (displacement and pressure) describes the mixed form.

/// What each node carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unknowns {
    /// The two displacement components `u, v`.
    Displacement,
    /// Displacement and pressure `u, v, p`.
    DisplacementPressure,
}

impl Unknowns {
    /// Name in summaries and scene files: `displacement`, `displacement-pressure`.
    pub const fn name(self) -> &'static str {
        match self {
            Unknowns::Displacement => "displacement",
            Unknowns::DisplacementPressure => "displacement-pressure",
        }
    }

    /// Unknowns per node.
    pub const fn per_node(self) -> usize {
        match self {
            Unknowns::Displacement => 2,
            Unknowns::DisplacementPressure => 3,
        }
    }
}

/// Component index of the pressure in a [`Unknowns::DisplacementPressure`] layout.
pub const PRESSURE: usize = 2;

/// Maps (node, component) to the global unknown index and back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DofMap {
    nodes: usize,
    unknowns: Unknowns,
}

impl DofMap {
    /// Layout of `nodes` nodes carrying `unknowns` each.
    pub fn new(nodes: usize, unknowns: Unknowns) -> Self {
        DofMap { nodes, unknowns }
    }

    /// Displacement-only layout of `nodes` nodes.
    pub fn displacement_only(nodes: usize) -> Self {
        DofMap::new(nodes, Unknowns::Displacement)
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.nodes
    }

    /// What each node carries.
    pub fn unknowns(&self) -> Unknowns {
        self.unknowns
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        self.unknowns.per_node() * self.nodes
    }

    /// Whether there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.nodes == 0
    }

    /// Unknown of component `c` (0 = x, 1 = y, [`PRESSURE`]) of node `node`.
    #[inline]
    pub fn dof(&self, node: usize, c: usize) -> usize {
        debug_assert!(c < self.unknowns.per_node(), "component {c} of a {:?} layout", self.unknowns);
        self.unknowns.per_node() * node + c
    }

    /// `(node, component)` of unknown `dof`.
    #[inline]
    pub fn location(&self, dof: usize) -> (usize, usize) {
        let k = self.unknowns.per_node();
        (dof / k, dof % k)
    }

    /// Displacement of node `node` from a global vector.
    #[inline]
    pub fn displacement(&self, x: &[f64], node: usize) -> [f64; 2] {
        let k = self.unknowns.per_node() * node;
        [x[k], x[k + 1]]
    }

    /// Displacements of nodes `0..count` from a global vector.
    pub fn displacements(&self, x: &[f64], count: usize) -> Vec<[f64; 2]> {
        (0..count).map(|i| self.displacement(x, i)).collect()
    }

    /// A global vector holding `field(i)` as the displacement of every node `i` (other
    /// components zero).
    pub fn from_displacements(&self, field: impl Fn(usize) -> [f64; 2]) -> Vec<f64> {
        let mut x = vec![0.0; self.len()];
        for i in 0..self.nodes {
            let u = field(i);
            x[self.dof(i, 0)] = u[0];
            x[self.dof(i, 1)] = u[1];
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_round_trip() {
        for unknowns in [Unknowns::Displacement, Unknowns::DisplacementPressure] {
            let d = DofMap::new(5, unknowns);
            assert_eq!(d.len(), 5 * unknowns.per_node());
            let mut seen = vec![false; d.len()];
            for i in 0..5 {
                for c in 0..unknowns.per_node() {
                    let g = d.dof(i, c);
                    assert!(!seen[g], "{unknowns:?}: unknown {g} twice");
                    seen[g] = true;
                    assert_eq!(d.location(g), (i, c));
                }
            }
            let x = d.from_displacements(|i| [i as f64, -(i as f64)]);
            assert_eq!(d.displacements(&x, 5)[3], [3.0, -3.0]);
            if unknowns == Unknowns::DisplacementPressure {
                assert!((0..5).all(|i| x[d.dof(i, PRESSURE)] == 0.0));
            }
        }
    }
}
