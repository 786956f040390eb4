//! The result folder of a command is replaced as a whole
//! (docs/methods/what-a-run-computes.md, step 9, "Output"): a re-run leaves no file of
//! the earlier run that the new one does not write, a failure or an interrupt leaves
//! the earlier results byte for byte and no temporary folder, I/O errors give the
//! operating system's reason and the path; `[dynamics] snapshots = N`
//! writes N + 1 states (the final one only for N = 0); progress goes to stderr as
//! plain lines when stderr is not a terminal, and `--quiet` silences it.
//!
//! Every test runs the binary in its own temporary directory on small scenes of
//! `problems/` (each run well under 2 s).

mod common;

use common::{describe, names, tree};

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;
use tempfile::TempDir;

/// The `mlsm` binary, run in `dir`.
fn mlsm(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mlsm"));
    c.current_dir(dir).env_remove("MLSM_PROGRESS_INTERVAL");
    c
}

/// Run `mlsm args` in `dir`.
fn run(dir: &Path, args: &[&str]) -> Output {
    mlsm(dir).args(args).output().expect("cannot start the mlsm binary")
}

/// `problems/<name>.toml`.
fn problem(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("problems").join(format!("{name}.toml"))
}

/// `problems/<name>.toml` with each `from` replaced by its `to` (each must occur),
/// written into `dir` as `file`.
fn edited(dir: &Path, file: &str, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(problem(name)).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{from:?} not in {name}.toml");
        text = text.replace(from, to);
    }
    let p = dir.join(file);
    std::fs::write(&p, text).unwrap();
    p
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A static run: manufactured_dirichlet at h = 0.1 (121 nodes).
fn static_args(out: &Path) -> Vec<String> {
    ["--quiet", "run", s(&problem("manufactured_dirichlet")), "--spacing", "0.1", "--out", s(out)].map(String::from).to_vec()
}


/// The `(timestep, file)` entries of a `series.pvd`.
fn pvd_entries(pvd: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(pvd).unwrap();
    text.lines()
        .filter(|l| l.contains("<DataSet"))
        .map(|l| {
            let attr = |a: &str| l.split(&format!("{a}=\"")).nth(1).unwrap().split('"').next().unwrap().to_string();
            (attr("timestep").parse().unwrap(), attr("file"))
        })
        .collect()
}

#[test]
fn a_static_run_after_a_dynamic_one_leaves_no_series_and_keeps_other_files() {
    let tmp = TempDir::new().unwrap();
    let res = tmp.path().join("res");
    let o = run(tmp.path(), &["--quiet", "run", s(&problem("steel_plate_dynamic")), "--out", s(&res)]);
    assert!(o.status.success(), "{}", describe(&o));
    for f in ["snapshots", "series.pvd", "energies.csv", "solution.vtu", "summary.json"] {
        assert!(res.join(f).exists(), "{f} missing after the dynamic run");
    }
    // Files of other commands or of the user in the folder are not the run's.
    std::fs::create_dir(res.join("compare")).unwrap();
    std::fs::write(res.join("compare/compare.json"), "{}").unwrap();
    std::fs::write(res.join("notes.txt"), "mine").unwrap();
    let o = mlsm(tmp.path()).args(static_args(&res)).output().unwrap();
    assert!(o.status.success(), "{}", describe(&o));
    assert_eq!(names(&res), ["compare", "notes.txt", "solution.vtu", "summary.json"]);
    assert_eq!(std::fs::read(res.join("notes.txt")).unwrap(), b"mine");
    assert_eq!(std::fs::read(res.join("compare/compare.json")).unwrap(), b"{}");
    assert_eq!(names(tmp.path()), ["res"], "a temporary folder was left");
}

#[test]
fn a_failing_run_leaves_the_earlier_result_byte_for_byte() {
    let tmp = TempDir::new().unwrap();
    let res = tmp.path().join("res");
    let o = run(tmp.path(), &["--quiet", "run", s(&problem("steel_plate_dynamic")), "--out", s(&res)]);
    assert!(o.status.success(), "{}", describe(&o));
    let before = tree(&res);
    // BiCGSTAB with one iteration cannot reach 1e-14: a solver failure (exit 3).
    let solver = "[solver]\nkind = \"bicgstab\"\npreconditioner = \"jacobi\"\nmax_iterations = 1\ntolerance = 1e-14\n\n[exact]";
    let bad = edited(tmp.path(), "bad.toml", "manufactured_dirichlet", &[("[exact]", solver)]);
    let o = run(tmp.path(), &["--quiet", "run", s(&bad), "--spacing", "0.1", "--out", s(&res)]);
    assert_eq!(o.status.code(), Some(3), "{}", describe(&o));
    assert_eq!(tree(&res), before, "the earlier result changed");
    assert_eq!(names(tmp.path()), ["bad.toml", "res"], "a temporary folder was left");
}

