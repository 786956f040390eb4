//! The error estimate as a user gets it (`estimate.method = "auto"`: the `defect`
//! estimate, and the higher-degree reference where the defect cannot be trusted)
//! against the true error, and the checks that turn a doubtful run into a warning.
//!
//! Bands (issue 11): effectivity = estimate / true error in [0.5, 2] for e_inf(u) and
//! [0.33, 3] for e_inf(sigma) wherever the true error is above 1e-8. They are the
//! acceptance bands of the estimator, not fitted to it: measured effectivities on
//! these cases lie in 0.80..1.42 (docs/verification.md, "The error estimate: measured
//! effectivities").

mod common;

use common::{f, i, s, scene};
use mlsm::models::navier::{Estimate, Solution};
use mlsm::quality::warnings::{navier_static, Checks};
use mlsm::scene::problem::Problem;

/// A shipped scene with the default estimate (`auto`) and `edits`.
fn estimated(name: &str, edits: &[(&'static str, Option<toml::Value>)]) -> Problem {
    let mut all = vec![("estimate.method", s("auto"))];
    all.extend_from_slice(edits);
    scene(name, &all)
}

/// Solve and check; returns the solution and its checks.
fn run(p: &Problem) -> (Solution, Checks) {
    let sol = common::solve(p);
    let checks = navier_static(&sol, &p.navier, &p.case);
    (sol, checks)
}

/// `(effectivity of e_inf(u), effectivity of e_inf(sigma))`, asserted in the bands
/// where the true error is above 1e-8.
fn effectivities(label: &str, sol: &Solution) -> (f64, f64) {
    let e = sol.errors.expect("exact solution");
    let est = sol.estimate.done().unwrap_or_else(|| panic!("{label}: no estimate: {:?}", sol.estimate));
    let eu = est.norms.e_inf_u / e.e_inf_u;
    let es = est.norms.e_inf_sigma.unwrap() / e.e_inf_sigma.unwrap();
    eprintln!(
        "{label}: {} nodes, e_inf(u) {:.2e} est {:.2e} (eff {eu:.2}), e_inf(sigma) {:.2e} est {:.2e} (eff {es:.2}), reference {:.2} s",
        sol.nodes.len(),
        e.e_inf_u,
        est.norms.e_inf_u,
        e.e_inf_sigma.unwrap(),
        est.norms.e_inf_sigma.unwrap(),
        est.seconds
    );
    if e.e_inf_u > 1e-8 {
        assert!((0.5..=2.0).contains(&eu), "{label}: effectivity of e_inf(u) {eu:.3} outside [0.5, 2]");
    }
    if e.e_inf_sigma.unwrap() > 1e-8 {
        assert!((0.33..=3.0).contains(&es), "{label}: effectivity of e_inf(sigma) {es:.3} outside [0.33, 3]");
    }
    (eu, es)
}

/// The method `auto` took, and why when it is the higher-degree reference.
fn method_of(sol: &Solution) -> (&'static str, String) {
    let e = sol.estimate.done().expect("estimated");
    (e.method, e.reference.clone())
}

/// Every shipped static scene with an exact solution: the estimate is within the bands
/// and the healthy scene gets no warning. `auto` takes the `defect` estimate on each,
/// except the cantilever (186 nodes, too few for its fits: the higher-degree reference,
/// saying why). The tensor cantilever (the published MLSM setting, h = 0.125, 9 881
/// nodes), whose cubic exact solution made fits of 2.5x their monomials overshoot 1.5x
/// (4x at h = 0.035), is in the bands with fits of 10x.
#[test]
fn estimate_tracks_the_true_error_on_the_shipped_scenes() {
    for name in ["kirsch", "lame", "manufactured_traction", "manufactured_dirichlet", "flamant", "cantilever"] {
        let p = estimated(name, &[]);
        let (sol, checks) = run(&p);
        effectivities(name, &sol);
        let (method, reference) = method_of(&sol);
        match name {
            "cantilever" => assert!(method == "higher-degree" && reference.contains("defect estimate is unavailable"), "{reference}"),
            _ => assert_eq!(method, "defect", "{name}: {reference}"),
        }
        assert!(checks.warnings.is_empty(), "{name}: {:?}", checks.warnings);
        assert!(checks.singular_corners.is_empty(), "{name}: an exact solution is smooth: {:?}", checks.singular_corners);
    }
    let tensor = [
        ("approximation.basis", s("tensor")),
        ("approximation.degree", i(2)),
        ("approximation.weight", s("gaussian")),
        ("approximation.sigma", f(1.0)),
        ("approximation.support", i(13)),
        ("nodes.spacing", f(0.125)),
    ];
    let (sol, _) = run(&estimated("cantilever", &tensor));
    assert_eq!(method_of(&sol).0, "defect");
    effectivities("cantilever, tensor p = 2, h = 0.125", &sol);
}

/// The higher-degree reference, the certificate a user can ask for, within the same
/// bands on the shipped scenes.
#[test]
fn the_higher_degree_certificate_tracks_the_true_error_on_the_shipped_scenes() {
    for name in ["kirsch", "lame", "manufactured_traction", "manufactured_dirichlet", "flamant"] {
        let (sol, _) = run(&scene(name, &[("estimate.method", s("higher-degree"))]));
        assert_eq!(method_of(&sol).0, "higher-degree");
        effectivities(&format!("{name} (higher-degree)"), &sol);
    }
}

/// Every shipped static Navier scene, run as shipped: its estimate is made, never
/// skipped. Where `auto` takes the higher-degree reference it says why (the bracket:
/// its defect estimate warns, on the stress at a hole).
#[test]
fn the_default_estimate_is_never_skipped() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok()?.strip_suffix(".toml").map(String::from))
        .collect();
    names.sort();
    let mut run_count = 0;
    for name in names {
        let p = Problem::from_file(&dir.join(format!("{name}.toml"))).unwrap_or_else(|e| panic!("{e}"));
        if p.case.dynamics.is_some() || matches!(p.model, mlsm::scene::problem::ModelParams::Peridynamics(_)) {
            continue;
        }
        assert_eq!(p.navier.estimate.method, mlsm::models::navier::EstimateMethod::Auto, "{name} ships with another method");
        let sol = common::solve(&p);
        let (method, reference) = method_of(&sol);
        eprintln!("{name}: {method} ({reference})");
        assert!(method == "defect" || reference.contains("auto took it because"), "{name}: {reference}");
        run_count += 1;
    }
    assert!(run_count >= 10, "{run_count} static scenes");
}
/// Scenes with singular corners take the `defect` estimate with the higher-degree
/// operator's rows near the corners (`navier::corner_defect`). They have no exact
/// solution, so the yardstick is the full higher-degree reference: on the steel plate
/// and the dam the defect estimate's e_inf(u) is within [0.5, 2] of it (measured 1.02
/// and 1.07; with the fits alone the steel plate's was 0.06 of it, 1.3e-4 against
/// 2.2e-3). The bracket, whose defect estimate warns (e_inf(u) 2.3e-2, the stress at a
/// hole 0.21), takes the reference as a warned run does, and says why.
#[test]
fn singular_corners_take_the_defect_estimate_with_higher_degree_rows() {
    for name in ["steel_plate", "gravity_dam"] {
        let (sol, _) = run(&estimated(name, &[]));
        let (method, reference) = method_of(&sol);
        assert_eq!(method, "defect", "{name}: {reference}");
        assert!(reference.contains("near singular corners"), "{name}: {reference}");
        let cheap = sol.estimate.done().unwrap().norms.e_inf_u;
        let (certificate, _) = run(&estimated(name, &[("estimate.method", s("higher-degree"))]));
        let certified = certificate.estimate.done().unwrap().norms.e_inf_u;
        eprintln!("{name}: defect e_inf(u) {cheap:.2e}, higher-degree {certified:.2e} (ratio {:.2})", cheap / certified);
        assert!((0.5..=2.0).contains(&(cheap / certified)), "{name}: {cheap:.2e} against {certified:.2e}");
    }
    let (sol, _) = run(&estimated("bracket", &[]));
    let (method, reference) = method_of(&sol);
    assert_eq!(method, "higher-degree");
    assert!(reference.contains("auto took it because the defect estimate") && reference.contains("reaches"), "{reference}");
}

