//! The linear peridynamic solid (`peridynamics.solid = "lps"`): its operator is Navier's
//! on cubic fields for any Poisson ratio, its stiffness is the symmetric Jacobian of
//! its internal force, it converges at second order in delta to the Navier solution
//! with a Dirichlet collar, it leaves bond-based results unchanged at nu = 1/4, and the
//! choice of solid is validated.
//!
//! Scenes: problems/pd_manufactured.toml (Dirichlet volume constraint on every side)
//! and problems/steel_plate.toml (free edges, a traction layer), with `material.nu`
//! and `material.plane` edited.

mod common;

use common::*;
use mlsm::models::peridynamics::solve::Discretisation;
use mlsm::models::peridynamics::stiffness::DilatationPart;
use mlsm::models::peridynamics::{simulate, Solid};
use mlsm::scene::problem::Problem;
use mlsm::stages::{Silent, StageTimer};

/// A cubic field (all ten monomials in both components).
const UX: [f64; 10] = [0.1, 0.2, -0.3, 0.5, 0.4, -0.2, 0.3, -0.1, 0.2, 0.15];
const UY: [f64; 10] = [-0.2, 0.1, 0.3, -0.4, 0.25, 0.1, -0.2, 0.3, 0.1, -0.25];

/// The Poisson ratios of the issue, each in plane strain and plane stress.
const POISSON: [f64; 5] = [0.0, 0.2, 0.25, 1.0 / 3.0, 0.45];

fn discretise(p: &Problem) -> Discretisation {
    let exact = p.case.exact_solution();
    Discretisation::new(&p.case, p.model.peridynamics().unwrap(), exact.as_deref(), &mut StageTimer::new(&Silent)).unwrap()
}

