//! The discretisation error of a static peridynamic run at its own horizon (issue 52,
//! item 1), apart from its model difference to the local solution: estimated from the
//! run at `m -> 2m` with the same horizon (`models::peridynamics::discretisation`), and
//! warned above the threshold like a Navier run's estimate.

mod common;

use common::{i, scene};
use mlsm::domain::Point;
use mlsm::stages::Silent;

/// The static run of `name` with `m`, and its free nodes' positions and displacements.
fn run(name: &str, m: i64) -> (mlsm::scene::problem::Problem, mlsm::models::peridynamics::PdSolution) {
    let p = scene(name, &[("peridynamics.m", i(m))]);
    let params = *p.model.peridynamics().expect("[peridynamics]");
    let sol = mlsm::models::peridynamics::solve(&p.case, &params, &Silent).unwrap_or_else(|e| panic!("{name} m = {m}: {e}"));
    (p, sol)
}

/// `max |u - I v| / max |I v|` with `v` of `fine` interpolated to the nodes of `coarse`.
fn difference(coarse: &mlsm::models::peridynamics::PdSolution, fine: &mlsm::models::peridynamics::PdSolution) -> f64 {
    let (n, nf) = (coarse.nodes.free, fine.nodes.free);
    let targets: &[Point] = &coarse.nodes.positions[..n];
    let v = mlsm::mlsm::interpolate::mls_values_of_degree(&fine.nodes.positions[..nf], &fine.displacement[..nf], targets, 2).unwrap();
    mlsm::quality::post::relative_errors(&coarse.displacement[..n], &v).0
}

/// On the smooth shipped scenes (pd_manufactured, pd_trig: m = 3, horizon 0.2) the
/// estimate tracks the error at the horizon. The truth is taken as the difference to
/// the run at m = 12 (4x finer at the same horizon): for an order p >= 1 that run's
/// own error is at most a quarter of the run's, so the difference lies within
/// [0.75, 1.25] of the true error, and the band [0.5, 2] of e_inf(u) holds with that
/// margin. Measured: effectivity 1.17-1.26, estimates 1.5e-3 to 1.8e-3 (below the
/// threshold: not warned), while the difference to the exact local solution is
/// 1.8e-2 to 1.9e-2 (the model difference of the horizon).
#[test]
fn the_estimate_tracks_the_error_at_the_run_horizon() {
    for name in ["pd_manufactured", "pd_trig"] {
        let (p, mut sol) = run(name, 3);
        let params = *p.model.peridynamics().unwrap();
        let estimate = mlsm::models::peridynamics::discretisation::estimate(&p.case, &params, &sol).unwrap();
        let (_, fine) = run(name, 12);
        let truth = difference(&sol, &fine);
        let effectivity = estimate.e_inf_u / truth;
        eprintln!("{name}: estimated {:.2e}, difference to m = 12 {truth:.2e}, effectivity {effectivity:.3}, {:.2} s", estimate.e_inf_u, estimate.seconds);
        assert!((0.5..=2.0).contains(&effectivity), "{name}: effectivity {effectivity}");
        sol.discretisation = Some(Ok(estimate));
        let checks = mlsm::quality::warnings::peridynamics_static(&sol, &mlsm::models::navier::Estimate::Off, p.navier.estimate.threshold);
        assert!(!checks.warnings.iter().any(|w| w.check == "pd-discretisation"), "{name}: {:?}", checks.warnings);
    }
}

/// A run that its nodes do not resolve at its horizon is warned, and `--strict` makes
/// it exit 4: pd_trig with the field's wavelength shortened to 4e-8 m on nodes 0.067 m
/// apart (the case: e_inf(u) against the exact solution 7e13; before, a note
/// and exit 0), and pd_tension on the nonlocal surface (`boundary = "surface"`; the
/// default fictitious nodes solve it exactly), whose traction layer one spacing thick concentrates
/// as the spacing shrinks (e_inf(u) against the exact solution 0.14, 0.35, 0.75 at
/// m = 3, 6, 12: the run does not converge at its horizon; estimated 7.5e-2).
#[test]
fn unresolved_runs_are_warned_and_strict_exits_4() {
    let dir = tempfile::TempDir::new().unwrap();
    let problems = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
    let trig = std::fs::read_to_string(problems.join("pd_trig.toml")).unwrap();
    let short = trig.replacen("cos(pi*y/2)\"", "cos(pi*y/2e-08)\"", 1);
    assert_ne!(short, trig);
    let surface = "quadrature = \"ac\"\nboundary = \"surface\"";
    let tension = std::fs::read_to_string(problems.join("pd_tension.toml")).unwrap().replacen("quadrature = \"ac\"", surface, 1);
    assert!(tension.contains(surface));
    for (name, text) in [("short", short), ("tension", tension)] {
        let path = dir.path().join(format!("{name}.toml"));
        std::fs::write(&path, text).unwrap();
        let out_dir = dir.path().join(name);
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_mlsm"))
            .args(["--quiet", "run", "--strict"])
            .arg(&path)
            .arg("--out")
            .arg(&out_dir)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(4), "{name}: {stderr}");
        assert!(stderr.contains("pd-discretisation"), "{name}: {stderr}");
        let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap()).unwrap();
        let d = &summary["discretisation_estimate"];
        assert_eq!(d["method"], "fixed-horizon", "{name}: {d}");
        assert!(d["e_inf_u"].as_f64().unwrap() > 1e-2, "{name}: {d}");
        assert_eq!(d["reference_ratio"].as_f64(), Some(6.0), "{name}: {d}");
    }
}

/// `estimate.method = "none"` asks for no estimate: none is computed (the summary's
/// field is null) and nothing is warned for it, on the scene that warns by default.
#[test]
fn no_estimate_asked_none_computed() {
    let dir = tempfile::TempDir::new().unwrap();
    let problems = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
    let text = std::fs::read_to_string(problems.join("pd_tension.toml")).unwrap() + "\n[estimate]\nmethod = \"none\"\n";
    let path = dir.path().join("tension.toml");
    std::fs::write(&path, text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mlsm")).args(["--quiet", "run"]).arg(&path).arg("--out").arg(dir.path().join("o")).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("pd-discretisation"), "{stderr}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("o/summary.json")).unwrap()).unwrap();
    assert!(summary["discretisation_estimate"].is_null(), "{}", summary["discretisation_estimate"]);
}

/// A dynamic run is estimated over its kept history against the run at m / 2 (m >= 6)
/// with the same horizon and step: the shipped plate_pulse (m = 6, 14 steps) is not
/// resolved at its horizon (estimated 0.37; its local-model difference 1.2), warned,
/// and `--strict` exits 4; summary.json carries the estimate.
#[test]
fn a_dynamic_run_is_estimated_over_its_history() {
    let dir = tempfile::TempDir::new().unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/plate_pulse.toml");
    let out_dir = dir.path().join("o");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mlsm")).args(["--quiet", "run", "--strict"]).arg(&path).arg("--out").arg(&out_dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("pd-discretisation") && stderr.contains("over 8 states"), "{stderr}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap()).unwrap();
    let d = &summary["discretisation_estimate"];
    assert_eq!(d["reference_ratio"].as_f64(), Some(3.0), "{d}");
    assert!(d["e_inf_u"].as_f64().unwrap() > 1e-2, "{d}");
}
