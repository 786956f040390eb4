//! Shared helpers: load a shipped scene with edits, so that every test starts from
//! the same problem definitions as the CLI (problems/*.toml).
#![allow(dead_code)]

use mlsm::scene::problem::Problem;
use std::path::Path;

/// Load `problems/<name>.toml`, apply `edits` (dotted key -> TOML value; `None`
/// removes the key) and validate it. The error estimate (a second solve) is off
/// unless the scene or an edit sets `estimate.*`: the tests that measure true errors
/// do not pay for it; tests/estimate.rs turns it on.
pub fn scene(name: &str, edits: &[(&str, Option<toml::Value>)]) -> Problem {
    scene_result(name, edits).unwrap_or_else(|e| panic!("{e}"))
}

/// The error of a shipped scene with `edits` that validation must refuse.
#[allow(dead_code)]
pub fn scene_error(name: &str, edits: &[(&str, Option<toml::Value>)]) -> mlsm::scene::problem::ProblemError {
    match scene_result(name, edits) {
        Ok(_) => panic!("{name} with {edits:?} was accepted"),
        Err(e) => e,
    }
}

/// [`scene`], validated or refused.
pub fn scene_result(name: &str, edits: &[(&str, Option<toml::Value>)]) -> Result<Problem, mlsm::scene::problem::ProblemError> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems").join(format!("{name}.toml"));
    let text = std::fs::read_to_string(&path).unwrap();
    let mut doc: toml::Table = toml::from_str(&text).unwrap();
    if !doc.contains_key("estimate") && !edits.iter().any(|(k, _)| k.starts_with("estimate.")) {
        doc.insert("estimate".into(), toml::Value::Table(toml::toml! { method = "none" }));
    }
    for (key, value) in edits {
        let parts: Vec<&str> = key.split('.').collect();
        let mut table = &mut doc;
        for p in &parts[..parts.len() - 1] {
            table = table.entry(p.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new())).as_table_mut().unwrap();
        }
        match value {
            Some(v) => {
                table.insert(parts[parts.len() - 1].to_string(), v.clone());
            }
            None => {
                table.remove(parts[parts.len() - 1]);
            }
        }
    }
    Problem::from_str(&toml::to_string(&doc).unwrap(), &path)
}

/// A float TOML value.
pub fn f(v: f64) -> Option<toml::Value> {
    Some(toml::Value::Float(v))
}

/// An integer TOML value.
pub fn i(v: i64) -> Option<toml::Value> {
    Some(toml::Value::Integer(v))
}

/// A string TOML value.
pub fn s(v: &str) -> Option<toml::Value> {
    Some(toml::Value::String(v.into()))
}

/// A boolean TOML value.
pub fn b(v: bool) -> Option<toml::Value> {
    Some(toml::Value::Boolean(v))
}

/// Solve a problem silently.
pub fn solve(p: &Problem) -> mlsm::models::navier::Solution {
    mlsm::models::navier::solve(&p.case, &p.navier, &mlsm::stages::Silent).unwrap_or_else(|e| panic!("{}: {e}", p.name))
}

/// Errors `(e_inf_u, e_inf_sigma)` of a solved problem with an exact solution.
pub fn errors(p: &Problem) -> (usize, f64, f64) {
    let s = solve(p);
    let e = s.errors.expect("exact solution");
    (s.nodes.len(), e.e_inf_u, e.e_inf_sigma.expect("stress errors"))
}

