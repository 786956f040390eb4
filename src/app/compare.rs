//! `mlsm compare`: peridynamics at a sequence of horizons (fixed m = delta / h) against
//! the local solution; tables (CSV, JSON), a log-log plot (SVG) and one .vtu per run
//! (with `displacement`, the peridynamic one, for ParaView's Warp By Vector).

use super::fields::{integer, scalar, vector, write_points_vtu};
use super::summary::Header;
use super::terminal::Terminal;
use super::AppError;
use crate::scene::choice::Choice;
use crate::quality::compare::LocalReference;
use crate::models::dispatch;
use crate::output::{self, Series, StagedDir};
use crate::models::peridynamics::solve::interior_flags;
use crate::models::peridynamics::{PdParams, Quadrature};
use crate::stages::{Stage, StageTimings, OUTPUT};
use crate::quality::post::{masked_errors, observed_order};
use crate::scene::problem::{Model, ModelParams, Problem};
use serde::Serialize;
use std::ffi::OsStr;
use std::path::Path;
use std::time::Instant;

/// The local reference solve.
const REFERENCE: Stage = Stage::new("reference");
/// The peridynamic runs (each with its difference norms and .vtu).
const RUNS: Stage = Stage::new("runs");

/// What `compare` was asked for, after the command line was read.
pub(super) struct CompareRequest {
    pub m: Option<f64>,
    pub deltas: Option<Vec<f64>>,
    pub levels: usize,
    pub quadratures: Option<Vec<String>>,
    pub reference_spacing: Option<f64>,
}

/// One peridynamic run against the reference.
#[derive(Serialize)]
struct Row {
    quadrature: &'static str,
    delta: f64,
    h: f64,
    nodes: usize,
    interior_nodes: usize,
    bonds: usize,
    e_inf_interior: f64,
    rel_l2_interior: f64,
    e_inf_whole: f64,
    rel_l2_whole: f64,
    solver_iterations: usize,
    /// Wall-clock seconds of the peridynamic solve and its comparison.
    seconds: f64,
    /// Peak resident memory during the run (bytes), where the platform reports it.
    peak_memory_bytes: Option<u64>,
    vtu: String,
}

/// Least-squares orders in delta of one quadrature rule.
#[derive(Serialize)]
struct Orders {
    quadrature: &'static str,
    e_inf_interior: Option<f64>,
    rel_l2_interior: Option<f64>,
    e_inf_whole: Option<f64>,
    rel_l2_whole: Option<f64>,
}

#[derive(Serialize)]
struct Table<'a> {
    #[serde(flatten)]
    header: Header<'a>,
    reference: String,
    m: f64,
    kernel: String,
    correction: crate::models::peridynamics::SurfaceCorrection,
    rows: Vec<Row>,
    orders: Vec<Orders>,
}

/// The rules of `--quadratures` (default: the scene's).
fn quadratures(req: &CompareRequest, base: &PdParams) -> Result<Vec<Quadrature>, AppError> {
    match &req.quadratures {
        None => Ok(vec![base.quadrature]),
        Some(names) => {
            names.iter().map(|n| Quadrature::parse(n).map_err(|reason| AppError::Usage(format!("--quadratures: {reason}")))).collect()
        }
    }
}

/// The runs of a comparison.
struct Plan {
    quadratures: Vec<Quadrature>,
    deltas: Vec<f64>,
    m: f64,
    /// One problem per rule and horizon, rule by rule.
    runs: Vec<Problem>,
}