/// SIGINT (Ctrl-C) and SIGTERM (a job scheduler's stop) while snapshots are being
/// written (the time loop stops, exit 130) and during a static solve (the process ends
/// at once, exit 130): the earlier result stays as it was and no temporary folder is
/// left.
#[cfg(unix)]
#[test]
fn an_interrupted_run_leaves_the_earlier_result_and_no_temporary_folder() {
    let tmp = TempDir::new().unwrap();
    let res = tmp.path().join("res");
    let o = mlsm(tmp.path()).args(static_args(&res)).output().unwrap();
    assert!(o.status.success(), "{}", describe(&o));
    let before = tree(&res);
    // About 1.7e6 steps (minutes), interrupted after two snapshots; a 1e4-node static
    // run (seconds), interrupted as soon as its temporary folder exists.
    let long = edited(tmp.path(), "long.toml", "steel_plate_dynamic", &[("end_time = 1e-3", "end_time = 0.5")]);
    let cases: [(Vec<String>, &str, usize); 2] = [
        (vec!["--quiet".into(), "run".into(), s(&long).into(), "--out".into(), s(&res).into()], "snapshots", 2),
        (
            ["--quiet", "run", s(&problem("manufactured_dirichlet")), "--spacing", "0.01", "--out", s(&res)].map(String::from).to_vec(),
            "",
            0,
        ),
    ];
    for ((args, inside, entries), signal) in cases.iter().flat_map(|c| [(c, libc::SIGINT), (c, libc::SIGTERM)]) {
        let (args, inside, entries) = (args.as_slice(), *inside, *entries);
        let mut child = mlsm(tmp.path()).args(args).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
        let staged = tmp.path().join(format!(".res.tmp-{}", child.id())).join(inside);
        // Until the staged folder holds its entries or the run ends, however long that
        // takes: no clock.
        while !std::fs::read_dir(&staged).is_ok_and(|d| d.count() >= entries) {
            assert!(child.try_wait().unwrap().is_none(), "{args:?} ended before anything was staged");
            std::thread::sleep(Duration::from_millis(5));
        }
        // SAFETY: sending a signal to our own child process.
        assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, signal) }, 0);
        let o = child.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(130), "{args:?}, signal {signal}: {}", describe(&o));
        assert_eq!(tree(&res), before, "{args:?}, signal {signal}: the earlier result changed");
        assert_eq!(names(tmp.path()), ["long.toml", "res"], "{args:?}, signal {signal}: a temporary folder was left");
    }
}

#[test]
fn an_out_folder_below_a_file_is_an_error_with_the_reason_and_the_path() {
    let tmp = TempDir::new().unwrap();
    std::fs::write(tmp.path().join("file"), "x").unwrap();
    let res = tmp.path().join("file").join("res");
    let o = mlsm(tmp.path()).args(static_args(&res)).output().unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", describe(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("Not a directory") && err.contains(s(&res)), "{err}");
    assert_eq!(names(tmp.path()), ["file"]);
}

/// `snapshots = N` writes the states at t = 0, N - 1 evenly spaced times and the end;
/// `snapshots = 0` the final state only.
#[test]
fn snapshots_n_writes_n_plus_one_states_and_zero_the_final_one() {
    let tmp = TempDir::new().unwrap();
    for n in [0usize, 1, 7] {
        let scene = edited(tmp.path(), "dyn.toml", "steel_plate_dynamic", &[("snapshots = 20", &format!("snapshots = {n}"))]);
        let res = tmp.path().join(format!("res{n}"));
        let o = run(tmp.path(), &["--quiet", "run", s(&scene), "--out", s(&res)]);
        assert!(o.status.success(), "{}", describe(&o));
        let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(res.join("summary.json")).unwrap()).unwrap();
        let steps = summary["integration"]["steps"].as_u64().unwrap() as usize;
        assert!(steps > n, "{steps} steps");
        let entries = pvd_entries(&res.join("series.pvd"));
        assert_eq!(entries.len(), n + 1, "snapshots = {n}: {entries:?}");
        assert_eq!(names(&res.join("snapshots")).len(), n + 1);
        let last = entries.last().unwrap();
        assert!((last.0 - 1e-3).abs() < 1e-12, "the last state is at t_end: {last:?}");
        assert_eq!(last.1, format!("snapshots/step_{steps:06}.vtu"));
        if n > 0 {
            assert_eq!(entries[0], (0.0, "snapshots/step_000000.vtu".to_string()));
        }
    }
}

