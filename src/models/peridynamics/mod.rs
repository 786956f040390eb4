//! Linear bond-based peridynamics on the same plate (seed 000, chapter 4 and section 5.3).
//!
//! The nonlocal operator of the linear model (seed 000, eq. 4.1.3) is
//!
//! ```text
//! (L u)(x) = int_{|xi| < delta} lambda(|xi|) (xi ⊗ xi) (u(x + xi) - u(x)) dA,     -L u = b,
//! ```
//!
//! discretised with the nodes as quadrature points (seed 000, sec. 5.3):
//! `(L_h u)_i = sum_j c_ij (xi_ij ⊗ xi_ij)(u_j - u_i)`, one scalar `c_ij` per bond.
//!
//! Stages of a run: nodes (on a lattice, or on a Delaunay triangulation: [`triangulated`]), families, weights ([`solve::FAMILIES`],
//! [`solve::WEIGHTS`]), assembly, solve, post. Modules: [`params`] (the validated
//! `[peridynamics]` table), [`body`] (the solid with its collar), [`nodes`] (quadrature
//! points of square cells, plus the Dirichlet collar),
//! [`family`] (bonds within the horizon, k-d tree radius query), [`kernel`]
//! (calibrated micromodulus), [`weights`] (bond weights of each quadrature rule, the
//! volume surface correction and the asymptotically compatible weights of
//! [`compatible`]), [`loads`] (body force and tractions as a boundary-layer body
//! force), [`operator`] (internal force and stiffness), [`strain`] (nonlocal strain
//! for output), [`dilatation`] (the linear peridynamic solid's term), [`extension`]
//! (fictitious nodes at traction and free edges), [`stiffness`] (the static system and
//! its solve, the dilatation assembled or applied), [`solve`] (the static run),
//! [`discretisation`] (its estimated discretisation error at the same horizon),
//! [`dynamics`] (bond forces, energies, stable step), [`pairs`] (the force loop over
//! bond pairs) and [`block`] (its kernels over blocks of bonds), [`fracture`] (bonds that break,
//! pre-cracks, damage) and [`simulation`] (the time-dependent run).

pub mod assembly;
pub mod block;
pub mod body;
pub mod compatible;
pub mod dilatation;
pub mod discretisation;
pub mod dynamics;
pub mod extension;
pub mod family;
pub mod fracture;
pub mod kernel;
pub mod laws;
pub mod loads;
pub mod nodes;
pub mod operator;
pub mod pairs;
pub mod params;
pub mod simulation;
pub mod solve;
pub mod stiffness;
pub mod strain;
pub mod triangulated;
pub mod weights;

pub use simulation::{simulate, simulate_sampled, Simulation};
pub use kernel::{Kernel, KernelKind, Micromodulus};
pub use params::{BondForce, EdgeTreatment, PdParams, PointSet, Quadrature, Solid, SurfaceCorrection};
pub use solve::{solve, Discretisation, PdSolution};

/// A small plate shared by the stage tests of this model.
#[cfg(test)]
pub(crate) mod test_case {
    use super::family::Families;
    use super::nodes::{self, Body, PdNodes};
    use super::{BondForce, EdgeTreatment, Kernel, PdParams, PointSet, Quadrature, Solid, SurfaceCorrection};
    use crate::domain::Domain;
    use crate::physics::elasticity::conditions::{BoundaryCondition, ComponentCondition, Value};
    use crate::linalg::SolverParams;

    /// The plate `[0, 1] x [0, 0.5]`: left edge clamped, right edge loaded by the
    /// traction `t`, top and bottom free (parts bottom, right, top, left).
    pub(crate) fn plate(t: [f64; 2]) -> (Domain, Vec<BoundaryCondition>) {
        let clamped = BoundaryCondition { components: [ComponentCondition::Displacement; 2], value: Value::Constant([0.0, 0.0]) };
        let loaded = BoundaryCondition { components: [ComponentCondition::Traction; 2], value: Value::Constant(t) };
        (Domain::rectangle([0.0, 0.0], [1.0, 0.5]), vec![BoundaryCondition::FREE, loaded, BoundaryCondition::FREE, clamped])
    }

    /// Horizon `delta`, `m = 3`, the plain kernel and `quadrature`.
    pub(crate) fn params(delta: f64, quadrature: Quadrature) -> PdParams {
        PdParams {
            horizon: delta,
            ratio: 3.0,
            kernel: Kernel::Plain,
            quadrature,
            correction: SurfaceCorrection::None,
            solver: SolverParams::lu(),
            force: BondForce::Linear,
            solid: Solid::BondBased,
            boundary: EdgeTreatment::Surface,
            fracture: None,
            perturbation: 0.0,
            points: PointSet::Lattice,
            cut_cells: false,
        }
    }

    /// The nodes of the plate of [`plate`] for `params`.
    pub(crate) fn plate_nodes(domain: &Domain, conditions: &[BoundaryCondition], params: &PdParams) -> PdNodes {
        nodes::generate(&Body::new(domain, conditions, None, params), params)
    }

    /// The clamped plate of [`plate`] at `delta = 0.1`, `m = 3` (free nodes and a collar),
    /// its families and symmetric bond weights `c_ij = V_j / |xi|^3` (`V_i c_ij = V_j
    /// c_ji`), and one copy of them made asymmetric (one bond's weight off by 1e-9).
    pub(crate) fn plate_bonds() -> (Domain, PdNodes, Families, Vec<f64>, Vec<f64>) {
        let (domain, conditions) = plate([0.0, 0.0]);
        let nodes = plate_nodes(&domain, &conditions, &params(0.1, Quadrature::FullArea));
        let families = Families::within(&nodes.positions, nodes.free, 0.1 * (1.0 + 1e-9));
        let (x, v) = (&nodes.positions, &nodes.volumes);
        let c: Vec<f64> = (0..nodes.free)
            .flat_map(|i| {
                families.of(i).iter().map(move |&j| {
                    let j = j as usize;
                    v[j] / (x[j][0] - x[i][0]).hypot(x[j][1] - x[i][1]).powi(3)
                })
            })
            .collect();
        let mut skewed = c.clone();
        skewed[families.range(nodes.free / 2).start] *= 1.0 + 1e-9;
        (domain, nodes, families, c, skewed)
    }
}