/// Every peridynamic run of the comparison, each checked before the first solve.
fn planned_runs(p: &Problem, req: &CompareRequest) -> Result<Plan, AppError> {
    let Some(base) = p.model.peridynamics().copied() else {
        return Err(AppError::Usage(format!("{}: compare needs a [peridynamics] table (horizon, quadrature, ...)", p.source.display())));
    };
    if base.fracture.is_some() {
        return Err(AppError::Usage(format!(
            "{}: peridynamics.fracture: compare measures the nonlocal model against the local one, which has no crack; remove \
             [peridynamics.fracture] to compare the uncracked solid",
            p.source.display()
        )));
    }
    let quadratures = quadratures(req, &base)?;
    if req.levels > 6 && req.deltas.is_none() {
        return Err(AppError::Usage(format!("--levels {}: at most 6 halvings (each multiplies the node count by 4)", req.levels)));
    }
    let deltas: Vec<f64> = req.deltas.clone().unwrap_or_else(|| (0..=req.levels).map(|k| base.horizon / 2f64.powi(k as i32)).collect());
    if let Some((k, d)) = deltas.iter().enumerate().find(|(k, d)| deltas[..*k].contains(d)) {
        return Err(AppError::Usage(format!(
            "--deltas: {d} is given twice (entries {} and {}); give each horizon once",
            deltas.iter().position(|x| x == d).unwrap() + 1,
            k + 1
        )));
    }
    if deltas.len() < 2 {
        let given = if req.deltas.is_some() { "--deltas gives one horizon" } else { "--levels 0 gives one horizon" };
        return Err(AppError::Usage(format!("{given}; compare needs two horizons or more to measure an order")));
    }
    let m = req.m.unwrap_or(base.ratio);
    let mut runs = Vec::new();
    for &q in &quadratures {
        for &delta in &deltas {
            let params = PdParams { horizon: delta, ratio: m, quadrature: q, ..base };
            let run = Problem { model: ModelParams::Peridynamics(params), ..p.with_peridynamics(params)? };
            affordable(&run, &format!("delta = {delta:e} ({})", q.name()))?;
            runs.push(run);
        }
    }
    Ok(Plan { quadratures, deltas, m, runs })
}

/// Refuse `run` up front, like `mlsm run` does, when its memory estimate exceeds the
/// available memory; `what` names the run in the refusal. A compared peridynamic run
/// has no error estimate of its own, so its estimate is left out of the check (the
/// local reference runs with its own).
fn affordable(run: &Problem, what: &str) -> Result<(), AppError> {
    let mut checked = run.clone();
    if checked.model.kind() == Model::Peridynamics {
        checked.navier.estimate.method = crate::models::navier::EstimateMethod::None;
    }
    crate::models::resources::check(&checked).map(|_| ()).map_err(|e| {
        AppError::Problem(crate::scene::problem::ProblemError { reason: format!("compare, {what}: {}", e.reason), ..e })
    })
}

/// Solve run `k` and compare it with the reference; writes its .vtu.
fn compare_run(p: &Problem, run: &Problem, k: usize, reference: &LocalReference, dir: &Path, term: &Terminal) -> Result<Row, AppError> {
    let params = run.model.peridynamics().copied().expect("a peridynamic run");
    let t0 = Instant::now();
    let mark = output::restart_peak();
    let outcome = dispatch::solve(run, term, |_| Ok(())).map_err(|e| AppError::of_scene(p, e))?;
    let (free, displacement) = (outcome.positions(), outcome.displacement());
    let interior = interior_flags(&p.case.domain, free, params.horizon);
    let local = reference.displacement_at(free)?;
    let whole = masked_errors(displacement, &local, |_| true).expect("free nodes exist");
    let inner = masked_errors(displacement, &local, |i| interior[i]);
    let name = format!("{}_delta{k}.vtu", params.quadrature.name());
    let diff: Vec<[f64; 2]> = displacement.iter().zip(&local).map(|(a, b)| [a[0] - b[0], a[1] - b[1]]).collect();
    // `displacement` (the peridynamic one, as in `solution.vtu`) for ParaView's Warp By Vector.
    let fields = vec![
        vector("displacement", displacement.iter().copied()),
        vector("peridynamic_displacement", displacement.iter().copied()),
        vector("local_displacement", local.iter().copied()),
        vector("difference", diff.iter().copied()),
        scalar("difference_magnitude", diff.iter().map(|d| d[0].hypot(d[1]))),
        integer("interior", interior.iter().map(|&b| b as i32)),
    ];
    write_points_vtu(&dir.join(&name), free, &p.case.domain, fields)?;
    let inner = inner.ok_or_else(|| {
        AppError::Usage(format!("delta = {}: no node lies at distance >= delta from the boundary; use smaller horizons", params.horizon))
    })?;
    let bonds = match &outcome {
        dispatch::Outcome::PdStatic(s) => s.bonds,
        dispatch::Outcome::PdDynamic(s) => s.discretisation.families.bonds(),
        _ => unreachable!("a peridynamic run"),
    };
    Ok(Row {
        quadrature: params.quadrature.name(),
        delta: params.horizon,
        h: params.spacing(),
        nodes: free.len(),
        interior_nodes: interior.iter().filter(|&&b| b).count(),
        bonds,
        e_inf_interior: inner.e_inf_u,
        rel_l2_interior: inner.rel_l2_u,
        e_inf_whole: whole.e_inf_u,
        rel_l2_whole: whole.rel_l2_u,
        solver_iterations: outcome.iterations(),
        seconds: t0.elapsed().as_secs_f64(),
        peak_memory_bytes: output::peak_since(mark),
        vtu: name,
    })
}

