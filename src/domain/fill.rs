//! Interior nodes: a lattice (`grid`) or a scattered Poisson-disk-like fill, and the
//! optional relaxation of seed 002, algorithm 3.
//!
//! * `grid`: the lattice `lo + (i hx, j hy)` over the bounding box with
//!   `hx = Lx / round(Lx / h)` (so that it matches the boundary samples of a
//!   rectangle), keeping points at signed distance `< -h/2` from the boundary.
//! * `scattered`: an advancing-front Poisson-disk fill (Slak & Kosec, 2019). The
//!   boundary nodes seed a FIFO front; each front point `p` proposes `k = 12`
//!   candidates on the circle of radius `h(p)` around it (random rotation from the
//!   scene's seed); a candidate `c` inside the solid (`d < -0.3 h(c)`) is accepted when
//!   no node is closer than `h(c)`. Nearest-neighbour distances are then in
//!   `[h, ~1.3 h]`. With a graded spacing `h(x)` ([`super::density`]) the "is any node
//!   closer" queries use a hierarchy of hash grids, cells `h_min 2^l`, one level per
//!   doubling of the spacing.
//! * relaxation (algorithm 3): every interior node is pushed by its `s = 6` nearest
//!   neighbours, `F = sum r / |r|^alpha` with `r = (x_i - y) / r_chi`, `alpha = 3`,
//!   and moves by `F0 r_chi F` (`F0 = 1e-2`); all moves of one sweep use the old
//!   positions. A move that would leave the solid (or come within `h/4` of the
//!   boundary) is skipped instead of re-seeding the node at random as the seed does,
//!   which keeps the result independent of the thread count.

use super::density::SpacingField;
use super::shape::{Domain, Point};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;
use std::num::NonZeroUsize;

/// Lattice points of the bounding box strictly inside the solid.
pub fn grid_fill(domain: &Domain, h: f64) -> Vec<Point> {
    let (lo, hi) = domain.bounding_box();
    let nx = (((hi[0] - lo[0]) / h).round() as usize).max(1);
    let ny = (((hi[1] - lo[1]) / h).round() as usize).max(1);
    let (hx, hy) = ((hi[0] - lo[0]) / nx as f64, (hi[1] - lo[1]) / ny as f64);
    let margin = 0.5 * hx.min(hy);
    let mut out = Vec::new();
    for j in 1..ny {
        for i in 1..nx {
            let p = [lo[0] + i as f64 * hx, lo[1] + j as f64 * hy];
            if domain.signed_distance(p) < -margin {
                out.push(p);
            }
        }
    }
    out
}

/// "Is any node closer than r" for the nodes inserted so far.
trait Occupancy {
    fn insert(&mut self, p: Point);
    fn any_within(&self, p: Point, r: f64) -> bool;
}

/// Uniform bucket grid for "is any point closer than h" queries.
struct Buckets {
    lo: Point,
    cell: f64,
    nx: usize,
    ny: usize,
    head: Vec<u32>,
    next: Vec<u32>,
    points: Vec<Point>,
}

impl Buckets {
    fn new(lo: Point, hi: Point, cell: f64) -> Self {
        let nx = ((hi[0] - lo[0]) / cell).ceil() as usize + 1;
        let ny = ((hi[1] - lo[1]) / cell).ceil() as usize + 1;
        Buckets { lo, cell, nx, ny, head: vec![u32::MAX; nx * ny], next: Vec::new(), points: Vec::new() }
    }

    fn cell_of(&self, p: Point) -> (usize, usize) {
        let i = ((p[0] - self.lo[0]) / self.cell).floor().clamp(0.0, (self.nx - 1) as f64) as usize;
        let j = ((p[1] - self.lo[1]) / self.cell).floor().clamp(0.0, (self.ny - 1) as f64) as usize;
        (i, j)
    }
}

