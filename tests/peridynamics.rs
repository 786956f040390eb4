//! The peridynamic model: patch tests (linear and cubic fields), the continuum
//! calibration, the stiffness as the Jacobian of the internal force, rigid motions,
//! and the nonlocal-to-local convergence at a fixed ratio m = delta / h.
//!
//! Scenes come from problems/pd_manufactured.toml (Dirichlet volume constraint on
//! every side: every family is complete) and problems/steel_plate.toml /
//! problems/pd_tension.toml (free edges and a traction layer).

mod common;

use common::*;
use mlsm::physics::exact::{ExactSolution, Polynomial};
use mlsm::models::peridynamics::solve::Discretisation;
use mlsm::models::peridynamics::{Kernel, Micromodulus};
use mlsm::parallel::petsc::World;
use mlsm::stages::{Silent, StageTimer};
use mlsm::scene::problem::Problem;

const RULES: [&str; 7] = ["full-area", "partial-area", "gauss2x2", "triangle-p1", "triangle-p2", "triangle-p3", "ac"];

/// A cubic field (all ten monomials in both components).
const UX: [f64; 10] = [0.1, 0.2, -0.3, 0.5, 0.4, -0.2, 0.3, -0.1, 0.2, 0.15];
const UY: [f64; 10] = [-0.2, 0.1, 0.3, -0.4, 0.25, 0.1, -0.2, 0.3, 0.1, -0.25];

fn cubic_scene(rule: &str, kernel: Option<f64>, horizon: f64) -> Problem {
    let mut edits = vec![
        ("exact.kind", s("polynomial")),
        ("exact.ux", arr(&UX)),
        ("exact.uy", arr(&UY)),
        ("peridynamics.horizon", f(horizon)),
        ("peridynamics.quadrature", s(rule)),
        ("peridynamics.solver.kind", s("lu")),
    ];
    if let Some(alpha) = kernel {
        edits.push(("peridynamics.kernel", s("regularised")));
        edits.push(("peridynamics.alpha", f(alpha)));
    }
    scene("pd_manufactured", &edits)
}

fn discretise(p: &Problem) -> Discretisation {
    let exact = p.case.exact_solution();
    Discretisation::new(&p.case, p.model.peridynamics().unwrap(), exact.as_deref(), &mut StageTimer::new(&Silent)).unwrap()
}

/// `u` evaluated at every node (free and constrained).
fn nodal(d: &Discretisation, u: impl Fn([f64; 2]) -> [f64; 2]) -> Vec<[f64; 2]> {
    d.nodes.positions.iter().map(|x| u(*x)).collect()
}

/// `sum_j |c_ij| |xi|^2 |u_j - u_i|`: the size of the bond forces at node i, the scale
/// against which a residual is round-off or not.
fn force_scale(d: &Discretisation, u: &[[f64; 2]], i: usize) -> f64 {
    let x = &d.nodes.positions;
    d.families
        .range(i)
        .zip(d.families.of(i))
        .map(|(b, &j)| {
            let j = j as usize;
            let xi2 = (x[j][0] - x[i][0]).powi(2) + (x[j][1] - x[i][1]).powi(2);
            d.weights.coefficients[b].abs() * xi2 * (u[j][0] - u[i][0]).hypot(u[j][1] - u[i][1])
        })
        .sum()
}

/// Largest `|L_h u|_i / scale_i` over the free nodes.
fn relative_residual(d: &Discretisation, u: &[[f64; 2]], target: impl Fn(usize) -> [f64; 2]) -> f64 {
    let lu = d.bonds().apply(u);
    (0..d.nodes.free)
        .map(|i| {
            let t = target(i);
            (lu[i][0] - t[0]).hypot(lu[i][1] - t[1]) / force_scale(d, u, i)
        })
        .fold(0.0, f64::max)
}

