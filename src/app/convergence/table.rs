//! The tables of `mlsm convergence` ([`super`]): one row per level ([`Level`]),
//! `convergence.csv`, `convergence.json`, the log-log plot of the errors against the
//! spacing, and the table the terminal shows.

use super::super::summary::Header;
use super::super::AppError;
use crate::domain::Point;
use crate::output;
use crate::quality::post::observed_order;
use crate::quality::post::probe::ProbeQuantity;
use crate::quality::post::richardson::{extrapolate, Extrapolation};
use crate::scene::choice::Choice;
use crate::scene::problem::Problem;
use crate::stages::{Stage, StageTimings, OUTPUT};
use serde::Serialize;
use std::ffi::OsStr;
use std::path::Path;
use std::time::Instant;

/// The solves of all levels.
const LEVELS: Stage = Stage::new("levels");

/// One row of a convergence table.
#[derive(Serialize, Clone)]
pub(super) struct Level {
    pub(super) nodes: usize,
    pub(super) h: f64,
    pub(super) spacing: f64,
    /// Errors against the exact solution (scenes with one).
    pub(super) e_inf_u: Option<f64>,
    pub(super) e_inf_sigma: Option<f64>,
    pub(super) rel_l2_u: Option<f64>,
    pub(super) order_e_inf_u: Option<f64>,
    pub(super) order_e_inf_sigma: Option<f64>,
    /// The run's own error estimate (`estimate.method`).
    pub(super) estimated_e_inf_u: Option<f64>,
    pub(super) estimated_e_inf_sigma: Option<f64>,
    /// `e_inf` of this level's field against the next finer level's (filled in when
    /// that level finishes).
    pub(super) difference_e_inf_u: Option<f64>,
    pub(super) difference_e_inf_sigma: Option<f64>,
    pub(super) order_difference_u: Option<f64>,
    pub(super) order_difference_sigma: Option<f64>,
    /// The probes' values, in scene order.
    pub(super) probes: Vec<f64>,
    pub(super) seconds: f64,
}

/// A probe over the levels.
#[derive(Serialize)]
struct ProbeSeries {
    name: String,
    quantity: ProbeQuantity,
    at: Point,
    /// One value per finished level.
    values: Vec<f64>,
    /// The exact value, where the scene has a closed-form solution.
    exact: Option<f64>,
    /// Richardson over the last three levels (two when only two finished).
    extrapolation: Option<Extrapolation>,
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
    fitted_order_difference_u: Option<f64>,
    fitted_order_difference_sigma: Option<f64>,
    /// The formal order `max(p - 1, 1)` the extrapolation is capped by.
    formal_order: f64,
    probes: Vec<ProbeSeries>,
    notes: Vec<String>,
    /// Doubts about the study: the finest level's estimate above `estimate.threshold`
    /// (the levels are not in the asymptotic range, so their orders and
    /// extrapolations prove nothing).
    warnings: Vec<String>,
}

/// What [`write_tables`] wrote, for the terminal once the study is in place.
pub(super) struct Written {
    /// The table as printed.
    pub(super) table: String,
    /// The plot's note (no system font for the PNG).
    pub(super) plot_note: Option<String>,
    /// The study's warnings.
    pub(super) warnings: Vec<String>,
}

/// Whether `name` is a file `convergence` writes: a new study replaces those of the
/// earlier one and keeps anything else in the folder (a run's results, the user's files).
pub(super) fn convergence_owns(name: &OsStr) -> bool {
    FILES.split(", ").any(|f| name == f)
}

