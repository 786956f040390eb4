//! The applied loads inside a balance's contour: the tractions prescribed on the
//! boundary the contour encloses and the body force over the region it encloses,
//!
//! ```text
//! F = integral over the enclosed boundary of t ds + integral over V of f dA,
//! M = the same integrals of r x t and r x f,   r from the contour's centre,
//! ```
//!
//! which the arc's tractions must balance, `integral over the arc of sigma(u) n ds = -F`
//! (and `-M`): the equilibrium of `V` with `div sigma + f = 0` in it. Both integrals
//! are Gauss-Legendre sums fine enough that their error stays far below the arc's own
//! midpoint rule: the boundary by the primitive curves of the enclosed parts (a line
//! clipped to the contour's disc exactly, a circle in pieces), keeping the points on
//! the solid's boundary; the region in polar coordinates about the centre, each ray
//! cut where it leaves the solid (found by bisection).

use super::arc::Arc;
use super::dist;
use crate::physics::case::Case;
use crate::domain::shape::Curve;
use crate::domain::Point;
use crate::physics::exact::{self, ExactSolution};

/// Gauss-Legendre nodes and weights on `[-1, 1]`, four points (exact to degree 7).
const GAUSS: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// Pieces of each curve, and of the contour's angles, summed by [`GAUSS`].
const PIECES: usize = 128;

/// Pieces of each ray's stretch inside the solid.
const RAY_PIECES: usize = 32;

/// Samples along a ray that look for where it leaves or enters the solid.
const RAY_SAMPLES: usize = 64;

/// `[Fx, Fy, M]` of the loads inside the contour `arc` around `centre` (module docs);
/// `parts` are the boundary parts it encloses (a corner's two edges, a hole's parts).
pub(super) fn enclosed(case: &Case, exact: Option<&dyn ExactSolution>, centre: Point, arc: &Arc, parts: &[usize]) -> [f64; 3] {
    let edges = boundary(case, exact, centre, arc.radius, parts);
    let body = if case.body_force.is_zero() { [0.0; 3] } else { body(case, exact, centre, arc) };
    std::array::from_fn(|k| edges[k] + body[k])
}

/// `sum of w g(a + (b - a) (1 + x) / 2)` over `pieces` pieces of `[a, b]`, each by
/// [`GAUSS`].
fn gauss(a: f64, b: f64, pieces: usize, mut g: impl FnMut(f64, f64)) {
    let piece = (b - a) / pieces as f64;
    for k in 0..pieces {
        let start = a + k as f64 * piece;
        for &(x, w) in &GAUSS {
            g(start + 0.5 * piece * (1.0 + x), 0.5 * piece * w);
        }
    }
}

/// Adds `w v` to the force and `w (p - centre) x v` to the moment.
fn accumulate(total: &mut [f64; 3], centre: Point, p: Point, v: [f64; 2], w: f64) {
    let r = [p[0] - centre[0], p[1] - centre[1]];
    total[0] += w * v[0];
    total[1] += w * v[1];
    total[2] += w * (r[0] * v[1] - r[1] * v[0]);
}

/// The prescribed tractions on the boundary of `parts` within `radius` of `centre`.
fn boundary(case: &Case, exact: Option<&dyn ExactSolution>, centre: Point, radius: f64, parts: &[usize]) -> [f64; 3] {
    let tolerance = 1e-9 * case.domain.scale();
    let mut total = [0.0; 3];
    for piece in case.domain.boundary_curves().into_iter().filter(|c| parts.contains(&c.part)) {
        let condition = &case.conditions[piece.part];
        if condition.value.is_zero() {
            continue;
        }
        let Some((s0, s1)) = within(&piece.curve, centre, radius) else { continue };
        gauss(s0, s1, PIECES, |s, w| {
            let (p, n) = piece.curve.at(s);
            let on_solid = case.domain.signed_distance(p).abs() <= tolerance;
            if on_solid && dist(p, centre) <= radius {
                let t = exact::value(&condition.value, p, exact, |e| e.traction(p, n));
                accumulate(&mut total, centre, p, t, w);
            }
        });
    }
    total
}