/// The free nodes' volumes add up to the area of the solid for every rule (the shipped
/// PD scenes are rectangles aligned with the cells), with free edges (steel plate) and
/// with a Dirichlet collar on every side (pd_manufactured): shared points of the
/// seven-point triangle rule on the boundary get the inner cells' shares only.
#[test]
fn free_volumes_add_up_to_the_area() {
    for (name, area) in [("steel_plate", 0.3), ("pd_manufactured", 1.0)] {
        for rule in RULES {
            let d = discretise(&scene(name, &[("peridynamics.quadrature", s(rule)), ("peridynamics.horizon", f(0.1))]));
            let total: f64 = d.nodes.volumes[..d.nodes.free].iter().sum();
            assert!((total - area).abs() < 1e-12, "{name} {rule}: {total}");
        }
    }
}

/// Rigid motions (translation + infinitesimal rotation) give zero force at every node
/// with every rule, free edges included: each bond force `xi (xi . (W xi))` vanishes.
/// Tolerance 1e-13: the sum of about 30 bond forces in double precision.
#[test]
fn rigid_motions_give_zero_force() {
    for rule in RULES {
        let p = scene("steel_plate", &[("peridynamics.quadrature", s(rule))]);
        let d = discretise(&p);
        let u = nodal(&d, |x| [1e-3 - 2e-3 * x[1], -5e-4 + 2e-3 * x[0]]);
        let r = relative_residual(&d, &u, |_| [0.0, 0.0]);
        eprintln!("{rule}: rigid motion residual {r:.2e}");
        assert!(r < 1e-13, "{rule}: {r}");
    }
}

/// Linear fields on the fully constrained square (every family complete): zero
/// residual to round-off for the rules whose point sets are centrally symmetric
/// around every node (full-area, partial-area, ac). The 2x2 Gauss and triangle point
/// sets are not (the Gauss points of neighbouring cells are not mirror images), so
/// their third moments do not vanish and a linear field leaves a residual: measured
/// 3.6e-3 to 4.1e-2 of the bond forces (P3: 3.1e-2, 4.1e-2). It is asserted here so
/// that a change shows.
#[test]
fn linear_fields_have_zero_residual_with_the_symmetric_rules() {
    let g = [[0.3, -0.2], [0.1, 0.4]];
    for rule in RULES {
        for kernel in [None, Some(-3.0)] {
            let d = discretise(&cubic_scene(rule, kernel, 0.2));
            assert_eq!(d.weights.complete_families, d.nodes.free, "{rule}: every family complete");
            let u = nodal(&d, |x| [0.1 + g[0][0] * x[0] + g[0][1] * x[1], -0.2 + g[1][0] * x[0] + g[1][1] * x[1]]);
            let r = relative_residual(&d, &u, |_| [0.0, 0.0]);
            eprintln!("{rule} {kernel:?}: linear-field residual {r:.2e}");
            if ["full-area", "partial-area", "ac"].contains(&rule) {
                assert!(r < 1e-12, "{rule} {kernel:?}: {r}");
            } else {
                assert!(r > 1e-3 && r < 5e-2, "{rule} {kernel:?}: {r}");
            }
        }
    }
}

/// Cubic fields: with the compatible weights `-L_h u = N u` (the Navier operator, i.e.
/// minus the body force) at every node to round-off, for every kernel; the full-area
/// and partial-area rules are off by 1e-3 or more (their quadrature error at fixed m).
#[test]
fn cubic_fields_are_reproduced_by_the_compatible_weights() {
    for kernel in [None, Some(-3.0), Some(-2.0), Some(0.0), Some(1.0)] {
        for rule in ["ac", "full-area", "partial-area"] {
            let p = cubic_scene(rule, kernel, 0.1);
            let exact = p.case.exact_solution().unwrap();
            let d = discretise(&p);
            let u = nodal(&d, |x| exact.displacement(x));
            let navier = |i: usize| {
                let b = exact.body_force(d.nodes.positions[i]);
                [-b[0], -b[1]]
            };
            let lu = d.bonds().apply(&u);
            let scale = (0..d.nodes.free).map(|i| navier(i)[0].hypot(navier(i)[1])).fold(0.0, f64::max);
            let err = (0..d.nodes.free).map(|i| (lu[i][0] - navier(i)[0]).hypot(lu[i][1] - navier(i)[1])).fold(0.0, f64::max) / scale;
            eprintln!("{rule} {kernel:?}: max |L_h u - N u| / max |N u| = {err:.2e}");
            if rule == "ac" {
                assert!(err < 1e-9, "{rule} {kernel:?}: {err}");
            } else {
                assert!(err > 1e-3, "{rule} {kernel:?}: {err}");
            }
        }
    }
}

