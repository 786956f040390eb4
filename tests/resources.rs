//! The memory estimate (`mlsm::models::resources`) against the peak the kernel
//! reports for the run (its maximum resident set, as `wait4` gives it to the parent,
//! and `summary.json`'s `peak_memory_bytes`), and the refusals it drives. Each run is
//! its own process, so each peak is that run's.

mod common;

use common::describe;

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};
use tempfile::TempDir;

fn mlsm(args: &[&str], limit: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mlsm"));
    c.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    if let Some(l) = limit {
        c.env("MLSM_MEMORY_LIMIT", l);
    }
    c.output().expect("cannot start the mlsm binary")
}

/// What one run reported and what the kernel saw, bytes.
struct Peaks {
    /// `estimated_peak_memory_bytes`: the model of the run as it went.
    estimated: f64,
    /// `peak_memory_bytes`: VmHWM as the run read it at its end.
    summary: f64,
    /// The child's maximum resident set as the kernel reports it to its parent
    /// (`wait4`'s rusage, what /usr/bin/time prints).
    outside: f64,
}

/// [`Peaks`] of `mlsm run args...` (exit 0 asserted).
fn peaks(args: &[&str]) -> Peaks {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("res");
    let err = tmp.path().join("stderr");
    let mut all = vec!["--quiet", "run"];
    all.extend_from_slice(args);
    all.extend(["--out", out.to_str().unwrap()]);
    let mut command = Command::new(env!("CARGO_BIN_EXE_mlsm"));
    // A `pre_exec` makes std fork rather than `posix_spawn`. With the vfork-style
    // spawn, which runs the child on this process's memory until its exec, `wait4`
    // reported 143-167 MB for runs of 22-80 MB while other tests of this binary ran
    // (never with one test thread); with fork it matched the run's own VmHWM.
    // SAFETY: the closure does nothing, so it is async-signal-safe.
    unsafe {
        std::os::unix::process::CommandExt::pre_exec(&mut command, || Ok(()));
    }
    let child = command
        .args(&all)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::null())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("cannot start the mlsm binary");
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: an all-zero rusage is a valid value; wait4 writes into both out-parameters.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let waited = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(waited, pid, "wait4 failed");
    let stderr = std::fs::read_to_string(&err).unwrap_or_default();
    assert!(libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0, "{args:?}: status {status}: {stderr}");
    let s: Value = serde_json::from_slice(&std::fs::read(Path::new(&out).join("summary.json")).unwrap()).unwrap();
    Peaks {
        estimated: s["estimated_peak_memory_bytes"].as_f64().unwrap(),
        summary: s["peak_memory_bytes"].as_f64().unwrap(),
        outside: usage.ru_maxrss as f64 * 1024.0,
    }
}

/// The bar: the estimate within 1.5x of the peak either way.
const WITHIN: f64 = 1.5;

/// Every case of `cases`: the peak an outside tool sees is the run's own (mlsm does
/// not reset the kernel's high-water mark: within 5 %, the pages the output stage
/// touches after its reading), and the estimate is within [`WITHIN`] of it.
fn assert_within(cases: &[Vec<String>]) {
    let mut failed = Vec::new();
    for args in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let p = peaks(&args);
        let ratio = p.estimated / p.outside;
        eprintln!("{args:?}: estimated {:.0} MB, peak {:.0} MB (summary {:.0} MB), ratio {ratio:.2}", p.estimated / 1e6, p.outside / 1e6, p.summary / 1e6);
        assert!((p.summary / p.outside - 1.0).abs() <= 0.05, "{args:?}: the summary's peak {:.3e} B is not the kernel's {:.3e} B", p.summary, p.outside);
        if !(1.0 / WITHIN..=WITHIN).contains(&ratio) {
            failed.push(format!("{args:?}: estimate {:.3e} B against a peak of {:.3e} B ({ratio:.2})", p.estimated, p.outside));
        }
    }
    assert!(failed.is_empty(), "outside 1/{WITHIN}..{WITHIN}:\n{}", failed.join("\n"));
}

fn case(args: &[&str]) -> Vec<String> {
    args.iter().map(|a| a.to_string()).collect()
}

/// Every shipped scene as shipped, and every static one with each preset (solver
/// `auto`, the default estimate). Measured ratios 0.77-1.28 (benches/memory_estimate.sh,
/// BENCHMARKS.md "What the memory estimate misses"). Not here: the bracket with
/// `balanced` (44 193 nodes, a 9 GB, 150 s run: its GMRES fails and LU takes over,
/// measured by the bench at 1.06) and `accurate` (its solve fails, exit 3: docs/limits.md).
#[test]
fn memory_estimate_bounds_the_peak_on_every_shipped_scene_and_preset() {
    let statics = ["cantilever", "cantilever_traction", "manufactured_dirichlet", "manufactured_traction", "lame", "kirsch", "flamant", "bracket", "gravity_dam"];
    let mut cases = Vec::new();
    for scene in statics {
        let file = format!("problems/{scene}.toml");
        cases.push(case(&[&file]));
        for preset in ["fast", "balanced", "accurate"] {
            if scene == "bracket" && preset != "fast" {
                continue;
            }
            cases.push(case(&[&file, "--preset", preset]));
        }
    }
    for scene in ["steel_plate", "steel_plate_dynamic", "plate_pulse", "pd_plate_hole", "pd_three_point_bending_a", "pd_three_point_bending_b"] {
        cases.push(case(&[&format!("problems/{scene}.toml")]));
    }
    for scene in ["pd_manufactured", "pd_trig", "pd_tension"] {
        cases.push(case(&[&format!("problems/{scene}.toml"), "--model", "peridynamics"]));
    }
    assert_within(&cases);
}

