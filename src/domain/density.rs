//! The node spacing as a function of position: uniform, or graded towards boundary
//! parts and points where the solution varies fast (holes, re-entrant corners,
//! loads):
//!
//! ```text
//! h(x) = min(h_max, h_min + g d(x))
//! ```
//!
//! with `d(x)` the distance to the nearest refinement target (boundary parts named in
//! the scene, or points), `h_min` the spacing there, `h_max` the spacing far away and
//! `g` the growth rate (spacing gained per unit of distance). With `g < 1` the spacing
//! of neighbouring nodes differs by less than a factor `1 + g`, so the density has no
//! jumps (Slak and Kosec 2019 use the same kind of function).

use super::shape::{Domain, Point};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use serde::Serialize;
use std::num::NonZeroUsize;
use std::sync::Arc;

/// A refinement of the node spacing (the `[nodes.refine]` table, validated).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refinement {
    /// Spacing at the targets `h_min` (m).
    pub spacing: f64,
    /// Spacing gained per unit of distance from the targets (dimensionless, < 1).
    pub growth: f64,
    /// Boundary parts to refine towards (indices into `Domain::parts`).
    pub parts: Vec<usize>,
    /// Points to refine towards.
    pub points: Vec<Point>,
}

/// A spacing given at sample points (an adapted node set: the spacing each node of
/// the previous set asked for); between samples `h(x)` is the inverse-distance mean
/// of the [`SAMPLE_NEIGHBOURS`] nearest samples (exact at a sample).
#[derive(Debug, Clone, PartialEq)]
pub struct SpacingSamples {
    /// Sample positions.
    pub points: Vec<Point>,
    /// Spacing at each sample (m), positive.
    pub spacing: Vec<f64>,
}

/// Samples averaged by [`SpacingSamples`] between sample points.
pub const SAMPLE_NEIGHBOURS: usize = 3;

impl SpacingSamples {
    /// The same samples with every spacing multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> SpacingSamples {
        SpacingSamples { points: self.points.clone(), spacing: self.spacing.iter().map(|h| h * factor).collect() }
    }

    /// The smallest sampled spacing.
    pub fn min(&self) -> f64 {
        self.spacing.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// `h(x)` of a node set (module docs); cheap to clone.
#[derive(Clone)]
pub struct SpacingField {
    far: f64,
    refinement: Option<(Refinement, Arc<ImmutableKdTree<f64, 2>>)>,
    samples: Option<(Arc<SpacingSamples>, Arc<ImmutableKdTree<f64, 2>>)>,
}

impl std::fmt::Debug for SpacingField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpacingField")
            .field("far", &self.far)
            .field("refinement", &self.refinement.as_ref().map(|r| &r.0))
            .field("samples", &self.samples.as_ref().map(|s| s.0.points.len()))
            .finish()
    }
}

impl SpacingField {
    /// The constant spacing `h`.
    pub fn uniform(h: f64) -> Self {
        SpacingField { far: h, refinement: None, samples: None }
    }

