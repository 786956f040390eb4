//! `mlsm convergence`: the static Navier solve at K halvings of the node spacing, for
//! any static scene. Each level reports
//! - its errors against the exact solution and their observed orders, where the scene
//!   has one;
//! - its own error estimate (`estimate.method`; switched on, with a note, for a scene
//!   without an exact solution);
//! - the difference to the next finer level: `e_inf` of `u_{k-1} - u_k` (and of the
//!   stress, away from singular corners) at the nodes of level `k-1`, the finer field
//!   interpolated there by moving least squares, relative to the finer field's
//!   largest value; with their observed orders;
//! - the value of every `[[probe]]` of the scene, extrapolated over the last three
//!   levels by Richardson with a GCI error bar (`post::richardson`).
//!
//! `convergence.csv` and `convergence.json` are rewritten after every level
//! (atomically, `complete: false` until the last), and so is the plot of the errors
//! against the spacing, `convergence.svg` and `convergence.png` (log-log), all in a
//! staged folder beside the result folder ([`StagedDir`]) that replaces the study's
//! files in it when the last level is written: an interrupt (Ctrl-C, SIGTERM, SIGHUP)
//! or a kill leaves an earlier study complete. A level that fails ends the study with
//! the levels that finished (`complete: false`), which then replace the earlier study.

use super::summary::Header;
use super::terminal::Terminal;
use super::AppError;
use crate::scene::choice::Choice;
use crate::domain::Point;
use crate::mlsm::interpolate::mls_values;
use crate::models::navier::{self, EstimateMethod};
use crate::output::{self, StagedDir};
use crate::stages::{RunError, Stage, StageTimings, OUTPUT};
use crate::quality::post::observed_order;
use crate::quality::post::probe::ProbeQuantity;
use crate::quality::post::relative_errors;
use crate::quality::post::richardson::{extrapolate, Extrapolation};
use crate::scene::problem::Problem;
use crate::quality::warnings::{displacement_estimate_factor, singular_corners, singular_estimate_note};
use serde::Serialize;
use std::ffi::OsStr;
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
    /// Errors against the exact solution (scenes with one).
    e_inf_u: Option<f64>,
    e_inf_sigma: Option<f64>,
    rel_l2_u: Option<f64>,
    order_e_inf_u: Option<f64>,
    order_e_inf_sigma: Option<f64>,
    /// The run's own error estimate (`estimate.method`).
    estimated_e_inf_u: Option<f64>,
    estimated_e_inf_sigma: Option<f64>,
    /// `e_inf` of this level's field against the next finer level's (filled in when
    /// that level finishes).
    difference_e_inf_u: Option<f64>,
    difference_e_inf_sigma: Option<f64>,
    order_difference_u: Option<f64>,
    order_difference_sigma: Option<f64>,
    /// The probes' values, in scene order.
    probes: Vec<f64>,
    seconds: f64,
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

/// What a level keeps for the difference to the next one.
struct LevelFields {
    positions: Vec<Point>,
    displacement: Vec<[f64; 2]>,
    stress: Option<Vec<[f64; 3]>>,
    /// Nodes farther than the singular-corner radius from every singular corner.
    regular: Vec<bool>,
}

/// Run the study of `p` over `levels` halvings and write its tables into `dir`.
pub(super) fn run(p: &Problem, levels: usize, dir: &Path, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    if p.case.dynamics.is_some() {
        return Err(AppError::Usage(format!(
            "{}: convergence studies the static solve; remove the [dynamics] table to study the static problem",
            p.source.display()
        )));
    }
    if levels > 8 {
        return Err(AppError::Usage(format!("--levels {levels}: at most 8 halvings (each multiplies the node count by 4)")));
    }
    if levels == 0 {
        return Err(AppError::Usage("--levels 0: a study needs at least one halving (two levels)".into()));
    }
    let mut p = p.clone();
    let mut notes = Vec::new();
    if p.case.exact.is_none() && !p.navier.estimate.method.static_navier_estimates() {
        p.navier.estimate.method = EstimateMethod::Auto;
        notes.push("the scene has no exact solution: the error estimate is switched on (estimate.method = \"auto\")".to_string());
    }
    if !quiet {
        for n in &notes {
            eprintln!("note: {n}");
        }
    }
    // Refuse an unaffordable finest level before solving the coarse ones, and at once:
    // its node count is the first level's times 4 per halving (the whole spacing field
    // is scaled), not integrated again at the finest spacing (16 s on the Kirsch plate
    // at --levels 5, before the refusal). Its node-count range is checked after that.
    let factor = 2f64.powi(levels as i32);
    let mut finest = p.clone();
    finest.navier.fill = p.navier.fill.scaled(1.0 / factor);
    let first = p.expected_nodes();
    crate::models::resources::check_navier_nodes(&finest, first * factor * factor)?;
    p.with_spacing(p.navier.fill.spacing / factor)?;
    let staged = StagedDir::create(dir, convergence_owns)?;
    let staged_dir = staged.path().to_path_buf();
    let t0 = Instant::now();
    let area = p.case.domain.area_estimate(400);
    let mut rows: Vec<Level> = Vec::new();
    let mut coarser: Option<LevelFields> = None;
    let mut table = None;
    for k in 0..=levels {
        let (level, fields) = match solve_level(&p, (k, levels), rows.last(), area, term, quiet) {
            Ok(done) => done,
            Err(e) => {
                // The finished levels are the study's result: they replace the earlier one.
                if !rows.is_empty() && staged.commit().is_ok() {
                    eprintln!("level {k} failed; the {} finished level(s) are in {}", rows.len(), dir.join("convergence.csv").display());
                }
                return Err(e);
            }
        };
        if let (Some(c), Some(before)) = (&coarser, rows.last_mut()) {
            let (du, ds) = difference(c, &fields)?;
            before.difference_e_inf_u = Some(du);
            before.difference_e_inf_sigma = ds;
            let n = rows.len();
            if n >= 2 {
                let (a, b) = (&rows[n - 2], &rows[n - 1]);
                let (order_u, order_s) = (
                    order(a.h, b.h, a.difference_e_inf_u, b.difference_e_inf_u),
                    order(a.h, b.h, a.difference_e_inf_sigma, b.difference_e_inf_sigma),
                );
                rows[n - 1].order_difference_u = order_u;
                rows[n - 1].order_difference_sigma = order_s;
            }
        }
        if k == 0 && fields.regular.iter().any(|r| !r) {
            let note = singular_estimate_note("the estimated e_inf(u) counts");
            if !quiet {
                eprintln!("note: {note}");
            }
            notes.push(note);
        }
        rows.push(level);
        coarser = Some(fields);
        table = Some(write_tables(&p, &rows, (levels + 1, &notes), (&staged_dir, dir), t0)?);
    }
    staged.commit()?;
    let written = table.expect("at least two levels");
    if !quiet {
        print!("{}", written.table);
        if let Some(n) = written.plot_note {
            eprintln!("note: {n}");
        }
    }
    // Also under --quiet: a doubtful study is never silent.
    for w in &written.warnings {
        eprintln!("warning [estimate]: {w}");
    }
    Ok(())
}