/// Near-incompressible plane strain with the displacement form: the error grows
/// (Lame, 3388 nodes: e_inf(sigma) 5.8e-2 at nu = 0.45 to 51 at nu = 0.4999) and every
/// run is warned with an estimate inside the bands.
#[test]
fn near_incompressible_runs_are_warned_with_a_faithful_estimate() {
    let ls2 = [("approximation.basis", s("monomials")), ("approximation.degree", i(2)), ("approximation.formulation", s("displacement"))];
    for nu in [0.45, 0.49, 0.4999] {
        let mut edits = ls2.to_vec();
        edits.push(("material.nu", f(nu)));
        let (sol, checks) = run(&estimated("lame", &edits));
        effectivities(&format!("lame nu = {nu}"), &sol);
        let w = checks.warnings.iter().find(|w| w.check == "estimate").unwrap_or_else(|| panic!("nu = {nu}: not warned"));
        assert!(w.message.contains("incompressible"), "{}", w.message);
    }
    // manufactured_traction on a grid at nu = 0.49999 (e_inf(u) ~ 1).
    let mut edits = ls2.to_vec();
    edits.extend([("material.nu", f(0.49999)), ("nodes.spacing", f(0.025)), ("nodes.fill", s("grid"))]);
    let (sol, checks) = run(&estimated("manufactured_traction", &edits));
    effectivities("manufactured_traction nu = 0.49999", &sol);
    assert!(checks.warnings.iter().any(|w| w.check == "estimate"));
}

