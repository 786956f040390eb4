//! The `[peridynamics]` table of a scene, validated: horizon, ratio `m = delta / h`,
//! kernel, quadrature rule (which is also the node layout), surface correction,
//! linear solver and bond force law.

use super::kernel::Kernel;
use crate::scene::choice::choice;
use crate::domain::Point;
use serde::Serialize;

choice! {
    /// How each cell of the lattice is integrated; the nodes are the rule's points.
    pub enum Quadrature("peridynamics.quadrature", default Some(Quadrature::Compatible), serde "kebab-case") {
        /// One node at each cell centre with the full cell area (FA; the seed's midpoint rule, Q1).
        FullArea = "full-area" => "cell-centre nodes with the full cell area (the seed's midpoint rule)",
        /// Cell-centre nodes weighted by the exact area of the cell inside the horizon disc.
        PartialArea = "partial-area" => "cell-centre nodes weighted by the cell area inside the horizon",
        /// Four nodes per cell at the 2x2 Gauss points, a quarter of the area each (Q3).
        Gauss2x2 = "gauss2x2" => "four nodes per cell at the 2x2 Gauss points",
        /// Each cell split into two triangles, one node at each centroid (P1).
        TriangleP1 = "triangle-p1" => "two triangles per cell, one node at each centroid",
        /// Each cell split into two triangles, three interior nodes
        /// `(2/3, 1/6, 1/6)` (barycentric) per triangle with a third of its area each (P2).
        TriangleP2 = "triangle-p2" => "two triangles per cell, three interior nodes each",
        /// Each cell split into two triangles, the seven-point rule per triangle (vertices
        /// 3, edge midpoints 8, centroid 27, times `|T|/60`; P3, the seed's "type 3"); the
        /// vertices and edge midpoints are shared with the neighbouring cells.
        TriangleP3 = "triangle-p3" => "two triangles per cell, seven-point rule with shared vertices and edge midpoints",
        /// Cell-centre nodes; at nodes with a complete family the bond weights are
        /// corrected to reproduce the continuum moments exactly ([`super::compatible`]).
        Compatible = "ac" => "cell-centre nodes, bond weights matched to the continuum moments (asymptotically compatible)",
    }
}

impl Quadrature {
    /// Points of one unit cell `[0, 1]^2` with their share of the cell area.
    pub fn unit_cell(self) -> Vec<(Point, f64)> {
        match self {
            Quadrature::FullArea | Quadrature::PartialArea | Quadrature::Compatible => vec![([0.5, 0.5], 1.0)],
            Quadrature::Gauss2x2 => {
                let g = 3f64.sqrt() / 6.0;
                let (a, b) = (0.5 - g, 0.5 + g);
                vec![([a, a], 0.25), ([b, a], 0.25), ([a, b], 0.25), ([b, b], 0.25)]
            }
            Quadrature::TriangleP1 => vec![([2.0 / 3.0, 1.0 / 3.0], 0.5), ([1.0 / 3.0, 2.0 / 3.0], 0.5)],
            Quadrature::TriangleP3 => {
                // The periodic unit of the 7-point rule on the two triangles of every cell:
                // a vertex (shared by 6 triangles, 6 x 3/120), three edge midpoints (2 x 8/120
                // each) and the two centroids (27/120 each).
                vec![
                    ([0.0, 0.0], 0.15),
                    ([0.5, 0.0], 2.0 / 15.0),
                    ([0.0, 0.5], 2.0 / 15.0),
                    ([0.5, 0.5], 2.0 / 15.0),
                    ([2.0 / 3.0, 1.0 / 3.0], 0.225),
                    ([1.0 / 3.0, 2.0 / 3.0], 0.225),
                ]
            }
            Quadrature::TriangleP2 => {
                // Triangles (0,0),(1,0),(1,1) and (0,0),(1,1),(0,1); points 2/3 A + 1/6 B + 1/6 C.
                let tris = [[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]];
                let mut pts = Vec::new();
                for t in tris {
                    for k in 0..3 {
                        let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                        let p = [(4.0 * a[0] + b[0] + c[0]) / 6.0, (4.0 * a[1] + b[1] + c[1]) / 6.0];
                        pts.push((p, 1.0 / 6.0));
                    }
                }
                pts
            }
        }
    }
}

choice! {
    /// Surface correction of bonds near free edges.
    pub enum SurfaceCorrection("peridynamics.correction", default Some(SurfaceCorrection::None), serde "lowercase") {
        /// Bonds as they are: nodes near a free edge are softer (the PD surface effect).
        None = "none" => "bonds as they are (nodes near a free edge are softer)",
        /// Volume method: bond `ij` scaled by `2 V_delta / (V_i + V_j)`, `V_i` the family
        /// volume of node `i` and `V_delta = pi delta^2` (Le & Bobaru 2018, volume method).
        Volume = "volume" => "bond ij scaled by 2 V_delta / (V_i + V_j) (volume method)",
    }
}

