//! The discretised solid: geometry (CSG of primitives with named boundary parts),
//! boundary and interior nodes, outward normals, and node neighbourhoods.
//!
//! Nodes `0..boundary.len()` are boundary nodes (in boundary order); the rest are
//! interior nodes. Every boundary node knows the parts it touches and the outward
//! unit normal of each (corner rule in [`boundary`]).

pub mod boundary;
pub mod cells;
pub mod fill;
pub mod ghost;
pub mod neighbors;
pub mod shape;

use crate::choice::choice;
pub use boundary::BoundarySample;
pub use shape::{CsgOp, Domain, Point, Primitive, PrimitiveKind, Region};

choice! {
    /// How interior nodes are placed.
    pub enum FillKind("nodes.fill", default None, note "\"grid\" for a single rectangle, else \"scattered\"", serde "lowercase") {
        /// Lattice of the bounding box, clipped to the solid.
        Grid = "grid" => "lattice of the bounding box at the spacing, clipped to the solid",
        /// Advancing-front Poisson-disk fill.
        Scattered = "scattered" => "advancing-front Poisson-disk fill, seeded by `seed`",
    }
}

/// Parameters of the node generator.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FillParams {
    /// Target spacing `h` (m).
    pub spacing: f64,
    /// Interior fill.
    pub kind: FillKind,
    /// Seed of every random choice.
    pub seed: u64,
    /// Relaxation sweeps (0 = none).
    pub relax_iterations: usize,
}

/// Nodes of a discretised solid.
#[derive(Debug, Clone)]
pub struct NodeSet {
    /// All node positions; boundary nodes first.
    pub positions: Vec<Point>,
    /// Boundary nodes `0..boundary.len()`: parts touched and their normals.
    pub boundary: Vec<BoundarySample>,
    /// Target spacing used to build the set.
    pub spacing: f64,
}

impl NodeSet {
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Whether node `i` lies on the boundary.
    pub fn is_boundary(&self, i: usize) -> bool {
        i < self.boundary.len()
    }

    /// Outward unit normal of boundary node `i` (corner: bisector).
    pub fn normal(&self, i: usize) -> Point {
        self.boundary[i].normal()
    }
}

/// Generate the nodes of `domain` (boundary sampling, interior fill, relaxation).
pub fn generate(domain: &Domain, params: &FillParams) -> NodeSet {
    let h = params.spacing;
    let boundary = boundary::discretise_boundary(domain, h);
    let mut positions: Vec<Point> = boundary.iter().map(|s| s.position).collect();
    let interior = match params.kind {
        FillKind::Grid => fill::grid_fill(domain, h),
        FillKind::Scattered => fill::scattered_fill(domain, &positions, h, params.seed),
    };
    positions.extend(interior);
    if params.relax_iterations > 0 {
        fill::relax(domain, &mut positions, boundary.len(), h, params.relax_iterations);
    }
    NodeSet { positions, boundary, spacing: h }
}