fn material(nu: f64, plane: &str) -> [(&'static str, Option<toml::Value>); 2] {
    [("material.nu", f(nu)), ("material.plane", s(plane))]
}

/// With the compatible weights and the `2 delta` Dirichlet collar, the solid's discrete
/// operator applied to a cubic field equals the Navier operator `-b` of the material
/// (`mu lap u + (lambda + mu) grad div u`) at every free node, for nu = 0, 0.2, 1/4, 1/3,
/// 0.45 in plane strain and plane stress: the bond part is exact on cubics for
/// `lambda = mu`, the dilatation part for `(lambda - mu) grad div u`. Tolerance 1e-9 of
/// the largest `|N u|`: the moment fits are accepted at 1e-9 of their scale
/// (`compatible_weights`), and round-off of sums of ~30 bonds of size `M / delta^2` is
/// 1e-13 (measured 3.4e-14 to 8.5e-14).
#[test]
fn lps_operator_is_navier_on_cubic_fields() {
    for plane in ["strain", "stress"] {
        for nu in POISSON {
            let mut edits = vec![
                ("exact.kind", s("polynomial")),
                ("exact.ux", arr(&UX)),
                ("exact.uy", arr(&UY)),
                ("peridynamics.horizon", f(0.1)),
                ("peridynamics.solid", s("lps")),
            ];
            edits.extend(material(nu, plane));
            let p = scene("pd_manufactured", &edits);
            let exact = p.case.exact_solution().unwrap();
            let d = discretise(&p);
            assert!(d.dilatation.as_ref().unwrap().fit_failures == 0);
            let u: Vec<[f64; 2]> = d.nodes.positions.iter().map(|x| exact.displacement(*x)).collect();
            let lu = d.operator(&u);
            let navier = |i: usize| {
                let b = exact.body_force(d.nodes.positions[i]);
                [-b[0], -b[1]]
            };
            let scale = (0..d.nodes.free).map(|i| navier(i)[0].hypot(navier(i)[1])).fold(0.0, f64::max);
            let err = (0..d.nodes.free).map(|i| (lu[i][0] - navier(i)[0]).hypot(lu[i][1] - navier(i)[1])).fold(0.0, f64::max) / scale;
            eprintln!("plane {plane}, nu = {nu:.4}: max |L_h u - N u| / max |N u| = {err:.2e}");
            assert!(err < 1e-9, "plane {plane}, nu = {nu}: {err}");
        }
    }
}

/// The assembled stiffness (bonds plus dilatation) equals the central finite-difference
/// Jacobian of the internal force `-V_i (L_h u)_i` on the steel plate (free edges, a
/// traction layer, a collar; truncated families everywhere near the edges) at nu = 0.3
/// and nu = 0.1 (a negative dilatation factor), and is symmetric: the dilatation term is
/// `beta D_h^T V D_h`. The force is linear: the difference quotient is exact up to
/// cancellation (`eps |f| / step`, about 1e-13 of the largest entry), tolerance 1e-10;
/// the bond part is symmetric to 1e-12 (its own test), the dilatation part by
/// construction (tolerance 1e-12, measured 3.6e-16; the Jacobian 1.1e-13).
#[test]
fn lps_stiffness_is_the_symmetric_jacobian_of_the_internal_force() {
    for nu in [0.3, 0.1] {
        let mut edits = vec![
            ("peridynamics.horizon", f(0.1)),
            ("peridynamics.quadrature", s("ac")),
            ("peridynamics.solid", s("lps")),
            ("peridynamics.boundary", s("surface")),
        ];
        edits.extend(material(nu, "strain"));
        let p = scene("steel_plate", &edits);
        let d = discretise(&p);
        let n = 2 * d.nodes.free;
        let (m, _) = d.stiffness(&vec![[0.0, 0.0]; d.nodes.free], &[], DilatationPart::Assembled).unwrap();
        let mut k = vec![vec![0.0; n]; n];
        for (r, c, v) in m.entries() {
            k[r][c] += v;
        }
        let kmax = k.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        let force = |x: &[f64]| -> Vec<f64> {
            let mut u: Vec<[f64; 2]> = (0..d.nodes.free).map(|i| [x[2 * i], x[2 * i + 1]]).collect();
            u.extend(std::iter::repeat_n([0.0, 0.0], d.nodes.constrained()));
            let lu = d.operator(&u);
            (0..n).map(|r| -d.nodes.volumes[r / 2] * lu[r / 2][r % 2]).collect()
        };
        let worst = jacobian_mismatch(&k, force, 11);
        let asym = (0..n).flat_map(|r| (0..n).map(move |c| (r, c))).map(|(r, c)| (k[r][c] - k[c][r]).abs()).fold(0.0, f64::max);
        eprintln!("nu = {nu}: |K - J| / max|K| = {:.2e}, |K - K^T| / max|K| = {:.2e}", worst / kmax, asym / kmax);
        assert!(worst < 1e-10 * kmax, "nu = {nu}: Jacobian mismatch {}", worst / kmax);
        assert!(asym < 1e-12 * kmax, "nu = {nu}: asymmetry {}", asym / kmax);
    }
}

/// Nonlocal-to-local with the Dirichlet collar, manufactured solution, m = 3, four
/// horizons 0.2 to 0.025, GMRES + AMG (the default solver): the solid converges to the
/// Navier solution at second order for nu = 0.3 (plane strain) and nu = 0.1 (plane
/// stress). Measured at nu = 0.3: whole-plate e_inf 2.2e-2, 5.0e-3, 1.2e-3, 2.9e-4,
/// least-squares order 2.10, worst step 2.04. Required: least squares and worst step
/// >= 1.9 (the bar), and the finest error below 5e-4.
#[test]
fn lps_converges_at_second_order_with_a_dirichlet_collar() {
    let deltas = [0.2, 0.1, 0.05, 0.025];
    for (nu, plane) in [(0.3, "strain"), (0.1, "stress")] {
        let errors: Vec<f64> = deltas
            .iter()
            .map(|&delta| {
                let mut edits = vec![("peridynamics.horizon", f(delta))];
                edits.extend(material(nu, plane));
                let p = scene("pd_manufactured", &edits);
                assert_eq!(p.model.peridynamics().unwrap().solid, Solid::Linear, "auto picks the solid for nu = {nu}");
                let sol = mlsm::models::peridynamics::solve(&p.case, p.model.peridynamics().unwrap(), &Silent).unwrap();
                sol.errors.unwrap().0.e_inf_u
            })
            .collect();
        let (ls, worst) = least_squares_and_worst_order(&deltas, &errors);
        eprintln!("nu = {nu} plane {plane}: e_inf {errors:?} -> least squares {ls:.2}, worst step {worst:.2}");
        assert!(ls >= 1.9 && worst >= 1.9, "nu = {nu}: orders {ls}, {worst}");
        assert!(errors[3] < 5e-4, "nu = {nu}: {}", errors[3]);
    }
}

/// At nu = 1/4 (plane strain) the scene's default (`auto`) is bond-based, and the
/// solid, whose dilatation factor `lambda - mu` is then zero, solves to the same
/// displacement (its collar is wider, which bonds of length delta do not reach): both
/// with sparse LU, relative difference 1e-12 (round-off of two factorisations of the
/// same matrix with a different number of stored zeros; measured 1e-15).
#[test]
fn bond_based_is_unchanged_at_a_quarter() {
    let solve = |solid: Option<&str>| {
        let mut edits = vec![("peridynamics.horizon", f(0.1)), ("peridynamics.solver.kind", s("lu"))];
        if let Some(solid) = solid {
            edits.push(("peridynamics.solid", s(solid)));
        }
        let p = scene("pd_manufactured", &edits);
        let params = *p.model.peridynamics().unwrap();
        let sol = mlsm::models::peridynamics::solve(&p.case, &params, &Silent).unwrap();
        (params.solid, sol.displacement[..sol.nodes.free].to_vec(), sol.nodes.positions[..sol.nodes.free].to_vec())
    };
    let (auto, u_auto, x_auto) = solve(None);
    let (bond, u_bond, _) = solve(Some("bond-based"));
    let (lps, u_lps, x_lps) = solve(Some("lps"));
    assert_eq!((auto, bond, lps), (Solid::BondBased, Solid::BondBased, Solid::Linear));
    assert_eq!(u_auto, u_bond, "auto is bond-based, bit for bit");
    assert_eq!(x_auto, x_lps, "the same free nodes");
    let scale = u_bond.iter().map(|u| u[0].hypot(u[1])).fold(0.0, f64::max);
    let diff = u_bond.iter().zip(&u_lps).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max) / scale;
    eprintln!("nu = 1/4: |u_lps - u_bond| / max |u| = {diff:.2e}");
    assert!(diff < 1e-12, "{diff}");
}

