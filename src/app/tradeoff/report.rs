//! The results of a sweep: fronts, cheapest configuration per accuracy decade, the
//! CSV, JSON and plot files, and the terminal table.

use super::{Field, Row, Status};
use crate::app::AppError;
use crate::output::{self, FrontPanel, OutputError, PointGroup};
use crate::scene::problem::Problem;
use crate::tradeoff::design::Sweep;
use crate::tradeoff::front::pareto_front;
use crate::tradeoff::variant::Setting;
use serde::Serialize;
use std::path::Path;
use std::time::{Duration, Instant};

/// One family and why it stopped.
#[derive(Serialize)]
struct FamilyLine {
    name: String,
    /// `null` for the scene's own setting.
    basis: Option<&'static str>,
    degree: Option<u32>,
    support: Option<usize>,
    solver: Option<&'static str>,
    runs: usize,
    stopped: Option<String>,
}

/// The cheapest finished configuration whose error is at most `bound`.
#[derive(Serialize)]
struct Advice {
    bound: f64,
    id: String,
    family: String,
    seconds: f64,
    nodes: u64,
    error: f64,
    exact: bool,
    snippet: String,
}

/// Everything `tradeoff.json` holds.
#[derive(Serialize)]
pub(super) struct Summary {
    scene: String,
    source: String,
    version: &'static str,
    budget_s: f64,
    elapsed_s: f64,
    /// `exact` when the fronts are drawn on errors against the scene's exact solution,
    /// `estimated` when on the runs' own estimates.
    front_error: &'static str,
    available_memory_bytes: Option<f64>,
    families: Vec<FamilyLine>,
    runs: Vec<Row>,
    /// Ids of the runs on the front of seconds against e_inf(sigma) and e_inf(u).
    front_sigma: Vec<String>,
    front_u: Vec<String>,
    /// Per decade of e_inf(sigma) (of u where no stress is computed).
    advice_field: &'static str,
    advice: Vec<Advice>,
    notes: Vec<String>,
}

/// Ids of the finished runs on the front of seconds against `field`, after marking them.
fn mark_front(rows: &mut [Row], field: Field) -> Vec<String> {
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| match (r.trusted(), r.seconds, r.error(field)) {
            (true, Some(t), Some((e, _))) => (t, e),
            _ => (f64::NAN, f64::NAN),
        })
        .collect();
    let front = pareto_front(&points);
    for &i in &front {
        match field {
            Field::Sigma => rows[i].on_front_sigma = true,
            Field::U => rows[i].on_front_u = true,
        }
    }
    front.iter().map(|&i| rows[i].id.clone()).collect()
}

/// The cheapest run at or below each power of ten of `field`'s error, from the decade
/// of the largest error down to that of the smallest (one entry per distinct run).
fn advice(rows: &[Row], field: Field) -> Vec<Advice> {
    let done: Vec<(&Row, f64, f64, bool)> = rows
        .iter()
        .filter_map(|r| Some((r, r.seconds?, r.error(field)?.0, r.error(field)?.1)))
        .filter(|x| x.0.trusted() && x.2 > 0.0)
        .collect();
    let Some(hi) = done.iter().map(|x| x.2).reduce(f64::max) else { return Vec::new() };
    let lo = done.iter().map(|x| x.2).fold(f64::INFINITY, f64::min);
    let mut out: Vec<Advice> = Vec::new();
    let mut k = hi.log10().ceil() as i32;
    while 10f64.powi(k) >= lo {
        let bound = 10f64.powi(k);
        if let Some((r, t, e, exact)) = done.iter().filter(|x| x.2 <= bound).min_by(|a, b| a.1.total_cmp(&b.1)) {
            if out.last().is_some_and(|a| a.id == r.id) {
                out.last_mut().expect("checked").bound = bound;
            } else {
                let snippet = r.snippet.clone();
                out.push(Advice {
                    bound,
                    id: r.id.clone(),
                    family: r.family.clone(),
                    seconds: *t,
                    nodes: r.nodes.unwrap_or(0),
                    error: *e,
                    exact: *exact,
                    snippet,
                });
            }
        }
        k -= 1;
    }
    out
}

impl Summary {
    /// The summary of a finished sweep: fronts marked, advice chosen.
    pub(super) fn new(
        p: &Problem,
        budget: Duration,
        mut runs: Vec<Row>,
        families: &[(String, Option<Setting>)],
        sweep: &Sweep,
        notes: Vec<String>,
        start: Instant,
    ) -> Self {
        let front_sigma = mark_front(&mut runs, Field::Sigma);
        let front_u = mark_front(&mut runs, Field::U);
        let field = if runs.iter().any(|r| r.error(Field::Sigma).is_some()) { Field::Sigma } else { Field::U };
        let advice = advice(&runs, field);
        let families = families
            .iter()
            .zip(&sweep.families)
            .map(|((name, s), state)| FamilyLine {
                name: name.clone(),
                basis: s.as_ref().map(|s| s.basis),
                degree: s.as_ref().map(|s| s.degree),
                support: s.as_ref().and_then(|s| s.support),
                solver: s.as_ref().and_then(|s| s.solver),
                runs: state.runs.len(),
                stopped: state.stopped.clone(),
            })
            .collect();
        Summary {
            scene: p.name.clone(),
            source: p.source.display().to_string(),
            version: env!("CARGO_PKG_VERSION"),
            budget_s: budget.as_secs_f64(),
            elapsed_s: start.elapsed().as_secs_f64(),
            front_error: if p.case.exact.is_some() { "exact" } else { "estimated" },
            available_memory_bytes: output::available_memory_bytes(),
            families,
            runs,
            front_sigma,
            front_u,
            advice_field: if field == Field::Sigma { "e_inf_sigma" } else { "e_inf_u" },
            advice,
            notes,
        }
    }