/// Write `convergence.csv` and `convergence.json` for the levels finished so far into
/// `dir`; returns the table as printed (naming the result folder `target`), the plot's
/// note and the study's warnings.
pub(super) fn write_tables(
    p: &Problem,
    rows: &[Level],
    (requested, notes): (usize, &[String]),
    (dir, target): (&Path, &Path),
    t0: Instant,
) -> Result<Written, AppError> {
    let mut timings = StageTimings::default();
    timings.record(LEVELS, rows.iter().map(|r| r.seconds).sum());
    let h: Vec<f64> = rows.iter().map(|r| r.h).collect();
    // A fitted order over the levels that have the column (all of them, or none).
    let fitted = |column: &dyn Fn(&Level) -> Option<f64>| {
        let (hs, es): (Vec<f64>, Vec<f64>) = rows.iter().filter_map(|r| column(r).map(|e| (r.h, e))).unzip();
        observed_order(&hs, &es)
    };
    let formal_order = p.navier.approximation.formal_order();
    let exact = p.case.exact_solution();
    let probes = p
        .case
        .probes
        .iter()
        .enumerate()
        .map(|(j, probe)| {
            let values: Vec<f64> = rows.iter().map(|r| r.probes[j]).collect();
            ProbeSeries {
                name: probe.name.clone(),
                quantity: probe.quantity,
                at: probe.at,
                extrapolation: extrapolate(&h, &values, formal_order),
                values,
                exact: exact.as_deref().map(|e| probe.quantity.exact(e, probe.at)),
            }
        })
        .collect();
    let threshold = p.navier.estimate.threshold;
    let warnings = match rows.last() {
        Some(last) => [("u", last.estimated_e_inf_u), ("sigma", last.estimated_e_inf_sigma)]
            .iter()
            .filter_map(|(what, e)| e.filter(|e| *e > threshold).map(|e| (what, e)))
            .map(|(what, e)| {
                format!(
                    "the finest level's estimated e_inf({what}) ~ {e:.1e} is above the threshold {threshold:e}: the levels are not \
                     in the asymptotic range, and their orders, differences and extrapolations are not to be trusted"
                )
            })
            .collect(),
        None => Vec::new(),
    };
    let t_out = Instant::now();
    write_csv(p, rows, dir)?;
    let plot_note = write_plot(&p.name, rows, dir)?;
    timings.record(OUTPUT, t_out.elapsed().as_secs_f64());
    let table = ConvergenceTable {
        header: Header::new(p, &timings, t0),
        levels_requested: requested,
        complete: rows.len() == requested,
        levels: rows.to_vec(),
        fitted_order_e_inf_u: fitted(&|r| r.e_inf_u),
        fitted_order_e_inf_sigma: fitted(&|r| r.e_inf_sigma),
        fitted_order_difference_u: fitted(&|r| r.difference_e_inf_u),
        fitted_order_difference_sigma: fitted(&|r| r.difference_e_inf_sigma),
        formal_order,
        probes,
        notes: notes.to_vec(),
        warnings,
    };
    output::write_json(&dir.join("convergence.json"), &table)?;
    Ok(Written { table: render_table(&table, target), plot_note, warnings: table.warnings })
}

/// The files of a study, as the terminal lists them.
const FILES: &str = "convergence.csv, convergence.json, convergence.svg, convergence.png";

/// One column of the table, where a level has it.
type Column = fn(&Level) -> Option<f64>;

/// `convergence.svg` and `convergence.png`: every error column of `rows` against the
/// spacing `h` (log-log), the estimate dashed beside the true error it estimates;
/// nothing before a column has a point. Returns the PNG's note (no system font).
fn write_plot(scene: &str, rows: &[Level], dir: &Path) -> Result<Option<String>, AppError> {
    // (label, column, dashed)
    let columns: [(&str, Column, bool); 6] = [
        ("e_inf(u), exact", |l| l.e_inf_u, false),
        ("e_inf(u), estimated", |l| l.estimated_e_inf_u, true),
        ("e_inf(sigma), exact", |l| l.e_inf_sigma, false),
        ("e_inf(sigma), estimated", |l| l.estimated_e_inf_sigma, true),
        ("u, difference to the next level", |l| l.difference_e_inf_u, false),
        ("sigma, difference to the next level", |l| l.difference_e_inf_sigma, true),
    ];
    let series: Vec<output::Series> = columns
        .iter()
        .map(|(label, column, dashed)| output::Series {
            label: label.to_string(),
            points: rows.iter().filter_map(|l| column(l).filter(|e| *e > 0.0).map(|e| (l.h, e))).collect(),
            dashed: *dashed,
        })
        .filter(|s| !s.points.is_empty())
        .collect();
    if series.is_empty() {
        return Ok(None);
    }
    let title = format!("{scene}: error against node spacing");
    let axes = ("node spacing h = sqrt(area / nodes) (m)", "relative error, max norm");
    Ok(output::write_loglog_plot(&dir.join("convergence.svg"), &dir.join("convergence.png"), &title, axes, &series)?)
}