/// Least-squares orders in delta of each rule.
fn orders(quadratures: &[Quadrature], rows: &[Row]) -> Vec<Orders> {
    quadratures
        .iter()
        .map(|q| {
            let r: Vec<&Row> = rows.iter().filter(|r| r.quadrature == q.name()).collect();
            let d: Vec<f64> = r.iter().map(|r| r.delta).collect();
            let fit = |f: fn(&Row) -> f64| observed_order(&d, &r.iter().map(|r| f(r)).collect::<Vec<_>>());
            Orders {
                quadrature: q.name(),
                e_inf_interior: fit(|r| r.e_inf_interior),
                rel_l2_interior: fit(|r| r.rel_l2_interior),
                e_inf_whole: fit(|r| r.e_inf_whole),
                rel_l2_whole: fit(|r| r.rel_l2_whole),
            }
        })
        .collect()
}

/// Whether `name` is a file `compare` writes (`compare.json`, `compare.svg`,
/// `compare_<rule>.csv`, `<rule>_delta<k>.vtu`): a re-run replaces those of the earlier
/// comparison and keeps anything else in the folder.
fn compare_owns(name: &OsStr) -> bool {
    let n = name.to_string_lossy();
    n == "compare.json"
        || n == "compare.svg"
        || (n.starts_with("compare_") && n.ends_with(".csv"))
        || (n.contains("_delta") && n.ends_with(".vtu"))
}

/// Run the comparison of `p` and write its tables, plot and fields into a staged
/// folder that replaces `out` when everything is written.
pub(super) fn compare(p: &Problem, req: CompareRequest, out: &Path, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    // Every run (and below, the local reference) is refused up front when it would not
    // fit, before any folder is made.
    let Plan { quadratures, deltas, m, runs } = planned_runs(p, &req)?;
    let base = p.model.peridynamics().copied().expect("checked");
    let reference_problem = match req.reference_spacing {
        Some(h) if p.case.exact.is_none() => p.with_spacing(h)?,
        _ => p.clone(),
    };
    if reference_problem.case.dynamics.is_some() || reference_problem.case.exact.is_none() {
        let local = reference_problem.model.running(Model::Navier).expect("the Navier model always runs");
        affordable(&Problem { model: local, ..reference_problem.clone() }, "the local reference")?;
    }
    let staged = StagedDir::create(out, compare_owns)?;
    let dir_buf = staged.path().to_path_buf();
    let dir = dir_buf.as_path();
    if !quiet {
        eprintln!("{}: local reference", p.name);
    }
    let t0 = Instant::now();
    let mut timings = StageTimings::default();
    let reference = LocalReference::build(&reference_problem, term)?;
    timings.record(REFERENCE, t0.elapsed().as_secs_f64());
    let mut rows = Vec::new();
    for (k, run) in runs.iter().enumerate() {
        let params = run.model.peridynamics().copied().expect("a peridynamic run");
        if !quiet {
            let (q, d, h) = (params.quadrature.name(), params.horizon, params.spacing());
            eprintln!("run {} of {}: {q} delta = {d:.4e} (h = {h:.4e})", k + 1, runs.len());
        }
        let t = Instant::now();
        rows.push(compare_run(p, run, k % deltas.len(), &reference, dir, term)?);
        timings.record(RUNS, t.elapsed().as_secs_f64());
    }
    let orders = orders(&quadratures, &rows);
    let t_out = Instant::now();
    let kernel = base.kernel.label();
    write_tables(&format!("{}: peridynamics vs local, m = {m}, kernel {kernel}", p.name), &rows, &orders, dir)?;
    timings.record(OUTPUT, t_out.elapsed().as_secs_f64());
    let table = Table {
        header: Header::new(p, &timings, t0),
        reference: reference.describe(),
        m,
        kernel,
        correction: base.correction,
        rows,
        orders,
    };
    output::write_json(&dir.join("compare.json"), &table)?;
    let target = staged.target().to_path_buf();
    staged.commit()?;
    if !quiet {
        print_table(&table, &target);
    }
    Ok(())
}

