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
//! Stages: nodes, supports, shapes, assembly, solve, post (`pipeline::stage` and
//! [`discrete::SUPPORTS`], [`discrete::SHAPES`]).
//!
//! 1. [`discrete`]: nodes (`domain`), boundary equations of each boundary node
//!    ([`equations`]), ghost nodes, supports, and the shape functions of exactly the
//!    operators each node needs (`mlsm`);
//! 2. [`rows`] and [`system`]: one row per unknown (Navier, traction, displacement),
//!    assembled into a sparse matrix;
//! 3. [`solve`]: the static run (solve, strain, stress, errors, the global force
//!    balance of [`equilibrium`]);
//! 4. [`dynamics`]: explicit elastodynamics `rho u_tt = Navier(u) + f` with the
//!    boundary rows as constraints;
//! 5. [`estimate`]: what an error estimate is and holds; [`dynamic_estimate`]: the
//!    references of a dynamic run; [`run`]: a run with its estimate.

pub mod cloud;
pub mod corner_defect;
pub mod defect;
pub mod discrete;
pub mod dynamic_estimate;
pub mod dynamics;
pub mod equations;
pub mod equilibrium;
pub mod estimate;
pub mod formulation;
pub mod low_order;
pub mod rows;
pub mod run;
pub mod sector;
pub mod solve;
pub mod system;

use crate::domain::FillParams;
use crate::linalg::SolverParams;
use crate::mlsm::Approximation;

pub use discrete::Discretisation;
pub use dynamics::{simulate_sampled, Sampling, Simulation};
pub use estimate::{ErrorEstimate, Estimate, EstimateMethod, EstimateParams};
pub use formulation::Formulation;
pub use run::{simulate, solve};
pub use solve::Solution;

/// How the Navier model discretises a case: node generation, local approximation,
/// linear solver.
#[derive(Debug, Clone, PartialEq)]
pub struct NavierParams {
    /// Node generation (spacing resolved).
    pub fill: FillParams,
    /// Local approximation (basis, weight, support, ghost nodes).
    pub approximation: Approximation,
    /// Unknowns: displacement, or displacement and pressure.
    pub formulation: Formulation,
    /// `tau` of the continuity rows' pressure stabilisation in the displacement-pressure
    /// form (`navier::formulation`; 0: none).
    pub pressure_stabilisation: f64,
    /// Linear solver.
    pub solver: SolverParams,
    /// The operator the multigrid preconditioner is built on.
    pub multigrid: low_order::MultigridOperator,
    /// Error estimate.
    pub estimate: EstimateParams,
    /// Keep the assembled system in the solution (`mlsm run --export-system`).
    pub keep_system: bool,
}

/// A small case shared by the stage tests of this model.
#[cfg(test)]
pub(crate) mod test_case {
    use super::NavierParams;
    use crate::physics::case::{Case, Outputs};
    use crate::domain::{Domain, FillKind, FillParams};
    use crate::physics::elasticity::conditions::{BoundaryCondition, ComponentCondition, Value};
    use crate::physics::elasticity::material::{Material, PlaneModel, YoungPoisson};
    use crate::physics::exact::{ExactKind, NamedSolution, Parameters};
    use crate::linalg::SolverParams;
    use crate::mlsm::{Approximation, Basis, Weight};

    /// The plate `[0, 1] x [0, 0.5]` with the quadratic field
    /// `u = (1 + x + 2 y + 0.5 x^2, -y + 0.25 x y - y^2)` as exact solution: its
    /// displacement on the left edge, its traction on the others, its body force;
    /// degree-2 monomials, ghost nodes, the given fill at spacing `h`.
    pub(crate) fn quadratic_plate(fill: FillKind, h: f64) -> (Case, NavierParams) {
        let mut parameters = Parameters::default();
        parameters.insert("ux", vec![1.0, 1.0, 2.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        parameters.insert("uy", vec![0.0, 0.0, -1.0, 0.0, 0.25, -1.0, 0.0, 0.0, 0.0, 0.0]);
        let traction = BoundaryCondition { components: [ComponentCondition::Traction; 2], value: Value::Exact };
        let displacement = BoundaryCondition { components: [ComponentCondition::Displacement; 2], value: Value::Exact };
        let case = Case {
            domain: Domain::rectangle([0.0, 0.0], [1.0, 0.5]),
            material: Material { elastic: YoungPoisson { young: 3.0, poisson: 0.3 }, plane: PlaneModel::Stress },
            body_force: Value::Exact,
            conditions: vec![traction.clone(), traction.clone(), traction, displacement],
            exact: Some(NamedSolution { kind: ExactKind::Polynomial, parameters }),
            outputs: Outputs::default(),
            dynamics: None,
            probes: Vec::new(),
        };
        let support = if fill == FillKind::Grid { 13 } else { 12 };
        let params = NavierParams {
            fill: FillParams { spacing: h, refine: None, adapted: None, kind: fill, seed: 1, relax_iterations: 0 },
            approximation: Approximation {
                basis: Basis::Monomials { degree: 2 },
                weight: Weight::Gaussian { sigma: 1.0 },
                support,
                ghost_nodes: true,
            },
            formulation: super::Formulation::Displacement,
            pressure_stabilisation: super::formulation::PRESSURE_STABILISATION,
            solver: SolverParams::lu(),
            multigrid: super::low_order::MultigridOperator::Auto,
            estimate: Default::default(),
            keep_system: false,
        };
        (case, params)
    }
}