/// The solid runs explicit dynamics: on the free steel plate (nu = 0.3, plane strain,
/// m = 3) with Verlet the total energy, elastic energy of the dilatation included, stays
/// within 5e-3 of its initial value (the bond-based plate's bound, measured 2.6e-3
/// there), and a uniform velocity moves it rigidly with no elastic energy.
#[test]
fn lps_dynamics_conserves_energy_and_moves_rigidly() {
    let plate = |edits: &[(&str, Option<toml::Value>)]| {
        let mut all = vec![("peridynamics.m", f(3.0)), ("peridynamics.quadrature", s("ac")), ("dynamics.integrator", s("verlet"))];
        all.extend(material(0.3, "strain"));
        all.extend_from_slice(edits);
        scene("steel_plate_dynamic", &all)
    };
    let run =
        |p: &Problem| simulate(&p.case, p.model.peridynamics().unwrap(), p.case.dynamics.as_ref().unwrap(), &Silent, |_| Ok(())).unwrap();
    let sim = run(&plate(&[]));
    assert!(sim.discretisation.dilatation.is_some());
    let total = |e: &mlsm::models::dynamics::driver::EnergyRow| e[1] + e[2] + e[3];
    let e0 = total(&sim.energies[0]);
    let drift = sim.energies.iter().map(|e| (total(e) - e0).abs() / e0).fold(0.0, f64::max);
    let peak_elastic = sim.energies.iter().map(|e| e[2]).fold(0.0, f64::max) / e0;
    eprintln!("lps plate, Verlet: max |E - E0| / E0 = {drift:.2e}, peak E_el / E0 = {peak_elastic:.2e}");
    assert!(drift < 5e-3 && peak_elastic > 1e-2, "{drift} {peak_elastic}");
    let v0 = toml::Value::try_from(std::collections::BTreeMap::from([("x", vec![3.0, 0.0, 0.0]), ("y", vec![-2.0, 0.0, 0.0])])).unwrap();
    let rigid = run(&plate(&[("dynamics.initial_velocity", Some(v0))]));
    let t = rigid.energies.last().unwrap()[0];
    let worst = rigid.u.iter().map(|u| (u[0] - 3.0 * t).abs().max((u[1] + 2.0 * t).abs())).fold(0.0, f64::max);
    let elastic = rigid.energies.iter().map(|e| e[2].abs()).fold(0.0, f64::max);
    eprintln!("lps plate, uniform velocity: max |u - v0 t| = {worst:.1e}, max |E_el| = {elastic:.1e}");
    assert!(worst < 1e-14 && elastic < 1e-18, "{worst} {elastic}");
}