fn write_csv(p: &Problem, rows: &[Level], dir: &Path) -> Result<(), AppError> {
    let nan = |o: Option<f64>| o.unwrap_or(f64::NAN);
    let csv: Vec<Vec<f64>> = rows
        .iter()
        .map(|l| {
            let mut row = vec![
                l.nodes as f64,
                l.h,
                l.spacing,
                nan(l.e_inf_u),
                nan(l.e_inf_sigma),
                nan(l.rel_l2_u),
                nan(l.order_e_inf_u),
                nan(l.order_e_inf_sigma),
                nan(l.estimated_e_inf_u),
                nan(l.estimated_e_inf_sigma),
                nan(l.difference_e_inf_u),
                nan(l.difference_e_inf_sigma),
                nan(l.order_difference_u),
                nan(l.order_difference_sigma),
            ];
            row.extend(&l.probes);
            row.push(l.seconds);
            row
        })
        .collect();
    let probe_columns: Vec<String> = p.case.probes.iter().map(|q| format!("probe_{}", q.name)).collect();
    let mut header = vec![
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
        "difference_e_inf_u",
        "difference_e_inf_sigma",
        "order_difference_u",
        "order_difference_sigma",
    ];
    header.extend(probe_columns.iter().map(String::as_str));
    header.push("seconds");
    output::write_csv(&dir.join("convergence.csv"), &header, &csv)?;
    Ok(())
}

/// The table as the terminal shows it, ending with the folder it was written to.
fn render_table(table: &ConvergenceTable, dir: &Path) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let e = |o: Option<f64>| o.map_or("-".to_string(), |v| format!("{v:.2e}"));
    let f = |o: Option<f64>| o.map_or("-".to_string(), |v| format!("{v:.2}"));
    let _ = writeln!(
        out,
        "{:>9} {:>10} {:>9} {:>9} {:>6} {:>6} {:>9} {:>9} {:>9} {:>9} {:>6} {:>6}",
        "nodes", "h", "e_inf_u", "e_inf_sig", "p_u", "p_sig", "est_u", "est_sig", "diff_u", "diff_sig", "pd_u", "pd_sig"
    );
    for l in &table.levels {
        let _ = writeln!(
            out,
            "{:>9} {:>10.3e} {:>9} {:>9} {:>6} {:>6} {:>9} {:>9} {:>9} {:>9} {:>6} {:>6}",
            l.nodes,
            l.h,
            e(l.e_inf_u),
            e(l.e_inf_sigma),
            f(l.order_e_inf_u),
            f(l.order_e_inf_sigma),
            e(l.estimated_e_inf_u),
            e(l.estimated_e_inf_sigma),
            e(l.difference_e_inf_u),
            e(l.difference_e_inf_sigma),
            f(l.order_difference_u),
            f(l.order_difference_sigma)
        );
    }
    let _ = writeln!(
        out,
        "fitted order: e_inf(u) {}  e_inf(sigma) {}  level differences: u {}  sigma {}",
        f(table.fitted_order_e_inf_u),
        f(table.fitted_order_e_inf_sigma),
        f(table.fitted_order_difference_u),
        f(table.fitted_order_difference_sigma)
    );
    for s in &table.probes {
        let values: Vec<String> = s.values.iter().map(|v| format!("{v:.6e}")).collect();
        let _ = write!(out, "probe {} ({} at [{}, {}]): {}", s.name, s.quantity.name(), s.at[0], s.at[1], values.join(", "));
        if let Some(x) = &s.extrapolation {
            let _ = write!(out, "; extrapolated {:.6e} +- {:.1e} ({}", x.value, x.error_bar, x.behaviour.name());
            if let Some(q) = x.observed_order {
                let _ = write!(out, ", observed order {q:.2}");
            }
            let _ = write!(out, ")");
        }
        if let Some(x) = s.exact {
            let _ = write!(out, "; exact {x:.6e}");
        }
        out.push('\n');
    }
    let _ = writeln!(out, "written: {} ({FILES})", dir.display());
    out
}
