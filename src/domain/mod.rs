//! The discretised solid: geometry (CSG of primitives with named boundary parts),
//! boundary and interior nodes, outward normals, and node neighbourhoods.
//!
//! Nodes `0..boundary.len()` are boundary nodes (in boundary order); the rest are
//! interior nodes. Every boundary node knows the parts it touches and the outward
//! unit normal of each (corner rule in [`boundary`]).

pub mod adapt;
pub mod boundary;
pub mod cells;
pub mod corner;
pub mod density;
pub mod fill;
pub mod ghost;
pub mod neighbors;
pub mod shape;

use crate::scene::choice::choice;
pub use boundary::BoundarySample;
pub use density::{Refinement, SpacingField, SpacingSamples};
pub use shape::{CsgOp, Domain, Point, Primitive, PrimitiveKind, Region};
use std::sync::Arc;

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
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FillParams {
    /// Target spacing `h` (m); with a refinement, the spacing far from its targets.
    pub spacing: f64,
    /// Graded spacing towards boundary parts or points (scattered fills only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refine: Option<Refinement>,
    /// A spacing adapted to an error indicator (`run --target-error`), capping the
    /// spacing of `spacing` and `refine` (scattered fills only).
    #[serde(skip)]
    pub adapted: Option<Arc<SpacingSamples>>,
    /// Interior fill.
    pub kind: FillKind,
    /// Seed of every random choice.
    pub seed: u64,
    /// Relaxation sweeps (0 = none).
    pub relax_iterations: usize,
}

impl FillParams {
    /// The spacing function `h(x)` of these parameters on `domain`.
    pub fn field(&self, domain: &Domain) -> SpacingField {
        let field = match &self.refine {
            None => SpacingField::uniform(self.spacing),
            Some(r) => SpacingField::graded(self.spacing, r, boundary::refined_parts(domain, r)),
        };
        match &self.adapted {
            None => field,
            Some(s) => field.capped_by(s.clone()),
        }
    }

    /// Whether the spacing is the same everywhere.
    pub fn is_uniform(&self) -> bool {
        self.refine.is_none() && self.adapted.is_none()
    }

    /// The same parameters with the spacing function multiplied by `factor`:
    /// `h(x) -> factor h(x)` everywhere (both spacings and the growth rate), a uniform
    /// refinement of the whole graded node set.
    pub fn scaled(&self, factor: f64) -> FillParams {
        let mut p = self.clone();
        p.spacing *= factor;
        if let Some(r) = p.refine.as_mut() {
            r.spacing *= factor;
            r.growth *= factor;
        }
        p.adapted = p.adapted.map(|s| Arc::new(s.scaled(factor)));
        p
    }
}

/// Nodes of a discretised solid.
#[derive(Debug, Clone)]
pub struct NodeSet {
    /// All node positions; boundary nodes first.
    pub positions: Vec<Point>,
    /// Boundary nodes `0..boundary.len()`: parts touched and their normals.
    pub boundary: Vec<BoundarySample>,
    /// Target spacing used to build the set (the largest, with a refinement).
    pub spacing: f64,
    /// Target spacing at each node.
    pub local_spacing: Vec<f64>,
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
    let field = params.field(domain);
    let boundary = boundary::discretise_boundary_graded(domain, &field);
    let mut positions: Vec<Point> = boundary.iter().map(|s| s.position).collect();
    let interior = match params.kind {
        FillKind::Grid => fill::grid_fill(domain, h),
        FillKind::Scattered => fill::scattered_fill(domain, &positions, &field, params.seed),
    };
    positions.extend(interior);
    if params.relax_iterations > 0 {
        fill::relax(domain, &mut positions, boundary.len(), &field, params.relax_iterations);
    }
    let local_spacing = if field.is_uniform() { vec![h; positions.len()] } else { positions.iter().map(|&p| field.at(p)).collect() };
    NodeSet { positions, boundary, spacing: h, local_spacing }
}
