//! `mlsm convergence`: the static Navier solve at K halvings of the node spacing
//! against the scene's exact solution; errors, per-level and fitted observed orders
//! (`convergence.csv`, `convergence.json`), with each level's own error estimate
//! beside its true error. Both files are rewritten after every level (atomically,
//! `complete: false` until the last), so a failure or a kill at a fine level loses
//! nothing that finished.

use super::summary::Header;
use super::terminal::Terminal;
use super::{create_dir, AppError};
use crate::navier;
use crate::output;
use crate::pipeline::{Stage, StageTimings, OUTPUT};
use crate::post::observed_order;
use crate::problem::Problem;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The solves of all levels.
const LEVELS: Stage = Stage::new("levels");

/// One row of a convergence table.
#[derive(Serialize, Clone)]
struct Level {
    nodes: usize,
    h: f64,
    spacing: f64,
    e_inf_u: f64,
    e_inf_sigma: Option<f64>,
    rel_l2_u: f64,
    order_e_inf_u: Option<f64>,
    order_e_inf_sigma: Option<f64>,
    /// The run's own error estimate (`estimate.method`), beside the true error.
    estimated_e_inf_u: Option<f64>,
    estimated_e_inf_sigma: Option<f64>,
    seconds: f64,
}

#[derive(Serialize)]
struct ConvergenceTable<'a> {
    #[serde(flatten)]
    header: Header<'a>,
    /// Levels asked for (`--levels` + 1 runs).
    levels_requested: usize,
    /// Whether every requested level finished.
    complete: bool,
    levels: Vec<Level>,
    fitted_order_e_inf_u: Option<f64>,
    fitted_order_e_inf_sigma: Option<f64>,
}

/// Run the study of `p` over `levels` halvings and write its tables into `dir`.
pub(super) fn run(p: &Problem, levels: usize, dir: &Path, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    if p.case.exact.is_none() {
        return Err(AppError::Usage(format!("{}: convergence needs an [exact] solution in the scene", p.source.display())));
    }
    if p.case.dynamics.is_some() {
        return Err(AppError::Usage(format!(
            "{}: convergence studies the static solve; remove the [dynamics] table to study the static problem",
            p.source.display()
        )));
    }
    if levels > 8 {
        return Err(AppError::Usage(format!("--levels {levels}: at most 8 halvings (each multiplies the node count by 4)")));
    }
    // Refuse an unaffordable finest level before solving the coarse ones.
    crate::resources::check(&p.with_spacing(p.navier.fill.spacing / 2f64.powi(levels as i32))?)?;
    create_dir(dir)?;
    let t0 = Instant::now();
    let area = p.case.domain.area_estimate(400);
    let mut rows: Vec<Level> = Vec::new();
    for k in 0..=levels {
        match solve_level(p, (k, levels), rows.last(), area, term, quiet) {
            Ok(level) => rows.push(level),
            Err(e) => {
                if !rows.is_empty() {
                    eprintln!("level {k} failed; the {} finished level(s) are in {}", rows.len(), dir.join("convergence.csv").display());
                }
                return Err(e);
            }
        }
        write_tables(p, &rows, levels + 1, dir, t0, k == levels && !quiet)?;
    }
    Ok(())
}

/// Write `convergence.csv` and `convergence.json` for the levels finished so far (and
/// print the table when `print`).
fn write_tables(p: &Problem, rows: &[Level], requested: usize, dir: &Path, t0: Instant, print: bool) -> Result<(), AppError> {
    let mut timings = StageTimings::default();
    timings.record(LEVELS, rows.iter().map(|r| r.seconds).sum());
    let h: Vec<f64> = rows.iter().map(|r| r.h).collect();
    let fitted_u = observed_order(&h, &rows.iter().map(|r| r.e_inf_u).collect::<Vec<_>>());
    let es: Vec<f64> = rows.iter().map(|r| r.e_inf_sigma.unwrap_or(f64::NAN)).collect();
    let fitted_sigma = if es.iter().all(|e| e.is_finite()) { observed_order(&h, &es) } else { None };
    let t_out = Instant::now();
    write_csv(rows, dir)?;
    timings.record(OUTPUT, t_out.elapsed().as_secs_f64());
    let table = ConvergenceTable {
        header: Header::new(p, &timings, t0),
        levels_requested: requested,
        complete: rows.len() == requested,
        levels: rows.to_vec(),
        fitted_order_e_inf_u: fitted_u,
        fitted_order_e_inf_sigma: fitted_sigma,
    };
    output::write_json(&dir.join("convergence.json"), &table)?;
    if print {
        print_table(&table, dir);
    }
    Ok(())
}

