//! Delaunay cells of a node set: triangles inside the solid, so that ParaView has
//! cells to draw, and the lumped nodal areas (a third of each triangle at each
//! corner) that the explicit MLSM dynamics weighs its energies with. The collocation
//! equations never use them.

use super::Domain;
use delaunator::Point;

/// The Delaunay triangles of `points` whose centroid lies in `domain` (see [`triangulate`]).
pub fn cells_inside(domain: &Domain, points: &[[f64; 2]]) -> Vec<[usize; 3]> {
    triangulate(points, |c| domain.contains(c))
}

/// Lumped nodal areas: a third of every triangle at each of its corners.
pub fn nodal_areas(points: &[[f64; 2]], triangles: &[[usize; 3]]) -> Vec<f64> {
    let mut a = vec![0.0; points.len()];
    for t in triangles {
        let (p, q, r) = (points[t[0]], points[t[1]], points[t[2]]);
        let area = 0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1])).abs();
        for &k in t {
            a[k] += area / 3.0;
        }
    }
    a
}

/// Delaunay triangulation (delaunator) of the nodes; drops triangles for which
/// `keep(centroid)` is false (holes, concave parts) and degenerate ones (area < 1e-12 * bbox
/// area).
///
/// * Returned indices refer to `points`; every triangle is counter-clockwise (positive signed
///   area in the usual x-right/y-up frame), so ParaView normals point to +z.
/// * Points with a non-finite coordinate are left out of the triangulation (they keep their
///   index but belong to no triangle). Exact duplicates are used once by delaunator.
/// * Fewer than three usable points, or all points collinear, give an empty list.
/// * The centroid test is exact only when every triangle lies entirely inside or entirely
///   outside the domain, e.g. when boundary nodes are dense enough along concave boundaries and
///   holes; a triangle straddling a concave boundary is kept or dropped as a whole by its
///   centroid. This is a picture for ParaView, not a mesh the collocation depends on.
pub fn triangulate(points: &[[f64; 2]], keep: impl Fn([f64; 2]) -> bool) -> Vec<[usize; 3]> {
    // Map from delaunator's (finite-only) numbering back to the caller's.
    let index: Vec<usize> = (0..points.len()).filter(|&i| points[i][0].is_finite() && points[i][1].is_finite()).collect();
    if index.len() < 3 {
        return Vec::new();
    }
    let pts: Vec<Point> = index.iter().map(|&i| Point { x: points[i][0], y: points[i][1] }).collect();

    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &pts {
        lo = [lo[0].min(p.x), lo[1].min(p.y)];
        hi = [hi[0].max(p.x), hi[1].max(p.y)];
    }
    let min_area = 1e-12 * (hi[0] - lo[0]) * (hi[1] - lo[1]);

    let tri = delaunator::triangulate(&pts);
    let mut out = Vec::with_capacity(tri.triangles.len() / 3);
    for t in tri.triangles.chunks_exact(3) {
        let (a, b, c) = (&pts[t[0]], &pts[t[1]], &pts[t[2]]);
        let twice_area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        let area = 0.5 * twice_area.abs();
        // A NaN area (overflow) counts as degenerate too.
        if area.is_nan() || area < min_area || area == 0.0 {
            continue;
        }
        let centroid = [(a.x + b.x + c.x) / 3.0, (a.y + b.y + c.y) / 3.0];
        if !keep(centroid) {
            continue;
        }
        let (i, j, k) = (index[t[0]], index[t[1]], index[t[2]]);
        out.push(if twice_area > 0.0 { [i, j, k] } else { [i, k, j] });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(p: &[[f64; 2]], t: &[usize; 3]) -> f64 {
        let (a, b, c) = (p[t[0]], p[t[1]], p[t[2]]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    }

    /// True if the triangle and the open axis-aligned box `(lo, hi)` share a region of
    /// positive area (separating-axis test, exact for convex polygons up to `eps`).
    fn overlaps_open_box(tri: [[f64; 2]; 3], lo: [f64; 2], hi: [f64; 2], eps: f64) -> bool {
        let boxc = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
        let mut axes = vec![[1.0, 0.0], [0.0, 1.0]];
        for i in 0..3 {
            let (p, q) = (tri[i], tri[(i + 1) % 3]);
            axes.push([-(q[1] - p[1]), q[0] - p[0]]);
        }
        for ax in axes {
            let n = (ax[0] * ax[0] + ax[1] * ax[1]).sqrt();
            let proj = |v: [f64; 2]| (v[0] * ax[0] + v[1] * ax[1]) / n;
            let (t0, t1) = tri.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(proj(v)), b.max(proj(v))));
            let (b0, b1) = boxc.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(proj(v)), b.max(proj(v))));
            if t1.min(b1) - t0.max(b0) <= eps {
                return false; // separated (or only touching) along this axis
            }
        }
        true
    }

    #[test]
    fn square_with_hole_on_grid_is_tiled_exactly() {
        // Unit square minus the open hole (0.3, 0.7)^2; nodes on a 21x21 grid (h = 0.05), so
        // nodes lie exactly on the hole boundary.
        let n = 20;
        let (lo, hi) = ([0.3, 0.3], [0.7, 0.7]);
        let in_hole = |p: [f64; 2]| p[0] > lo[0] && p[0] < hi[0] && p[1] > lo[1] && p[1] < hi[1];
        let in_hole_strict = |p: [f64; 2]| p[0] > 0.3 + 1e-9 && p[0] < 0.7 - 1e-9 && p[1] > 0.3 + 1e-9 && p[1] < 0.7 - 1e-9;
        let mut pts = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let p = [i as f64 / n as f64, j as f64 / n as f64];
                if !in_hole_strict(p) {
                    pts.push(p);
                }
            }
        }
        let tris = triangulate(&pts, |c| !in_hole(c));
        assert!(!tris.is_empty());
        let mut total = 0.0;
        for t in &tris {
            let a = area(&pts, t);
            assert!(a > 0.0, "triangle {t:?} is not counter-clockwise");
            total += a;
            let c = [(pts[t[0]][0] + pts[t[1]][0] + pts[t[2]][0]) / 3.0, (pts[t[0]][1] + pts[t[1]][1] + pts[t[2]][1]) / 3.0];
            assert!((0.0..=1.0).contains(&c[0]) && (0.0..=1.0).contains(&c[1]));
            assert!(!in_hole(c), "centroid {c:?} inside the hole");
            let tri = [pts[t[0]], pts[t[1]], pts[t[2]]];
            assert!(!overlaps_open_box(tri, lo, hi, 1e-12), "triangle {tri:?} crosses the hole");
        }
        // On a square lattice every Delaunay triangle is half a lattice cell (only the cell's
        // own 4 corners lie on its circumcircle), and every cell is entirely inside or outside
        // the hole, so the kept triangles tile the domain exactly: only rounding error remains.
        let exact = 1.0 - 0.4 * 0.4;
        assert!((total - exact).abs() < 1e-12, "area {total} vs {exact}");
        // 2 triangles per cell outside the hole: 400 cells - 64 hole cells.
        assert_eq!(tris.len(), 2 * (400 - 64));
    }

    #[test]
    fn l_shape_with_jittered_nodes() {
        // L = [0,1]^2 minus the notch (0.5,1]x(0.5,1]. Boundary nodes are exactly on the
        // boundary (spacing h); interior nodes are jittered by up to 0.3 h per coordinate (deterministic LCG).
        let n = 40;
        let h = 1.0 / n as f64;
        let in_notch = |p: [f64; 2]| p[0] > 0.5 && p[1] > 0.5;
        let mut seed: u64 = 12345;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut pts = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let p = [i as f64 * h, j as f64 * h];
                let on_boundary = i == 0 || j == 0 || i == n || j == n || (i == n / 2 && j >= n / 2) || (j == n / 2 && i >= n / 2);
                if in_notch(p) && !on_boundary {
                    continue;
                }
                if in_notch(p) && (i == n || j == n) {
                    continue; // outer boundary of the notch is not part of the domain
                }
                if on_boundary {
                    pts.push(p);
                } else {
                    pts.push([p[0] + 0.6 * h * rnd(), p[1] + 0.6 * h * rnd()]);
                }
            }
        }
        let tris = triangulate(&pts, |c| !in_notch(c));
        let mut total = 0.0;
        for t in &tris {
            let a = area(&pts, t);
            assert!(a > 0.0);
            total += a;
            let c = [(pts[t[0]][0] + pts[t[1]][0] + pts[t[2]][0]) / 3.0, (pts[t[0]][1] + pts[t[1]][1] + pts[t[2]][1]) / 3.0];
            assert!(!in_notch(c) && c[0] >= 0.0 && c[1] >= 0.0 && c[0] <= 1.0 && c[1] <= 1.0);
            let tri = [pts[t[0]], pts[t[1]], pts[t[2]]];
            assert!(!overlaps_open_box(tri, [0.5, 0.5], [1.5, 1.5], 1e-12), "triangle {tri:?} crosses into the notch");
        }
        // Why the tolerance is rounding-level rather than O(h): every pair of consecutive
        // boundary nodes on the notch edges (distance h) is a Gabriel edge, since all other
        // nodes are at least 0.7 h from those edges, outside the circle of radius h/2 on the
        // pair. Gabriel edges are Delaunay edges and Delaunay edges never cross, so the
        // triangulation conforms to the notch boundary: each triangle lies entirely in the L or
        // entirely in the notch, the centroid test classifies it correctly, and the kept area
        // is exact. (With nodes not on the boundary the error would be O(h * boundary length).)
        let exact = 0.75;
        assert!((total - exact).abs() < 1e-12, "area {total} vs {exact}");
    }

    #[test]
    fn degenerate_inputs() {
        // Collinear points: no triangles.
        let line: Vec<[f64; 2]> = (0..10).map(|i| [i as f64, 2.0 * i as f64]).collect();
        assert!(triangulate(&line, |_| true).is_empty());
        // Too few points.
        assert!(triangulate(&[[0.0, 0.0], [1.0, 0.0]], |_| true).is_empty());
        // A sliver whose area is below 1e-12 of the bounding box is dropped, a normal one kept.
        let pts = [[0.0, 0.0], [1.0, 0.0], [0.5, 1e-14], [0.5, 1.0]];
        let tris = triangulate(&pts, |_| true);
        assert!(!tris.is_empty());
        for t in &tris {
            assert!(area(&pts, t) >= 1e-12 * 1.0);
        }
        // Non-finite points are skipped but indices still refer to the input.
        let pts = [[0.0, 0.0], [f64::NAN, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let tris = triangulate(&pts, |_| true);
        assert_eq!(tris.len(), 1);
        let mut t = tris[0].to_vec();
        t.sort();
        assert_eq!(t, vec![0, 2, 3]);
        // `keep` rejecting everything gives nothing.
        assert!(triangulate(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], |_| false).is_empty());
    }
}