choice! {
    /// The constitutive model of the peridynamic solid (`peridynamics.solid`).
    pub enum Solid("peridynamics.solid", default Some(Solid::Auto), serde "kebab-case") {
        /// Bond-based where it represents the material, the linear peridynamic solid otherwise
        /// (resolved by validation: a validated [`PdParams`] never holds it).
        Auto = "auto" => "bond-based where it represents the material (nu = 1/4 plane strain, 1/3 plane stress), else the linear peridynamic solid",
        /// Pairwise bonds only: in-plane `lambda = mu` ([`super::kernel`]).
        BondBased = "bond-based" => "pairwise bonds only (in-plane lambda = mu: nu = 1/4 plane strain, 1/3 plane stress)",
        /// Bonds plus the dilatation term of [`super::dilatation`]: any `nu`.
        Linear = "lps" => "the linear peridynamic solid: bonds plus a dilatation term, any nu",
    }
}

choice! {
    /// How traction and free edges are treated (`peridynamics.boundary`).
    pub enum EdgeTreatment("peridynamics.boundary", default Some(EdgeTreatment::Fictitious), serde "kebab-case") {
        /// Fictitious nodes beyond traction and free edges, their displacements extended
        /// from the solid by a cubic fit that meets the local traction condition
        /// ([`super::extension`]): every family is complete, and the run converges to the
        /// Navier solution at second order in delta.
        Fictitious = "fictitious" => "fictitious nodes beyond traction and free edges, extended from the solid under the local traction condition (static runs)",
        /// The nonlocal model's own free surface: truncated families, tractions as a body
        /// force in the first cell layer ([`super::loads`]); the surface effect converges at
        /// first order in delta.
        Surface = "surface" => "truncated families at free edges, tractions as a layer body force (the nonlocal surface)",
    }
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
    /// Constitutive model (bond-based or the linear peridynamic solid, never `Auto`).
    pub solid: Solid,
    /// Treatment of traction and free edges.
    pub boundary: EdgeTreatment,
    /// Bonds that break and pre-cracks (`[peridynamics.fracture]`, [`super::fracture`]).
    pub fracture: Option<super::fracture::Fracture>,
    /// A perturbed lattice: every point moved by a uniform offset of up to
    /// `perturbation h / 2` per coordinate, weights kept (0: the rule's lattice).
    pub perturbation: f64,
}

choice! {
    /// Bond force law.
    pub enum BondForce("peridynamics.force", default Some(BondForce::Linear), serde "kebab-case") {
        /// `f = c_ij (xi ⊗ xi) eta` (seed 000, eq. 4.1.3).
        Linear = "linear" => "f = c (xi ⊗ xi) eta (the linear model; static and dynamic runs)",
        /// `f = c_ij |xi|^3 s (xi + eta)/|xi + eta|`, `s = (|xi + eta| - |xi|)/|xi|` (seed 000,
        /// definition 4.1.1); its linearisation is the linear law. Dynamics only.
        BondStretch = "bond-stretch" => "f = c |xi|^3 s (xi + eta)/|xi + eta| (nonlinear; dynamics only)",
    }
}

impl PdParams {
    /// Cell size `h = delta / m`.
    pub fn spacing(&self) -> f64 {
        self.horizon / self.ratio
    }

    /// Whether the dilatation term of the linear peridynamic solid is on.
    pub fn has_dilatation(&self) -> bool {
        self.solid == Solid::Linear
    }

    /// Whether traction and free edges get fictitious nodes ([`super::extension`]).
    pub fn has_fictitious_nodes(&self) -> bool {
        self.boundary == EdgeTreatment::Fictitious
    }

    /// Width of the Dirichlet collar outside displacement parts (and of the band of
    /// fictitious nodes outside traction parts): `delta + 0.75 h`
    /// (the extra `0.75 h` covers the cells the partial-area rule counts beyond
    /// `delta`), and one more `delta` for the linear peridynamic solid, whose
    /// dilatation at a collar node next to the solid reads the collar's own family.
    pub fn collar_width(&self) -> f64 {
        let reach = if self.has_dilatation() { 2.0 } else { 1.0 };
        reach * self.horizon + 0.75 * self.spacing()
    }

    /// Nodes per cell of the rule.
    pub fn nodes_per_cell(&self) -> usize {
        self.quadrature.unit_cell().len()
    }
}