impl Occupancy for Buckets {
    fn insert(&mut self, p: Point) {
        let (i, j) = self.cell_of(p);
        let c = j * self.nx + i;
        self.next.push(self.head[c]);
        self.head[c] = self.points.len() as u32;
        self.points.push(p);
    }

    fn any_within(&self, p: Point, r: f64) -> bool {
        let (i, j) = self.cell_of(p);
        for jj in j.saturating_sub(1)..=(j + 1).min(self.ny - 1) {
            for ii in i.saturating_sub(1)..=(i + 1).min(self.nx - 1) {
                let mut k = self.head[jj * self.nx + ii];
                while k != u32::MAX {
                    let q = self.points[k as usize];
                    if (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) < r * r {
                        return true;
                    }
                    k = self.next[k as usize];
                }
            }
        }
        false
    }
}

/// Hash grids of cells `h_min 2^l` for `l = 0..levels`: a query of radius `r` scans the
/// 3 x 3 cells of the smallest level whose cell is at least `r`.
struct LevelGrid {
    h_min: f64,
    levels: Vec<HashMap<(i64, i64), Vec<u32>>>,
    points: Vec<Point>,
}

impl LevelGrid {
    fn new(h_min: f64, h_max: f64) -> Self {
        let levels = ((h_max / h_min).log2().ceil().max(0.0) as usize) + 1;
        LevelGrid { h_min, levels: (0..levels).map(|_| HashMap::default()).collect(), points: Vec::new() }
    }

    fn cell(&self, p: Point, level: usize) -> (i64, i64) {
        let size = self.h_min * (1u64 << level) as f64;
        ((p[0] / size).floor() as i64, (p[1] / size).floor() as i64)
    }
}

impl Occupancy for LevelGrid {
    fn insert(&mut self, p: Point) {
        let k = self.points.len() as u32;
        for l in 0..self.levels.len() {
            let c = self.cell(p, l);
            self.levels[l].entry(c).or_default().push(k);
        }
        self.points.push(p);
    }

