//! Peridynamic nodes on a Delaunay triangulation (`peridynamics.points = "delaunay"`,
//! seed 000, sec. 1.1.3 and 6.2): the solid is filled with the boundary-conforming
//! scattered node set of the classical model ([`crate::domain::generate`]: boundary nodes
//! at spacing `h` on every edge and hole, a Poisson-disk interior), triangulated
//! ([`crate::domain::cells::triangulate`], triangles whose centroid is outside dropped),
//! and each triangle integrated by a triangle rule (types 1-6, [`Quadrature::triangle_rule`]).
//! The nodes are the rule's points; a vertex or edge midpoint shared by several
//! triangles is one node carrying the sum of their shares.
//!
//! The triangles tile the polygon through the boundary nodes, so a curved edge or hole
//! is followed to `O(h^2)` in area per unit length, with no partial cell to weigh.
//! The Dirichlet collar outside displacement parts is the lattice's: square cells of
//! side `h`, each giving one constrained node at the centroid of its part outside the
//! solid, weighted by that part's area ([`cut_cell`]), so that collar and triangles
//! cover the plane without overlap up to the cut cells' sampling.

use super::body::Body;
use super::params::on_triangle;
use super::PdParams;
use crate::domain::cells::triangulate;
use crate::domain::{self, FillKind, FillParams, Point};
use rayon::prelude::*;
use std::collections::HashMap;

/// Sub-samples per side of a cut cell (`n^2` sub-cell centres): its inside share is
/// right to within the sub-cells the boundary crosses, at most `2 / n` of the cell for a
/// straight edge and about `1 / n^2` per crossed sub-cell on average.
pub const CUT_SAMPLES: usize = 8;

/// The part of the square cell `[corner, corner + h]^2` inside the solid: its share of
/// the cell area and the centroids of the parts inside and outside, from
/// [`CUT_SAMPLES`]`^2` sub-cell centres (a cell with its centre deeper than `h / sqrt 2`
/// on one side is whole).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutCell {
    /// Share of the cell area inside the solid, in `[0, 1]`.
    pub inside: f64,
    /// Centroid of the part inside (the cell centre when none is).
    pub inside_centroid: Point,
    /// Centroid of the part outside (the cell centre when none is).
    pub outside_centroid: Point,
}

/// The cut of the cell at `corner` of side `h` by `domain` ([`CutCell`]).
pub fn cut_cell(domain: &domain::Domain, corner: Point, h: f64) -> CutCell {
    let centre = [corner[0] + 0.5 * h, corner[1] + 0.5 * h];
    let d = domain.signed_distance(centre);
    if d.abs() > h * std::f64::consts::FRAC_1_SQRT_2 {
        let inside = if d < 0.0 { 1.0 } else { 0.0 };
        return CutCell { inside, inside_centroid: centre, outside_centroid: centre };
    }
    let n = CUT_SAMPLES;
    let (mut count, mut sum_in, mut sum_out) = (0usize, [0.0; 2], [0.0; 2]);
    for a in 0..n {
        for b in 0..n {
            let p = [corner[0] + (a as f64 + 0.5) * h / n as f64, corner[1] + (b as f64 + 0.5) * h / n as f64];
            let sum = if domain.signed_distance(p) <= 0.0 {
                count += 1;
                &mut sum_in
            } else {
                &mut sum_out
            };
            sum[0] += p[0];
            sum[1] += p[1];
        }
    }
    let mean = |s: [f64; 2], k: usize| if k == 0 { centre } else { [s[0] / k as f64, s[1] / k as f64] };
    CutCell { inside: count as f64 / (n * n) as f64, inside_centroid: mean(sum_in, count), outside_centroid: mean(sum_out, n * n - count) }
}

/// Where a rule point of a triangle lies: a vertex and an edge midpoint are keyed by
/// the node set's vertex numbers (shared between triangles), an interior point by its
/// triangle and its place in the rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Vertex(usize),
    Edge(usize, usize),
    Interior(usize, u8),
}

