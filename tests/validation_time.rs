//! Every input is refused or accepted in time proportional to the work it asks for
//! (issue 52, item 3): a tiny `[nodes.refine] spacing` hung in boundary sampling
//! (flamant at 1e-8: over 300 s in `discretise_boundary_graded`; Kirsch at 1e-5 never
//! reached the memory refusal), and constants that refer forward took cubic time
//! (1 000 chained: 12 s in `mlsm check`, 3 000: over a minute).
//!
//! Bound on the wall-clock time: 10 s for each command. Measured on a 2-core machine:
//! 0.01-0.7 s (the flamant run 0.7 s, the Kirsch refusals 0.03-0.05 s, 5 000 chained
//! constants 0.3 s); the bound leaves room for a loaded CI machine and still fails
//! on the old behaviour by an order of magnitude or more.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

const BOUND: Duration = Duration::from_secs(10);

/// `problems/<name>.toml` with each `(from, to)` replaced once (each must occur).
fn edited(name: &str, pairs: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("problems").join(format!("{name}.toml"))).unwrap();
    for (from, to) in pairs {
        assert!(text.contains(from), "{name}: {from}");
        text = text.replacen(from, to, 1);
    }
    text
}

/// `mlsm <args> scene.toml` on `text` in a temporary folder (`run` writes into it),
/// with the environment `env`; the output and the elapsed time, within [`BOUND`].
fn timed(args: &[&str], text: &str, env: &[(&str, &str)]) -> (Output, String) {
    let dir = tempfile::TempDir::new().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let mut command = Command::new(env!("CARGO_BIN_EXE_mlsm"));
    command.arg("--quiet").args(args).arg(&scene);
    if args.contains(&"run") {
        command.arg("--out").arg(dir.path().join("out"));
    }
    command.envs(env.iter().copied());
    let start = Instant::now();
    let out = command.output().unwrap();
    let elapsed = start.elapsed();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(elapsed < BOUND, "mlsm {args:?} took {elapsed:?}: {stderr}");
    eprintln!("mlsm {args:?}: {elapsed:?}, exit {:?}", out.status.code());
    (out, stderr)
}

/// Flamant refined towards its load point at 1e-8 m: the growth of 0.03 keeps the
/// node count small (about 5 700), and the boundary is probed every `h(x) / 8`, not
/// every `1e-8 / 8` m: checked and run.
#[test]
fn a_tiny_refinement_spacing_towards_a_point_is_run() {
    let text = edited("flamant", &[("spacing = 0.0005", "spacing = 1e-8")]);
    let (out, stderr) = timed(&["check"], &text, &[]);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let (out, stderr) = timed(&["run"], &text, &[]);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
}

/// Kirsch refined towards its hole at 1e-5 m (about 3.5e6 nodes) under a memory limit
/// of 1 000 bytes is refused by the memory check; at 1e-7 (3.5e8 nodes) the node
/// count refuses it, naming `nodes.refine.spacing`. The count of a refinement towards
/// boundary parts comes from the parts' length before any sampling at its spacing.
#[test]
fn a_tiny_refinement_spacing_towards_a_hole_is_refused_at_once() {
    let text = edited("kirsch", &[("spacing = 0.01", "spacing = 1e-5")]);
    let (out, stderr) = timed(&["run"], &text, &[("MLSM_MEMORY_LIMIT", "1000")]);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("more than the") && stderr.contains("available"), "{stderr}");
    let text = edited("kirsch", &[("spacing = 0.01", "spacing = 1e-7")]);
    let (out, stderr) = timed(&["check"], &text, &[]);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("nodes.refine.spacing") && stderr.contains("over 5e7"), "{stderr}");
}

/// Kirsch's plate stretched to 4e54 m (a strip 1e54 spacings long; found by
/// benches/fuzz.sh, where `mlsm check` ran for over 120 s): refused by its node count
/// within the bound (about 0.5 s), naming `nodes.refine.spacing`.
#[test]
fn a_plate_stretched_beyond_any_count_is_refused_at_once() {
    let text = edited("kirsch", &[("max = [4.0, 4.0]", "max = [4.0e54, 4.0]")]);
    let (out, stderr) = timed(&["check"], &text, &[]);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("nodes.refine.spacing") && stderr.contains("inf nodes"), "{stderr}");
}

/// 5 000 constants, each the next one plus 1 (every reference forward in the order of
/// the names): validated; closed into a cycle they are refused naming it.
#[test]
fn long_chains_of_constants_are_validated_in_linear_time() {
    let n = 5000;
    let chain: Vec<String> = (0..n).map(|k| format!("c{k:05} = \"c{:05} + 1\"", k + 1)).collect();
    let scene = |constants: &str| edited("manufactured_dirichlet", &[("[exact]", &format!("[constants]\n{constants}\n\n[exact]"))]);
    let text = scene(&format!("{}\nc{n:05} = 1.0", chain.join("\n")));
    let (out, stderr) = timed(&["check"], &text, &[]);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let cycle: Vec<String> = (0..n).map(|k| format!("c{k:05} = \"c{:05} + 1\"", (k + 1) % n)).collect();
    let (out, stderr) = timed(&["check"], &scene(&cycle.join("\n")), &[]);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("constants.c00000") && stderr.contains(&format!("cycle of {n}")), "{stderr}");
}
