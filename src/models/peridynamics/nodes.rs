//! Peridynamic nodes: the quadrature points of a lattice of square cells of side
//! `h = delta / m` (seed 000, sec. 5.3: "nodes are quadrature points"), aligned with
//! the lower-left corner of the solid's bounding box.
//!
//! A rule point inside the solid (signed distance <= 0) is a free node with volume
//! `weight * h^2`. The triangle rules of types 1-3 share vertices and edge midpoints
//! between cells: a shared point gets the sum of the shares of the cells that hold
//! material, and a point on the boundary is free with the shares of the inner cells. A rule point outside, within the collar `delta + 0.75 h` (`2 delta + 0.75 h`
//! for the linear peridynamic solid, [`PdParams::collar_width`]) of a
//! boundary part with a displacement condition, is a constrained node: the
//! Dirichlet volume constraint gives it the prescribed displacement (the constant of
//! the part, or the exact solution evaluated at the node itself). The extra `0.75 h`
//! covers the cells that the partial-area rule counts beyond `delta` (up to
//! `delta + h/sqrt(2)`). Other outside points are dropped (free edges).
//!
//! Cells cut by a curved or unaligned boundary keep their points' full weights, or with
//! `peridynamics.cut_cells` give them their area inside and outside the solid
//! ([`super::triangulated::cut_cell`]). On a Delaunay triangulation
//! (`peridynamics.points = "delaunay"`) the free nodes come from [`super::triangulated`].

pub use super::body::{Body, Foot};
use super::triangulated::{self, cut_cell};
use super::{PdParams, PointSet, Quadrature};
use crate::domain::Point;
use crate::physics::elasticity::dofs::DofMap;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// What one cell adds to its points: `(point in [0, 1]^2, share of the cell area,
/// index of the point in the periodic unit `q.unit_cell()`)` ([`Quadrature::cell_contributions`]).
/// Only the triangle rules of types 1-3 put points on cell edges and corners, shared
/// with the neighbouring cells.
fn contributions(q: Quadrature) -> Vec<(Point, f64, u8)> {
    let unit = q.unit_cell();
    q.cell_contributions()
        .into_iter()
        .map(|(p, w)| (p, w, super::params::unit_index(&unit, p).expect("a point of the unit") as u8))
        .collect()
}

/// The `rule_point` of a node of a Delaunay set: no point of the lattice's unit.
pub const NO_RULE_POINT: u8 = u8::MAX;

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
    /// The boundary part whose displacement condition constrains node `free + k`.
    pub collar_part: Vec<usize>,
    /// Index of the rule point each node is (its position within its cell;
    /// [`NO_RULE_POINT`] on a Delaunay set).
    pub rule_point: Vec<u8>,
    /// First fictitious node: nodes `free..fictitious` are the Dirichlet collar, nodes
    /// `fictitious..` fictitious nodes outside traction parts (`prescribed` holds zero
    /// for them and `collar_part` the first traction part of their foot).
    pub fictitious: usize,
    /// The boundary point nearest to each fictitious node (`k = node - fictitious`).
    pub feet: Vec<Foot>,
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

    /// Layout of the unknowns: the displacements of the free nodes.
    pub fn dofs(&self) -> DofMap {
        DofMap::displacement_only(self.free)
    }

    /// Number of constrained nodes (collar and fictitious).
    pub fn constrained(&self) -> usize {
        self.len() - self.free
    }

    /// Number of fictitious nodes.
    pub fn fictitious_count(&self) -> usize {
        self.len() - self.fictitious
    }
}

/// A lattice point after merging the cells that share it: position, index in the
/// unit cell, shares of the cells inside the solid and of the cells outside.
type Merged = (Point, u8, f64, f64);

/// What a rule point becomes.
enum Role {
    /// A free node.
    Free,
    /// A node of the Dirichlet collar with its part and prescribed displacement.
    Constrained(usize, [f64; 2]),
    /// A fictitious node outside a traction part.
    Fictitious(Foot),
    /// Not a node (outside the solid and its collar, or without material).
    Dropped,
}

