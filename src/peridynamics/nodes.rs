//! Peridynamic nodes: the quadrature points of a lattice of square cells of side
//! `h = delta / m` (seed 000, sec. 5.3: "nodes are quadrature points"), aligned with
//! the lower-left corner of the solid's bounding box.
//!
//! A rule point inside the solid (signed distance <= 0) is a free node with volume
//! `weight * h^2`. A rule point outside, within the collar `delta + 0.75 h` of a
//! boundary part with a displacement condition, is a constrained node: the
//! Dirichlet volume constraint gives it the prescribed displacement (the constant of
//! the part, or the exact solution evaluated at the node itself). The extra `0.75 h`
//! covers the cells that the partial-area rule counts beyond `delta` (up to
//! `delta + h/sqrt(2)`). Other outside points are dropped (free edges).
//!
//! Cells cut by a curved or unaligned boundary keep their points' full weights.

use crate::domain::{boundary::discretise_boundary, Domain, Point};
use crate::exact::ExactSolution;
use crate::problem::{BoundaryCondition, ComponentCondition, Value};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::{PdParams, Quadrature};

/// Points of one unit cell `[0, 1]^2` with their share of the cell area.
pub fn rule(q: Quadrature) -> Vec<(Point, f64)> {
    match q {
        Quadrature::FullArea | Quadrature::PartialArea | Quadrature::Compatible => vec![([0.5, 0.5], 1.0)],
        Quadrature::Gauss2x2 => {
            let g = 3f64.sqrt() / 6.0;
            let (a, b) = (0.5 - g, 0.5 + g);
            vec![([a, a], 0.25), ([b, a], 0.25), ([a, b], 0.25), ([b, b], 0.25)]
        }
        Quadrature::TriangleP1 => vec![([2.0 / 3.0, 1.0 / 3.0], 0.5), ([1.0 / 3.0, 2.0 / 3.0], 0.5)],
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

/// Nodes of a peridynamic discretisation: free nodes `0..free`, constrained nodes after.
#[derive(Debug, Clone)]
pub struct PdNodes {
    /// Positions (free first).
    pub positions: Vec<Point>,
    /// Quadrature weight (volume per unit thickness) of every node.
    pub volumes: Vec<f64>,
    /// Number of free nodes.
    pub free: usize,
    /// Prescribed displacement of constrained node `free + k`.
    pub prescribed: Vec<[f64; 2]>,
    /// Index of the rule point each node is (its position within its cell).
    pub rule_point: Vec<u8>,
    /// Cell size h.
    pub spacing: f64,
}

impl PdNodes {
    /// Number of nodes, constrained ones included.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Number of constrained (collar) nodes.
    pub fn constrained(&self) -> usize {
        self.len() - self.free
    }
}

/// The solid together with its Dirichlet collar: which points carry material and
/// which of them are constrained.
pub struct Body<'a> {
    domain: &'a Domain,
    conditions: &'a [BoundaryCondition],
    exact: Option<&'a dyn ExactSolution>,
    samples: Vec<crate::domain::BoundarySample>,
    tree: ImmutableKdTree<f64, 2>,
    /// Collar width `delta + 0.75 h`.
    pub collar: f64,
}

impl<'a> Body<'a> {
    /// The body of `domain` for the horizon and cell size of `params`.
    pub fn new(domain: &'a Domain, conditions: &'a [BoundaryCondition], exact: Option<&'a dyn ExactSolution>, params: &PdParams) -> Self {
        let h = params.spacing();
        // Which boundary part is nearest to an outside point: fine boundary samples.
        let samples = discretise_boundary(domain, h / 4.0);
        let points: Vec<Point> = samples.iter().map(|s| s.position).collect();
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&points).expect("finite boundary samples");
        Body { domain, conditions, exact, samples, tree, collar: params.horizon + 0.75 * h }
    }

    /// Prescribed displacement of an outside point whose nearest boundary part has a
    /// displacement condition (corner rule as for MLSM: a displacement part wins).
    pub fn constraint(&self, p: Point) -> Option<[f64; 2]> {
        let nearest = self.tree.query(&p).nearest_one::<SquaredEuclidean<f64>>().execute();
        let s = &self.samples[nearest.item as usize];
        s.touches.iter().map(|(part, _)| self.conditions[*part]).find(|bc| bc.components == [ComponentCondition::Displacement; 2]).map(
            |bc| match bc.value {
                Value::Constant(v) => v,
                Value::Exact => self.exact.expect("validated: exact values need an exact solution").displacement(p),
            },
        )
    }

    /// Whether `p` carries material: inside the solid or in the constrained collar.
    pub fn contains(&self, p: Point) -> bool {
        let d = self.domain.signed_distance(p);
        d <= 0.0 || (d <= self.collar && self.constraint(p).is_some())
    }
}

/// Lay out the nodes of `params.quadrature` over the body (solid and collar).
pub fn generate(body: &Body, params: &PdParams) -> PdNodes {
    let domain = body.domain;
    let h = params.spacing();
    let collar = body.collar;
    let (lo, hi) = domain.bounding_box();
    let pad = (collar / h).ceil() as i64 + 1;
    let nx = ((hi[0] - lo[0]) / h).ceil() as i64;
    let ny = ((hi[1] - lo[1]) / h).ceil() as i64;
    let rule = rule(params.quadrature);
    let constraint_of = |p: Point| body.constraint(p);

    // Row by row in parallel, then free nodes first, constrained after, each in lattice order.
    type Free = (Point, f64, u8);
    type Fixed = (Point, f64, u8, [f64; 2]);
    let rows: Vec<(Vec<Free>, Vec<Fixed>)> = (-pad..ny + pad)
        .into_par_iter()
        .map(|j| {
            let mut free = Vec::new();
            let mut fixed = Vec::new();
            for i in -pad..nx + pad {
                let corner = [lo[0] + i as f64 * h, lo[1] + j as f64 * h];
                for (k, (q, w)) in rule.iter().enumerate() {
                    let p = [corner[0] + q[0] * h, corner[1] + q[1] * h];
                    let d = domain.signed_distance(p);
                    if d <= 0.0 {
                        free.push((p, w * h * h, k as u8));
                    } else if d <= collar {
                        if let Some(u) = constraint_of(p) {
                            fixed.push((p, w * h * h, k as u8, u));
                        }
                    }
                }
            }
            (free, fixed)
        })
        .collect();
    let mut positions = Vec::new();
    let mut volumes = Vec::new();
    let mut rule_point = Vec::new();
    for (free, _) in &rows {
        for (p, v, k) in free {
            positions.push(*p);
            volumes.push(*v);
            rule_point.push(*k);
        }
    }
    let free = positions.len();
    let mut prescribed = Vec::new();
    for (_, fixed) in &rows {
        for (p, v, k, u) in fixed {
            positions.push(*p);
            volumes.push(*v);
            rule_point.push(*k);
            prescribed.push(*u);
        }
    }
    PdNodes { positions, volumes, free, prescribed, rule_point, spacing: h }
}
