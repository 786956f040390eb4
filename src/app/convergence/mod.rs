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

mod table;

use super::terminal::Terminal;
use super::AppError;
use crate::domain::Point;
use crate::mlsm::interpolate::mls_values;
use crate::models::navier::{self, EstimateMethod};
use crate::output::StagedDir;
use crate::quality::post::relative_errors;
use crate::quality::warnings::{displacement_estimate_factor, singular_corners, singular_estimate_note};
use crate::scene::problem::Problem;
use crate::stages::RunError;
use std::path::Path;
use std::time::Instant;
use table::{convergence_owns, write_tables, Level};

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
