//! The written solution.vtu reads back (vtkio) with the expected arrays and values,
//! and summary.json agrees with the run.

mod common;
use common::*;
use mlsm::app::cli::Cli;
use mlsm::output::read_vtu;
use std::path::PathBuf;

/// Copy `problems/<name>.toml` into a temp dir with `edit` applied, and run it through
/// the command-line entry point; returns the temp dir, the scene path and the output folder.
fn run_scene(name: &str, edit: impl Fn(String) -> String) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join(format!("{name}.toml"));
    let text = std::fs::read_to_string(format!("{}/problems/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    std::fs::write(&scene_path, edit(text)).unwrap();
    let out = dir.path().join("res");
    let cli =
        <Cli as clap::Parser>::try_parse_from(["mlsm", "--quiet", "run", scene_path.to_str().unwrap(), "--out", out.to_str().unwrap()])
            .unwrap();
    mlsm::app::run(&cli).unwrap();
    (dir, scene_path, out)
}

#[test]
fn vtu_reads_back_with_expected_arrays() {
    let (_dir, scene_path, out) = run_scene("kirsch", |t| t.replace("spacing = 0.04", "spacing = 0.1"));

    // The same run through the library, to compare values.
    let p = mlsm::scene::problem::Problem::from_file(&scene_path).unwrap();
    let sol = solve(&p);
    let vtu = read_vtu(&out.join("solution.vtu")).unwrap();
    let n = sol.nodes.len();
    assert_eq!(vtu.points.len(), n);
    assert!(vtu.cells > n, "a triangulated surface has about 2 triangles per node, got {}", vtu.cells);
    for (p, q) in vtu.points.iter().zip(&sol.nodes.positions) {
        assert_eq!([p[0], p[1], p[2]], [q[0], q[1], 0.0]);
    }
    for name in [
        "displacement",
        "sigma_xx",
        "sigma_yy",
        "sigma_xy",
        "von_mises",
        "node_kind",
        "boundary_part",
        "normal",
        "exact_displacement",
        "error_displacement",
        "error_stress",
    ] {
        assert!(vtu.fields.contains_key(name), "missing array {name}; have {:?}", vtu.fields.keys().collect::<Vec<_>>());
    }
    assert!(!vtu.fields.contains_key("sigma_zz"), "plane stress writes no sigma_zz");
    let (c, u) = &vtu.fields["displacement"];
    assert_eq!(*c, 3);
    for i in 0..n {
        assert_eq!([u[3 * i], u[3 * i + 1], u[3 * i + 2]], [sol.displacement[i][0], sol.displacement[i][1], 0.0]);
    }
    let stress = sol.stress.as_ref().unwrap();
    let (s, vm) = (&stress.sigma, &stress.von_mises);
    let sxx = &vtu.fields["sigma_xx"].1;
    let vmf = &vtu.fields["von_mises"].1;
    for i in 0..n {
        assert_eq!(sxx[i], s[i][0]);
        assert_eq!(vmf[i], vm[i]);
        // Plane stress von Mises: sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2).
        let check = (s[i][0].powi(2) - s[i][0] * s[i][1] + s[i][1].powi(2) + 3.0 * s[i][2].powi(2)).sqrt();
        assert!((vm[i] - check).abs() <= 1e-12 * check.max(1.0));
    }
    // Node kinds: interior 0, displacement 1, traction 2, mixed 3 (symmetry edges).
    let kinds = &vtu.fields["node_kind"].1;
    let nb = sol.nodes.boundary.len();
    assert!(kinds[nb..].iter().all(|k| *k == 0.0));
    assert!(kinds[..nb].contains(&3.0) && kinds[..nb].contains(&2.0));

    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["nodes"], n);
    assert_eq!(summary["unknowns"], sol.unknowns);
    assert_eq!(summary["errors"]["e_inf_u"], sol.errors.unwrap().e_inf_u);
    for stage in ["nodes", "supports", "shapes", "assembly", "solve", "post", "output", "total"] {
        assert!(summary["timings_s"][stage].as_f64().unwrap() >= 0.0, "{stage}");
    }
}

#[test]
fn plane_strain_writes_sigma_zz_and_only_requested_fields() {
    let (_dir, _, out) = run_scene("steel_plate", |t| {
        format!("{}\n[output]\nfields = [\"displacement\", \"stress\", \"strain\"]\n", t.replace("spacing = 0.01", "spacing = 0.05"))
    });
    let vtu = read_vtu(&out.join("solution.vtu")).unwrap();
    for name in ["sigma_zz", "eps_xx", "eps_yy", "eps_xy"] {
        assert!(vtu.fields.contains_key(name), "missing {name}");
    }
    for name in ["von_mises", "error_displacement"] {
        assert!(!vtu.fields.contains_key(name), "{name} was not requested");
    }
}
