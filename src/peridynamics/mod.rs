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
//! Stages: [`nodes`] (quadrature points of square cells, plus the Dirichlet collar),
//! [`family`] (bonds within the horizon, k-d tree radius query), [`kernel`]
//! (calibrated micromodulus), [`weights`] (bond weights of each quadrature rule, the
//! volume surface correction and the asymptotically compatible weights of
//! [`compatible`]), [`loads`] (body force and tractions as a boundary-layer body
//! force), [`operator`] (internal force and stiffness), [`strain`] (nonlocal strain
//! for output), [`solve`] (the static run) and [`dynamics`] (bond forces, energies,
//! stable step and the time-dependent run).

pub mod compatible;
pub mod dynamics;
pub mod family;
pub mod kernel;
pub mod loads;
pub mod nodes;
pub mod operator;
pub mod solve;
pub mod strain;
pub mod weights;

pub use kernel::{Kernel, Micromodulus};
use serde::Serialize;

/// How each cell of the lattice is integrated; the nodes are the rule's points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quadrature {
    /// One node at each cell centre with the full cell area (FA; the seed's midpoint rule, Q1).
    FullArea,
    /// Cell-centre nodes weighted by the exact area of the cell inside the horizon disc.
    PartialArea,
    /// Four nodes per cell at the 2x2 Gauss points, a quarter of the area each (Q3).
    Gauss2x2,
    /// Each cell split into two triangles, one node at each centroid (P1).
    TriangleP1,
    /// Each cell split into two triangles, three interior nodes
    /// `(2/3, 1/6, 1/6)` (barycentric) per triangle with a third of its area each (P2).
    TriangleP2,
    /// Each cell split into two triangles, the seven-point rule per triangle (vertices
    /// 3, edge midpoints 8, centroid 27, times `|T|/60`; P3, the seed's "type 3"); the
    /// vertices and edge midpoints are shared with the neighbouring cells.
    TriangleP3,
    /// Cell-centre nodes; at nodes with a complete family the bond weights are
    /// corrected to reproduce the continuum moments exactly ([`compatible`]).
    Compatible,
}

impl Quadrature {
    /// Every rule with its scene name.
    pub const ALL: [(&'static str, Quadrature); 7] = [
        ("full-area", Quadrature::FullArea),
        ("partial-area", Quadrature::PartialArea),
        ("gauss2x2", Quadrature::Gauss2x2),
        ("triangle-p1", Quadrature::TriangleP1),
        ("triangle-p2", Quadrature::TriangleP2),
        ("triangle-p3", Quadrature::TriangleP3),
        ("ac", Quadrature::Compatible),
    ];

    /// Scene name of the rule.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(_, q)| *q == self).map(|(n, _)| *n).expect("every rule is listed")
    }
}

/// Surface correction of bonds near free edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceCorrection {
    /// Bonds as they are: nodes near a free edge are softer (the PD surface effect).
    None,
    /// Volume method: bond `ij` scaled by `2 V_delta / (V_i + V_j)`, `V_i` the family
    /// volume of node `i` and `V_delta = pi delta^2` (Le & Bobaru 2018, volume method).
    Volume,
}

/// The `[peridynamics]` table of a scene, validated.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PdParams {
    /// Horizon delta (m).
    pub horizon: f64,
    /// Ratio `m = delta / h`; `h` is the cell size.
    pub ratio: f64,
    /// Micromodulus shape.
    pub kernel: Kernel,
    /// Quadrature rule (and node layout).
    pub quadrature: Quadrature,
    /// Surface correction.
    pub correction: SurfaceCorrection,
    /// Linear solver of the static system (`[peridynamics.solver]`).
    pub solver: crate::linalg::SolverParams,
    /// Bond force law.
    pub force: BondForce,
}

/// Bond force law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BondForce {
    /// `f = c_ij (xi ⊗ xi) eta` (seed 000, eq. 4.1.3).
    Linear,
    /// `f = c_ij |xi|^3 s (xi + eta)/|xi + eta|`, `s = (|xi + eta| - |xi|)/|xi|` (seed 000,
    /// definition 4.1.1); its linearisation is the linear law. Dynamics only.
    BondStretch,
}

impl PdParams {
    /// Cell size `h = delta / m`.
    pub fn spacing(&self) -> f64 {
        self.horizon / self.ratio
    }

    /// Nodes per cell of the rule.
    pub fn nodes_per_cell(&self) -> usize {
        nodes::rule(self.quadrature).len()
    }
}