/// Solving the cubic problem with the compatible weights and sparse LU returns the
/// cubic field itself (relative 1e-12: round-off amplified by the condition number).
#[test]
fn cubic_solution_is_exact_with_the_compatible_weights() {
    let p = cubic_scene("ac", None, 0.1);
    let sol = mlsm::models::peridynamics::solve(&p.case, p.model.peridynamics().unwrap(), &Silent).unwrap();
    let (whole, interior) = sol.errors.unwrap();
    eprintln!("cubic: e_inf {:.2e}, interior {:.2e}", whole.e_inf_u, interior.unwrap().e_inf_u);
    assert!(whole.e_inf_u < 1e-12, "{}", whole.e_inf_u);
}

/// The continuum operator of every calibrated kernel applied to a cubic field equals
/// the Navier operator of the model's material (lambda = mu = M/2): polar Gauss-Legendre
/// quadrature (64 panels x 20 points in r, 64 points in theta; the integrand is a
/// trigonometric polynomial of degree 6 in theta) at a point; tolerance 1e-9 relative.
#[test]
fn continuum_operator_of_calibrated_kernels_is_navier_on_cubics() {
    use gauss_quad::GaussLegendre;
    use std::num::NonZeroUsize;
    let p = cubic_scene("ac", None, 0.1);
    let poly = Polynomial::new(UX, UY, p.case.material).unwrap();
    let moment = mlsm::models::peridynamics::kernel::fourth_moment(&p.case.material);
    let x = [0.37, 0.61];
    let r_rule = GaussLegendre::new(NonZeroUsize::new(20).unwrap());
    let t_rule = GaussLegendre::new(NonZeroUsize::new(64).unwrap());
    for kernel in [
        Kernel::Plain,
        Kernel::Regularised { alpha: -3.0 },
        Kernel::Regularised { alpha: -2.0 },
        Kernel::Regularised { alpha: 0.0 },
        Kernel::Regularised { alpha: 1.0 },
    ] {
        let delta = 0.1;
        let mm = Micromodulus::calibrated(kernel, delta, moment);
        let ux = poly.displacement(x);
        let mut lu = [0.0, 0.0];
        for k in 0..64 {
            let (r0, r1) = (delta * k as f64 / 64.0, delta * (k + 1) as f64 / 64.0);
            for &(rn, rw) in r_rule.as_node_weight_pairs() {
                let r = 0.5 * (r0 + r1) + 0.5 * (r1 - r0) * rn;
                let wr = 0.5 * (r1 - r0) * rw;
                for &(tn, tw) in t_rule.as_node_weight_pairs() {
                    let th = std::f64::consts::PI * (1.0 + tn);
                    let wt = std::f64::consts::PI * tw;
                    let xi = [r * th.cos(), r * th.sin()];
                    let up = poly.displacement([x[0] + xi[0], x[1] + xi[1]]);
                    let eta = [up[0] - ux[0], up[1] - ux[1]];
                    let proj = xi[0] * eta[0] + xi[1] * eta[1];
                    let w = mm.value(r) * proj * r * wr * wt;
                    lu[0] += w * xi[0];
                    lu[1] += w * xi[1];
                }
            }
        }
        let b = poly.body_force(x);
        let err = (lu[0] + b[0]).hypot(lu[1] + b[1]) / b[0].hypot(b[1]);
        eprintln!("{kernel:?}: |L u - N u| / |N u| = {err:.2e}");
        assert!(err < 1e-9, "{kernel:?}: {err}");
    }
}