/// The arc-length interval of `curve` inside the disc of `radius` around `centre`,
/// exactly (a circle's may start below 0: `Curve::at` takes any arc length, and the
/// sum over it then needs no wrap at angle 0).
fn within(curve: &Curve, centre: Point, radius: f64) -> Option<(f64, f64)> {
    match *curve {
        Curve::Line { a, b, .. } => {
            // |a + s d - c|^2 = radius^2 with |d| = 1: s^2 + 2 s (d.e) + |e|^2 - radius^2 = 0.
            let length = curve.length();
            let d = [(b[0] - a[0]) / length, (b[1] - a[1]) / length];
            let e = [a[0] - centre[0], a[1] - centre[1]];
            let half = d[0] * e[0] + d[1] * e[1];
            let disc = half * half - (e[0] * e[0] + e[1] * e[1] - radius * radius);
            if disc <= 0.0 {
                return None;
            }
            let (s0, s1) = ((-half - disc.sqrt()).max(0.0), (-half + disc.sqrt()).min(length));
            (s1 > s0).then_some((s0, s1))
        }
        Curve::Circle { center, radius: rc, .. } => {
            // |center + rc e(t) - c|^2 <= radius^2 <=> cos(t - phi) >= (rc^2 + d^2 - radius^2) / (2 rc d),
            // phi the direction of c seen from the circle's centre, d their distance.
            let d = dist(center, centre);
            if d <= 1e-12 * rc {
                return (rc <= radius).then_some((0.0, curve.length()));
            }
            let cosine = (rc * rc + d * d - radius * radius) / (2.0 * rc * d);
            if cosine >= 1.0 {
                return None;
            }
            let (phi, half) = ((centre[1] - center[1]).atan2(centre[0] - center[0]), cosine.max(-1.0).acos());
            Some((rc * (phi - half), rc * (phi + half)))
        }
    }
}

/// The body force over the solid inside the contour: polar coordinates about `centre`
/// over the arc's angles, each ray integrated over its stretches inside the solid.
fn body(case: &Case, exact: Option<&dyn ExactSolution>, centre: Point, arc: &Arc) -> [f64; 3] {
    let at = |t: f64, r: f64| [centre[0] + r * t.cos(), centre[1] + r * t.sin()];
    let mut total = [0.0; 3];
    gauss(arc.angles.0, arc.angles.1, PIECES, |t, wt| {
        for (r0, r1) in inside_stretches(|r| case.domain.contains(at(t, r)), arc.radius) {
            gauss(r0, r1, RAY_PIECES, |r, wr| {
                let p = at(t, r);
                let f = exact::value(&case.body_force, p, exact, |e| e.body_force(p));
                accumulate(&mut total, centre, p, f, wt * wr * r);
            });
        }
    });
    total
}