/// Lay out the nodes of `params.quadrature` over the body (solid and collar): free
/// nodes first, constrained after, each in lattice (row-major) order.
pub fn generate(body: &Body, params: &PdParams) -> PdNodes {
    let h = params.spacing();
    let classified: Vec<(Point, f64, u8, Role)> = match params.points {
        PointSet::Lattice => merged_points(body, params).into_par_iter().map(|m| classify(body, h, m)).collect(),
        PointSet::Delaunay => {
            let inside = triangulated::triangle_points(body, params);
            let mut all: Vec<_> = inside.into_iter().map(|(p, w, _)| (p, w, NO_RULE_POINT, Role::Free)).collect();
            let collar = triangulated::collar_points(body, params);
            all.extend(collar.into_iter().map(|(p, w, part, u)| (p, w, NO_RULE_POINT, Role::Constrained(part, u))));
            all
        }
    };
    let mut nodes = PdNodes {
        positions: Vec::new(),
        volumes: Vec::new(),
        free: 0,
        prescribed: Vec::new(),
        collar_part: Vec::new(),
        rule_point: Vec::new(),
        fictitious: 0,
        feet: Vec::new(),
        spacing: h,
    };
    for (p, w, r, role) in &classified {
        if let Role::Free = role {
            nodes.positions.push(*p);
            nodes.volumes.push(*w);
            nodes.rule_point.push(*r);
        }
    }
    nodes.free = nodes.positions.len();
    for (p, w, r, role) in &classified {
        if let Role::Constrained(part, u) = role {
            nodes.positions.push(*p);
            nodes.volumes.push(*w);
            nodes.rule_point.push(*r);
            nodes.prescribed.push(*u);
            nodes.collar_part.push(*part);
        }
    }
    nodes.fictitious = nodes.positions.len();
    for (p, w, r, role) in classified {
        if let Role::Fictitious(foot) = role {
            nodes.positions.push(p);
            nodes.volumes.push(w);
            nodes.rule_point.push(r);
            nodes.prescribed.push([0.0, 0.0]);
            nodes.collar_part.push(foot.parts[0].0);
            nodes.feet.push(foot);
        }
    }
    nodes
}

/// A point on the boundary (shared rules only) is free and carries the shares of the
/// inner cells; a point in the collar carries every share and the constraint of its
/// nearest displacement part.
fn classify(body: &Body, h: f64, (p, r, w_in, w_out): Merged) -> (Point, f64, u8, Role) {
    let d = body.domain().signed_distance(p);
    if d <= 1e-9 * h && w_in > 0.0 {
        (p, w_in, r, Role::Free)
    } else if d > 1e-9 * h && d <= body.collar {
        let role = match body.constraint(p) {
            Some((part, u)) => Role::Constrained(part, u),
            None if body.has_fictitious() => body.foot(p).map_or(Role::Dropped, Role::Fictitious),
            None => Role::Dropped,
        };
        (p, w_in + w_out, r, role)
    } else {
        (p, 0.0, r, Role::Dropped)
    }
}

/// One cell's contribution to a rule point: its lattice key, the point, its share of the
/// area, its index in the unit cell, whether the cell is inside the solid.
type Share = ((i64, i64), Point, f64, u8, bool);

