//! The solid together with its Dirichlet collar and fictitious band, as the node
//! generators see it ([`super::nodes`], [`super::triangulated`]): which points carry
//! material, which are constrained and by which boundary part, and where a segment
//! leaves the solid.

use super::PdParams;
use crate::domain::{boundary::discretise_boundary, Domain, Point};
use crate::physics::elasticity::conditions::{BoundaryCondition, ComponentCondition};
use crate::physics::exact::{self, ExactSolution};
use kiddo::{ImmutableKdTree, SquaredEuclidean};

/// The boundary point nearest to a fictitious node, with the traction parts there and
/// their outward normals (two at a corner between traction parts).
#[derive(Debug, Clone)]
pub struct Foot {
    /// The boundary point.
    pub point: Point,
    /// `(part, outward unit normal)` of every part at the point.
    pub parts: Vec<(usize, Point)>,
}

/// The solid together with its Dirichlet collar: which points carry material and
/// which of them are constrained.
pub struct Body<'a> {
    domain: &'a Domain,
    conditions: &'a [BoundaryCondition],
    exact: Option<&'a dyn ExactSolution>,
    samples: Vec<crate::domain::BoundarySample>,
    tree: ImmutableKdTree<f64, 2>,
    /// Collar width ([`PdParams::collar_width`]).
    pub collar: f64,
    /// Whether outside points near traction parts are fictitious nodes.
    fictitious: bool,
}

impl<'a> Body<'a> {
    /// The body of `domain` for the horizon and cell size of `params`.
    pub fn new(domain: &'a Domain, conditions: &'a [BoundaryCondition], exact: Option<&'a dyn ExactSolution>, params: &PdParams) -> Self {
        let h = params.spacing();
        // Which boundary part is nearest to an outside point: fine boundary samples.
        let samples = discretise_boundary(domain, h / 4.0);
        let points: Vec<Point> = samples.iter().map(|s| s.position).collect();
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&points).expect("finite boundary samples");
        Body { domain, conditions, exact, samples, tree, collar: params.collar_width(), fictitious: params.has_fictitious_nodes() }
    }

    /// The part and prescribed displacement of an outside point whose nearest
    /// boundary part has a displacement condition (corner rule as for MLSM: a
    /// displacement part wins).
    pub fn constraint(&self, p: Point) -> Option<(usize, [f64; 2])> {
        let nearest = self.tree.query(&p).nearest_one::<SquaredEuclidean<f64>>().execute();
        let s = &self.samples[nearest.item as usize];
        s.touches
            .iter()
            .map(|&(part, _)| (part, &self.conditions[part]))
            .find(|(_, bc)| bc.is_all(ComponentCondition::Displacement))
            .map(|(part, bc)| (part, exact::value(&bc.value, p, self.exact, |e| e.displacement(p))))
    }

    /// The boundary point nearest to `p` with its parts, when none of them carries a
    /// displacement condition (then `p`, outside, is a fictitious node).
    pub(super) fn foot(&self, p: Point) -> Option<Foot> {
        let nearest = self.tree.query(&p).nearest_one::<SquaredEuclidean<f64>>().execute();
        let s = &self.samples[nearest.item as usize];
        let any_displacement = s.touches.iter().any(|&(part, _)| self.conditions[part].is_all(ComponentCondition::Displacement));
        (!any_displacement).then(|| Foot { point: s.position, parts: s.touches.clone() })
    }

    /// Where the segment from `from` (inside the solid) to `to` (outside) first leaves
    /// the solid and the outward normals of the parts there: stepped in `h / 4` and
    /// bisected to `1e-10` of its length; `None` when it does not leave it.
    pub fn exit(&self, from: Point, to: Point, h: f64) -> Option<(Point, Vec<Point>)> {
        let at = |t: f64| [from[0] + t * (to[0] - from[0]), from[1] + t * (to[1] - from[1])];
        let length = (to[0] - from[0]).hypot(to[1] - from[1]);
        let steps = ((4.0 * length / h).ceil() as usize).max(1);
        let k = (1..=steps).find(|&k| self.domain.signed_distance(at(k as f64 / steps as f64)) > 0.0)?;
        let (mut lo, mut hi) = ((k - 1) as f64 / steps as f64, k as f64 / steps as f64);
        while hi - lo > 1e-10 {
            let mid = 0.5 * (lo + hi);
            if self.domain.signed_distance(at(mid)) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let nearest = self.tree.query(&at(hi)).nearest_one::<SquaredEuclidean<f64>>().execute();
        let s = &self.samples[nearest.item as usize];
        Some((at(hi), s.touches.iter().map(|&(_, n)| n).collect()))
    }

    /// The solid.
    pub fn domain(&self) -> &'a Domain {
        self.domain
    }

    /// The lattice of cells of side `h` over the body (the solid's bounding box, padded
    /// by the collar and one cell), aligned with the box's lower-left corner `lo`:
    /// `(lo, rows, columns)`, cell `(i, j)` having its corner at `lo + (i, j) h`.
    pub fn lattice(&self, h: f64) -> (Point, std::ops::Range<i64>, std::ops::Range<i64>) {
        let (lo, hi) = self.domain.bounding_box();
        let pad = (self.collar / h).ceil() as i64 + 1;
        let nx = ((hi[0] - lo[0]) / h).ceil() as i64;
        let ny = ((hi[1] - lo[1]) / h).ceil() as i64;
        (lo, -pad..ny + pad, -pad..nx + pad)
    }

    /// Whether outside points near traction parts are fictitious nodes.
    pub fn has_fictitious(&self) -> bool {
        self.fictitious
    }

    /// Whether `p` carries material or a fictitious node: inside the solid, in the
    /// constrained collar or in the band of fictitious nodes.
    pub fn contains(&self, p: Point) -> bool {
        let d = self.domain.signed_distance(p);
        d <= 0.0 || (d <= self.collar && (self.fictitious || self.constraint(p).is_some()))
    }
}