/// A cantilever of aspect ratio 200 with 5 nodes across the depth: degree-2 least
/// squares is warned (e_inf(u) 2.6e-2) with an estimate within the bands. PHS degree 4
/// is accurate to round-off of its system, which is warned as such: κ₁ ≈ 3.9e12
/// (`conditioning`, κ₁ ε = 8.6e-4). There both the error and the estimate are
/// round-off: one-ulp changes in the stencil distances moved e_inf(u) between 7.1e-7,
/// 1.3e-6 and 3.8e-6 and the estimate between 7.8e-8 and 4.5e-6, so no effectivity
/// is asserted; both must stay below 1e-5, 2 600 times below degree 2's error (and the
/// estimate must not warn a run that is this accurate).
#[test]
fn a_thin_cantilever_is_accurate_or_warned() {
    let thin = |basis: &str, degree: i64| {
        estimated(
            "cantilever",
            &[
                ("approximation.basis", s(basis)),
                ("approximation.degree", i(degree)),
                ("nodes.spacing", f(0.0375)),
                ("exact.depth", f(0.15)),
            ],
        )
    };
    for (basis, degree) in [("monomials", 2), ("phs", 4)] {
        let mut p = thin(basis, degree);
        p.case.domain = mlsm::domain::Domain::rectangle([0.0, -0.075], [30.0, 0.075]);
        let (sol, checks) = run(&p);
        assert_eq!(sol.nodes.len(), 4005, "801 x 5 grid");
        let warned = |check: &str| checks.warnings.iter().any(|w| w.check == check);
        if degree == 2 {
            effectivities(&format!("thin cantilever {basis} {degree}"), &sol);
            assert!(warned("estimate"), "{basis}: {:?}", checks.warnings);
        } else {
            let (e, est) = (sol.errors.expect("exact").e_inf_u, sol.estimate.done().expect("estimated").norms.e_inf_u);
            eprintln!("thin cantilever {basis} {degree}: e_inf(u) {e:.2e}, estimated {est:.2e}");
            assert!(e < 1e-5 && est < 1e-5, "{basis}: e_inf(u) {e:.2e}, estimated {est:.2e}");
            assert!(!warned("estimate") && warned("conditioning"), "{basis}: {:?}", checks.warnings);
        }
    }
}

