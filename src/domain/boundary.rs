//! Boundary nodes: each primitive edge is clipped to the boundary of the CSG solid
//! and sampled at the target spacing, endpoints included.
//!
//! A point of an edge lies on the solid's boundary iff the solid's signed distance
//! vanishes there (`|d| <= tol`). Edges are classified on a fine parameter sample
//! (step `h / 8`, or `h(x) / 8` where that would take more than [`MAX_PROBES`] probes a
//! curve); every change of class is located by bisection to `1e-13` of the
//! edge length, then to the zero of the signed distance, extrapolated from two
//! points just past it, so the corners where two primitives meet are found to
//! round-off and both edges produce the same corner point. Points closer than `1e-3 h` are
//! merged into one node that remembers every part it touches, with the normal of
//! each ([`BoundarySample::touches`]).
//!
//! Corner rule: a node touching several parts carries the normalised sum of their
//! normals (the bisector at a rectangle corner); how the boundary conditions of the
//! parts are combined there is decided in `navier::equations`.

use super::density::{Refinement, SpacingField};
use super::shape::{BoundaryCurve, Domain, Point};

/// A boundary node before it joins the node set.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundarySample {
    /// Position.
    pub position: Point,
    /// Every boundary part at this point with that part's outward unit normal.
    pub touches: Vec<(usize, Point)>,
    /// Arc length of each part in `touches` that this node stands for (half the
    /// distance along the curve to each neighbouring sample): the trapezoid weights of
    /// `∮ f ds ≈ Σ_i Σ_k lengths[k] f(x_i, n_k)`.
    pub lengths: Vec<f64>,
}

impl BoundarySample {
    /// Outward unit normal of the node: the normalised sum of the normals of its parts.
    pub fn normal(&self) -> Point {
        let mut n = [0.0, 0.0];
        for (_, m) in &self.touches {
            n[0] += m[0];
            n[1] += m[1];
        }
        let l = n[0].hypot(n[1]);
        if l > 1e-12 {
            [n[0] / l, n[1] / l]
        } else {
            self.touches[0].1
        }
    }
}

/// Most probes of one curve when looking for where it lies on the boundary: a step of
/// `len / 2^22` (2.4e-7 of the curve) resolves every feature a node set could carry, and
/// the probing of a graded or tiny spacing stays in time proportional to the curve's
/// nodes (a refinement spacing of 1e-8 probed every h/8 took 1e8 probes per metre).
const MAX_PROBES: usize = 1 << 22;

/// The probe parameters of [`on_boundary_intervals`] on `[0, len]`: equal steps of the
/// smallest spacing over 8 while they number at most [`MAX_PROBES`] (a change of units
/// then scales every probe exactly, and so every corner found), else every `h(x) / 8` of
/// a graded spacing, between `len / MAX_PROBES` and `len / 16`; the last is `len`.
fn probe_parameters(c: &BoundaryCurve, field: &SpacingField) -> Vec<f64> {
    let len = c.curve.length();
    let equal = (len / (field.min() / 8.0)).ceil();
    if field.is_uniform() || equal <= MAX_PROBES as f64 {
        let samples = (equal as usize).clamp(16, MAX_PROBES);
        let ds = len / samples as f64;
        return (1..=samples).map(|k| if k == samples { len } else { k as f64 * ds }).collect();
    }
    let (shortest, longest) = (len / MAX_PROBES as f64, len / 16.0);
    let mut out = Vec::new();
    let mut s = 0.0;
    while s < len {
        let step = (field.at(c.curve.at(s).0) / 8.0).clamp(shortest, longest);
        s = if s + step >= len * (1.0 - 1e-12) { len } else { s + step };
        out.push(s);
    }
    out
}

