//! Peridynamic point sets beyond the plain lattice: Delaunay triangulations integrated
//! by the seed's triangle rules (types 1-6), their Dirichlet collar, and cut-cell
//! weights on the lattice (`peridynamics.points`, `peridynamics.cut_cells`).

mod common;

use common::*;
use mlsm::domain::Domain;
use mlsm::models::peridynamics::nodes::{self, Body, PdNodes};
use mlsm::models::peridynamics::triangulated::CUT_SAMPLES;
use mlsm::models::peridynamics::PdParams;
use mlsm::scene::problem::Problem;
use std::f64::consts::PI;

/// The nodes of a peridynamic scene.
fn nodes_of(p: &Problem) -> (PdNodes, PdParams) {
    let params = *p.model.peridynamics().expect("a [peridynamics] table");
    let exact = p.case.exact_solution();
    let body = Body::new(&p.case.domain, &p.case.conditions, exact.as_deref(), &params);
    (nodes::generate(&body, &params), params)
}

fn free_volume(n: &PdNodes) -> f64 {
    n.volumes[..n.free].iter().sum()
}

/// Area of the plate with the hole of `problems/pd_plate_hole.toml`.
const HOLE_RADIUS: f64 = 0.0375;

fn plate_area() -> f64 {
    0.3 - PI * HOLE_RADIUS * HOLE_RADIUS
}

/// On a Delaunay set every rule carries the triangles' area, the same for all six
/// (to round-off), and that area is the plate's but for the polygon inscribed in the
/// hole: a chord of length `l` on a circle of radius `R` cuts off `l^3 / (12 R)`, so the
/// whole hole loses about `pi h^2 / 6` with chords of length `h` (bound: 1.5x that, for
/// chords somewhat longer than `h`; the straight edges are exact). Every node is on the
/// polygon or inside it: in the closed solid, or within a chord's sagitta
/// `l^2 / (8 R)` of it at the hole (the midpoint of a chord; bound with `l <= 1.5 h`).
#[test]
fn delaunay_points_tile_the_solid() {
    let mut areas = Vec::new();
    for rule in ["triangle-vertex", "triangle-edge", "triangle-p3", "triangle-p2", "triangle-p1", "triangle-hillion"] {
        let p =
            scene("pd_plate_hole", &[("peridynamics.horizon", f(0.1)), ("peridynamics.m", f(4.0)), ("peridynamics.quadrature", s(rule))]);
        let (n, params) = nodes_of(&p);
        let h = params.spacing();
        assert_eq!(n.free, n.len(), "{rule}: all edges free, no collar");
        let sagitta = (1.5 * h).powi(2) / (8.0 * HOLE_RADIUS);
        let farthest = n.positions.iter().map(|&x| p.case.domain.signed_distance(x)).fold(f64::MIN, f64::max);
        assert!(farthest <= sagitta, "{rule}: a node {farthest:e} outside the solid (sagitta {sagitta:e})");
        let area = free_volume(&n);
        assert!((area - plate_area()).abs() < 1.5 * PI * h * h / 6.0, "{rule}: {area} against {}", plate_area());
        areas.push(area);
    }
    let spread = areas.iter().fold(0.0f64, |m, a| m.max((a - areas[0]).abs()));
    assert!(spread < 1e-12, "the rules carry different areas: {areas:?}");
}

/// On the lattice, cut-cell weights give the cells around the hole their area inside
/// the plate: the total is right to within the sub-cells the circle crosses, at most
/// `2 / n` of a cell per cut cell (n = [`CUT_SAMPLES`]); full weights are off by whole
/// half-cells, more than the cut cells' error.
#[test]
fn cut_cells_weigh_the_cells_around_the_hole() {
    let edits = |cut: bool| {
        vec![
            ("peridynamics.points", s("lattice")),
            ("peridynamics.quadrature", s("full-area")),
            ("peridynamics.horizon", f(0.05)),
            ("peridynamics.m", f(3.0)),
            ("peridynamics.cut_cells", b(cut)),
        ]
    };
    let (full, params) = nodes_of(&scene("pd_plate_hole", &edits(false)));
    let (cut, _) = nodes_of(&scene("pd_plate_hole", &edits(true)));
    let h = params.spacing();
    let (e_full, e_cut) = ((free_volume(&full) - plate_area()).abs(), (free_volume(&cut) - plate_area()).abs());
    // Cells the circle crosses: about its length over h, times 2 for the diagonal ones.
    let crossed = 2.0 * 2.0 * PI * HOLE_RADIUS / h;
    assert!(e_cut < crossed * 2.0 / CUT_SAMPLES as f64 * h * h, "cut cells off by {e_cut:e}");
    assert!(e_cut < e_full, "cut cells {e_cut:e}, full weights {e_full:e}");
    let partial = cut.volumes[..cut.free].iter().filter(|&&v| v < 0.999 * h * h).count();
    assert!(partial > 10, "{partial} cut cells");
}