    /// Spacing `far` away from the targets of `refinement`: its points and
    /// `part_samples`, samples of the boundary parts it names
    /// ([`super::boundary::refined_parts`]), the distance to a part being measured to them.
    pub fn graded(far: f64, refinement: &Refinement, part_samples: Vec<Point>) -> Self {
        let mut targets: Vec<Point> = refinement.points.clone();
        targets.extend(part_samples);
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&targets).expect("finite refinement targets");
        SpacingField { far, refinement: Some((refinement.clone(), Arc::new(tree))), samples: None }
    }

    /// This field capped by `samples`: `h(x) = min(h_self(x), h_samples(x))`.
    pub fn capped_by(mut self, samples: Arc<SpacingSamples>) -> Self {
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&samples.points).expect("finite spacing samples");
        self.samples = Some((samples, Arc::new(tree)));
        self
    }

    /// `h(x)`.
    pub fn at(&self, x: Point) -> f64 {
        let graded = match &self.refinement {
            None => self.far,
            Some((r, tree)) => {
                let d = tree.query(&x).nearest_one::<SquaredEuclidean<f64>>().execute().distance.sqrt();
                (r.spacing + r.growth * d).min(self.far)
            }
        };
        match &self.samples {
            None => graded,
            Some((s, tree)) => graded.min(sampled(s, tree, x)),
        }
    }

    /// The smallest spacing anywhere.
    pub fn min(&self) -> f64 {
        let graded = self.refinement.as_ref().map_or(self.far, |(r, _)| r.spacing.min(self.far));
        self.samples.as_ref().map_or(graded, |(s, _)| graded.min(s.min()))
    }

    /// The largest spacing (far from the targets).
    pub fn max(&self) -> f64 {
        self.far
    }

    /// Whether the spacing is the same everywhere.
    pub fn is_uniform(&self) -> bool {
        self.refinement.is_none() && self.samples.is_none()
    }

    /// About how many nodes a fill of `domain` at this spacing holds: `int dA / h^2`,
    /// by adaptive cell subdivision down to cells of four local spacings; the count
    /// stops growing once it passes `cap` (the answer is then "more than `cap`"). A
    /// domain whose count is still below one node a cell after [`MAX_ESTIMATE_CELLS`]
    /// cells (a strip 1e54 spacings long and 400 wide, found by benches/fuzz.sh:
    /// the cells stop halving at depth 40, still 1e42 long) is counted as infinite: no
    /// fill of it could be held.
    pub fn node_estimate(&self, domain: &Domain, cap: f64) -> f64 {
        let (lo, hi) = domain.bounding_box();
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let mut total = 0.0;
        let mut stack = vec![(lo, size, 0u32)];
        let mut cells = 0usize;
        while let Some((corner, side, depth)) = stack.pop() {
            if total > cap {
                break;
            }
            cells += 1;
            // Leaves of four spacings hold up to 16 nodes: a count that stays below one
            // node a cell is a domain the cells cannot resolve.
            if cells > MAX_ESTIMATE_CELLS && total < cells as f64 {
                return f64::INFINITY;
            }
            let centre = [corner[0] + side / 2.0, corner[1] + side / 2.0];
            // A cell entirely outside the solid holds nothing.
            if domain.signed_distance(centre) > side * std::f64::consts::FRAC_1_SQRT_2 {
                continue;
            }
            let h = self.at(centre);
            if side > 4.0 * h && depth < 40 {
                let half = side / 2.0;
                for (dx, dy) in [(0.0, 0.0), (half, 0.0), (0.0, half), (half, half)] {
                    stack.push(([corner[0] + dx, corner[1] + dy], half, depth + 1));
                }
            } else {
                // Fraction of the cell inside, from a 4 x 4 sample.
                let inside = (0..16)
                    .filter(|k| {
                        domain.signed_distance([
                            corner[0] + side * ((k % 4) as f64 + 0.5) / 4.0,
                            corner[1] + side * ((k / 4) as f64 + 0.5) / 4.0,
                        ]) <= 0.0
                    })
                    .count();
                total += side * side * inside as f64 / 16.0 / (h * h);
            }
        }
        total
    }
}

/// Cells after which [`SpacingField::node_estimate`] gives up on a domain it cannot
/// resolve (about half a second; the shipped scenes need 281 to 5 205).
pub const MAX_ESTIMATE_CELLS: usize = 1_000_000;

/// `sum w_k h_k / sum w_k` over the nearest samples, `w_k = 1 / d_k^2`; the sample's
/// own spacing at a sample.
fn sampled(s: &SpacingSamples, tree: &ImmutableKdTree<f64, 2>, x: Point) -> f64 {
    let k = NonZeroUsize::new(SAMPLE_NEIGHBOURS.min(s.points.len()).max(1)).expect("at least one");
    let (mut num, mut den) = (0.0, 0.0);
    for n in tree.query(&x).nearest_n::<SquaredEuclidean<f64>>(k).execute() {
        let h = s.spacing[n.item as usize];
        if n.distance <= (1e-12 * h).powi(2) {
            return h;
        }
        num += h / n.distance;
        den += 1.0 / n.distance;
    }
    num / den
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point refinement: `h = min(h_max, h_min + g r)`, and about
    /// `int 2 pi r dr / (h_min + g r)^2` nodes inside the radius where it reaches h_max
    /// plus `area / h_max^2` outside.
    #[test]
    fn graded_spacing_and_node_estimate() {
        let domain = Domain::rectangle([-1.0, -1.0], [1.0, 1.0]);
        assert!((SpacingField::uniform(0.05).node_estimate(&domain, f64::INFINITY) - 1600.0).abs() < 1e-6 * 1600.0);
        let (h_min, g, h_max) = (0.002, 0.2, 0.05);
        let r = Refinement { spacing: h_min, growth: g, parts: Vec::new(), points: vec![[0.0, 0.0]] };
        let field = SpacingField::graded(h_max, &r, Vec::new());
        assert_eq!(field.at([0.0, 0.0]), h_min);
        assert!((field.at([0.1, 0.0]) - (h_min + g * 0.1)).abs() < 1e-15);
        assert_eq!(field.at([0.9, 0.9]), h_max);
        // Analytic count: R = (h_max - h_min) / g, inner part 2 pi / g^2 (ln(h_max/h_min) + h_min/h_max - 1).
        let big_r = (h_max - h_min) / g;
        let inner = 2.0 * std::f64::consts::PI / (g * g) * ((h_max / h_min).ln() + h_min / h_max - 1.0);
        let outer = (4.0 - std::f64::consts::PI * big_r * big_r) / (h_max * h_max);
        let estimate = field.node_estimate(&domain, f64::INFINITY);
        assert!(field.node_estimate(&domain, 100.0) > 100.0);
        assert!((estimate - (inner + outer)).abs() < 0.05 * (inner + outer), "{estimate} vs {}", inner + outer);
    }
}