/// Every rule point of every lattice cell over the body, merged where cells share a
/// point, in lattice (row-major) order.
fn merged_points(body: &Body, params: &PdParams) -> Vec<Merged> {
    let domain = body.domain();
    let h = params.spacing();
    let (lo, rows, columns) = body.lattice(h);
    let cell = contributions(params.quadrature);
    let shared = params.quadrature.shares_points();
    // A point is keyed by its lattice position in units of h/12 (every rule's points are
    // at distinct keys), so that a point shared by several cells is one node whose weight
    // is the sum of their shares.
    let key = |p: Point| (((p[1] - lo[1]) * 12.0 / h).round() as i64, ((p[0] - lo[0]) * 12.0 / h).round() as i64);
    // A perturbed lattice moves every point of a cell-interior rule by a uniform offset of
    // up to `perturbation h / 2` per coordinate, drawn row by row from a generator seeded
    // by the row: the same points in every run and for any thread count.
    let jitter = params.perturbation * h;
    let rows: Vec<Vec<Share>> = rows
        .into_par_iter()
        .map(|j| {
            let mut out = Vec::new();
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(j as u64 ^ 0x5eed_0f_1a77_1ce5);
            for i in columns.clone() {
                let corner = [lo[0] + i as f64 * h, lo[1] + j as f64 * h];
                // With shared points, a cell adds its shares only if it is material (its
                // centre inside the solid or in the constrained collar), so that points on a
                // free edge get the weight of the inner cells only.
                let c = [corner[0] + 0.5 * h, corner[1] + 0.5 * h];
                let inside = domain.signed_distance(c) <= 0.0;
                if shared && !inside && !body.contains(c) {
                    continue;
                }
                let first = out.len();
                for (q, w, k) in &cell {
                    let at = [corner[0] + q[0] * h, corner[1] + q[1] * h];
                    let p = if jitter > 0.0 {
                        [at[0] + jitter * (rng.random::<f64>() - 0.5), at[1] + jitter * (rng.random::<f64>() - 0.5)]
                    } else {
                        at
                    };
                    // Rules with points strictly inside cells keep every point inside the
                    // solid (a cell cut by a curved edge keeps its inner points).
                    let inner = if shared { inside } else { domain.signed_distance(p) <= 0.0 };
                    out.push((key(at), p, w * h * h, *k, inner));
                }
                if params.cut_cells && !shared {
                    let cut = cut_cell(domain, corner, h);
                    if cut.inside > 0.0 && cut.inside < 1.0 {
                        cut_weights(&mut out, first, &cut, h, key);
                    }
                }
            }
            out
        })
        .collect();
    let mut merged: BTreeMap<(i64, i64), Merged> = BTreeMap::new();
    for (k, p, w, r, inside) in rows.into_iter().flatten() {
        let e = merged.entry(k).or_insert((p, r, 0.0, 0.0));
        if inside {
            e.2 += w;
        } else {
            e.3 += w;
        }
    }
    merged.into_values().collect()
}

/// Cut-cell weights of the points `out[first..]` of one cut cell: the points inside the
/// solid share the cell's area inside (`inside h^2`), those outside the area outside,
/// each side in proportion to the rule's shares. A side with area but none of the
/// rule's points gets one more point at its centroid carrying its area (a cell whose
/// centre is in a hole still gives the solid its sliver, and the collar its part).
fn cut_weights(
    out: &mut Vec<Share>,
    first: usize,
    cut: &super::triangulated::CutCell,
    h: f64,
    key: impl Fn(Point) -> (i64, i64),
) {
    let rule_point = out[first].3;
    for (side, area, centroid) in [(true, cut.inside, cut.inside_centroid), (false, 1.0 - cut.inside, cut.outside_centroid)] {
        let shares: f64 = out[first..].iter().filter(|p| p.4 == side).map(|p| p.2).sum();
        if shares > 0.0 {
            for p in out[first..].iter_mut().filter(|p| p.4 == side) {
                p.2 *= area * h * h / shares;
            }
        } else {
            out.push((key(centroid), centroid, area * h * h, rule_point, side));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_case::{plate, plate_nodes, params};
    use super::super::Quadrature;

    /// A perturbed lattice moves each point by at most `perturbation h / 2` per
    /// coordinate and is the same in every run. Midpoints (half a cell from any edge) all
    /// stay inside, in the same order: their offsets are measured one by one; 2x2 Gauss
    /// points near an edge may leave the solid (dropped): their count stays within 5 %.
    #[test]
    fn a_perturbed_lattice_moves_points_within_their_bound() {
        let (domain, conditions) = plate([1.0, 0.0]);
        for quadrature in [Quadrature::FullArea, Quadrature::Gauss2x2] {
            let lattice = params(0.1, quadrature);
            let perturbed = super::super::PdParams { perturbation: 0.5, ..lattice };
            let nodes = |p| plate_nodes(&domain, &conditions, p);
            let (a, b, c) = (nodes(&lattice), nodes(&perturbed), nodes(&perturbed));
            assert_eq!(b.positions, c.positions, "the same points in every run");
            let h = lattice.spacing();
            if quadrature == Quadrature::FullArea {
                assert_eq!(a.free, b.free);
                let largest = a.positions[..a.free]
                    .iter()
                    .zip(&b.positions[..b.free])
                    .map(|(p, q)| (p[0] - q[0]).abs().max((p[1] - q[1]).abs()))
                    .fold(0.0, f64::max);
                assert!(largest > 0.2 * h && largest <= 0.25 * h * (1.0 + 1e-12), "largest offset {largest:e} of h = {h:e}");
            } else {
                assert!((a.free as f64 - b.free as f64).abs() < 0.05 * a.free as f64, "{} {}", a.free, b.free);
                assert_ne!(a.positions[..10], b.positions[..10]);
            }
        }
    }
}