    fn any_within(&self, p: Point, r: f64) -> bool {
        let level = ((r / self.h_min).log2().ceil().max(0.0) as usize).min(self.levels.len() - 1);
        let (i, j) = self.cell(p, level);
        for dj in -1..=1 {
            for di in -1..=1 {
                if let Some(list) = self.levels[level].get(&(i + di, j + dj)) {
                    if list.iter().any(|&k| {
                        let q = self.points[k as usize];
                        (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) < r * r
                    }) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// Advancing-front Poisson-disk fill seeded by the boundary nodes (module docs).
pub fn scattered_fill(domain: &Domain, boundary: &[Point], field: &SpacingField, seed: u64) -> Vec<Point> {
    let (lo, hi) = domain.bounding_box();
    if field.is_uniform() {
        advancing_front(domain, boundary, field, seed, Buckets::new(lo, hi, field.max()))
    } else {
        advancing_front(domain, boundary, field, seed, LevelGrid::new(field.min(), field.max()))
    }
}

fn advancing_front(domain: &Domain, boundary: &[Point], field: &SpacingField, seed: u64, mut index: impl Occupancy) -> Vec<Point> {
    let mut front: Vec<Point> = boundary.to_vec();
    for &p in boundary {
        index.insert(p);
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut next = 0usize;
    let mut interior = Vec::new();
    while next < front.len() {
        // The front points known now, in order: their random rotations drawn in that
        // order (one each, as one at a time would), their candidates and spacings made
        // in parallel (a graded spacing is a nearest-target query, most of a sequential
        // fill: docs/notebook/2026-11-26-up-form-iterative-solvers.md, "The graded
        // fill's spacings in parallel"), then accepted one by one in the same order:
        // the same nodes as a point-by-point front, bit for bit.
        let batch: Vec<(Point, f64)> = front[next..].iter().map(|&p| (p, rng.random::<f64>() * std::f64::consts::TAU)).collect();
        next = front.len();
        let proposals: Vec<(f64, [Candidate; CANDIDATES])> = batch.par_iter().map(|&(p, theta0)| candidates(field, p, theta0)).collect();
        for (h, candidates) in proposals {
            for Candidate { position: c, spacing: hc } in candidates {
                // The exclusion radius is the smaller of the two spacings: with `h(c)` alone a
                // candidate where the spacing grows (h(c) > h(p) = |c - p|) is blocked by its
                // own parent, and the front dies out in coarsening regions, leaving holes.
                if domain.signed_distance(c) < -0.3 * hc && !index.any_within(c, hc.min(h) * (1.0 - 1e-9)) {
                    index.insert(c);
                    front.push(c);
                    interior.push(c);
                }
            }
        }
    }
    interior
}

/// Candidates proposed by each front point.
const CANDIDATES: usize = 12;

/// A proposed node and the spacing there.
#[derive(Clone, Copy, Default)]
struct Candidate {
    position: Point,
    spacing: f64,
}

/// `h(p)` and the [`CANDIDATES`] points on the circle of that radius around `p`, the
/// first at angle `theta0`, each with its own spacing.
fn candidates(field: &SpacingField, p: Point, theta0: f64) -> (f64, [Candidate; CANDIDATES]) {
    let h = field.at(p);
    let mut out = [Candidate::default(); CANDIDATES];
    for (k, slot) in out.iter_mut().enumerate() {
        let th = theta0 + std::f64::consts::TAU * k as f64 / CANDIDATES as f64;
        let c = [p[0] + h * th.cos(), p[1] + h * th.sin()];
        *slot = Candidate { position: c, spacing: if field.is_uniform() { h } else { field.at(c) } };
    }
    (h, out)
}

/// Relaxation sweeps over the interior nodes `positions[first_interior..]` (module
/// docs), each node scaled by its local spacing.
pub fn relax(domain: &Domain, positions: &mut [Point], first_interior: usize, field: &SpacingField, iterations: usize) {
    const NEIGHBOURS: usize = 6;
    const F0: f64 = 1e-2;
    const ALPHA: i32 = 3;
    if positions.len() <= NEIGHBOURS {
        return;
    }
    for _ in 0..iterations {
        let Ok(tree) = ImmutableKdTree::<f64, 2>::new_from_slice(positions) else { return };
        let k = NonZeroUsize::new(NEIGHBOURS + 1).unwrap();
        let moved: Vec<Point> = positions[first_interior..]
            .par_iter()
            .map(|&x| {
                let h = field.at(x);
                let r_chi = h;
                let mut f = [0.0, 0.0];
                for nb in tree.query(&x).nearest_n::<SquaredEuclidean<f64>>(k).execute() {
                    let y = positions[nb.item as usize];
                    let r = [(x[0] - y[0]) / r_chi, (x[1] - y[1]) / r_chi];
                    let len = r[0].hypot(r[1]);
                    if len > 0.0 {
                        let s = len.powi(ALPHA);
                        f[0] += r[0] / s;
                        f[1] += r[1] / s;
                    }
                }
                let cand = [x[0] + F0 * r_chi * f[0], x[1] + F0 * r_chi * f[1]];
                if domain.signed_distance(cand) < -0.25 * h {
                    cand
                } else {
                    x
                }
            })
            .collect();
        positions[first_interior..].copy_from_slice(&moved);
    }
}

#[cfg(test)]
mod tests {
    use super::super::shape::{CsgOp, Primitive, Region};
    use super::*;

    fn disc() -> Domain {
        Domain {
            regions: vec![Region { primitive: Primitive::Disc { center: [0.0, 0.0], radius: 1.0 }, op: CsgOp::Union, edge_parts: vec![0] }],
            parts: vec!["rim".into()],
        }
    }

    #[test]
    fn scattered_fill_respects_min_distance_and_is_deterministic() {
        let d = disc();
        let h = 0.05;
        let boundary: Vec<Point> = super::super::boundary::discretise_boundary(&d, h).into_iter().map(|s| s.position).collect();
        let a = scattered_fill(&d, &boundary, &SpacingField::uniform(h), 7);
        let b = scattered_fill(&d, &boundary, &SpacingField::uniform(h), 7);
        assert_eq!(a, b);
        // Hexagonal packing at spacing h has pi / (sqrt(3)/2 h^2) ~ 1451 nodes; a
        // Poisson-disk fill reaches 70-95 % of it.
        let n = a.len() as f64;
        assert!(n > 0.6 * 1451.0 && n < 1451.0, "{n}");
        let mut all = boundary.clone();
        all.extend(&a);
        for (i, p) in a.iter().enumerate() {
            for q in all.iter().skip(boundary.len() + i + 1) {
                assert!((p[0] - q[0]).hypot(p[1] - q[1]) >= h * (1.0 - 1e-6));
            }
            assert!(d.contains(*p));
        }
    }

    /// A fill graded towards the centre of a square: no two interior nodes closer than
    /// the smaller of their local spacings divided by `1 + g` (the exclusion radius is
    /// the smaller of the candidate's and its parent's spacing, and the parent is one
    /// spacing away, where h differs by at most the growth `g`), no hole larger than about twice the local
    /// spacing, and a node count near the integral of `1.1 / h^2` (the packing of the
    /// uniform fill).
    #[test]
    fn graded_fill_follows_the_local_spacing() {
        use crate::domain::density::Refinement;
        let d = Domain::rectangle([-1.0, -1.0], [1.0, 1.0]);
        let r = Refinement { spacing: 0.01, growth: 0.2, parts: Vec::new(), points: vec![[0.0, 0.0]] };
        let field = SpacingField::graded(0.1, &r, Vec::new());
        let boundary: Vec<Point> = super::super::boundary::discretise_boundary_graded(&d, &field).into_iter().map(|s| s.position).collect();
        let interior = scattered_fill(&d, &boundary, &field, 3);
        assert_eq!(interior, scattered_fill(&d, &boundary, &field, 3), "deterministic");
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(&interior).unwrap();
        for p in &interior {
            let found = tree.query(p).nearest_n::<SquaredEuclidean<f64>>(NonZeroUsize::new(2).unwrap()).execute();
            let q = interior[found[1].item as usize];
            let dist = found[1].distance.sqrt();
            assert!(dist >= field.at(*p).min(field.at(q)) / (1.0 + r.growth) * (1.0 - 1e-6), "{p:?} and {q:?} at {dist}");
        }
        // Fill distance: sample points are never more than ~2 local spacings from a node.
        for k in 0..400 {
            let x = [-0.95 + 1.9 * ((k * 37) % 400) as f64 / 400.0, -0.95 + 1.9 * k as f64 / 400.0];
            let d2 = tree.query(&x).nearest_one::<SquaredEuclidean<f64>>().execute().distance;
            assert!(d2.sqrt() <= 2.0 * field.at(x), "hole at {x:?}");
        }
        let estimate = 1.1 * field.node_estimate(&d, f64::INFINITY);
        let n = (interior.len() + boundary.len()) as f64;
        assert!(n > 0.8 * estimate && n < 1.25 * estimate, "{n} nodes, estimate {estimate}");
    }

    #[test]
    fn relaxation_keeps_nodes_inside() {
        let d = disc();
        let h = 0.1;
        let boundary: Vec<Point> = super::super::boundary::discretise_boundary(&d, h).into_iter().map(|s| s.position).collect();
        let mut pts = boundary.clone();
        let nb = pts.len();
        pts.extend(scattered_fill(&d, &boundary, &SpacingField::uniform(h), 1));
        let before = pts.clone();
        relax(&d, &mut pts, nb, &SpacingField::uniform(h), 10);
        assert_eq!(&pts[..nb], &before[..nb]);
        assert!(pts[nb..].iter().all(|p| d.contains(*p)));
        assert!(pts != before);
    }
}