/// The triangulated node set of the solid and the volume of each rule point
/// (module docs), before the collar: `(position, volume, rule point index)`.
pub fn triangle_points(body: &Body, params: &PdParams) -> Vec<(Point, f64, u8)> {
    let h = params.spacing();
    let domain = body.domain();
    let fill = FillParams { spacing: h, refine: None, adapted: None, kind: FillKind::Scattered, seed: 0, relax_iterations: 0 };
    let set = domain::generate(domain, &fill);
    let vertices = &set.positions;
    let triangles = triangulate(vertices, |c| domain.contains(c));
    let rule = params.quadrature.triangle_rule().expect("validation: a triangle rule with Delaunay points");
    let near = |a: f64, b: f64| (a - b).abs() < 1e-12;
    let mut index: HashMap<Key, usize> = HashMap::new();
    let mut points: Vec<(Point, f64, u8)> = Vec::new();
    for (t, tri) in triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|k| vertices[k]);
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
        for (k, &(q, w)) in rule.iter().enumerate() {
            let corner = |u: f64, v: f64| near(q[0], u) && near(q[1], v);
            let edge = |i: usize, j: usize| Key::Edge(tri[i].min(tri[j]), tri[i].max(tri[j]));
            let key = if corner(0.0, 0.0) {
                Key::Vertex(tri[0])
            } else if corner(1.0, 0.0) {
                Key::Vertex(tri[1])
            } else if corner(0.0, 1.0) {
                Key::Vertex(tri[2])
            } else if corner(0.5, 0.0) {
                edge(0, 1)
            } else if corner(0.5, 0.5) {
                edge(1, 2)
            } else if corner(0.0, 0.5) {
                edge(0, 2)
            } else {
                Key::Interior(t, k as u8)
            };
            let p = on_triangle(q, [a, b, c]);
            let at = *index.entry(key).or_insert_with(|| {
                points.push((p, 0.0, k as u8));
                points.len() - 1
            });
            points[at].1 += w * area;
        }
    }
    // Row-major order in bands of h, as the lattice's nodes: neighbours in space are
    // neighbours in memory.
    points.sort_by(|p, q| {
        let band = |x: &Point| ((x[1] - set.positions[0][1]) / h).floor() as i64;
        band(&p.0).cmp(&band(&q.0)).then(p.0[0].total_cmp(&q.0[0]))
    });
    points
}

/// The Dirichlet collar of a triangulated set, `(position, volume, part, prescribed
/// displacement)` of each constrained node: one per lattice cell of
/// side `h` (aligned with the bounding box's lower-left corner) with a part outside the
/// solid within the collar of a displacement part, at that part's centroid and
/// weighted by its area ([`cut_cell`]).
pub fn collar_points(body: &Body, params: &PdParams) -> Vec<(Point, f64, usize, [f64; 2])> {
    let h = params.spacing();
    let domain = body.domain();
    let (lo, rows, columns) = body.lattice(h);
    let reach = h * std::f64::consts::FRAC_1_SQRT_2;
    rows.into_par_iter()
        .flat_map_iter(|j| {
            columns.clone().filter_map(move |i| {
                let corner = [lo[0] + i as f64 * h, lo[1] + j as f64 * h];
                let centre = [corner[0] + 0.5 * h, corner[1] + 0.5 * h];
                let d = domain.signed_distance(centre);
                if d < -reach || d > body.collar + reach {
                    return None;
                }
                let cut = cut_cell(domain, corner, h);
                let outside = 1.0 - cut.inside;
                let p = cut.outside_centroid;
                if outside <= 0.0 || domain.signed_distance(p) > body.collar {
                    return None;
                }
                let (part, u) = body.constraint(p)?;
                Some((p, outside * h * h, part, u))
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::{CsgOp, Domain, Primitive, Region};

    /// The unit square with a hole of radius `r` at its centre.
    pub(crate) fn square_with_hole(r: f64) -> Domain {
        let mut d = Domain::rectangle([0.0, 0.0], [1.0, 1.0]);
        d.regions.push(Region { primitive: Primitive::Disc { center: [0.5, 0.5], radius: r }, op: CsgOp::Subtract, edge_parts: vec![4] });
        d.parts.push("hole".into());
        d
    }

    /// A cut cell's inside share is the area fraction to within the sampling: a
    /// straight edge at a quarter of the cell (the sub-cell centres split exactly) and
    /// the cells around a hole, whose inside shares add up to the area around the hole
    /// in them to within `2 / n` of a cell per cut cell (a bound, the sum is far closer).
    #[test]
    fn cut_cells_measure_the_area_inside() {
        let square = Domain::rectangle([0.0, 0.0], [1.0, 1.0]);
        let h = 0.1;
        let c = cut_cell(&square, [0.975, 0.5], h);
        assert!((c.inside - 0.25).abs() < 1e-12, "{c:?}");
        assert!((c.inside_centroid[0] - 0.9875).abs() < 1e-12 && (c.outside_centroid[0] - 1.0375).abs() < 1e-12, "{c:?}");
        assert_eq!(cut_cell(&square, [0.3, 0.3], h).inside, 1.0);
        assert_eq!(cut_cell(&square, [1.3, 0.3], h).inside, 0.0);
        let r = 0.23;
        let holed = square_with_hole(r);
        let h = 0.05;
        let (mut area, mut cut) = (0.0, 0);
        for i in 0..20 {
            for j in 0..20 {
                let c = cut_cell(&holed, [i as f64 * h, j as f64 * h], h);
                area += c.inside * h * h;
                cut += usize::from(c.inside > 0.0 && c.inside < 1.0);
            }
        }
        let exact = 1.0 - std::f64::consts::PI * r * r;
        assert!(cut > 20, "{cut} cut cells");
        assert!((area - exact).abs() < cut as f64 * 2.0 / CUT_SAMPLES as f64 * h * h, "{area} against {exact}");
        assert!((area - exact).abs() < 1e-3 * exact, "{area} against {exact}");
    }
}
