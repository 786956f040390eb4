//! The classical model: the 2D Navier (Cauchy-Navier) equation of linear elasticity,
//!
//! ```text
//! (lambda + mu) grad div u + mu lap u + f = 0        in the solid,
//! u_c = g_c  or  (sigma(u) n)_c = t_c                 per component on the boundary,
//! ```
//!
//! discretised in strong form by meshless shape functions (MLSM, seed 002): every
//! node is a collocation point. The pipeline, one file per stage:
//!
//! 1. [`discrete`]: nodes (`domain`), boundary equations of each boundary node
//!    ([`equations`]), ghost nodes, supports, and the shape functions of exactly the
//!    operators each node needs (`mlsm`);
//! 2. [`rows`] and [`system`]: one row per unknown (Navier, traction, displacement),
//!    assembled into a sparse matrix;
//! 3. [`solve`]: the static run (solve, strain, stress, errors);
//! 4. [`dynamics`]: explicit elastodynamics `rho u_tt = Navier(u) + f` with the
//!    boundary rows as constraints.

pub mod discrete;
pub mod dynamics;
pub mod equations;
pub mod rows;
pub mod solve;
pub mod system;

use crate::domain::FillParams;
use crate::linalg::SolverParams;
use crate::mlsm::Approximation;
use crate::pipeline::Stage;

pub use discrete::Discretisation;
pub use dynamics::{simulate, Simulation};
pub use solve::{solve, Solution};

/// How the Navier model discretises a case: node generation, local approximation,
/// linear solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavierParams {
    /// Node generation (spacing resolved).
    pub fill: FillParams,
    /// Local approximation (basis, weight, support, ghost nodes).
    pub approximation: Approximation,
    /// Linear solver.
    pub solver: SolverParams,
}

/// The stages of a Navier run, in order.
pub mod stage {
    use super::Stage;
    /// Node generation.
    pub const NODES: Stage = Stage::new("nodes");
    /// Ghost placement and support search.
    pub const SUPPORTS: Stage = Stage::new("supports");
    /// Shape functions.
    pub const SHAPES: Stage = Stage::new("shapes");
    /// Matrix assembly (for dynamics also the split and the boundary factorisation).
    pub const ASSEMBLY: Stage = Stage::new("assembly");
    /// Linear solve.
    pub const SOLVE: Stage = Stage::new("solve");
    /// Strain, stress, errors.
    pub const POST: Stage = Stage::new("post");
}
