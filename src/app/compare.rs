//! `mlsm compare`: peridynamics at a sequence of horizons (fixed m = delta / h) against
//! the local solution; tables (CSV, JSON), a log-log plot (SVG) and one .vtu per run.

use super::{create_dir, scalar, vector, write_points_vtu, AppError, Terminal};
use crate::compare::LocalReference;
use crate::output::{self, FieldValues, PointField, Series};
use crate::peridynamics::solve::interior_flags;
use crate::peridynamics::{PdParams, Quadrature};
use crate::post::{masked_errors, observed_order};
use crate::problem::Problem;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

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
    seconds: f64,
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
    scene: &'a str,
    reference: String,
    m: f64,
    kernel: String,
    correction: crate::peridynamics::SurfaceCorrection,
    rows: Vec<Row>,
    orders: Vec<Orders>,
}

/// One peridynamic run of a comparison: the static solve, or the state at `end_time`.
struct PdResult {
    positions: Vec<[f64; 2]>,
    displacement: Vec<[f64; 2]>,
    interior: Vec<bool>,
    bonds: usize,
    /// Solver iterations (static) or time steps (dynamic).
    iterations: usize,
}

impl PdResult {
    fn solve(problem: &Problem, params: &PdParams, term: &Terminal) -> Result<PdResult, AppError> {
        if problem.dynamics.is_some() {
            let sim = crate::peridynamics::dynamics::simulate(problem, params, term, |_, _, _, _, _| Ok::<(), AppError>(()))
                .map_err(super::dynamics::app_error)?;
            let nodes = &sim.discretisation.nodes;
            let positions = nodes.positions[..nodes.free].to_vec();
            let interior = interior_flags(&problem.domain, &positions, params.horizon);
            return Ok(PdResult {
                positions,
                displacement: sim.u,
                interior,
                bonds: sim.discretisation.families.bonds(),
                iterations: sim.report.steps,
            });
        }
        let sol = crate::peridynamics::solve::solve(problem, params, term)?;
        Ok(PdResult {
            positions: sol.nodes.positions[..sol.nodes.free].to_vec(),
            displacement: sol.displacement[..sol.nodes.free].to_vec(),
            interior: sol.interior,
            bonds: sol.bonds,
            iterations: sol.solver.iterations,
        })
    }
}