#[test]
fn compare_re_run_replaces_its_files_and_keeps_foreign_ones() {
    let tmp = TempDir::new().unwrap();
    let res = tmp.path().join("cmp");
    let scene = problem("pd_manufactured");
    let o = run(tmp.path(), &["--quiet", "compare", s(&scene), "--deltas", "0.4,0.2,0.1", "--out", s(&res)]);
    assert!(o.status.success(), "{}", describe(&o));
    assert!(res.join("ac_delta2.vtu").exists());
    std::fs::write(res.join("notes.txt"), "mine").unwrap();
    let o = run(tmp.path(), &["--quiet", "compare", s(&scene), "--deltas", "0.4,0.2", "--out", s(&res)]);
    assert!(o.status.success(), "{}", describe(&o));
    assert_eq!(names(&res), ["ac_delta0.vtu", "ac_delta1.vtu", "compare.json", "compare.svg", "compare_ac.csv", "notes.txt"]);
    assert_eq!(names(tmp.path()), ["cmp"]);
}

/// With stderr captured (not a terminal) the time loop prints plain progress lines
/// with a percent at the interval of `MLSM_PROGRESS_INTERVAL`; `--quiet` prints none.
/// How many lines a run prints depends on the machine's speed, so the test asks for
/// one only of a time loop that lasted ten intervals or more (`timings_s.integrate`
/// of its own summary.json): 665 steps took about 1 s on 2 cores, 100 intervals of
/// 0.01 s.
#[test]
fn progress_lines_when_stderr_is_not_a_terminal() {
    let tmp = TempDir::new().unwrap();
    let scene = edited(tmp.path(), "dyn.toml", "steel_plate_dynamic", &[("end_time = 1e-3", "end_time = 5e-3")]);
    let interval = 0.01;
    let res = tmp.path().join("res");
    let lines = |quiet: bool| -> (Vec<String>, f64) {
        let mut c = mlsm(tmp.path());
        c.env("MLSM_PROGRESS_INTERVAL", interval.to_string());
        if quiet {
            c.arg("--quiet");
        }
        let o = c.args(["run", s(&scene), "--out", s(&res)]).output().unwrap();
        assert!(o.status.success(), "{}", describe(&o));
        let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(res.join("summary.json")).unwrap()).unwrap();
        let integrate = summary["timings_s"]["integrate"].as_f64().expect("the time loop's seconds");
        (String::from_utf8_lossy(&o.stderr).lines().filter(|l| l.contains("[integrate]")).map(String::from).collect(), integrate)
    };
    let (shown, seconds) = lines(false);
    let progress = |l: &String| l.contains(" % (") && l.contains("steps") && l.contains("elapsed") && l.contains("ETA");
    if seconds >= 10.0 * interval {
        assert!(shown.iter().any(progress), "{seconds} s of time loop: {shown:?}");
    }
    assert!(shown.iter().all(|l| progress(l) || !l.contains('%')), "{shown:?}");
    assert_eq!(lines(true).0, Vec::<String>::new());
}

/// An iterative solve's progress is the residual's digits gained of those its
/// tolerance asks for, with an ETA, in the plain lines of the solve stage
/// (`linalg::watch`), and of the estimate stage (the `defect` estimate's fits, then
/// its correction's digits of 3). As for the time loop, a line is asked for only of a solve that
/// lasted ten intervals or more (`timings_s.solve` of its own summary.json): GMRES on
/// the cantilever at spacing 0.125 (9 881 nodes) took 0.6 s on 2 busy cores, 60 intervals.
#[test]
fn an_iterative_solve_reports_its_residual_digits() {
    let tmp = TempDir::new().unwrap();
    let scene = edited(tmp.path(), "gm.toml", "cantilever", &[("kind = \"lu\"", "kind = \"gmres\"")]);
    let interval = 0.01;
    let res = tmp.path().join("res");
    let mut c = mlsm(tmp.path());
    c.env("MLSM_PROGRESS_INTERVAL", interval.to_string());
    let o = c.args(["run", s(&scene), "--spacing", "0.125", "--out", s(&res)]).output().unwrap();
    assert!(o.status.success(), "{}", describe(&o));
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(res.join("summary.json")).unwrap()).unwrap();
    assert!(summary["solver"]["method"].as_str().unwrap().starts_with("gmres"), "{}", summary["solver"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    for stage in ["solve", "estimate"] {
        let seconds = summary["timings_s"][stage].as_f64().expect("the stage's seconds");
        let shown: Vec<&str> = stderr.lines().filter(|l| l.contains(&format!("[{stage}]"))).collect();
        // The `defect` estimate fits its solution first, then solves to its own
        // tolerance (1e-2: 2 digits).
        let unit = |l: &&str| match stage {
            "solve" => l.contains("/10 residual digits)"),
            _ => l.contains("/2 residual digits)") || l.contains(" fit centres)"),
        };
        let progress = |l: &&str| l.contains(" % (") && unit(l) && l.contains("ETA");
        if seconds >= 10.0 * interval {
            assert!(shown.iter().any(progress), "{seconds} s of {stage}: {shown:?}");
        }
        assert!(shown.iter().all(|l| progress(l) || l.contains("running")), "{stage}: {shown:?}");
    }
}