/// Dense copy of the stiffness from its triplets.
fn dense_stiffness(d: &Discretisation) -> Vec<Vec<f64>> {
    let n = 2 * d.nodes.free;
    let (m, _) = d.bonds().stiffness(&vec![[0.0, 0.0]; d.nodes.free]).unwrap();
    let mut dense = vec![vec![0.0; n]; n];
    for (r, c, v) in m.entries() {
        dense[r][c] += v;
    }
    dense
}

/// The assembled stiffness equals the central finite-difference Jacobian of the
/// internal force `f_i(u) = -V_i (L_h u)_i` (free edges, traction layer and collar of
/// the steel plate, every rule). The force is linear, so the difference quotient is
/// exact up to cancellation, about `eps |f| / step` = 1e-13 of the largest entry for a
/// step of 1e-3 on displacements of order 1 (measured 1.3e-13 to 3.7e-13); tolerance
/// 1e-10. Every rule is symmetric to round-off (tolerance 1e-13, measured <= 4e-17 for
/// the cell rules); the compatible one is symmetrised wherever a truncated family is
/// involved and is symmetric elsewhere up to the round-off of the moment solves
/// (measured 3.4e-16; tolerance 1e-12).
#[test]
fn stiffness_is_the_symmetric_jacobian_of_the_internal_force() {
    for rule in RULES {
        let p = scene("steel_plate", &[("peridynamics.quadrature", s(rule)), ("peridynamics.horizon", f(0.1))]);
        let d = discretise(&p);
        let k = dense_stiffness(&d);
        let n = 2 * d.nodes.free;
        let kmax = k.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        let force = |x: &[f64]| -> Vec<f64> {
            let mut u: Vec<[f64; 2]> = (0..d.nodes.free).map(|i| [x[2 * i], x[2 * i + 1]]).collect();
            u.extend(std::iter::repeat_n([0.0, 0.0], d.nodes.constrained()));
            let lu = d.bonds().apply(&u);
            (0..n).map(|r| -d.nodes.volumes[r / 2] * lu[r / 2][r % 2]).collect()
        };
        let worst = jacobian_mismatch(&k, force, 7);
        let asym = (0..n).flat_map(|r| (0..n).map(move |c| (r, c))).map(|(r, c)| (k[r][c] - k[c][r]).abs()).fold(0.0, f64::max);
        eprintln!("{rule}: |K - J| / max|K| = {:.2e}, |K - K^T| / max|K| = {:.2e}", worst / kmax, asym / kmax);
        assert!(worst < 1e-10 * kmax, "{rule}: Jacobian mismatch {}", worst / kmax);
        let tol = if rule == "ac" { 1e-12 } else { 1e-13 };
        assert!(asym < tol * kmax, "{rule}: asymmetry {}", asym / kmax);
    }
}

/// Observed order of the peridynamic solution against the exact (local) solution of
/// pd_manufactured at fixed m = 3, delta = 0.2, 0.1, 0.05.
fn local_limit(rule: &str) -> (f64, Vec<f64>) {
    let deltas = [0.2, 0.1, 0.05];
    let errors: Vec<f64> = deltas
        .iter()
        .map(|&delta| {
            let p = scene(
                "pd_manufactured",
                &[("peridynamics.horizon", f(delta)), ("peridynamics.quadrature", s(rule)), ("peridynamics.solver.kind", s("lu"))],
            );
            let sol = mlsm::models::peridynamics::solve(&p.case, p.model.peridynamics().unwrap(), &Silent).unwrap();
            sol.errors.unwrap().0.e_inf_u
        })
        .collect();
    let order = mlsm::quality::post::observed_order(&deltas, &errors).unwrap();
    eprintln!("{rule}: e_inf {errors:?} -> order {order:.2}");
    (order, errors)
}