/// Parameter intervals `[s0, s1]` of `curve` that lie on the solid's boundary, probed
/// every `h(x) / 8` ([`probe_parameters`]); `h` the smallest spacing.
fn on_boundary_intervals(domain: &Domain, c: &BoundaryCurve, field: &SpacingField, tol: f64) -> Vec<(f64, f64)> {
    let len = c.curve.length();
    let h = field.min();
    let on = |s: f64| domain.signed_distance(c.curve.at(s).0).abs() <= tol;
    // The corner between an "on" and an "off" parameter (the off one a sample, so a
    // valid parameter): bisection to the last "on" point, which lies where |d|
    // reaches `tol`, up to `tol / sin(angle)` past the true corner; then the zero of
    // `d` extrapolated from two points past it, where `d` is the other primitive's
    // distance, linear in `s` to `O(delta^2 / radius)`.
    let distance = |s: f64| domain.signed_distance(c.curve.at(s).0);
    let refine = |s_on: f64, s_sample_off: f64| {
        let (mut s_on, mut s_off) = (s_on, s_sample_off);
        while (s_on - s_off).abs() > 1e-13 * len {
            let mid = 0.5 * (s_on + s_off);
            if on(mid) {
                s_on = mid;
            } else {
                s_off = mid;
            }
        }
        exact_corner(s_on, s_off, s_sample_off, &distance, h).unwrap_or(s_on)
    };
    let mut intervals = Vec::new();
    let mut start = if on(0.0) { Some(0.0) } else { None };
    let mut prev = 0.0;
    for s in probe_parameters(c, field) {
        match (start, on(s)) {
            (None, true) => start = Some(refine(s, prev)),
            (Some(s0), false) => {
                intervals.push((s0, refine(prev, s)));
                start = None;
            }
            _ => {}
        }
        prev = s;
    }
    if let Some(s0) = start {
        intervals.push((s0, len));
    }
    // A curve that only touches the solid (a tangent point, where the bisection
    // leaves an interval of length ~sqrt(tol r)) or a sliver shorter than h/4
    // cannot carry nodes of its own: its ends are corners found by other curves.
    intervals.retain(|(a, b)| b - a > 0.25 * h);
    // A closed curve whose first and last intervals meet at s = 0 is one interval.
    if c.curve.is_closed() && intervals.len() > 1 && intervals[0].0 == 0.0 && intervals.last().unwrap().1 == len {
        let last = intervals.pop().unwrap();
        intervals[0].0 = last.0 - len;
    }
    intervals
}

/// The parameter where the signed distance `d` of the solid vanishes between the
/// last on-boundary parameter `s_on` and the first off-boundary one `s_off` (both from
/// a bisection), extrapolated linearly from `d(s_off)` and `d` one small step
/// (`1e-4 h`, at most as far as the off-boundary sample `s_sample_off`) further off.
/// `None` if `d` does not change over that step (a clamped parameter, a tangent
/// meeting) or the zero lies more than `1e-3 h` from `s_on` (not a transversal corner).
fn exact_corner(s_on: f64, s_off: f64, s_sample_off: f64, d: &dyn Fn(f64) -> f64, h: f64) -> Option<f64> {
    let step = (s_sample_off - s_off).signum() * (1e-4 * h).min((s_sample_off - s_off).abs());
    let (d0, d1) = (d(s_off), d(s_off + step));
    if step == 0.0 || d1 == d0 || !(d0.is_finite() && d1.is_finite()) {
        return None;
    }
    let s = s_off - d0 * step / (d1 - d0);
    (s.is_finite() && (s - s_on).abs() <= 1e-3 * h).then_some(s)
}

/// Samples, every `h_min / 4` of `refinement`, of the boundary parts it refines
/// towards (none when it names no part). Only the curves of those parts are sampled:
/// the cost is their length over `h_min`, where sampling the whole boundary at
/// `h_min / 4` (and probing it at `h_min / 32`) took minutes at `h_min = 1e-5`.
pub fn refined_parts(domain: &Domain, refinement: &Refinement) -> Vec<Point> {
    if refinement.parts.is_empty() {
        return Vec::new();
    }
    discretise_curves(domain, &SpacingField::uniform(refinement.spacing / 4.0), |part| refinement.parts.contains(&part))
        .into_iter()
        .filter(|s| s.touches.iter().any(|(part, _)| refinement.parts.contains(part)))
        .map(|s| s.position)
        .collect()
}

/// Length of the boundary that the parts `parts` make, probed every `h / 8` (the
/// intervals' ends are bisected to round-off): what a refinement towards them puts
/// nodes along, known before any sampling at the refinement's spacing.
pub fn parts_length(domain: &Domain, parts: &[usize], h: f64) -> f64 {
    let field = SpacingField::uniform(h);
    let tol = on_boundary_tolerance(domain, h);
    domain
        .boundary_curves()
        .into_iter()
        .filter(|c| parts.contains(&c.part))
        .flat_map(|c| on_boundary_intervals(domain, &c, &field, tol))
        .map(|(a, b)| b - a)
        .sum()
}

/// Sample the boundary of `domain` at spacing about `h` (see module docs).
pub fn discretise_boundary(domain: &Domain, h: f64) -> Vec<BoundarySample> {
    discretise_boundary_graded(domain, &SpacingField::uniform(h))
}