/// Every solver path, with the default estimate and without: LU, GMRES and BiCGSTAB
/// set in the scene on Kirsch, Lame and the bracket. On the bracket the default
/// estimate takes the higher-degree reference, whose GMRES fails and falls back to LU
/// (250 MB against 23 MB without the estimate); the model follows the path the run
/// took (`resources::of_static_run`). Measured ratios 0.77-1.27.
#[test]
fn memory_estimate_bounds_the_peak_on_every_solver_path() {
    let tmp = TempDir::new().unwrap();
    let mut cases = Vec::new();
    for scene in ["kirsch", "lame", "bracket"] {
        let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("problems/{scene}.toml"))).unwrap();
        assert!(!text.contains("[solver]") && !text.contains("[estimate]"), "{scene} sets its own solver or estimate");
        for kind in ["lu", "gmres", "bicgstab"] {
            for estimate in ["auto", "none"] {
                let file = tmp.path().join(format!("{scene}-{kind}-{estimate}.toml"));
                std::fs::write(&file, format!("{text}\n[solver]\nkind = \"{kind}\"\n\n[estimate]\nmethod = \"{estimate}\"\n")).unwrap();
                cases.push(case(&[file.to_str().unwrap()]));
            }
        }
    }
    assert_within(&cases);
}

/// Three sizes of the graded Kirsch plate (PHS p = 4, with its error estimate: 1.2e3
/// to 1.8e4 nodes), manufactured_traction, a peridynamic run with a smaller horizon
/// (with the local-model estimate's Navier run), an explicit peridynamic run with a
/// smaller horizon (4.4e5 bonds; the model counted an LU factorisation it never makes,
/// 1.92x the peak, until 2026-11-29) and a dynamic Navier run (with Richardson's
/// estimate's run on a quarter of the nodes).
#[test]
fn memory_estimate_tracks_the_measured_peak() {
    let cases = [
        case(&["problems/kirsch.toml", "--spacing", "0.16"]),
        case(&["problems/kirsch.toml", "--spacing", "0.08"]),
        case(&["problems/kirsch.toml", "--spacing", "0.04"]),
        case(&["problems/pd_manufactured.toml", "--model", "peridynamics", "--horizon", "0.05"]),
        case(&["problems/steel_plate_dynamic.toml", "--horizon", "0.05"]),
        case(&["problems/steel_plate_dynamic.toml", "--model", "navier"]),
    ];
    assert_within(&cases);
}

/// What cannot fit is refused up front (exit 2, naming the setting that drives it and
/// the estimate), before any node is generated: an oversized support, a tiny
/// peridynamic horizon, and any run above `MLSM_MEMORY_LIMIT`.
#[test]
fn runs_that_cannot_fit_are_refused_naming_the_setting() {
    let tmp = TempDir::new().unwrap();
    let scene = tmp.path().join("support.toml");
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/manufactured_dirichlet.toml")).unwrap();
    let text = text.replace("support = 9", "support = 10000").replace("spacing = 0.025", "spacing = 0.0025");
    std::fs::write(&scene, text).unwrap();
    let out = tmp.path().join("res");
    let cases: [(Vec<&str>, Option<&str>, &str); 3] = [
        (vec!["run", scene.to_str().unwrap()], None, "approximation.support"),
        (vec!["run", "problems/pd_manufactured.toml", "--model", "peridynamics", "--horizon", "0.001"], None, "peridynamics.horizon"),
        (vec!["run", "problems/kirsch.toml"], Some("3e7"), "nodes.spacing"),
    ];
    for (mut args, limit, field) in cases {
        args.extend(["--out", out.to_str().unwrap()]);
        let o = mlsm(&args, limit);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", describe(&o));
        assert!(err.contains(field) && err.contains("GB") && err.contains("nonzeros"), "{args:?}: {err}");
        // Refused up front: no stage of the run was reached (a check on the stages
        // run, not on the clock).
        let printed = format!("{}{err}", String::from_utf8_lossy(&o.stdout));
        assert!(
            !printed.lines().any(|l| ["nodes ", "supports ", "families ", "shapes "].iter().any(|s| l.trim_start().starts_with(s))),
            "{args:?}: {printed}"
        );
        assert!(!out.exists(), "a refused run wrote output");
    }
    // A limit that is not a number of bytes is refused, not ignored.
    let o = mlsm(&["run", "problems/kirsch.toml", "--out", out.to_str().unwrap()], Some("lots"));
    assert_eq!(o.status.code(), Some(2), "{}", describe(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("MLSM_MEMORY_LIMIT"), "{}", describe(&o));
    assert!(!out.exists(), "a refused run wrote output");
}