/// `peridynamics.solid`: `auto` picks bond-based at nu = 1/4 and the solid elsewhere,
/// `bond-based` at another nu and the bond-stretch law with the solid are refused with
/// the field named, nu = 1/2 in plane strain is refused where the peridynamic model
/// runs (not for a Navier scene that only carries the table), and a Poisson ratio
/// written near 1/4 is snapped for bond-based but kept for a solid named `lps`.
#[test]
fn the_choice_of_solid_is_validated() {
    let pick = |edits: &[(&str, Option<toml::Value>)]| scene("pd_manufactured", edits).model.peridynamics().unwrap().solid;
    assert_eq!(pick(&[]), Solid::BondBased);
    assert_eq!(pick(&[("material.nu", f(0.3))]), Solid::Linear);
    assert_eq!(pick(&[("material.nu", f(0.25000001))]), Solid::BondBased);
    let kept = scene("pd_manufactured", &[("material.nu", f(0.25000001)), ("peridynamics.solid", s("lps"))]);
    assert_eq!(kept.case.material.elastic.poisson, 0.25000001);
    let refused = |edits: &[(&str, Option<toml::Value>)]| scene_error("pd_manufactured", edits);
    let e = refused(&[("material.nu", f(0.3)), ("peridynamics.solid", s("bond-based"))]);
    assert!(e.field == "peridynamics.solid" && e.reason.contains("lps"), "{e:?}");
    let e = refused(&[("peridynamics.solid", s("elastic"))]);
    assert!(e.field == "peridynamics.solid" && e.reason.contains("bond-based"), "{e:?}");
    let e = scene_error("steel_plate_dynamic", &[("material.nu", f(0.3)), ("peridynamics.force", s("bond-stretch"))]);
    assert!(e.field == "peridynamics.force", "{e:?}");
    for solid in ["auto", "lps"] {
        let e = scene_error("steel_plate", &[("model", s("peridynamics")), ("material.nu", f(0.5)), ("peridynamics.solid", s(solid))]);
        assert!(e.field == "material.nu" && e.reason.contains("infinite"), "{solid}: {e:?}");
    }
    // A Navier scene that only carries the table runs at nu = 1/2; compare and
    // --horizon (with_peridynamics) refuse it.
    let navier = scene("steel_plate", &[("material.nu", f(0.5))]);
    let params = *navier.model.peridynamics().unwrap();
    let e = navier.with_peridynamics(params).unwrap_err();
    assert!(e.field == "material.nu" && e.reason.contains("infinite"), "{e:?}");
}