/// Parameters of the samples of `[s0, s1]` on `curve`, the ends included, spaced by
/// `h(x(s))`: equal steps of `int ds / h`, rounded to a whole number of segments (for a
/// uniform `h`, `round((s1 - s0) / h)` equal segments).
fn sample_parameters(curve: &BoundaryCurve, s0: f64, s1: f64, field: &SpacingField) -> Vec<f64> {
    if field.is_uniform() {
        let segments = (((s1 - s0) / field.max()).round() as usize).max(1);
        return (0..=segments).map(|k| s0 + (s1 - s0) * k as f64 / segments as f64).collect();
    }
    // Cumulative int ds / h on a fine midpoint rule (32 cells per local spacing at
    // least): equal cells of the smallest spacing while they number at most
    // MAX_PROBES (a change of units then scales every sample exactly), else cells of the
    // local spacing (a tiny refinement spacing: equal cells would be too many).
    let equal_cells = ((s1 - s0) / field.min() * 32.0).ceil();
    let (cells, at): (usize, Box<dyn Fn(f64) -> f64>) = if equal_cells <= MAX_PROBES as f64 {
        let cells = (equal_cells as usize).max(64);
        let ds = (s1 - s0) / cells as f64;
        (cells, Box::new(move |x: f64| s0 + x * ds))
    } else {
        let mut edges = vec![s0];
        let mut s = s0;
        while s < s1 {
            let step = (field.at(curve.curve.at(s).0) / 32.0).max((s1 - s0) / MAX_PROBES as f64);
            s = if s + step >= s1 - 1e-12 * (s1 - s0) { s1 } else { s + step };
            edges.push(s);
        }
        // Parameter at `x` cells: linear within a cell.
        let cells = edges.len() - 1;
        (cells, Box::new(move |x: f64| {
            let k = (x.floor() as usize).min(cells - 1);
            edges[k] + (x - k as f64) * (edges[k + 1] - edges[k])
        }))
    };
    let mut cumulative = Vec::with_capacity(cells + 1);
    cumulative.push(0.0);
    for k in 0..cells {
        let h = field.at(curve.curve.at(at(k as f64 + 0.5)).0);
        let width = if equal_cells <= MAX_PROBES as f64 { (s1 - s0) / cells as f64 } else { at(k as f64 + 1.0) - at(k as f64) };
        cumulative.push(cumulative[k] + width / h);
    }
    let total = cumulative[cells];
    let segments = (total.round() as usize).max(1);
    let mut out = Vec::with_capacity(segments + 1);
    let mut cell = 0;
    for k in 0..=segments {
        let target = total * k as f64 / segments as f64;
        while cell + 1 < cells && cumulative[cell + 1] < target {
            cell += 1;
        }
        let (a, b) = (cumulative[cell], cumulative[cell + 1]);
        let t = if b > a { ((target - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
        out.push(if k == segments { s1 } else { at(cell as f64 + t) });
    }
    out
}

/// Sample the boundary of `domain` with the spacing `field` (see module docs).
pub fn discretise_boundary_graded(domain: &Domain, field: &SpacingField) -> Vec<BoundarySample> {
    discretise_curves(domain, field, |_| true)
}

/// The on-boundary tolerance of the signed distance at the smallest spacing `h`.
fn on_boundary_tolerance(domain: &Domain, h: f64) -> f64 {
    (1e-9 * domain.scale()).min(1e-6 * h)
}

/// [`discretise_boundary_graded`] of the curves of the parts `keep` accepts.
fn discretise_curves(domain: &Domain, field: &SpacingField, keep: impl Fn(usize) -> bool) -> Vec<BoundarySample> {
    let h = field.min();
    let tol = on_boundary_tolerance(domain, h);
    let mut raw: Vec<BoundarySample> = Vec::new();
    for c in domain.boundary_curves().into_iter().filter(|c| keep(c.part)) {
        let len = c.curve.length();
        for (s0, s1) in on_boundary_intervals(domain, &c, field, tol) {
            let whole_closed = c.curve.is_closed() && s0 == 0.0 && s1 == len;
            let params = sample_parameters(&c, s0, s1, field);
            let mut lengths: Vec<f64> =
                (0..params.len()).map(|k| 0.5 * (params[(k + 1).min(params.len() - 1)] - params[k.saturating_sub(1)])).collect();
            let mut params = params;
            if whole_closed {
                // The last sample is the first one again: its half segment joins it.
                params.pop();
                let last = lengths.pop().unwrap_or(0.0);
                lengths[0] += last;
            }
            for (s, length) in params.into_iter().zip(lengths) {
                let s = if c.curve.is_closed() { s.rem_euclid(len) } else { s };
                let (p, n) = c.curve.at(s);
                raw.push(BoundarySample { position: p, touches: vec![(c.part, n)], lengths: vec![length] });
            }
        }
    }
    // Corners found by two curves agree to round-off (`exact_corner`); anything closer
    // than h/1000 is one node.
    merge_coincident(raw, 1e-3 * h)
}

/// Merge samples closer than `eps` (corners produced by two edges).
fn merge_coincident(raw: Vec<BoundarySample>, eps: f64) -> Vec<BoundarySample> {
    let mut out: Vec<BoundarySample> = Vec::with_capacity(raw.len());
    // Corners are few: index the kept samples by a coarse hash of their position.
    let key = |p: Point| ((p[0] / eps).floor() as i64, (p[1] / eps).floor() as i64);
    let mut index: std::collections::HashMap<(i64, i64), Vec<usize>> = std::collections::HashMap::new();
    for s in raw {
        let (kx, ky) = key(s.position);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(list) = index.get(&(kx + dx, ky + dy)) {
                    for &i in list {
                        let q = out[i].position;
                        if (q[0] - s.position[0]).hypot(q[1] - s.position[1]) <= eps {
                            found = Some(i);
                            break 'search;
                        }
                    }
                }
            }
        }
        match found {
            Some(i) => {
                for (t, length) in s.touches.into_iter().zip(s.lengths) {
                    match out[i].touches.iter().position(|(p, _)| *p == t.0) {
                        Some(k) => out[i].lengths[k] += length,
                        None => {
                            out[i].touches.push(t);
                            out[i].lengths.push(length);
                        }
                    }
                }
            }
            None => {
                index.entry((kx, ky)).or_default().push(out.len());
                out.push(s);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::shape::{CsgOp, Primitive, Region};
    use super::*;

    fn quarter_plate() -> Domain {
        super::super::shape::tests::plate_with_hole()
    }

    #[test]
    fn rectangle_corners_are_shared_and_bisected() {
        let d = Domain {
            regions: vec![Region {
                primitive: Primitive::Rectangle { min: [0.0, 0.0], max: [2.0, 1.0] },
                op: CsgOp::Union,
                edge_parts: vec![0, 1, 2, 3],
            }],
            parts: ["bottom", "right", "top", "left"].iter().map(|s| s.to_string()).collect(),
        };
        let b = discretise_boundary(&d, 0.1);
        // 20 + 10 segments per side pair: perimeter / h = 60 distinct nodes.
        assert_eq!(b.len(), 60);
        let corners: Vec<_> = b.iter().filter(|s| s.touches.len() == 2).collect();
        assert_eq!(corners.len(), 4);
        let c = corners.iter().find(|s| s.position == [0.0, 0.0]).unwrap();
        let n = c.normal();
        assert!((n[0] + 0.5f64.sqrt()).abs() < 1e-15 && (n[1] + 0.5f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn hole_meets_edges_at_exact_corners() {
        let b = discretise_boundary(&quarter_plate(), 0.05);
        // The hole arc meets the left edge at (0, 1) and the bottom edge at (1, 0). The
        // bisection alone stops where |d| reaches tol = 1e-9 * domain size (5.7e-9
        // here), which put the arc's corner node 5.7e-9 outside the solid; the
        // extrapolated zero of d puts it on both curves to round-off.
        for target in [[0.0, 1.0], [1.0, 0.0]] {
            let s = b.iter().find(|s| (s.position[0] - target[0]).hypot(s.position[1] - target[1]) < 1e-8).expect("corner node");
            assert_eq!(s.touches.len(), 2, "{:?}", s);
            let off = (s.position[0] - target[0]).hypot(s.position[1] - target[1]);
            assert!(off < 1e-15, "corner {:?} is {off:.1e} from {target:?}", s.position);
        }
        // No node inside the hole, all on the boundary.
        for s in &b {
            let r = s.position[0].hypot(s.position[1]);
            assert!(r > 1.0 - 1e-8, "{:?}", s.position);
            // Hole normals point to the centre (outward of the solid).
            if s.touches.iter().all(|t| t.0 == 4) {
                let n = s.normal();
                assert!((n[0] * s.position[0] + n[1] * s.position[1] + r).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn lengths_are_trapezoid_weights_of_the_boundary() {
        // Perimeter of the quarter plate: 3 + 4 + 4 + 3 + pi/2 (the weights are arc
        // lengths), to round-off now that the clipped edges end at their exact corners
        // (the bisection alone overshot by up to 1e-9 * scale: 1.7e-8 over 8 edge
        // ends); area by the divergence theorem, (1/2) ∮ x·n ds, exact on the straight
        // edges (x·n is linear there) and O(h^2) on the arc.
        let b = discretise_boundary(&quarter_plate(), 0.05);
        let perimeter: f64 = b.iter().flat_map(|s| s.lengths.iter()).sum();
        assert!((perimeter - (14.0 + std::f64::consts::FRAC_PI_2)).abs() < 1e-12, "{perimeter}");
        let area: f64 = b
            .iter()
            .flat_map(|s| s.touches.iter().zip(&s.lengths).map(|((_, n), l)| 0.5 * l * (s.position[0] * n[0] + s.position[1] * n[1])))
            .sum();
        let exact = 16.0 - std::f64::consts::FRAC_PI_4;
        assert!((area - exact).abs() < 0.05f64.powi(2), "{area} vs {exact}");
        assert!(b.iter().all(|s| s.lengths.len() == s.touches.len() && s.lengths.iter().all(|l| *l > 0.0)));
    }
}
