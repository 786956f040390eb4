//! The PETSc backend (cargo feature `petsc`; `.ci/run` installs PETSc and Open MPI and
//! runs this file with the feature): `mpirun -n 2` agrees with the serial in-process
//! run on the cantilever and on a peridynamic scene, PETSc's options pass through, a
//! PETSc failure is reported with PETSc's converged reason and exit 3. Without the
//! feature, `solver.kind = "petsc"` is refused with the reason.

mod common;
use common::describe;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `problems/<name>`.
fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("problems").join(name)
}

/// `mlsm run SCENE --out OUT ARGS...`, under `mpirun -n ranks` when `ranks > 0`.
fn mlsm(ranks: usize, scene: &Path, out: &Path, args: &[&str]) -> Output {
    let exe = env!("CARGO_BIN_EXE_mlsm");
    let mut c = if ranks > 0 {
        let mut c = Command::new("mpirun");
        c.args(["--oversubscribe", "-n", &ranks.to_string(), exe]);
        c
    } else {
        Command::new(exe)
    };
    c.args(["run"]).arg(scene).arg("--out").arg(out).args(args);
    // Open MPI refuses root unless told (CI containers run as root).
    c.env("OMPI_ALLOW_RUN_AS_ROOT", "1").env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
    c.output().expect("start mlsm")
}