/// Nonlocal-to-local: with the compatible weights the PD solution converges to the
/// Navier solution at second order in delta (measured 2.12; required >= 1.8). The
/// one-point rules stall at a fixed m (they converge to another local limit): measured
/// full-area 1.6e-2, 2.0e-2, 2.1e-2 (order -0.18) and partial-area 1.6e-2, 7.9e-3,
/// 7.5e-3 (fitted 0.54, last step 0.07).
#[test]
fn compatible_weights_converge_to_navier_and_one_point_rules_stall() {
    let (ac, e_ac) = local_limit("ac");
    assert!(ac >= 1.8, "ac order {ac}");
    assert!(e_ac[2] < 2e-3, "ac error {}", e_ac[2]);
    let (fa, e_fa) = local_limit("full-area");
    assert!(fa < 0.3 && e_fa[2] > 1e-2, "full-area should stall: order {fa}, error {}", e_fa[2]);
    let (pa, e_pa) = local_limit("partial-area");
    let last = (e_pa[1] / e_pa[2]).ln() / 2f64.ln();
    assert!(last < 0.5 && e_pa[2] > 5e-3, "partial-area should stall: last order {last} (fitted {pa}), error {}", e_pa[2]);
}

/// The nonlocal surface (`boundary = "surface"`): free edges and a traction layer
/// (pd_tension, exact local solution: uniform tension): with the compatible weights the
/// whole-plate difference decreases at first order in delta (measured relative L2 order
/// 1.0-1.1, e_inf 0.85), the boundary-layer rate of the PD surface effect. Before
/// truncated families were given moment-matched and symmetrised weights, the interior
/// error stalled at 6 %.
#[test]
fn free_edges_of_the_nonlocal_surface_converge_at_first_order() {
    let deltas = [0.1, 0.05, 0.025];
    let errors: Vec<(f64, f64)> = deltas
        .iter()
        .map(|&delta| {
            let p = scene("pd_tension", &[("peridynamics.horizon", f(delta)), ("peridynamics.boundary", s("surface"))]);
            let sol = mlsm::models::peridynamics::solve(&p.case, p.model.peridynamics().unwrap(), &Silent).unwrap();
            let (w, i) = sol.errors.unwrap();
            (w.rel_l2_u, i.unwrap().e_inf_u)
        })
        .collect();
    let l2: Vec<f64> = errors.iter().map(|e| e.0).collect();
    let order = mlsm::quality::post::observed_order(&deltas, &l2).unwrap();
    eprintln!("pd_tension: {errors:?} -> whole-plate L2 order {order:.2}");
    assert!(order > 0.8, "{order}");
    assert!(errors[2].1 < errors[0].1 / 2.0, "interior error must decrease: {errors:?}");
}

/// An MPI rank assembles only the rows of the nodes it owns
/// (`Bonds::stiffness_rows`): the other rows are empty with a zero load, and the
/// rows of two complementary owner sets together are the whole stiffness and load,
/// bit for bit (the same bonds summed in the same order).
#[test]
fn owned_rows_of_two_ranks_make_the_whole_stiffness() {
    let p = cubic_scene("ac", None, 0.1);
    let d = discretise(&p);
    let body: Vec<[f64; 2]> = (0..d.nodes.free).map(|i| [1.0 + i as f64, -0.5 * i as f64]).collect();
    let (whole, load) = d.bonds().stiffness(&body).unwrap();
    let owner = mlsm::parallel::partition::morton_owners(&d.nodes.positions[..d.nodes.free], 2);
    let mut entries = Vec::new();
    let mut joined = vec![0.0; load.len()];
    for rank in 0..2 {
        let (part, part_load) = d.bonds().stiffness_rows(&body, |i| owner[i] == rank).unwrap();
        for (r, c, v) in part.entries() {
            assert_eq!(owner[r / 2], rank, "row {r} of node {} assembled by rank {rank}", r / 2);
            entries.push((r, c, v));
        }
        for (r, v) in part_load.iter().enumerate() {
            if owner[r / 2] != rank {
                assert_eq!(*v, 0.0, "load of row {r} on rank {rank}");
            } else {
                joined[r] = *v;
            }
        }
    }
    assert!(owner.contains(&0) && owner.contains(&1));
    entries.sort_by_key(|e| (e.0, e.1));
    let mut all: Vec<_> = whole.entries().collect();
    all.sort_by_key(|e| (e.0, e.1));
    assert_eq!(entries, all);
    assert_eq!(joined, load);
}