    /// Write `tradeoff.csv`, `tradeoff.json`, `tradeoff.svg` and `tradeoff.png` into `dir`.
    pub(super) fn write(&mut self, dir: &Path) -> Result<(), AppError> {
        write_csv(&dir.join("tradeoff.csv"), &self.runs)?;
        let panels: Vec<FrontPanel> = [(Field::Sigma, "e_inf(sigma)"), (Field::U, "e_inf(u)")]
            .into_iter()
            .filter(|(f, _)| self.runs.iter().any(|r| r.error(*f).is_some()))
            .map(|(f, name)| self.panel(f, name))
            .collect();
        if !panels.is_empty() {
            let title = format!("{}: seconds against error (filled: exact, hollow: estimated)", self.scene);
            if let Some(n) = output::write_front_plot(&dir.join("tradeoff.svg"), &dir.join("tradeoff.png"), &title, &panels)? {
                self.notes.push(n);
            }
        }
        output::write_json(&dir.join("tradeoff.json"), self)?;
        Ok(())
    }

    /// One panel: a point group per family, the front on the front's error.
    fn panel(&self, field: Field, name: &str) -> FrontPanel {
        let mut groups: Vec<PointGroup> = Vec::new();
        for fam in &self.families {
            let runs = self.runs.iter().filter(|r| r.family == fam.name && r.status == Status::Ok);
            let mut g = PointGroup { label: fam.name.clone(), exact: Vec::new(), estimated: Vec::new() };
            for r in runs {
                let Some(t) = r.seconds else { continue };
                if let Some(e) = r.exact.and_then(|n| n.e_inf(field)) {
                    g.exact.push((t, e));
                }
                if let Some(e) = r.estimated.and_then(|n| n.e_inf(field)) {
                    g.estimated.push((t, e));
                }
            }
            groups.push(g);
        }
        let on = |r: &&Row| if field == Field::Sigma { r.on_front_sigma } else { r.on_front_u };
        let front = self.runs.iter().filter(on).filter_map(|r| Some((r.seconds?, r.error(field)?.0))).collect();
        FrontPanel {
            title: format!("seconds against {name}"),
            x_label: "seconds (run without its estimate)".into(),
            y_label: name.into(),
            groups,
            front,
        }
    }

    /// The table, the families' ends and the advice, on the terminal.
    pub(super) fn print(&self, dir: &Path) {
        println!(
            "{:<4} {:<28} {:>10} {:>8} {:>8} {:>8} {:>10} {:>10} {:>10} {:>10}  front",
            "id", "family", "spacing", "nodes", "seconds", "peak MB", "e_inf(u)", "est.", "e_inf(sig)", "est."
        );
        let e = |n: &Option<super::Norms>, f: Field| n.and_then(|n| n.e_inf(f)).map_or("-".into(), |v| format!("{v:.2e}"));
        for r in self.runs.iter().filter(|r| r.status == Status::Ok) {
            let mark = match (r.on_front_sigma, r.on_front_u) {
                (true, true) => "sigma, u",
                (true, false) => "sigma",
                (false, true) => "u",
                _ if !r.trusted() => "(doubtful solve: off the fronts)",
                _ => "",
            };
            println!(
                "{:<4} {:<28} {:>10.3e} {:>8} {:>8.3} {:>8.0} {:>10} {:>10} {:>10} {:>10}  {mark}",
                r.id,
                r.family,
                r.spacing,
                r.nodes.unwrap_or(0),
                r.seconds.unwrap_or(f64::NAN),
                r.peak_memory_bytes.unwrap_or(f64::NAN) / 1e6,
                e(&r.exact, Field::U),
                e(&r.estimated, Field::U),
                e(&r.exact, Field::Sigma),
                e(&r.estimated, Field::Sigma),
            );
        }
        for r in self.runs.iter().filter(|r| r.status != Status::Ok) {
            println!("{:<4} {:<28} {:>10.3e}  {:?}: {}", r.id, r.family, r.spacing, r.status, r.reason.as_deref().unwrap_or(""));
        }
        for f in &self.families {
            println!("family \"{}\": {} run(s), stopped: {}", f.name, f.runs, f.stopped.as_deref().unwrap_or("-"));
        }
        println!("\ncheapest configuration per decade of {} ({} errors):", self.advice_field, self.front_error);
        for a in &self.advice {
            println!(
                "# {} <= {:.0e}: {} \"{}\", {:.3} s, {} nodes, {} {:.2e}",
                self.advice_field,
                a.bound,
                a.id,
                a.family,
                a.seconds,
                a.nodes,
                if a.exact { "exact" } else { "estimated" },
                a.error
            );
            print!("{}", a.snippet);
            println!();
        }
        for n in &self.notes {
            println!("note: {n}");
        }
        // The plot only when a run finished (a budget that ended the first run has none).
        let written: Vec<&str> =
            ["tradeoff.csv", "tradeoff.json", "tradeoff.svg", "tradeoff.png"].into_iter().filter(|f| dir.join(f).exists()).collect();
        println!("written: {} ({})", dir.display(), written.join(", "));
    }
}