/// `compare_<rule>.csv` and `compare.svg` (`compare.json` is written last).
fn write_tables(title: &str, rows: &[Row], orders: &[Orders], dir: &Path) -> Result<(), AppError> {
    let mut series = Vec::new();
    for o in orders {
        let r: Vec<&Row> = rows.iter().filter(|r| r.quadrature == o.quadrature).collect();
        let csv: Vec<Vec<f64>> = r
            .iter()
            .map(|r| {
                vec![
                    r.delta,
                    r.h,
                    r.nodes as f64,
                    r.interior_nodes as f64,
                    r.e_inf_interior,
                    r.rel_l2_interior,
                    r.e_inf_whole,
                    r.rel_l2_whole,
                    r.seconds,
                    r.bonds as f64,
                    r.peak_memory_bytes.map_or(f64::NAN, |b| b as f64),
                ]
            })
            .collect();
        output::write_csv(
            &dir.join(format!("compare_{}.csv", o.quadrature)),
            &[
                "delta",
                "h",
                "nodes",
                "interior_nodes",
                "e_inf_interior",
                "rel_l2_interior",
                "e_inf_whole",
                "rel_l2_whole",
                "seconds",
                "bonds",
                "peak_memory_bytes",
            ],
            &csv,
        )?;
        let order = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.2}"));
        series.push(Series {
            label: format!("{} interior (order {})", o.quadrature, order(o.e_inf_interior)),
            points: r.iter().map(|r| (r.delta, r.e_inf_interior)).collect(),
            dashed: false,
        });
        series.push(Series {
            label: format!("{} whole plate (order {})", o.quadrature, order(o.e_inf_whole)),
            points: r.iter().map(|r| (r.delta, r.e_inf_whole)).collect(),
            dashed: true,
        });
    }
    output::write_loglog_svg(&dir.join("compare.svg"), title, "horizon delta (m)", "max |u_PD - u_local| / max |u_local|", &series)?;
    Ok(())
}

fn print_table(t: &Table, dir: &Path) {
    println!("reference: {}; m = {}, kernel {}", t.reference, t.m, t.kernel);
    println!(
        "{:<13} {:>10} {:>8} {:>10} {:>11} {:>11} {:>11} {:>11} {:>8} {:>8}",
        "quadrature", "delta", "nodes", "bonds", "einf_int", "l2_int", "einf_all", "l2_all", "seconds", "peak MB"
    );
    for r in &t.rows {
        let peak = r.peak_memory_bytes.map_or("-".to_string(), |b| format!("{:.0}", b as f64 / 1e6));
        println!(
            "{:<13} {:>10.4e} {:>8} {:>10} {:>11.3e} {:>11.3e} {:>11.3e} {:>11.3e} {:>8.2} {:>8}",
            r.quadrature, r.delta, r.nodes, r.bonds, r.e_inf_interior, r.rel_l2_interior, r.e_inf_whole, r.rel_l2_whole, r.seconds, peak
        );
    }
    let f = |o: Option<f64>| o.map_or("-".to_string(), |v| format!("{v:.2}"));
    println!("observed order in delta (least squares):");
    for o in &t.orders {
        println!(
            "  {:<13} interior e_inf {:>6}  l2 {:>6}   whole e_inf {:>6}  l2 {:>6}",
            o.quadrature,
            f(o.e_inf_interior),
            f(o.rel_l2_interior),
            f(o.e_inf_whole),
            f(o.rel_l2_whole)
        );
    }
    println!("written: {}", dir.join("compare.json").display());
}