/// A rank of a distributed run builds the families and weights of its own nodes and
/// their halo only (`Discretisation::on_rank`): its rows are those of the whole
/// operator bit for bit, for the compatible rule (whose symmetrisation reads the
/// neighbours' rows) with and without the volume correction (which reads the
/// neighbours' family volumes) and for a plain rule; the two ranks' counts add up to
/// the whole, and each rank holds fewer bonds than the whole.
#[test]
fn a_rank_builds_the_rows_of_its_nodes_from_its_halo() {
    for (rule, correction) in [("ac", "volume"), ("ac", "none"), ("full-area", "volume"), ("partial-area", "none"), ("gauss2x2", "volume")]
    {
        let mut p = cubic_scene(rule, None, 0.1);
        p.model.peridynamics_mut().unwrap().correction = if correction == "volume" {
            mlsm::models::peridynamics::SurfaceCorrection::Volume
        } else {
            mlsm::models::peridynamics::SurfaceCorrection::None
        };
        let whole = discretise(&p);
        let body: Vec<[f64; 2]> = (0..whole.nodes.free).map(|i| [1.0 + i as f64, -0.5 * i as f64]).collect();
        let exact = p.case.exact_solution();
        let (mut bonds, mut complete, mut compatible) = (0, 0, 0);
        for rank in 0..2 {
            let params = p.model.peridynamics().unwrap();
            let part = Discretisation::on_rank(&p.case, params, exact.as_deref(), &mut StageTimer::new(&Silent), Some(World { rank, size: 2 })).unwrap();
            let own = |i: usize| part.owns(i);
            let (a, a_load) = part.bonds().stiffness_rows(&body, own).unwrap();
            let (b, b_load) = whole.bonds().stiffness_rows(&body, own).unwrap();
            let what = format!("{rule}, correction {correction}, rank {rank}");
            let (a, b): (Vec<_>, Vec<_>) = (a.entries().collect(), b.entries().collect());
            let first = a.iter().zip(&b).find(|(x, y)| x != y);
            assert!(a.len() == b.len() && first.is_none(), "{what}: {} against {} entries, first difference {first:?}", a.len(), b.len());
            assert_eq!(a_load, b_load, "{what}");
            assert!(part.families.bonds() < whole.families.bonds(), "{what}: the rank holds the whole families");
            bonds += part.bond_count;
            complete += part.weights.complete_families;
            compatible += part.weights.compatible_rows;
        }
        assert_eq!(
            (bonds, complete, compatible),
            (whole.bond_count, whole.weights.complete_families, whole.weights.compatible_rows),
            "{rule}"
        );
    }
}

/// A perturbed lattice (`peridynamics.perturbation`, the seed's "random" rows) is refused
/// outside 0..1 and with the rules and corrections that count on the lattice's families,
/// with the field and the reason; with `full-area` it runs.
#[test]
fn perturbed_lattices_are_refused_where_the_rule_needs_the_lattice() {
    let refused = |edits: &[(&str, Option<toml::Value>)], says: &str| {
        let e = scene_error("steel_plate_dynamic", edits).to_string();
        assert!(e.contains("peridynamics.perturbation") && e.contains(says), "{e}");
    };
    refused(&[("peridynamics.perturbation", f(1.5))], "between 0 and 1");
    refused(&[("peridynamics.perturbation", f(0.5)), ("peridynamics.quadrature", s("ac"))], "full-area and gauss2x2");
    refused(&[("peridynamics.perturbation", f(0.5)), ("peridynamics.correction", s("volume"))], "without a surface correction");
    let p = scene("steel_plate_dynamic", &[("peridynamics.perturbation", f(0.5)), ("peridynamics.horizon", f(0.05)), ("dynamics.end_time", f(1e-5))]);
    assert_eq!(p.model.peridynamics().unwrap().perturbation, 0.5);
    mlsm::models::peridynamics::simulate(&p.case, p.model.peridynamics().unwrap(), p.case.dynamics.as_ref().unwrap(), &mlsm::stages::Silent, |_| Ok(()))
        .unwrap();
}