/// Observed order in the effective spacing `sqrt(1/N)` over a sequence of spacings.
/// Each level is the edited scene at `nodes.spacing = h`; a graded spacing function
/// is scaled as a whole (`Problem::with_spacing`), so its levels are refinements.
pub fn orders(name: &str, spacings: &[f64], extra: &[(&str, Option<toml::Value>)]) -> (f64, f64, Vec<(usize, f64, f64)>) {
    let base = scene(name, extra);
    let rows: Vec<(usize, f64, f64)> = spacings.iter().map(|&h| errors(&base.with_spacing(h).unwrap_or_else(|e| panic!("{e}")))).collect();
    let hs: Vec<f64> = rows.iter().map(|r| (1.0 / r.0 as f64).sqrt()).collect();
    let eu: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let es: Vec<f64> = rows.iter().map(|r| r.2).collect();
    let pu = mlsm::quality::post::observed_order(&hs, &eu).unwrap();
    let ps = mlsm::quality::post::observed_order(&hs, &es).unwrap();
    eprintln!("{name}: {rows:?} -> order u {pu:.3}, sigma {ps:.3}");
    (pu, ps, rows)
}

/// An array-of-floats TOML value.
pub fn arr(v: &[f64]) -> Option<toml::Value> {
    Some(toml::Value::Array(v.iter().map(|x| toml::Value::Float(*x)).collect()))
}

/// Edits that pin the least-squares setting (monomials of degree 2 on 12 nodes,
/// uniform spacing) on a scene that ships another one, for the tests that measured it.
pub fn least_squares_2() -> Vec<(&'static str, Option<toml::Value>)> {
    vec![("approximation.basis", s("monomials")), ("approximation.degree", i(2)), ("approximation.support", i(12)), ("nodes.refine", None)]
}

/// `least_squares_2()` followed by `edits`.
pub fn pinned(edits: &[(&'static str, Option<toml::Value>)]) -> Vec<(&'static str, Option<toml::Value>)> {
    let mut all = least_squares_2();
    all.extend_from_slice(edits);
    all
}

/// Exit code, stdout and stderr of a finished `mlsm` process, for assertion messages.
pub fn describe(o: &std::process::Output) -> String {
    format!(
        "exit {:?}\n--- stdout\n{}--- stderr\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Every file under `dir` (relative path -> bytes): a folder's contents, to check
/// that an interrupted or refused command left it byte for byte.
pub fn tree(dir: &std::path::Path) -> std::collections::BTreeMap<std::path::PathBuf, Vec<u8>> {
    fn walk(root: &std::path::Path, dir: &std::path::Path, out: &mut std::collections::BTreeMap<std::path::PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(p.strip_prefix(root).unwrap().to_path_buf(), std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = std::collections::BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Names in `dir`, sorted.
pub fn names(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// Largest `|(f(x + s e_c) - f(x - s e_c)) / 2s - K[r][c]|` over every row `r` and every
/// `every`-th column `c`, at a fixed pseudo-random `x` in [-0.5, 0.5] and step
/// `s = 1e-3`: how far the dense matrix `k` is from the central finite-difference
/// Jacobian of `force` (exact up to cancellation for a linear force).
pub fn jacobian_mismatch(k: &[Vec<f64>], force: impl Fn(&[f64]) -> Vec<f64>, every: usize) -> f64 {
    let n = k.len();
    let base: Vec<f64> = (0..n).map(|r| ((r * 7919) % 13) as f64 / 13.0 - 0.5).collect();
    let step = 1e-3;
    let mut worst: f64 = 0.0;
    for col in (0..n).step_by(every) {
        let (mut up, mut down) = (base.clone(), base.clone());
        up[col] += step;
        down[col] -= step;
        let (fu, fd) = (force(&up), force(&down));
        for r in 0..n {
            worst = worst.max(((fu[r] - fd[r]) / (2.0 * step) - k[r][col]).abs());
        }
    }
    worst
}

/// Least-squares order and worst single-step order of `errors` over `sizes`.
pub fn least_squares_and_worst_order(sizes: &[f64], errors: &[f64]) -> (f64, f64) {
    let ls = mlsm::quality::post::observed_order(sizes, errors).unwrap();
    let worst = (1..sizes.len()).map(|k| (errors[k - 1] / errors[k]).ln() / (sizes[k - 1] / sizes[k]).ln()).fold(f64::INFINITY, f64::min);
    (ls, worst)
}