/// About 30 nodes: every run is warned by its estimate. The estimate is then as coarse
/// as the run: within the bands on Lame, the manufactured plate and the cantilever;
/// on Kirsch (32 nodes) it is a factor 4 low in u (effectivity 0.23), still 18 times
/// the threshold.
#[test]
fn a_handful_of_nodes_is_warned() {
    for (name, in_bands) in [("lame", true), ("manufactured_traction", true), ("cantilever", true), ("kirsch", false)] {
        let p = estimated(
            name,
            &[
                ("approximation.basis", s("monomials")),
                ("approximation.degree", i(2)),
                ("nodes.spacing", None),
                ("nodes.refine", None),
                ("nodes.count", i(30)),
            ],
        );
        let (sol, checks) = run(&p);
        assert!(sol.nodes.len() < 50, "{name}: {} nodes", sol.nodes.len());
        if in_bands {
            effectivities(&format!("{name} with {} nodes", sol.nodes.len()), &sol);
        }
        let est = sol.estimate.done().expect("estimate");
        assert!(est.norms.e_inf_u > 10.0 * p.navier.estimate.threshold, "{name}: {:?}", est.norms);
        assert!(checks.warnings.iter().any(|w| w.check == "estimate"), "{name}: not warned");
    }
}

/// Without an exact solution: the clamped corners of the steel plate are found as
/// singular, the stress check skips them, and the healthy run gets notes, not a
/// warning (the corners, and a global force imbalance of 1.1e-2 that the singular
/// reactions explain: below ten times the threshold). The bracket (a re-entrant
/// corner and two clamped ones) is warned by its stress estimate (the singular
/// corner). Its displacement estimate is 9.4e-3 at 2 mm (the tip is 2.9 % off finite
/// elements): it was 1.4e-2 while least squares had no ghosts near the corner, 0.17,
/// and 0.98 before that, while the estimate's reference, PHS
/// of degree 4, carried a spurious load of 0.24 F on a hole, and earlier had no ghosts
/// near the corner (docs/limits.md). Its reactions, 31 % off the applied load
/// before the balances of the corner's sector and of the holes (`navier::sector`),
/// then 8.4 %, are now 2.9 % off: the note of singular reactions, not a warning.
#[test]
fn singular_corners_get_a_note_and_a_broken_run_a_warning() {
    let (sol, checks) = run(&estimated("steel_plate", &[]));
    let corners: Vec<_> = checks.singular_corners.iter().map(|c| (c.at, c.reason)).collect();
    assert_eq!(corners, vec![([0.0, 0.0], "clamped meets traction"), ([0.0, 0.3], "clamped meets traction")]);
    let est = sol.estimate.done().unwrap();
    assert!(est.norms.e_inf_sigma.unwrap() > 0.1, "the peak stress at the clamped corners is not converged: {:?}", est.norms);
    assert!(checks.warnings.is_empty(), "{:?}", checks.warnings);
    assert_eq!(checks.notes.len(), 2, "{:?}", checks.notes);
    let q = sol.equilibrium.unwrap();
    // Slow, h^0.75, convergence of singular reactions: between the threshold and 10x.
    assert!((1e-3..0.1).contains(&q.relative), "{q:?}");
    assert!(checks.notes[1].contains("singular corners converge slowly"), "{}", checks.notes[1]);

    let (sol, checks) = run(&estimated("bracket", &[]));
    let reentrant: Vec<_> = checks.singular_corners.iter().filter(|c| c.reason == "re-entrant").map(|c| c.at).collect();
    assert_eq!(reentrant, vec![[0.06, 0.14]]);
    assert_eq!(checks.singular_corners.len(), 3);
    let est = &sol.estimate.done().unwrap().norms;
    assert!(est.e_inf_u < 0.05 && est.e_inf_sigma.unwrap() > 0.1, "{est:?}");
    assert!(checks.warnings.iter().any(|w| w.check == "estimate"));
    assert!(sol.equilibrium.unwrap().relative < 0.05, "{:?}", sol.equilibrium);
    assert!(!checks.warnings.iter().any(|w| w.check == "equilibrium"), "{:?}", checks.warnings);
}

