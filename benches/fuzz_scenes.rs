//! Fuzzing the scene files: random mutations of the shipped scenes, each run through
//! `mlsm check` and `mlsm run`, for a fixed time. Every outcome must be accurate,
//! warned or refused: exit 0 with a readable summary.json, 4 (warned, `--strict`), 2
//! (invalid input) or 3 (solver failure) with no output folder left. A finding is a
//! panic (exit 101), a signal (abort, segfault, out of memory), another exit code, a
//! run that outlives its time limit, a half-written output, or a summary.json that
//! does not parse.
//!
//! The mutations come from proptest strategies over the scene's TOML tree: a number
//! scaled by 10^k (|k| <= 300), negated, set to 0, NaN or infinity, or made a string;
//! a string emptied, lengthened, replaced by an expression fragment or an option word
//! of another key; a key dropped or duplicated under another table; an array
//! truncated or repeated. Up to four mutations per scene.
//!
//! Run by hand (not in CI): `FUZZ_SECONDS=600 cargo bench --bench fuzz_scenes`
//! (benches/fuzz.sh). Findings are written to output/fuzz/ (the mutated scene and the
//! output), and a table of outcomes is printed for BENCHMARKS.md.

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, TestRunner};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use toml::Value;

/// The scenes mutated.
const SCENES: [&str; 15] = [
    "cantilever", "cantilever_traction", "manufactured_dirichlet", "manufactured_traction", "lame", "kirsch", "flamant",
    "bracket", "gravity_dam", "steel_plate", "steel_plate_dynamic", "plate_pulse", "pd_manufactured", "pd_trig",
    "pd_tension",
];

/// Words of the scene language that a string may be replaced by.
const WORDS: [&str; 16] = [
    "", "auto", "lu", "gmres", "bicgstab", "none", "grid", "scattered", "phs", "monomials", "traction", "displacement",
    "x*y/0", "sqrt(-1)", "exp(1000*x)", "((((",
];

/// One edit of a scene's tree.
#[derive(Debug, Clone)]
enum Mutation {
    /// Scale the `pick`-th number by 10^exponent.
    Scale { pick: usize, exponent: i32 },
    /// Replace the `pick`-th number by a special value.
    Special { pick: usize, which: usize },
    /// Replace the `pick`-th string by a word.
    Word { pick: usize, word: usize },
    /// Drop the `pick`-th key.
    Drop { pick: usize },
    /// Truncate (`keep` entries) the `pick`-th array, or repeat it when `keep` is 0.
    Array { pick: usize, keep: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<usize>(), -300i32..=300).prop_map(|(pick, exponent)| Mutation::Scale { pick, exponent }),
        2 => (any::<usize>(), 0usize..6).prop_map(|(pick, which)| Mutation::Special { pick, which }),
        2 => (any::<usize>(), 0..WORDS.len()).prop_map(|(pick, word)| Mutation::Word { pick, word }),
        1 => any::<usize>().prop_map(|pick| Mutation::Drop { pick }),
        1 => (any::<usize>(), 0usize..3).prop_map(|(pick, keep)| Mutation::Array { pick, keep }),
    ]
}

/// A scene and its mutations.
fn case() -> impl Strategy<Value = (usize, Vec<Mutation>)> {
    (0..SCENES.len(), prop::collection::vec(mutation(), 1..=4))
}

/// Paths to the leaves (or arrays, or keys) of `v` that `keep` accepts.
fn paths(v: &Value, keep: &dyn Fn(&Value) -> bool, here: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    if keep(v) {
        out.push(here.clone());
    }
    match v {
        Value::Table(t) => {
            for (k, child) in t {
                here.push(k.clone());
                paths(child, keep, here, out);
                here.pop();
            }
        }
        Value::Array(a) => {
            for (i, child) in a.iter().enumerate() {
                here.push(format!("#{i}"));
                paths(child, keep, here, out);
                here.pop();
            }
        }
        _ => {}
    }
}

/// The value at `path`, mutable.
fn at<'a>(v: &'a mut Value, path: &[String]) -> Option<&'a mut Value> {
    let Some((first, rest)) = path.split_first() else { return Some(v) };
    let child = match v {
        Value::Table(t) => t.get_mut(first)?,
        Value::Array(a) => a.get_mut(first.strip_prefix('#')?.parse::<usize>().ok()?)?,
        _ => return None,
    };
    at(child, rest)
}

/// `scene` with `m` applied (unchanged where `m` finds nothing to edit).
fn apply(scene: &mut Value, m: &Mutation) {
    let pick = |keep: &dyn Fn(&Value) -> bool, pick: usize| {
        let mut out = Vec::new();
        paths(scene, keep, &mut Vec::new(), &mut out);
        out.retain(|p| !p.is_empty());
        (!out.is_empty()).then(|| out[pick % out.len()].clone())
    };
    let number = |v: &Value| matches!(v, Value::Float(_) | Value::Integer(_));
    match *m {
        Mutation::Scale { pick: p, exponent } => {
            if let Some(path) = pick(&number, p) {
                let v = at(scene, &path).unwrap();
                let x = match v {
                    Value::Float(f) => *f,
                    Value::Integer(i) => *i as f64,
                    _ => unreachable!(),
                };
                *v = Value::Float(x * 10f64.powi(exponent));
            }
        }
        Mutation::Special { pick: p, which } => {
            if let Some(path) = pick(&number, p) {
                *at(scene, &path).unwrap() = match which {
                    0 => Value::Float(f64::NAN),
                    1 => Value::Float(f64::INFINITY),
                    2 => Value::Float(0.0),
                    3 => Value::Integer(-1),
                    4 => Value::Integer(i64::MAX),
                    _ => Value::String("1e3".into()),
                };
            }
        }
        Mutation::Word { pick: p, word } => {
            if let Some(path) = pick(&|v: &Value| v.is_str(), p) {
                *at(scene, &path).unwrap() = Value::String(WORDS[word].into());
            }
        }
        Mutation::Drop { pick: p } => {
            if let Some(path) = pick(&|_: &Value| true, p) {
                let (last, parent) = path.split_last().unwrap();
                match at(scene, parent) {
                    Some(Value::Table(t)) => {
                        t.remove(last);
                    }
                    Some(Value::Array(a)) => {
                        if let Some(i) = last.strip_prefix('#').and_then(|i| i.parse::<usize>().ok()) {
                            a.remove(i);
                        }
                    }
                    _ => {}
                }
            }
        }
        Mutation::Array { pick: p, keep } => {
            if let Some(path) = pick(&|v: &Value| v.is_array(), p) {
                if let Some(Value::Array(a)) = at(scene, &path) {
                    if keep == 0 {
                        let copy = a.clone();
                        a.extend(copy);
                    } else {
                        a.truncate(keep);
                    }
                }
            }
        }
    }
}