pub(super) fn compare(p: &Problem, req: CompareRequest, dir: &Path, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    let Some(base) = p.peridynamics else {
        return Err(AppError::Usage(format!("{}: compare needs a [peridynamics] table (horizon, quadrature, ...)", p.source.display())));
    };
    let quadratures: Vec<Quadrature> = match &req.quadratures {
        None => vec![base.quadrature],
        Some(names) => names
            .iter()
            .map(|n| {
                Quadrature::ALL.iter().find(|(k, _)| k == n).map(|(_, q)| *q).ok_or_else(|| {
                    let known: Vec<&str> = Quadrature::ALL.iter().map(|(k, _)| *k).collect();
                    AppError::Usage(format!("--quadratures: unknown rule \"{n}\" (expected one of {})", known.join(", ")))
                })
            })
            .collect::<Result<_, _>>()?,
    };
    if req.levels > 6 && req.deltas.is_none() {
        return Err(AppError::Usage(format!("--levels {}: at most 6 halvings (each multiplies the node count by 4)", req.levels)));
    }
    let deltas: Vec<f64> = req.deltas.clone().unwrap_or_else(|| (0..=req.levels).map(|k| base.horizon / 2f64.powi(k as i32)).collect());
    if deltas.len() < 2 {
        return Err(AppError::Usage("compare needs at least two horizons to measure an order".into()));
    }
    let m = req.m.unwrap_or(base.ratio);
    // Every run is checked before the first solve.
    let mut runs = Vec::new();
    for &q in &quadratures {
        for &delta in &deltas {
            let params = PdParams { horizon: delta, ratio: m, quadrature: q, ..base };
            runs.push((p.with_peridynamics(params)?, params));
        }
    }
    let reference_problem = match req.reference_spacing {
        Some(h) if p.exact.is_none() => p.with_spacing(h)?,
        _ => p.clone(),
    };
    create_dir(dir)?;
    if !quiet {
        eprintln!("{}: local reference", p.name);
    }
    let reference = LocalReference::build(&reference_problem, term)?;
    let mut rows = Vec::new();
    for (k, (problem, params)) in runs.iter().enumerate() {
        if !quiet {
            eprintln!("{} delta = {:.4e} (h = {:.4e})", params.quadrature.name(), params.horizon, params.spacing());
        }
        let t0 = Instant::now();
        let sol = PdResult::solve(problem, params, term)?;
        let free = &sol.positions[..];
        let local = reference.displacement_at(free)?;
        let whole = masked_errors(&sol.displacement, &local, |_| true).expect("free nodes exist");
        let interior = masked_errors(&sol.displacement, &local, |i| sol.interior[i]);
        let name = format!("{}_delta{}.vtu", params.quadrature.name(), k % deltas.len());
        let diff: Vec<[f64; 2]> = sol.displacement.iter().zip(&local).map(|(a, b)| [a[0] - b[0], a[1] - b[1]]).collect();
        let fields = vec![
            vector("peridynamic_displacement", sol.displacement.iter().copied()),
            vector("local_displacement", local.iter().copied()),
            vector("difference", diff.iter().copied()),
            scalar("difference_magnitude", diff.iter().map(|d| d[0].hypot(d[1]))),
            PointField {
                name: "interior".into(),
                components: 1,
                values: FieldValues::I32(sol.interior.iter().map(|&b| b as i32).collect()),
            },
        ];
        write_points_vtu(&dir.join(&name), free, &p.domain, &fields)?;
        let interior = interior.ok_or_else(|| {
            AppError::Usage(format!(
                "delta = {}: no node lies at distance >= delta from the boundary; use smaller horizons",
                params.horizon
            ))
        })?;
        rows.push(Row {
            quadrature: params.quadrature.name(),
            delta: params.horizon,
            h: params.spacing(),
            nodes: sol.positions.len(),
            interior_nodes: sol.interior.iter().filter(|&&b| b).count(),
            bonds: sol.bonds,
            e_inf_interior: interior.e_inf_u,
            rel_l2_interior: interior.rel_l2_u,
            e_inf_whole: whole.e_inf_u,
            rel_l2_whole: whole.rel_l2_u,
            solver_iterations: sol.iterations,
            seconds: t0.elapsed().as_secs_f64(),
            vtu: name,
        });
    }
    let orders: Vec<Orders> = quadratures
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
        .collect();
    let table = Table {
        scene: &p.name,
        reference: reference.describe(),
        m,
        kernel: base.kernel.label(),
        correction: base.correction,
        rows,
        orders,
    };
    write_tables(&table, dir)?;
    if !quiet {
        print_table(&table, dir);
    }
    Ok(())
}

fn write_tables(t: &Table, dir: &Path) -> Result<(), AppError> {
    output::write_json(&dir.join("compare.json"), t)?;
    let mut series = Vec::new();
    for o in &t.orders {
        let r: Vec<&Row> = t.rows.iter().filter(|r| r.quadrature == o.quadrature).collect();
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
                ]
            })
            .collect();
        output::write_csv(
            &dir.join(format!("compare_{}.csv", o.quadrature)),
            &["delta", "h", "nodes", "interior_nodes", "e_inf_interior", "rel_l2_interior", "e_inf_whole", "rel_l2_whole", "seconds"],
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
    output::write_loglog_svg(
        &dir.join("compare.svg"),
        &format!("{}: peridynamics vs local, m = {}, kernel {}", t.scene, t.m, t.kernel),
        "horizon delta (m)",
        "max |u_PD - u_local| / max |u_local|",
        &series,
    )?;
    Ok(())
}

fn print_table(t: &Table, dir: &Path) {
    println!("reference: {}; m = {}, kernel {}", t.reference, t.m, t.kernel);
    println!(
        "{:<13} {:>10} {:>8} {:>11} {:>11} {:>11} {:>11} {:>8}",
        "quadrature", "delta", "nodes", "einf_int", "l2_int", "einf_all", "l2_all", "seconds"
    );
    for r in &t.rows {
        println!(
            "{:<13} {:>10.4e} {:>8} {:>11.3e} {:>11.3e} {:>11.3e} {:>11.3e} {:>8.2}",
            r.quadrature, r.delta, r.nodes, r.e_inf_interior, r.rel_l2_interior, r.e_inf_whole, r.rel_l2_whole, r.seconds
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
