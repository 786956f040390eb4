//! `mlsm tradeoff` and the presets: a budget that ends a sweep is reported, no run
//! starts that its memory estimate refuses, the files are complete, bad input is
//! refused, and a preset run lands in its stated accuracy band. No test here depends
//! on the machine's speed: a sweep is ended by a count of runs
//! (`MLSM_TRADEOFF_MAX_RUNS`, for tests), by a memory limit, or by the smallest
//! budget. (The Pareto front itself is unit-tested on synthetic tables in
//! src/tradeoff/front.rs; the sweep's rules and its budget, with the seconds the test
//! sets, in design.rs.)

mod common;

use mlsm::scene::problem::preset::Preset;
use mlsm::scene::problem::Problem;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn mlsm(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mlsm"));
    cmd.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("cannot start the mlsm binary")
}

fn problem(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("problems").join(format!("{name}.toml")).display().to_string()
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A sweep whose end the test sets by a count of runs, not by the clock
/// (`MLSM_TRADEOFF_MAX_RUNS`, for tests): eight runs of the Kirsch ladder, the cheapest
/// predicted first (about 5 s on 2 cores), under an hour of budget that is never
/// reached. Every run finishes, every family says why it stopped, every file is
/// written. (That a budget ends a sweep within 10 % past it is the arithmetic of
/// `design::Budget`, unit-tested in src/tradeoff/design.rs with the seconds the test
/// sets; the smallest budget is below.)
#[test]
fn tradeoff_writes_everything_for_a_sweep_of_eight_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = mlsm(
        &["--quiet", "tradeoff", &problem("kirsch"), "--budget", "1h", "--out", out.to_str().unwrap()],
        &[("MLSM_TRADEOFF_MAX_RUNS", "8")],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = read_json(&out.join("tradeoff.json"));
    let runs = s["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 8, "{runs:?}");
    let ok: Vec<&Value> = runs.iter().filter(|r| r["status"] == "ok").collect();
    assert_eq!(ok.len(), 8, "{runs:?}");
    for fam in s["families"].as_array().unwrap() {
        let why = fam["stopped"].as_str().unwrap_or_else(|| panic!("{fam}"));
        assert!(why == "8 runs were made (MLSM_TRADEOFF_MAX_RUNS, for tests)" || why.contains("beaten by"), "{fam}");
    }
    // Every finished run has its cost and both errors (Kirsch has an exact solution,
    // and the estimate is on); its seconds count the estimate (the run as users run
    // it) and stay within the process's wall clock; the fronts are non-empty and
    // consist of finished runs.
    for r in &ok {
        assert!(r["seconds"].as_f64().unwrap() > 0.0 && r["peak_memory_bytes"].as_f64().unwrap() > 0.0);
        let (seconds, estimate) = (r["seconds"].as_f64().unwrap(), r["estimate_seconds"].as_f64().unwrap());
        assert!(estimate > 0.0 && seconds > estimate && seconds <= r["wall_seconds"].as_f64().unwrap(), "{r}");
        assert!(r["exact"]["e_inf_sigma"].as_f64().is_some() && r["estimated"]["e_inf_sigma"].as_f64().is_some(), "{r}");
    }
    let front: Vec<&str> = s["front_sigma"].as_array().unwrap().iter().map(|v| v.as_str().unwrap()).collect();
    assert!(!front.is_empty());
    assert!(front.iter().all(|id| ok.iter().any(|r| r["id"] == *id && r["on_front_sigma"] == true)));
    assert!(!s["advice"].as_array().unwrap().is_empty());
    for f in ["tradeoff.csv", "tradeoff.svg", "tradeoff.png"] {
        assert!(std::fs::metadata(out.join(f)).unwrap().len() > 100, "{f}");
    }
    let csv = std::fs::read_to_string(out.join("tradeoff.csv")).unwrap();
    assert_eq!(csv.lines().count(), runs.len() + 1);
    // Each finished configuration is a scene that validates on its own.
    let first = ok[0]["id"].as_str().unwrap();
    Problem::from_file(&out.join("configs").join(format!("{first}.toml"))).unwrap();
}

/// The smallest budget (1 ns) has ended before the sweep's first run can finish, on any
/// machine: that run (it has no prediction to skip it by) is stopped, every family
/// says the budget ended, and the tables and the run's configuration are still written;
/// no plot, since no run finished, and the terminal names only the files written.
#[test]
fn the_smallest_budget_stops_the_first_run_and_still_writes_the_tables() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = mlsm(&["tradeoff", &problem("kirsch"), "--budget", "1ns", "--out", out.to_str().unwrap()], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = read_json(&out.join("tradeoff.json"));
    let runs = s["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 1, "{runs:?}");
    assert_eq!(runs[0]["status"], "stopped", "{}", runs[0]);
    assert_eq!(runs[0]["reason"], "the budget ended during the run", "{}", runs[0]);
    for fam in s["families"].as_array().unwrap() {
        assert_eq!(fam["stopped"], "the budget ended", "{fam}");
    }
    assert!(s["front_sigma"].as_array().unwrap().is_empty() && s["advice"].as_array().unwrap().is_empty());
    let csv = std::fs::read_to_string(out.join("tradeoff.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2, "{csv}");
    Problem::from_file(&out.join("configs").join("r01.toml")).unwrap();
    assert!(!out.join("tradeoff.svg").exists() && !out.join("tradeoff.png").exists());
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("Stopped: the budget ended during the run"), "{stdout}");
    assert!(stdout.contains("(tradeoff.csv, tradeoff.json)\n"), "{stdout}");
}

/// With 50 MB of memory, the finer configurations are refused by their estimate:
/// they are listed with the reason, and no process, folder or file was made for them.
/// The limit, not the clock, ends the sweep (every family is refused, stalls or is
/// beaten; about 10 s on 2 cores): the hour of budget is never reached.
#[test]
fn tradeoff_never_starts_a_run_its_memory_estimate_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let limit = 5.0e7;
    let o = mlsm(
        &["--quiet", "tradeoff", &problem("manufactured_traction"), "--budget", "1h", "--out", out.to_str().unwrap()],
        &[("MLSM_MEMORY_LIMIT", "5.0e7")],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = read_json(&out.join("tradeoff.json"));
    let runs = s["runs"].as_array().unwrap();
    let refused: Vec<&Value> = runs.iter().filter(|r| r["status"] == "refused").collect();
    assert!(!refused.is_empty(), "no configuration was refused at {limit:e} bytes");
    for r in &refused {
        let id = r["id"].as_str().unwrap();
        assert!(r["estimated_peak_memory_bytes"].as_f64().unwrap() > limit);
        assert!(r["reason"].as_str().unwrap().contains("more than the 0.05 GB available"), "{r}");
        assert!(r["seconds"].is_null() && r["nodes"].is_null());
        assert!(!out.join("runs").join(id).exists() && !out.join("configs").join(format!("{id}.toml")).exists());
    }
    for r in runs.iter().filter(|r| r["status"] != "refused") {
        assert!(r["estimated_peak_memory_bytes"].as_f64().unwrap() <= limit, "{r}");
    }
    // A refused family stops there (a finer level would need more).
    for fam in s["families"].as_array().unwrap() {
        let name = fam["name"].as_str().unwrap();
        let levels: Vec<(u64, &str)> =
            runs.iter().filter(|r| r["family"] == name).map(|r| (r["level"].as_u64().unwrap(), r["status"].as_str().unwrap())).collect();
        if let Some(k) = levels.iter().position(|l| l.1 == "refused") {
            assert_eq!(k, levels.len() - 1, "{name}: runs after a refusal: {levels:?}");
        }
    }
}

#[test]
fn tradeoff_refuses_bad_budgets_and_scenes_it_cannot_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let out = out.to_str().unwrap();
    for (budget, says) in
        [("0", "must be a positive number"), ("-5", "must be a positive number"), ("soon", "is not a duration"), ("0s", "longer than zero")]
    {
        let o = mlsm(&["tradeoff", &problem("lame"), "--budget", budget, "--out", out], &[]);
        assert_eq!(o.status.code(), Some(2), "--budget {budget}");
        assert!(stderr(&o).contains(says), "--budget {budget}: {}", stderr(&o));
    }
    let o = mlsm(&["tradeoff", &problem("lame"), "--budget", "100000000y", "--out", out], &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("longer than a year"), "{}", stderr(&o));
    let o = mlsm(&["tradeoff", &problem("lame"), "--budget", "5", "--out", out], &[("MLSM_MEMORY_LIMIT", "lots")]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("MLSM_MEMORY_LIMIT"), "{}", stderr(&o));
    let o = mlsm(&["tradeoff", &problem("lame"), "--budget", "5", "--out", out], &[("MLSM_TRADEOFF_MAX_RUNS", "0")]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("MLSM_TRADEOFF_MAX_RUNS=\"0\" must be a positive whole number"), "{}", stderr(&o));
    let o = mlsm(&["tradeoff", &problem("steel_plate_dynamic"), "--budget", "5", "--out", out], &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("static solve"), "{}", stderr(&o));
    let o = mlsm(&["tradeoff", &problem("pd_trig"), "--budget", "5", "--out", out], &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("mlsm compare"), "{}", stderr(&o));
    assert!(!Path::new(out).exists(), "a refused sweep wrote {out}");
}

/// The scene with `preset`, without its error estimate (the bands are on true errors).
fn with_preset(name: &str, preset: Preset) -> Problem {
    let path = PathBuf::from(problem(name));
    let mut doc: toml::Table = std::fs::read_to_string(&path).unwrap().parse().unwrap();
    doc.insert("estimate".into(), toml::Value::Table(toml::toml! { method = "none" }));
    Problem::from_str_with_preset(&toml::to_string(&doc).unwrap(), &path, Some(preset)).unwrap()
}

/// Each preset lands in the accuracy band its help states (`mlsm options`), on three
/// scenes of different geometry: a graded plate with a hole, a thin ring, a square. The
/// bands are two decades and more wide because at a fixed L / n the error depends on
/// how fast the solution itself varies; they were read off benches/presets.sh
/// (docs/verification.md, "Presets against their fronts"), where the seven shipped
/// scenes ranged over 6.8e-4..9.2e-3, 1.2e-6..1.2e-4 and 2.5e-8..3.4e-6. Kirsch
/// "accurate" (20 s) is left to that bench.
#[test]
fn presets_land_in_their_stated_bands() {
    for preset in [Preset::Fast, Preset::Balanced, Preset::Accurate] {
        let band = preset.band();
        for name in ["kirsch", "lame", "manufactured_traction"] {
            if name == "kirsch" && preset == Preset::Accurate {
                continue;
            }
            let p = with_preset(name, preset);
            assert!(p.notes.iter().any(|n| n.starts_with("preset")), "{:?}", p.notes);
            let (nodes, _, e_sigma) = common::errors(&p);
            assert!(
                e_sigma >= band.0 && e_sigma <= band.1,
                "{preset:?} on {name}: e_inf(sigma) = {e_sigma:.2e} on {nodes} nodes, band {band:?}"
            );
        }
    }
}

/// A `balanced` or `accurate` run first tries the `fast` preset with its error
/// estimate. On the cantilever, whose cubic solution every PHS stencil of degree >= 3
/// reproduces, the trial's estimate is round-off (about 6e-12), below the floor 1e-9 of
/// `accurate`, so the trial is the result written: the `fast` nodes and an error below
/// the floor (the accurate run itself had 5 300 nodes and 3.1e-9: docs/guide/tradeoff.md,
/// "The `fast` trial"). On the Lame
/// ring (a non-polynomial solution) the trial's estimate (6e-3) is far above the floor
/// 1e-7 of `balanced`: the preset's own, finer run is written, and the trial's seconds
/// are reported and counted in the total.
#[test]
fn a_preset_keeps_its_fast_trial_only_below_its_floor() {
    let dir = tempfile::tempdir().unwrap();
    let run = |scene: &str, preset: &str| {
        let out = dir.path().join(format!("{scene}_{preset}"));
        let o = mlsm(&["run", &problem(scene), "--preset", preset, "--out", out.to_str().unwrap()], &[]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        read_json(&out.join("summary.json"))
    };
    let fast = run("cantilever", "fast");
    assert!(fast.get("preset_trial").is_none(), "fast has no trial");
    let accurate = run("cantilever", "accurate");
    let trial = &accurate["preset_trial"];
    assert_eq!(trial["kept"], true, "{trial}");
    assert_eq!(accurate["nodes"], fast["nodes"]);
    assert!(trial["estimate"].as_f64().unwrap() <= Preset::Accurate.band().0, "{trial}");
    assert!(accurate["errors"]["e_inf_sigma"].as_f64().unwrap() <= Preset::Accurate.band().0, "{}", accurate["errors"]);
    assert!(accurate["notes"].as_array().unwrap().iter().any(|n| n.as_str().unwrap().contains("reproduces")), "{}", accurate["notes"]);

    // A preset named in the scene file is tried the same way; a spacing given on the
    // command line is the user's, and no trial replaces it.
    let scene = dir.path().join("c.toml");
    std::fs::write(&scene, format!("preset = \"accurate\"\n{}", std::fs::read_to_string(problem("cantilever")).unwrap())).unwrap();
    for (extra, trial) in [(&[][..], true), (&["--spacing", "0.5"][..], false)] {
        let out = dir.path().join(format!("file_{trial}"));
        let mut args = vec!["run", scene.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = mlsm(&args, &[]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let summary = read_json(&out.join("summary.json"));
        assert_eq!(summary.get("preset_trial").is_some(), trial, "{extra:?}");
        if !trial {
            assert_eq!(summary["nodes"], 61 * 11, "the spacing asked for");
        }
    }

    let balanced = run("lame", "balanced");
    let trial = &balanced["preset_trial"];
    assert_eq!(trial["kept"], false, "{trial}");
    assert!(trial["estimate"].as_f64().unwrap() > Preset::Balanced.band().0, "{trial}");
    assert!(balanced["nodes"].as_u64().unwrap() > trial["nodes"].as_u64().unwrap(), "the preset's own run is written");
    let seconds = trial["seconds"].as_f64().unwrap();
    assert!(seconds > 0.0 && balanced["timings_s"]["total"].as_f64().unwrap() > seconds, "{trial}");
}

#[test]
fn preset_errors_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let out = out.to_str().unwrap();
    let o = mlsm(&["run", &problem("lame"), "--preset", "quick", "--out", out], &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--preset") && stderr(&o).contains("\"balanced\""), "{}", stderr(&o));
    let o = mlsm(&["run", &problem("lame"), "--preset", "fast", "--spacing", "1e-3", "--out", out], &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not both"), "{}", stderr(&o));
    let o = mlsm(&["run", &problem("steel_plate_dynamic"), "--preset", "fast", "--out", out], &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("preset") && stderr(&o).contains("static"), "{}", stderr(&o));
    // In a scene file: the same word list, naming the file and the field.
    let scene = dir.path().join("s.toml");
    let text = std::fs::read_to_string(problem("lame")).unwrap();
    std::fs::write(&scene, format!("preset = \"best\"\n{text}")).unwrap();
    let o = mlsm(&["check", scene.to_str().unwrap()], &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("s.toml") && stderr(&o).contains("preset") && stderr(&o).contains("\"accurate\""), "{}", stderr(&o));
}

/// On a scene with singular corners the sweep counts the displacement estimate as the
/// run's `estimate` check does (x2): each finished run's estimated e_inf(u) is twice
/// what its own summary.json reports, and a note says why. The bracket's three
/// cheapest runs (`MLSM_TRADEOFF_MAX_RUNS`: a count, not the clock, ends the sweep).
#[test]
fn tradeoff_counts_the_displacement_estimate_double_at_singular_corners() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = mlsm(
        &["--quiet", "tradeoff", &problem("bracket"), "--budget", "1h", "--out", out.to_str().unwrap()],
        &[("MLSM_TRADEOFF_MAX_RUNS", "3")],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let s = read_json(&out.join("tradeoff.json"));
    assert!(s["notes"].as_array().unwrap().iter().any(|n| n.as_str().unwrap().contains("singular corners")), "{}", s["notes"]);
    let ok: Vec<&Value> = s["runs"].as_array().unwrap().iter().filter(|r| r["status"] == "ok").collect();
    assert!(!ok.is_empty());
    for r in ok {
        let own = read_json(&out.join("runs").join(r["id"].as_str().unwrap()).join("summary.json"));
        let raw = own["estimated_errors"]["e_inf_u"].as_f64().unwrap();
        let counted = r["estimated"]["e_inf_u"].as_f64().unwrap();
        assert_eq!(counted, 2.0 * raw, "{}", r["id"]);
        // The stress estimate is not counted.
        assert_eq!(r["estimated"]["e_inf_sigma"].as_f64().unwrap(), own["estimated_errors"]["e_inf_sigma"].as_f64().unwrap());
    }
}