/// How one command ended.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    /// Exit code 0, 2, 3 or 4, as expected.
    Exit(i32),
    /// A finding, with what was wrong.
    Finding(String),
}

/// Run `mlsm args` with `limit` and check its output folder `out` (when given).
fn run(args: &[&str], out: Option<&Path>, limit: Duration) -> Outcome {
    let mut child = match Command::new(env!("CARGO_BIN_EXE_mlsm"))
        .args(args)
        .env("MLSM_MEMORY_LIMIT", "4e9")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
    {
        Ok(c) => c,
        Err(e) => return Outcome::Finding(format!("cannot start mlsm: {e}")),
    };
    let t0 = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if t0.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                return Outcome::Finding(format!("still running after {} s", limit.as_secs()));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => return Outcome::Finding(format!("wait failed: {e}")),
        }
    };
    let Some(code) = status.code() else {
        use std::os::unix::process::ExitStatusExt;
        return Outcome::Finding(format!("killed by signal {:?}", status.signal()));
    };
    match (code, out) {
        (0 | 4, Some(out)) => match std::fs::read(out.join("summary.json")).map(|b| serde_json::from_slice::<serde_json::Value>(&b)) {
            Ok(Ok(_)) => Outcome::Exit(code),
            _ => Outcome::Finding(format!("exit {code} without a readable summary.json")),
        },
        (2 | 3, Some(out)) if out.exists() => Outcome::Finding(format!("exit {code} left the output folder")),
        (0 | 2 | 3 | 4, _) => Outcome::Exit(code),
        (101, _) => Outcome::Finding("panic (exit 101)".into()),
        (c, _) => Outcome::Finding(format!("exit {c}")),
    }
}

fn main() {
    let budget = Duration::from_secs(std::env::var("FUZZ_SECONDS").ok().and_then(|s| s.parse().ok()).unwrap_or(600));
    let limit = Duration::from_secs(std::env::var("FUZZ_RUN_LIMIT").ok().and_then(|s| s.parse().ok()).unwrap_or(60));
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let findings_dir = root.join("output/fuzz");
    std::fs::create_dir_all(&findings_dir).expect("cannot create output/fuzz");
    let work = tempfile::TempDir::new().expect("no temporary folder");
    let mut runner = TestRunner::new(Config { rng_seed: proptest::test_runner::RngSeed::Fixed(52), ..Config::default() });
    let strategy = case();
    let (mut tally, mut findings): (BTreeMap<(&str, Outcome), usize>, Vec<String>) = (BTreeMap::new(), Vec::new());
    let t0 = Instant::now();
    let mut cases = 0;
    while t0.elapsed() < budget {
        let (scene, mutations) = strategy.new_tree(&mut runner).expect("strategy").current();
        let text = std::fs::read_to_string(root.join(format!("problems/{}.toml", SCENES[scene]))).expect("shipped scene");
        let mut tree: Value = toml::from_str(&text).expect("shipped scene parses");
        for m in &mutations {
            apply(&mut tree, m);
        }
        let Ok(mutated) = toml::to_string(&tree) else { continue };
        cases += 1;
        let file = work.path().join(format!("case{cases}.toml"));
        std::fs::write(&file, &mutated).expect("write the scene");
        let out = work.path().join(format!("out{cases}"));
        let file_str = file.to_str().unwrap();
        let check = run(&["--quiet", "check", file_str], None, limit);
        let solve = run(&["--quiet", "run", file_str, "--strict", "--out", out.to_str().unwrap()], Some(&out), limit);
        for (command, outcome) in [("check", check), ("run", solve)] {
            if let Outcome::Finding(what) = &outcome {
                let saved = findings_dir.join(format!("finding{}-{command}.toml", findings.len() + 1));
                let _ = std::fs::write(&saved, format!("# {command}: {what}\n# from {} with {mutations:?}\n{mutated}", SCENES[scene]));
                findings.push(format!("{} ({command}): {what}; {}", SCENES[scene], saved.display()));
            }
            *tally.entry((command, outcome)).or_default() += 1;
        }
        let _ = std::fs::remove_dir_all(&out);
    }
    println!("{cases} mutated scenes in {:.0} s (run limit {} s, MLSM_MEMORY_LIMIT=4e9)\n", t0.elapsed().as_secs_f64(), limit.as_secs());
    println!("| command | outcome | count |\n|---|---|---|");
    for ((command, outcome), n) in &tally {
        let what = match outcome {
            Outcome::Exit(c) => format!("exit {c}"),
            Outcome::Finding(f) => format!("**finding**: {f}"),
        };
        println!("| {command} | {what} | {n} |");
    }
    println!("\n{} findings", findings.len());
    for f in &findings {
        println!("- {f}");
    }
}