/// Solve level `k` of `0..=last` (spacing halved `k` times); its orders against the
/// level before use the effective spacing `sqrt(area / N)`, so that scattered fills
/// are compared fairly.
fn solve_level(
    p: &Problem,
    (k, last): (usize, usize),
    before: Option<&Level>,
    area: f64,
    term: &Terminal,
    quiet: bool,
) -> Result<Level, AppError> {
    let spacing = p.navier.fill.spacing / 2f64.powi(k as i32);
    if !quiet {
        eprintln!("level {k} ({} of {}): spacing {spacing:.4e}", k + 1, last + 1);
    }
    let t0 = Instant::now();
    let q = p.with_spacing(spacing)?;
    let sol = navier::solve(&q.case, &q.navier, term)?;
    let e = sol.errors.expect("exact solution present");
    let h = (area / sol.nodes.len() as f64).sqrt();
    let order = |prev: Option<f64>, cur: Option<f64>| match (before, prev, cur) {
        (Some(last), Some(a), Some(b)) if a > 0.0 && b > 0.0 => Some((a / b).ln() / (last.h / h).ln()),
        _ => None,
    };
    Ok(Level {
        nodes: sol.nodes.len(),
        h,
        spacing,
        e_inf_u: e.e_inf_u,
        e_inf_sigma: e.e_inf_sigma,
        rel_l2_u: e.rel_l2_u,
        order_e_inf_u: order(before.map(|r| r.e_inf_u), Some(e.e_inf_u)),
        order_e_inf_sigma: order(before.and_then(|r| r.e_inf_sigma), e.e_inf_sigma),
        estimated_e_inf_u: sol.estimate.done().map(|x| x.norms.e_inf_u),
        estimated_e_inf_sigma: sol.estimate.done().and_then(|x| x.norms.e_inf_sigma),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

fn write_csv(rows: &[Level], dir: &Path) -> Result<(), AppError> {
    let nan = |o: Option<f64>| o.unwrap_or(f64::NAN);
    let csv: Vec<Vec<f64>> = rows
        .iter()
        .map(|l| {
            vec![
                l.nodes as f64,
                l.h,
                l.spacing,
                l.e_inf_u,
                nan(l.e_inf_sigma),
                l.rel_l2_u,
                nan(l.order_e_inf_u),
                nan(l.order_e_inf_sigma),
                nan(l.estimated_e_inf_u),
                nan(l.estimated_e_inf_sigma),
                l.seconds,
            ]
        })
        .collect();
    output::write_csv(
        &dir.join("convergence.csv"),
        &[
            "nodes",
            "h",
            "spacing",
            "e_inf_u",
            "e_inf_sigma",
            "rel_l2_u",
            "order_e_inf_u",
            "order_e_inf_sigma",
            "estimated_e_inf_u",
            "estimated_e_inf_sigma",
            "seconds",
        ],
        &csv,
    )?;
    Ok(())
}

fn print_table(table: &ConvergenceTable, dir: &Path) {
    println!(
        "{:>9} {:>11} {:>11} {:>11} {:>11} {:>7} {:>7} {:>9} {:>9}",
        "nodes", "h", "e_inf_u", "e_inf_sig", "rel_l2_u", "p_u", "p_sig", "est_u", "est_sig"
    );
    let e = |o: Option<f64>| o.map_or("-".to_string(), |v| format!("{v:.2e}"));
    let f = |o: Option<f64>| o.map_or("-".to_string(), |v| format!("{v:.2}"));
    for l in &table.levels {
        println!(
            "{:>9} {:>11.3e} {:>11.3e} {:>11} {:>11.3e} {:>7} {:>7} {:>9} {:>9}",
            l.nodes,
            l.h,
            l.e_inf_u,
            l.e_inf_sigma.map_or("-".into(), |v| format!("{v:.3e}")),
            l.rel_l2_u,
            f(l.order_e_inf_u),
            f(l.order_e_inf_sigma),
            e(l.estimated_e_inf_u),
            e(l.estimated_e_inf_sigma)
        );
    }
    println!("fitted order: e_inf(u) {}  e_inf(sigma) {}", f(table.fitted_order_e_inf_u), f(table.fitted_order_e_inf_sigma));
    println!("written: {}", dir.join("convergence.csv").display());
}