/// A Delaunay set's Dirichlet collar: constrained nodes outside the clamped edge only,
/// covering the collar region (the strip of the collar's width along the edge and the
/// quarter discs at its two corners) to within a lattice cell along the collar's
/// outer edge (cells are kept by their outside centroid).
#[test]
fn a_delaunay_collar_covers_the_clamped_edge() {
    let p = scene(
        "pd_tension",
        &[("peridynamics.points", s("delaunay")), ("peridynamics.quadrature", s("triangle-p2")), ("peridynamics.boundary", s("surface"))],
    );
    let (n, params) = nodes_of(&p);
    let h = params.spacing();
    let c = params.collar_width();
    let domain: &Domain = &p.case.domain;
    let collar = &n.positions[n.free..];
    assert!(!collar.is_empty());
    assert!(collar.iter().all(|x| x[0] < 0.0 && domain.signed_distance(*x) > 0.0), "a collar node off the clamped side");
    let volume: f64 = n.volumes[n.free..].iter().sum();
    let exact = c * 0.5 + 2.0 * PI * c * c / 4.0;
    assert!((volume - exact).abs() < (0.5 + PI * c) * h, "collar {volume} against {exact}");
    // The free nodes still tile the plate exactly (straight edges).
    assert!((free_volume(&n) - 0.5).abs() < 1e-12, "{}", free_volume(&n));
}

/// What a Delaunay set or cut cells cannot run with is refused, naming the field and
/// the reason.
#[test]
fn point_sets_refuse_what_they_cannot_run() {
    let refused = |name: &str, edits: &[(&str, Option<toml::Value>)], field: &str, words: &str| {
        let e = scene_error(name, edits);
        let text = e.to_string();
        assert!(text.contains(field) && text.contains(words), "{text}");
    };
    refused("pd_plate_hole", &[("peridynamics.quadrature", s("gauss2x2"))], "peridynamics.points", "triangle rule");
    refused(
        "pd_tension",
        &[("peridynamics.points", s("delaunay")), ("peridynamics.quadrature", s("triangle-p2"))],
        "peridynamics.points",
        "boundary = \"surface\"",
    );
    refused("pd_plate_hole", &[("peridynamics.correction", s("volume"))], "peridynamics.points", "volume correction");
    refused("pd_plate_hole", &[("peridynamics.cut_cells", b(true))], "peridynamics.points", "no cut cells");
    refused(
        "pd_plate_hole",
        &[("peridynamics.points", s("lattice")), ("peridynamics.quadrature", s("triangle-p3")), ("peridynamics.cut_cells", b(true))],
        "peridynamics.cut_cells",
        "shares its points",
    );
    refused("pd_plate_hole", &[("peridynamics.points", s("mesh"))], "peridynamics.points", "\"delaunay\"");
}

/// The seed's section 6.2 (`problems/pd_plate_hole.toml`, the interior-3 rule on a
/// Delaunay triangulation): a discontinuous initial velocity, so the order in h drops
/// to about one (the seed: "reduces to one"). Measured as the seed measures: e_inf(u)
/// at t_end over the nodes at distance >= delta from the boundary (the hole's too),
/// against the midpoint rule with cut cells at m = 16 interpolated by degree-2 MLS,
/// least-squares slope over m = 2, 3, 4, 6. The velocity jumps at x = 0.025 and 0.975 stay
/// put in a nonlocal model and lie outside the measured region (delta = 0.05), so the
/// interpolation of the reference never straddles them. Regularised kernel (alpha = 1):
/// the plain kernel's own O(h) horizon-edge error makes the reference's error as large
/// as the finest run's (docs/methods/dynamics.md, "The plate with a hole"). t_end =
/// 1e-4 s: the waves from the strips reach the hole (5.6 km/s). Measured 1.09, steps
/// 0.93 or more; the test asks for the slope within 0.35 of 1 and every step to lower
/// the error (a positive order).
#[test]
fn the_plate_with_a_hole_converges_at_first_order() {
    use mlsm::models::peridynamics::solve::{interior_errors, interior_flags};
    use mlsm::models::peridynamics::{simulate, PointSet, Quadrature};
    use mlsm::quality::post::observed_order;
    use mlsm::stages::Silent;
    let p = scene(
        "pd_plate_hole",
        &[
            ("peridynamics.kernel", s("regularised")),
            ("peridynamics.alpha", f(1.0)),
            ("peridynamics.horizon", f(0.05)),
            ("dynamics.end_time", f(1e-4)),
            ("dynamics.snapshots", i(0)),
        ],
    );
    let base = *p.model.peridynamics().unwrap();
    let dynamics = p.case.dynamics.as_ref().unwrap();
    let run = |params: PdParams| {
        let sim = simulate(&p.case, &params, dynamics, &Silent, |_| Ok(())).unwrap_or_else(|e| panic!("{e}"));
        let n = &sim.discretisation.nodes;
        let x = n.positions[..n.free].to_vec();
        let interior = interior_flags(&p.case.domain, &x, params.horizon);
        (x, sim.u, n.volumes[..n.free].to_vec(), interior)
    };
    let reference = run(PdParams { ratio: 16.0, quadrature: Quadrature::FullArea, points: PointSet::Lattice, cut_cells: true, ..base });
    let (mut hs, mut es) = (Vec::new(), Vec::new());
    for m in [2.0, 3.0, 4.0, 6.0] {
        let params = PdParams { ratio: m, ..base };
        let (x, u, v, interior) = run(params);
        let (e_inf, _) = interior_errors(&x, &u, &v, &interior, &reference.0, &reference.1).unwrap();
        eprintln!("m = {m}: {} nodes, e_inf(u) = {e_inf:.3e}", x.len());
        hs.push(params.spacing());
        es.push(e_inf);
    }
    let order = observed_order(&hs, &es).unwrap();
    eprintln!("order {order:.2}");
    assert!((order - 1.0).abs() < 0.35, "order {order}");
    assert!(es.windows(2).all(|w| w[1] < w[0]), "an error grew with refinement: {es:?}");
}