/// With singular corners the displacement estimate counts double against the
/// threshold (`warnings::SINGULAR_ESTIMATE_FACTOR`): there the degree-4 reference is
/// about as wrong as the run, and against finite elements the estimate was 0.45-0.55
/// of the true e_inf(u) (docs/guide/estimate-and-warnings.md, "Warnings"). The bracket
/// at 2 mm estimates 9.4e-3 where the tip is 2.9 % off: with the threshold at 1.5e-2 the
/// displacement is warned, counted as 1.9e-2; the steel plate (two clamped corners,
/// 2.2e-3) is not.
#[test]
fn with_singular_corners_the_displacement_estimate_counts_double() {
    let (sol, checks) = run(&estimated("bracket", &[("estimate.threshold", f(1.5e-2))]));
    let e = sol.estimate.done().unwrap().norms.e_inf_u;
    assert!((7.5e-3..1.5e-2).contains(&e), "the bracket's estimate moved: {e:e}");
    let warning = checks.warnings.iter().find(|w| w.check == "estimate").expect("warned");
    assert!(warning.message.contains(&format!("e_inf(u) ~ {e:.1e}, counted as {:.1e} (x2", 2.0 * e)), "{}", warning.message);

    let (sol, checks) = run(&estimated("steel_plate", &[]));
    assert!(!checks.singular_corners.is_empty() && 2.0 * sol.estimate.done().unwrap().norms.e_inf_u < 1e-2);
    assert!(!checks.warnings.iter().any(|w| w.check == "estimate"), "{:?}", checks.warnings);
}

/// A corner or hole that could carry a spurious load and gets no balance is named in a
/// note with the reason, never skipped silently: the L with its horizontal arm cut to
/// 1 cm (at 4 mm no arc of 4 to 10 spacings stays between the corner's two edges)
/// names its re-entrant corner. The shipped bracket balances its corner and both holes
/// and has no such note; so does its displacement-pressure form (balanced since
/// 2026-11-27, before named in the note).
#[test]
fn an_unbalanced_corner_or_hole_is_a_note() {
    use mlsm::models::navier::sector::Around;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/bracket_variants/L.toml");
    let l = std::fs::read_to_string(&path).unwrap();
    let short = l[..l.find("[[probe]]").expect("the L has a probe")].replace("[0.2, 0.14], [0.2, 0.2]", "[0.07, 0.14], [0.07, 0.2]");
    assert!(short.contains("[0.07, 0.14]"), "the L's vertices changed");
    let p = Problem::from_str(&format!("{short}\n[estimate]\nmethod = \"none\"\n"), &path).unwrap_or_else(|e| panic!("{e}"));
    let (sol, checks) = run(&p.with_spacing(0.004).unwrap());
    assert!(sol.sector_balances.is_empty());
    let places: Vec<_> = sol.unbalanced.iter().map(|u| (u.around, u.reason.contains("no arc"))).collect();
    assert_eq!(places, vec![(Around::Corner, true)]);
    let note = checks.notes.iter().find(|n| n.starts_with("not balanced")).expect("a note");
    assert!(note.contains("the re-entrant corner at (6.0000e-2, 1.4000e-1)"), "{note}");

    for formulation in ["displacement", "displacement-pressure"] {
        let (sol, checks) = run(&scene("bracket", &[("nodes.spacing", f(0.004)), ("approximation.formulation", s(formulation))]));
        assert_eq!(sol.sector_balances.len(), 3, "{formulation}");
        assert!(sol.unbalanced.is_empty() && !checks.notes.iter().any(|n| n.starts_with("not balanced")), "{:?}", sol.unbalanced);
    }
}

/// A run at the highest degree has no higher one to compare with: warned as
/// unestimated, never silent.
#[test]
fn no_estimate_is_a_warning() {
    let p = scene(
        "manufactured_traction",
        &[("estimate.method", s("higher-degree")), ("approximation.basis", s("phs")), ("approximation.degree", i(8))],
    );
    let (sol, checks) = run(&p);
    assert!(matches!(&sol.estimate, Estimate::Unavailable(_, why) if why.contains("degree 8")), "{:?}", sol.estimate);
    assert!(checks.warnings.iter().any(|w| w.check == "no-estimate"));
}

/// Too few nodes for the fits make the defect estimate unavailable with the reason,
/// never silently absent (80 nodes: just above the two supports' worth that the
/// validation asks for).
#[test]
fn the_defect_estimate_says_why_it_is_unavailable() {
    let (sol, _) = run(&scene("lame", &[("estimate.method", s("defect")), ("nodes.spacing", f(1.8e-3))]));
    match &sol.estimate {
        Estimate::Unavailable(method, why) => {
            assert_eq!(*method, "defect");
            assert!(why.contains("too few") || why.contains("determine"), "{why}");
        }
        other => panic!("expected unavailable, got {other:?}"),
    }
}
