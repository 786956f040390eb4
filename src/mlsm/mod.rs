//! Meshless shape functions: weighted least squares over each node's support (MLSM)
//! or RBF-FD on it.
//!
//! From the bottom up: [`ops`] the operators, [`radial`] the radial functions,
//! [`basis`] the local bases and weights, [`frame`] a stencil in local coordinates,
//! [`wls`] one least-squares solve, [`rbffd`] one RBF-FD solve, [`fit`] the one
//! dispatch from a basis to its solve, [`stencil`] default support sizes, [`shapes`]
//! the parallel computation for all nodes of exactly the operators each node needs,
//! [`interpolate`] nodal fields at other points, [`taylor`] local polynomial fits and
//! their Taylor parts.

pub mod basis;
pub mod fit;
pub mod frame;
pub mod interpolate;
pub mod null_space;
pub mod ops;
pub mod radial;
pub mod rbffd;
pub mod shapes;
pub mod stencil;
pub mod taylor;
pub mod wls;

pub use basis::{Basis, BasisKind, Weight, WeightKind};
pub use ops::{Op, OpSet};
pub use radial::Radial;
pub use shapes::{compute_shapes, degenerate_supports, ShapeError, Shapes};
pub use stencil::{default_rbf_fd_support, default_support};

/// Basis, weight and support size of the local fits.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Approximation {
    /// Local basis.
    pub basis: Basis,
    /// Local weight.
    pub weight: Weight,
    /// Support size `n` (the node itself included).
    pub support: usize,
    /// Ghost nodes: one fictitious node at distance `h` outside every boundary node
    /// whose two equations are tractions, so that such a node carries both its
    /// traction equations and the Navier equation (fictitious-point method).
    pub ghost_nodes: bool,
}

impl Approximation {
    /// The order `q = max(p - 1, 1)` in `e ~ h^q` that a collocation with basis
    /// degree `p` follows: the order of the fitted second derivatives.
    pub fn formal_order(&self) -> f64 {
        (self.basis.polynomial_degree() as f64 - 1.0).max(1.0)
    }
}