/// `tradeoff.csv`: one line per configuration, empty cells for what it has not.
fn write_csv(path: &Path, rows: &[Row]) -> Result<(), AppError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let header = [
        "id",
        "family",
        "level",
        "spacing",
        "status",
        "nodes",
        "seconds",
        "estimate_seconds",
        "wall_seconds",
        "peak_memory_mb",
        "estimated_peak_memory_mb",
        "e_inf_u",
        "e_inf_sigma",
        "rel_l2_u",
        "rel_l2_sigma",
        "estimated_e_inf_u",
        "estimated_e_inf_sigma",
        "front_sigma",
        "front_u",
        "warnings",
        "reason",
    ];
    let bad = |e: csv::Error| AppError::Output(OutputError::invalid(path, e.to_string()));
    w.write_record(header).map_err(bad)?;
    let num = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    for r in rows {
        let (x, s) = (r.exact, r.estimated);
        w.write_record([
            r.id.clone(),
            r.family.clone(),
            r.level.to_string(),
            format!("{:e}", r.spacing),
            format!("{:?}", r.status).to_lowercase(),
            r.nodes.map_or(String::new(), |n| n.to_string()),
            num(r.seconds),
            num(r.estimate_seconds),
            num(r.wall_seconds),
            num(r.peak_memory_bytes.map(|b| b / 1e6)),
            format!("{:.1}", r.estimated_peak_memory_bytes / 1e6),
            num(x.map(|n| n.e_inf_u)),
            num(x.and_then(|n| n.e_inf_sigma)),
            num(x.map(|n| n.rel_l2_u)),
            num(x.and_then(|n| n.rel_l2_sigma)),
            num(s.map(|n| n.e_inf_u)),
            num(s.and_then(|n| n.e_inf_sigma)),
            r.on_front_sigma.to_string(),
            r.on_front_u.to_string(),
            r.warnings.join(" "),
            r.reason.clone().unwrap_or_default(),
        ])
        .map_err(bad)?;
    }
    let bytes = w.into_inner().map_err(|e| AppError::Output(OutputError::invalid(path, e.to_string())))?;
    output::write_atomic(path, &bytes)?;
    Ok(())
}

/// One line per configuration while the sweep runs.
pub(super) fn progress_line(r: &Row, elapsed: f64) -> String {
    let head = format!("[{elapsed:6.1} s] {} {} h = {:.3e}", r.id, r.family, r.spacing);
    match r.status {
        Status::Ok => {
            let err = |f: Field, name: &str| {
                r.error(f).map_or(String::new(), |(e, exact)| format!(", {name} {e:.2e}{}", if exact { "" } else { " (est.)" }))
            };
            format!(
                "{head}: {} nodes, {:.2} s{}{}",
                r.nodes.unwrap_or(0),
                r.seconds.unwrap_or(f64::NAN),
                err(Field::U, "e_inf(u)"),
                err(Field::Sigma, "e_inf(sigma)")
            )
        }
        s => format!("{head}: {s:?}: {}", r.reason.as_deref().unwrap_or("")),
    }
}

#[cfg(test)]
mod tests {
    use super::super::Norms;
    use super::*;

    fn row(id: &str, seconds: f64, e_sigma: f64, warnings: &[&str]) -> Row {
        Row {
            id: id.into(),
            seconds: Some(seconds),
            exact: Some(Norms { e_inf_u: e_sigma, e_inf_sigma: Some(e_sigma), rel_l2_u: e_sigma, rel_l2_sigma: Some(e_sigma) }),
            warnings: warnings.iter().map(|w| w.to_string()).collect(),
            ..Row::default()
        }
    }

    /// A run whose solve is in doubt is neither on a front nor recommended, however
    /// good its numbers look; an error-threshold warning does not exclude a run.
    #[test]
    fn doubtful_solves_stay_off_the_front_and_the_advice() {
        let mut rows = vec![row("a", 1.0, 1e-3, &[]), row("b", 0.5, 1e-5, &["residual"]), row("c", 0.1, 2e-2, &["estimate"])];
        assert_eq!(mark_front(&mut rows, Field::Sigma), ["c", "a"]);
        assert!(!rows[1].on_front_sigma);
        let advice = advice(&rows, Field::Sigma);
        assert!(advice.iter().all(|a| a.id != "b"));
        assert_eq!(advice.last().map(|a| (a.id.as_str(), a.bound)), Some(("a", 1e-3)));
    }
}