/// What [`write_tables`] wrote, for the terminal once the study is in place.
struct Written {
    /// The table as printed.
    table: String,
    /// The plot's note (no system font for the PNG).
    plot_note: Option<String>,
    /// The study's warnings.
    warnings: Vec<String>,
}

/// Whether `name` is a file `convergence` writes: a new study replaces those of the
/// earlier one and keeps anything else in the folder (a run's results, the user's files).
fn convergence_owns(name: &OsStr) -> bool {
    FILES.split(", ").any(|f| name == f)
}

/// `ln(a / b) / ln(h_a / h_b)` for two positive values.
fn order(h_a: f64, h_b: f64, a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if a > 0.0 && b > 0.0 => Some((a / b).ln() / (h_a / h_b).ln()),
        _ => None,
    }
}

/// `e_inf` of the coarse level's displacement (and stress, at its regular nodes)
/// against the fine level's, interpolated at the coarse nodes.
fn difference(coarse: &LevelFields, fine: &LevelFields) -> Result<(f64, Option<f64>), AppError> {
    let shape = |e| AppError::Run(RunError::Shape(e));
    let u = mls_values(&fine.positions, &fine.displacement, &coarse.positions).map_err(shape)?;
    let (du, _) = relative_errors(&coarse.displacement, &u);
    let ds = match (&coarse.stress, &fine.stress) {
        (Some(cs), Some(fs)) => {
            let s = mls_values(&fine.positions, fs, &coarse.positions).map_err(shape)?;
            let keep = |v: &[[f64; 3]]| -> Vec<[f64; 3]> { v.iter().zip(&coarse.regular).filter(|(_, r)| **r).map(|(x, _)| *x).collect() };
            Some(relative_errors(&keep(cs), &keep(&s)).0)
        }
        _ => None,
    };
    Ok((du, ds))
}

/// Write `convergence.csv` and `convergence.json` for the levels finished so far into
/// `dir`; returns the table as printed (naming the result folder `target`), the plot's
/// note and the study's warnings.
fn write_tables(
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
) -> Result<(Level, LevelFields), AppError> {
    let spacing = p.navier.fill.spacing / 2f64.powi(k as i32);
    if !quiet {
        eprintln!("level {k} ({} of {}): spacing {spacing:.4e}", k + 1, last + 1);
    }
    let t0 = Instant::now();
    let q = p.with_spacing(spacing)?;
    let sol = navier::solve(&q.case, &q.navier, term)?;
    let h = (area / sol.nodes.len() as f64).sqrt();
    let e = sol.errors;
    let exact_order = |prev: Option<f64>, cur: Option<f64>| order(before?.h, h, prev, cur);
    let corners = singular_corners(&q.case, &sol.nodes);
    let regular = sol.nodes.positions.iter().map(|x| !corners.iter().any(|c| c.covers(*x))).collect();
    let level = Level {
        nodes: sol.nodes.len(),
        h,
        spacing,
        e_inf_u: e.map(|e| e.e_inf_u),
        e_inf_sigma: e.and_then(|e| e.e_inf_sigma),
        rel_l2_u: e.map(|e| e.rel_l2_u),
        order_e_inf_u: exact_order(before.and_then(|r| r.e_inf_u), e.map(|e| e.e_inf_u)),
        order_e_inf_sigma: exact_order(before.and_then(|r| r.e_inf_sigma), e.and_then(|e| e.e_inf_sigma)),
        estimated_e_inf_u: sol.estimate.done().map(|x| x.norms.e_inf_u * displacement_estimate_factor(&corners)),
        estimated_e_inf_sigma: sol.estimate.done().and_then(|x| x.norms.e_inf_sigma),
        difference_e_inf_u: None,
        difference_e_inf_sigma: None,
        order_difference_u: None,
        order_difference_sigma: None,
        probes: sol.probes.iter().map(|v| v.value).collect(),
        seconds: t0.elapsed().as_secs_f64(),
    };
    let fields =
        LevelFields { stress: sol.stress.map(|s| s.sigma), positions: sol.nodes.positions, displacement: sol.displacement, regular };
    Ok((level, fields))
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