/// The intervals of `[0, radius]` where `inside` holds, from [`RAY_SAMPLES`] samples
/// with each change refined by bisection (a stretch shorter than a sample's step may
/// be missed: the contours enclose no such sliver).
fn inside_stretches(inside: impl Fn(f64) -> bool, radius: f64) -> Vec<(f64, f64)> {
    let step = radius / RAY_SAMPLES as f64;
    let edge = |mut lo: f64, mut hi: f64| {
        let start = inside(lo);
        for _ in 0..50 {
            let mid = 0.5 * (lo + hi);
            if inside(mid) == start {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let mut stretches = Vec::new();
    let mut open = inside(0.0).then_some(0.0);
    let mut previous = open.is_some();
    for k in 1..=RAY_SAMPLES {
        let r = k as f64 * step;
        let now = inside(r);
        if now != previous {
            let cut = edge(r - step, r);
            match open.take() {
                Some(start) => stretches.push((start, cut)),
                None => open = Some(cut),
            }
            previous = now;
        }
    }
    if let Some(start) = open {
        stretches.push((start, radius));
    }
    stretches
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::problem::Problem;

    /// The loaded L of `benches/bracket_variants/L_manufactured.toml` (a smooth field as
    /// exact solution, its tractions on every edge but the base, its body force) with a
    /// hole cut in it, loaded by the same field's traction.
    fn l_with_a_hole() -> Case {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/bracket_variants/L_manufactured.toml");
        let mut text = std::fs::read_to_string(&path).expect("the loaded L");
        text += "\n[[domain.region]]\nshape = \"disc\"\nop = \"subtract\"\ncenter = [0.03, 0.05]\nradius = 0.012\nname = \"hole\"\n";
        text += "\n[[boundary]]\npart = \"hole\"\nkind = \"traction\"\nvalue = \"exact\"\n";
        Problem::from_str(&text, &path).unwrap_or_else(|e| panic!("{e}")).case
    }

    /// The loads inside a contour balance the exact field's tractions on it (the
    /// divergence theorem with `div sigma + f = 0`): the corner's sector of the L and
    /// the ring around its hole, both loaded on their edges and by the body force. The
    /// arc's integral here is a fine Gauss sum of the exact traction; the two agree to
    /// 1e-9 of the loads (both sums are far finer than the round-off of the field's
    /// size allows to see).
    #[test]
    fn the_enclosed_loads_balance_the_exact_tractions_on_the_contour() {
        let case = l_with_a_hole();
        let exact = case.exact_solution().expect("an exact solution");
        let part = |name: &str| case.domain.parts.iter().position(|p| p == name).expect("a part");
        let contours = [([0.06, 0.14], 0.03, vec![part("inner_v"), part("inner_h")]), ([0.03, 0.05], 0.025, vec![part("hole")])];
        for (centre, radius, parts) in contours {
            let angles = super::super::arc::inside_interval(&case, centre, radius).unwrap_or((0.0, std::f64::consts::TAU));
            let arc = Arc { radius, angles };
            let loads = enclosed(&case, Some(exact.as_ref()), centre, &arc, &parts);
            let mut on_arc = [0.0; 3];
            gauss(angles.0, angles.1, PIECES, |t, w| {
                let n = [t.cos(), t.sin()];
                let p = [centre[0] + radius * n[0], centre[1] + radius * n[1]];
                accumulate(&mut on_arc, centre, p, exact.traction(p, n), w * radius);
            });
            let size = loads.iter().chain(&on_arc).fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..3 {
                assert!((loads[k] + on_arc[k]).abs() < 1e-9 * size, "{centre:?}, component {k}: loads {loads:?}, arc {on_arc:?}");
            }
            assert!(loads[0].abs().max(loads[1].abs()) > 1e-3 * size, "the loads are not trivially zero: {loads:?}");
        }
    }

    /// A ray that enters the solid at 0.3 and leaves at 0.71 of the radius gives that
    /// one stretch, its ends to round-off.
    #[test]
    fn a_ray_is_cut_where_it_leaves_the_solid() {
        let stretches = inside_stretches(|r| (0.3..=0.71).contains(&r), 2.0);
        assert_eq!(stretches.len(), 1);
        assert!((stretches[0].0 - 0.3).abs() < 1e-12 && (stretches[0].1 - 0.71).abs() < 1e-12, "{stretches:?}");
        assert_eq!(inside_stretches(|r| r < 5.0, 2.0), vec![(0.0, 2.0)]);
    }

    /// A circle's stretch inside a disc is found exactly: the circle of radius 10 about
    /// the origin inside the unit disc about (10, 0) spans the angles +-acos(199/200),
    /// across angle 0; a concentric circle is inside whole or not at all.
    #[test]
    fn a_circle_is_clipped_to_the_disc() {
        let circle = Curve::Circle { center: [0.0, 0.0], radius: 10.0, outward: 1.0 };
        let (s0, s1) = within(&circle, [10.0, 0.0], 1.0).expect("they cross");
        let half = (199.0f64 / 200.0).acos();
        assert!((s0 + 10.0 * half).abs() < 1e-12 && (s1 - 10.0 * half).abs() < 1e-12, "{s0} {s1}");
        for s in [s0, s1] {
            assert!((dist(circle.at(s).0, [10.0, 0.0]) - 1.0).abs() < 1e-12, "the ends lie on the disc's edge");
        }
        assert_eq!(within(&circle, [13.0, 0.0], 1.0), None);
        assert_eq!(within(&circle, [0.0, 0.0], 11.0), Some((0.0, circle.length())));
        assert_eq!(within(&circle, [0.0, 0.0], 9.0), None);
    }

    /// The Gauss sum integrates `x^7` over `[0, 2]` exactly.
    #[test]
    fn the_gauss_sum_is_exact_to_degree_seven() {
        let mut sum = 0.0;
        gauss(0.0, 2.0, 3, |x, w| sum += w * x.powi(7));
        assert!((sum - 32.0).abs() < 1e-12, "{sum}");
    }
}