/// The cantilever with `solver.kind = "petsc"`, written into `dir`.
#[cfg(feature = "petsc")]
fn petsc_cantilever(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(scene("cantilever.toml")).unwrap().replace("kind = \"lu\"", "kind = \"petsc\"");
    assert!(text.contains("kind = \"petsc\""), "the cantilever names its solver");
    let path = dir.join("cantilever.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `summary.json` of a result folder.
fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The largest difference of the displacement arrays of two `solution.vtu`,
/// relative to the largest displacement of the first.
#[cfg(feature = "petsc")]
fn displacement_difference(a: &Path, b: &Path) -> f64 {
    field_difference(a, b, "displacement")
}

/// The same for the point field `name`.
#[cfg(feature = "petsc")]
fn field_difference(a: &Path, b: &Path, name: &str) -> f64 {
    let read = |d: &Path| mlsm::output::read_vtu(&d.join("solution.vtu")).unwrap().fields[name].1.clone();
    let (u, v) = (read(a), read(b));
    assert_eq!(u.len(), v.len(), "the same nodes");
    let largest = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    u.iter().zip(&v).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / largest
}

#[cfg(feature = "petsc")]
mod with_petsc {
    use super::*;

    /// The cantilever (grid, RBF-FD, ghost nodes) solved in one process by faer's LU
    /// and over two ranks, where its `lu` becomes MUMPS's distributed LU: both are
    /// direct, their residuals are ~1e-12 and the difference is round-off amplified by
    /// the condition number, so 1e-9 of the largest displacement bounds it (measured
    /// 3.0e-11). Each rank owns about half the rows and reports its stage times.
    #[test]
    fn two_ranks_agree_with_one_process_on_the_cantilever() {
        let dir = tempfile::tempdir().unwrap();
        let (one, two) = (dir.path().join("one"), dir.path().join("two"));
        let o = mlsm(0, &scene("cantilever.toml"), &one, &["-q"]);
        assert!(o.status.success(), "{}", describe(&o));
        let o = mlsm(2, &scene("cantilever.toml"), &two, &[]);
        assert!(o.status.success(), "{}", describe(&o));
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert_eq!(stdout.matches("solver petsc:").count(), 1, "rank 0 alone reports: {stdout}");
        let d = displacement_difference(&one, &two);
        eprintln!("cantilever, faer LU vs 2-rank MUMPS: {d:.1e}");
        assert!(d < 1e-9, "{d:e}");
        // Each rank found the supports and made the shapes of its own nodes only; the
        // stresses come from the gradients of every rank's own nodes, summed.
        let d = field_difference(&one, &two, "von_mises");
        eprintln!("cantilever von Mises, faer LU vs 2-rank MUMPS: {d:.1e}");
        assert!(d < 1e-8, "{d:e}");
        let s = summary(&two);
        let ranks = &s["solver"]["ranks"];
        assert_eq!(ranks["ranks"], 2);
        let rows: Vec<u64> = ranks["rows"].as_array().unwrap().iter().map(|r| r.as_u64().unwrap()).collect();
        assert_eq!(rows.iter().sum::<u64>(), s["unknowns"].as_u64().unwrap());
        assert!(rows.iter().all(|&r| r * 5 > s["unknowns"].as_u64().unwrap() * 2), "balanced within 20 %: {rows:?}");
        assert!(ranks["halo_unknowns"][0].as_u64().unwrap() > 0, "the two halves share a cut");
        assert_eq!(ranks["stage_seconds"].as_array().unwrap().len(), 2);
    }

    /// GMRES with PETSc's GAMG (plain aggregation, passed through after `--`) to a
    /// true residual of 1e-10, on one and on two ranks, against the direct solve: an
    /// iterative solution differs by up to tolerance x condition number; measured
    /// 5.6e-10 (one rank, 299 iterations) and 3.6e-10 (two ranks, 344); the bound 1e-7
    /// leaves a factor 100 for other partitions and PETSc versions.
    #[test]
    fn gmres_with_gamg_passes_through_and_agrees_over_two_ranks() {
        let dir = tempfile::tempdir().unwrap();
        let petsc_scene = petsc_cantilever(dir.path());
        let direct = dir.path().join("direct");
        let o = mlsm(0, &scene("cantilever.toml"), &direct, &["-q"]);
        assert!(o.status.success(), "{}", describe(&o));
        let amg = ["-q", "--", "-pc_type", "gamg", "-pc_gamg_agg_nsmooths", "0", "-ksp_max_it", "2000"];
        for ranks in [0, 2] {
            let out = dir.path().join(format!("gamg{ranks}"));
            let o = mlsm(ranks, &petsc_scene, &out, &amg);
            assert!(o.status.success(), "{ranks} ranks: {}", describe(&o));
            let s = summary(&out);
            assert_eq!(s["solver"]["method"], "petsc:gmres+gamg", "the options reached PETSc");
            assert!(s["solver"]["relative_residual"].as_f64().unwrap() <= 1e-9, "{}", s["solver"]);
            let d = displacement_difference(&direct, &out);
            eprintln!("cantilever, GMRES+GAMG on {ranks} ranks vs LU: {d:.1e}, {} iterations", s["solver"]["iterations"]);
            assert!(d < 1e-7, "{ranks} ranks: {d:e}");
        }
    }

    /// The peridynamic manufactured plate (static): its BiCGSTAB+ILU(0) in one process
    /// against GMRES with block-Jacobi ILU(0) over two ranks, both to 1e-10 (the
    /// scene's tolerance): the stiffness is well conditioned, and the two agree to
    /// 1.8e-10 (measured); 1e-7 is the bound, still 1e5 below the model error 1.8e-2.
    #[test]
    fn two_ranks_agree_with_one_process_on_a_peridynamic_plate() {
        let dir = tempfile::tempdir().unwrap();
        let (one, two) = (dir.path().join("one"), dir.path().join("two"));
        let args = ["--model", "peridynamics", "-q"];
        let o = mlsm(0, &scene("pd_manufactured.toml"), &one, &args);
        assert!(o.status.success(), "{}", describe(&o));
        let o = mlsm(2, &scene("pd_manufactured.toml"), &two, &args);
        assert!(o.status.success(), "{}", describe(&o));
        let s = summary(&two);
        assert_eq!(s["solver"]["ranks"]["ranks"], 2, "{}", s["solver"]);
        // Each rank assembled the rows of its own nodes: together, the whole stiffness;
        // each built the families and weights of its own nodes and their halo only: the
        // counts summed over the ranks are those of one process.
        let whole = summary(&one);
        assert_eq!(s["nonzeros"], whole["nonzeros"]);
        assert_eq!((&s["bonds"], &s["weights"]), (&whole["bonds"], &whole["weights"]));
        let d = displacement_difference(&one, &two);
        eprintln!("PD plate, one process vs two ranks: {d:.1e}");
        assert!(d < 1e-7, "{d:e}");
        // Each rank computed the nonlocal strain of its own nodes, summed over the ranks.
        let d = field_difference(&one, &two, "von_mises");
        eprintln!("PD plate von Mises, one process vs two ranks: {d:.1e}");
        assert!(d < 1e-6, "{d:e}");
    }

    /// The linear peridynamic solid with fictitious nodes (manufactured_traction as a
    /// peridynamic run: nu = 0.3, traction on two sides) over two ranks agrees with one
    /// process: each rank assembles its own rows of the bonds, the dilatation and the
    /// condensed fictitious columns (the dilatation and the extension are built whole on
    /// every rank), while one process applies the dilatation by its product (GMRES + AMG,
    /// its matrix holds the bonds only: fewer nonzeros). The same solution to 1e-7 (both
    /// solves to 1e-10, measured 5.9e-10; the model error is 1.8e-2).
    #[test]
    fn two_ranks_agree_with_one_process_on_the_peridynamic_solid() {
        let dir = tempfile::tempdir().unwrap();
        let (one, two) = (dir.path().join("one"), dir.path().join("two"));
        let args = ["--model", "peridynamics", "-q"];
        let o = mlsm(0, &scene("manufactured_traction.toml"), &one, &args);
        assert!(o.status.success(), "{}", describe(&o));
        let o = mlsm(2, &scene("manufactured_traction.toml"), &two, &args);
        assert!(o.status.success(), "{}", describe(&o));
        let (s, whole) = (summary(&two), summary(&one));
        assert_eq!(s["solver"]["ranks"]["ranks"], 2, "{}", s["solver"]);
        let choice = whole["solver"]["choice"].as_str().unwrap_or_default();
        assert!(choice.contains("applied without its matrix"), "{}", whole["solver"]);
        assert!(s["nonzeros"].as_u64().unwrap() > 2 * whole["nonzeros"].as_u64().unwrap(), "{} {}", s["nonzeros"], whole["nonzeros"]);
        let d = displacement_difference(&one, &two);
        eprintln!("PD solid with fictitious nodes, one process vs two ranks: {d:.1e}");
        assert!(d < 1e-7, "{d:e}");
    }

    /// A build with the feature gives freed memory back to the system: SuperLU_DIST's
    /// load-time constructor turns that off (`M_MMAP_MAX = 0`, `M_TRIM_THRESHOLD = -1`)
    /// and `main` turns it on again. The post-processing stage starts after the solve
    /// has freed the matrix and the multigrid, so its peak is well below the solve's;
    /// with the constructor's settings it equals it (measured on this cantilever,
    /// 6.1e4 nodes: 101 against 298 MB, and 421 = 421 MB without the fix).
    #[test]
    fn freed_memory_goes_back_to_the_system() {
        let dir = tempfile::tempdir().unwrap();
        let text = std::fs::read_to_string(scene("cantilever.toml")).unwrap().replace("kind = \"lu\"", "kind = \"gmres\"");
        assert!(text.contains("kind = \"gmres\"") && !text.contains("[estimate]"), "the cantilever names its solver, no estimate");
        let path = dir.path().join("cantilever.toml");
        std::fs::write(&path, text + "\n[estimate]\nmethod = \"none\"\n").unwrap();
        let out = dir.path().join("res");
        let o = mlsm(0, &path, &out, &["-q", "--spacing", "0.05"]);
        assert!(o.status.success(), "{}", describe(&o));
        let peaks = &summary(&out)["peak_memory_by_stage_bytes"];
        let (solve, post) = (peaks["solve"].as_f64().unwrap(), peaks["post"].as_f64().unwrap());
        assert!(post < 0.6 * solve, "post-processing peak {post:e} B against the solve's {solve:e} B");
    }

    /// What PETSc ran is in `summary.json` as its options database left it, and
    /// PETSc's own instruments work: `-ksp_type bcgs -ksp_rtol 1e-9 -ksp_max_it 4000
    /// -log_view` on one and two ranks gives `solver.petsc` with those settings and a
    /// converged reason, and rank 0's stdout carries `-log_view`'s performance summary
    /// (printed by `PetscFinalize`, which `main` calls at the end of the run).
    #[test]
    fn the_ksp_in_force_is_reported_and_log_view_works() {
        let dir = tempfile::tempdir().unwrap();
        let petsc_scene = petsc_cantilever(dir.path());
        for ranks in [0, 2] {
            let out = dir.path().join(format!("r{ranks}"));
            let o = mlsm(
                ranks,
                &petsc_scene,
                &out,
                &["-q", "--", "-ksp_type", "bcgs", "-ksp_rtol", "1e-9", "-ksp_max_it", "4000", "-log_view"],
            );
            assert!(o.status.success(), "{ranks} ranks: {}", describe(&o));
            let s = summary(&out);
            let k = &s["solver"]["petsc"];
            assert_eq!((k["ksp_type"].as_str(), k["pc_type"].as_str()), (Some("bcgs"), Some("gamg")), "{k}");
            assert_eq!((k["rtol"].as_f64(), k["max_it"].as_u64()), (Some(1e-9), Some(4000)), "{k}");
            assert!(k["converged_reason"].as_str().unwrap().starts_with("CONVERGED"), "{k}");
            let stdout = String::from_utf8_lossy(&o.stdout);
            assert_eq!(stdout.matches("PETSc Performance Summary").count(), 1, "{ranks} ranks: {stdout}");
            assert!(stdout.contains("KSPSolve"), "{stdout}");
        }
    }

    /// A KSP that stops (here at the iteration limit passed through) is a solver
    /// failure: exit 3, PETSc's converged reason and the true residual in the message,
    /// and no result folder left behind.
    #[test]
    fn a_diverged_ksp_exits_3_with_petscs_reason() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("res");
        let petsc_scene = petsc_cantilever(dir.path());
        for ranks in [0, 2] {
            let o = mlsm(ranks, &petsc_scene, &out, &["-q", "--", "-ksp_type", "bcgs", "-pc_type", "jacobi", "-ksp_max_it", "3"]);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(3), "{ranks} ranks: {}", describe(&o));
            assert!(err.contains("DIVERGED_ITS") && err.contains("petsc:bcgs+jacobi") && err.contains("true relative residual"), "{err}");
            assert!(!out.join("summary.json").exists());
        }
    }

    /// What cannot be distributed is refused by every rank before any work, with the
    /// reason: an explicit dynamic run, ILUT (which PETSc lacks), and the export of a
    /// system PETSc solved (never kept whole).
    #[test]
    fn mpirun_refuses_what_it_cannot_distribute() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("res");
        let o = mlsm(2, &scene("steel_plate_dynamic.toml"), &out, &["-q"]);
        assert_eq!(o.status.code(), Some(2), "{}", describe(&o));
        assert!(String::from_utf8_lossy(&o.stderr).contains("dynamic run is explicit"), "{}", describe(&o));
        let text = std::fs::read_to_string(scene("cantilever.toml"))
            .unwrap()
            .replace("kind = \"lu\"", "kind = \"bicgstab\"\npreconditioner = \"ilut\"");
        let ilut = dir.path().join("ilut.toml");
        std::fs::write(&ilut, text).unwrap();
        let o = mlsm(2, &ilut, &out, &["-q"]);
        assert_eq!(o.status.code(), Some(2), "{}", describe(&o));
        assert!(String::from_utf8_lossy(&o.stderr).contains("no PETSc counterpart"), "{}", describe(&o));
        // PETSc's system is not kept: --export-system is refused, not silently skipped.
        let petsc_scene = petsc_cantilever(dir.path());
        let o = mlsm(0, &petsc_scene, &out, &["-q", "--export-system", dir.path().join("sys").to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{}", describe(&o));
        assert!(String::from_utf8_lossy(&o.stderr).contains("--export-system"), "{}", describe(&o));
    }
}

/// A build without the feature names the field, the reason and the way to the
/// backend, with exit 2.
#[cfg(not(feature = "petsc"))]
#[test]
fn without_the_feature_petsc_is_refused_with_the_way_to_build_it() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene("cantilever.toml")).unwrap().replace("kind = \"lu\"", "kind = \"petsc\"");
    let path = dir.path().join("cantilever.toml");
    std::fs::write(&path, text).unwrap();
    let o = mlsm(0, &path, &dir.path().join("res"), &["-q"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{}", describe(&o));
    assert!(err.contains("solver.kind") && err.contains("--features petsc") && err.contains("install-petsc.sh"), "{err}");
    let _ = summary; // used by the feature's tests
}
