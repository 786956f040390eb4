//! Orchestration of the commands; the only module that prints.

mod compare;
mod dynamics;
mod peridynamics;

use crate::cli::{Cli, Command, ModelArg};
use crate::elasticity::conditions::ComponentEquation;
use crate::output::{self, FieldValues, OutputError, PointField};
use crate::peridynamics::PdParams;
use crate::post::{observed_order, ErrorNorms};
use crate::problem::Model;
use crate::problem::{Problem, ProblemError};
use crate::run::{self, Progress, RunError, Solution, Stage};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Any failure of a command, with its exit code.
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// Invalid scene (exit 2).
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// Numerical failure (exit 3).
    #[error(transparent)]
    Run(#[from] RunError),
    /// Writing results failed (exit 1).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Invalid command-line use (exit 2).
    #[error("{0}")]
    Usage(String),
}

impl AppError {
    /// Process exit code: 2 invalid input (a fixed time step above the stability limit
    /// included), 3 solver failure, 1 anything else.
    pub fn exit_code(&self) -> u8 {
        match self {
            AppError::Problem(_) | AppError::Usage(_) | AppError::Run(RunError::UnstableTimeStep { .. }) => 2,
            AppError::Run(_) => 3,
            AppError::Output(_) => 1,
        }
    }
}

/// Stage progress on the terminal: a spinner per stage, then one line with its time.
struct Terminal {
    quiet: bool,
    bar: Mutex<Option<ProgressBar>>,
}

impl Progress for Terminal {
    fn start(&self, stage: Stage) {
        if self.quiet {
            return;
        }
        let bar = if stage == Stage::Integrate {
            let bar = ProgressBar::new(0);
            bar.set_style(ProgressStyle::with_template("  {msg} [{bar:30}] {pos}/{len} steps ({elapsed}, ETA {eta})").unwrap());
            bar
        } else {
            let bar = ProgressBar::new_spinner();
            bar.set_style(ProgressStyle::with_template("  {spinner} {msg} ({elapsed})").unwrap());
            bar
        };
        bar.set_message(stage.name());
        bar.enable_steady_tick(Duration::from_millis(120));
        *self.bar.lock().unwrap() = Some(bar);
    }

    fn advance(&self, done: u64, total: u64) {
        if let Some(bar) = self.bar.lock().unwrap().as_ref() {
            bar.set_length(total);
            bar.set_position(done);
        }
    }

    fn finish(&self, stage: Stage, seconds: f64, note: &str) {
        if let Some(bar) = self.bar.lock().unwrap().take() {
            bar.finish_and_clear();
        }
        if !self.quiet {
            eprintln!("  {:<9} {:>9.3} s  {}", stage.name(), seconds, note);
        }
    }
}

/// Run the command of `cli`.
pub fn run(cli: &Cli) -> Result<(), AppError> {
    let term = Terminal { quiet: cli.quiet, bar: Mutex::new(None) };
    match &cli.command {
        Command::Check { scene } => {
            let p = Problem::from_file(scene)?;
            if !cli.quiet {
                println!("{}: valid", scene.display());
                println!("  boundary parts: {}", p.domain.parts.join(", "));
                println!(
                    "  spacing {:.4e} ({:?} fill), support {}, {}",
                    p.fill.spacing,
                    p.fill.kind,
                    p.approximation.support,
                    p.approximation.basis.describe()
                );
                if let Some(d) = &p.dynamics {
                    println!(
                        "  dynamics: rho {:.4e}, t_end {:.4e} s, {}, step {}",
                        d.density,
                        d.end_time,
                        d.integrator.name(),
                        d.time_step.map_or(format!("{} of the stable step", d.safety), |dt| format!("{dt:.4e} s"))
                    );
                }
                if let Some(pd) = &p.peridynamics {
                    println!(
                        "  peridynamics: horizon {:.4e}, m = {}, h = {:.4e}, {} nodes per cell, quadrature {}, kernel {}",
                        pd.horizon,
                        pd.ratio,
                        pd.spacing(),
                        pd.nodes_per_cell(),
                        pd.quadrature.name(),
                        pd.kernel.label()
                    );
                }
            }
            Ok(())
        }
        Command::Run { scene, out, spacing, model, horizon } => {
            let mut p = Problem::from_file(scene)?;
            if let Some(m) = model {
                p.model = match m {
                    ModelArg::Navier => Model::Navier,
                    ModelArg::Peridynamics => Model::Peridynamics,
                };
            }
            if let (Model::Peridynamics, Some(_), Some(params)) = (p.model, p.dynamics, p.peridynamics) {
                if spacing.is_some() {
                    return Err(AppError::Usage(
                        "--spacing sets the MLSM node spacing; for peridynamics use --horizon (h = delta / m)".into(),
                    ));
                }
                let params = match *horizon {
                    Some(d) => {
                        p = p.with_peridynamics(PdParams { horizon: d, ..params })?;
                        p.peridynamics.expect("just set")
                    }
                    None => params,
                };
                let dir = out.clone().unwrap_or_else(|| default_out(&p));
                return dynamics::run_pd_dynamic(&p, &params, &dir, &term, cli.quiet);
            }
            if let (Model::Navier, Some(_)) = (p.model, p.dynamics) {
                if let Some(h) = *spacing {
                    p = p.with_spacing(h)?;
                }
                let dir = out.clone().unwrap_or_else(|| default_out(&p));
                return dynamics::run_navier_dynamic(&p, &dir, &term, cli.quiet);
            }
            if p.model == Model::Peridynamics {
                let Some(mut params) = p.peridynamics else {
                    return Err(AppError::Usage(format!("{}: the peridynamic model needs a [peridynamics] table", scene.display())));
                };
                if spacing.is_some() {
                    return Err(AppError::Usage(
                        "--spacing sets the MLSM node spacing; for peridynamics use --horizon (h = delta / m)".into(),
                    ));
                }
                if let Some(d) = *horizon {
                    params.horizon = d;
                    p = p.with_peridynamics(params)?;
                }
                let dir = out.clone().unwrap_or_else(|| default_out(&p));
                if !cli.quiet {
                    eprintln!("{}: solving (peridynamics, {})", p.name, params.quadrature.name());
                }
                let t0 = Instant::now();
                let mut sol = crate::peridynamics::solve::solve(&p, &params, &term)?;
                let t_out = Instant::now();
                peridynamics::write_pd_run(&p, &mut sol, &dir, t0)?;
                if !cli.quiet {
                    eprintln!("  {:<9} {:>9.3} s  {}", "output", t_out.elapsed().as_secs_f64(), dir.display());
                    peridynamics::print_pd_result(&sol);
                }
                return Ok(());
            }
            if horizon.is_some() {
                return Err(AppError::Usage("--horizon belongs to the peridynamic model (--model peridynamics)".into()));
            }
            if let Some(h) = *spacing {
                p = p.with_spacing(h)?;
            }
            let dir = out.clone().unwrap_or_else(|| default_out(&p));
            if !cli.quiet {
                eprintln!("{}: solving", p.name);
            }
            let t0 = Instant::now();
            let mut sol = run::solve(&p, &term)?;
            let t_out = Instant::now();
            write_run(&p, &mut sol, &dir, t0)?;
            if !cli.quiet {
                eprintln!("  {:<9} {:>9.3} s  {}", "output", t_out.elapsed().as_secs_f64(), dir.display());
                print_result(&sol);
            }
            Ok(())
        }
        Command::Compare { scene, m, deltas, levels, quadratures, reference_spacing, out } => {
            let p = Problem::from_file(scene)?;
            let dir = out.clone().unwrap_or_else(|| default_out(&p).join("compare"));
            let req = compare::CompareRequest {
                m: *m,
                deltas: deltas.clone(),
                levels: *levels,
                quadratures: quadratures.clone(),
                reference_spacing: *reference_spacing,
            };
            compare::compare(&p, req, &dir, &term, cli.quiet)
        }
        Command::Convergence { scene, levels, out } => {
            let p = Problem::from_file(scene)?;
            if p.exact.is_none() {
                return Err(AppError::Usage(format!("{}: convergence needs an [exact] solution in the scene", scene.display())));
            }
            let dir = out.clone().unwrap_or_else(|| default_out(&p));
            convergence(&p, *levels, &dir, &term, cli.quiet)
        }
    }
}

fn default_out(p: &Problem) -> PathBuf {
    Path::new("output").join(&p.name)
}

fn print_result(sol: &Solution) {
    println!("nodes {}  unknowns {}  nonzeros {}", sol.nodes.len(), sol.unknowns, sol.nonzeros);
    println!("solver {}: {} iterations, relative residual {:.2e}", sol.solver.method, sol.solver.iterations, sol.solver.relative_residual);
    if let Some(e) = &sol.errors {
        print!("e_inf(u) = {:.4e}  rel_l2(u) = {:.4e}", e.e_inf_u, e.rel_l2_u);
        if let Some(s) = e.e_inf_sigma {
            print!("  e_inf(sigma) = {s:.4e}");
        }
        println!();
    }
}

/// `summary.json`.
#[derive(Serialize)]
struct Summary<'a> {
    scene: &'a str,
    source: String,
    version: &'static str,
    nodes: usize,
    boundary_nodes: usize,
    ghost_nodes: usize,
    unknowns: usize,
    nonzeros: usize,
    spacing: f64,
    fill: crate::domain::FillKind,
    seed: u64,
    relax_iterations: usize,
    approximation: crate::mlsm::Approximation,
    material: MaterialSummary,
    operators_computed: std::collections::BTreeMap<String, usize>,
    timings_s: TimingsSummary,
    solver: SolverSummary<'a>,
    errors: Option<ErrorNorms>,
    outputs: crate::problem::Outputs,
    peak_memory_bytes: Option<u64>,
    threads: usize,
}

#[derive(Serialize)]
struct SolverSummary<'a> {
    kind: &'static str,
    #[serde(flatten)]
    report: &'a crate::linalg::SolveReport,
}

#[derive(Serialize)]
struct MaterialSummary {
    young: f64,
    poisson: f64,
    plane: crate::elasticity::material::PlaneModel,
    lambda: f64,
    mu: f64,
}

impl MaterialSummary {
    fn of(m: &crate::elasticity::material::Material) -> Self {
        let lame = m.lame();
        MaterialSummary { young: m.elastic.young, poisson: m.elastic.poisson, plane: m.plane, lambda: lame.lambda, mu: lame.mu }
    }
}

/// Create `dir` (and parents) for a command's results.
fn create_dir(dir: &Path) -> Result<(), AppError> {
    std::fs::create_dir_all(dir).map_err(|e| AppError::Output(OutputError::Io { path: dir.to_path_buf(), source: e }))
}

/// Write `points` with `fields` to a .vtu, with Delaunay triangles inside the solid for viewing.
fn write_points_vtu(path: &Path, points: &[[f64; 2]], domain: &crate::domain::Domain, fields: &[PointField]) -> Result<(), AppError> {
    let tris = output::triangulate(points, |c| domain.contains(c));
    Ok(output::write_vtu(path, points, &tris, fields)?)
}

#[derive(Serialize)]
struct TimingsSummary {
    #[serde(flatten)]
    stages: run::Timings,
    total: f64,
}

fn summary<'a>(p: &'a Problem, sol: &'a Solution, total: f64) -> Summary<'a> {
    Summary {
        scene: &p.name,
        source: p.source.display().to_string(),
        version: env!("CARGO_PKG_VERSION"),
        nodes: sol.nodes.len(),
        boundary_nodes: sol.nodes.boundary.len(),
        ghost_nodes: sol.ghost_nodes,
        unknowns: sol.unknowns,
        nonzeros: sol.nonzeros,
        spacing: p.fill.spacing,
        fill: p.fill.kind,
        seed: p.fill.seed,
        relax_iterations: p.fill.relax_iterations,
        approximation: p.approximation,
        material: MaterialSummary::of(&p.material),
        operators_computed: sol.operators_computed.iter().cloned().collect(),
        timings_s: TimingsSummary { stages: sol.timings, total },
        solver: SolverSummary {
            kind: match p.solver.kind {
                crate::linalg::SolverKind::Lu => "lu",
                crate::linalg::SolverKind::Bicgstab { .. } => "bicgstab",
            },
            report: &sol.solver,
        },
        errors: sol.errors,
        outputs: p.outputs,
        peak_memory_bytes: output::peak_memory_bytes(),
        threads: rayon::current_num_threads(),
    }
}

/// Node kind for the viewer: 0 interior, 1 displacement, 2 traction, 3 mixed.
fn node_kind(eq: &[ComponentEquation; 2]) -> i32 {
    match eq.map(|e| matches!(e, ComponentEquation::Displacement { .. })) {
        [true, true] => 1,
        [false, false] => 2,
        _ => 3,
    }
}

fn vector(name: &str, v: impl Iterator<Item = [f64; 2]>) -> PointField {
    PointField { name: name.into(), components: 3, values: FieldValues::F64(v.flat_map(|a| [a[0], a[1], 0.0]).collect()) }
}

fn scalar(name: &str, v: impl Iterator<Item = f64>) -> PointField {
    PointField { name: name.into(), components: 1, values: FieldValues::F64(v.collect()) }
}

/// Strain, stress and von Mises arrays, as far as the scene asks for them.
fn stress_fields(
    p: &Problem,
    gradient: &Option<Vec<[[f64; 2]; 2]>>,
    stress: &Option<(Vec<[f64; 3]>, Vec<f64>, Vec<f64>)>,
) -> Vec<PointField> {
    let mut f = Vec::new();
    if let (Some(g), true) = (gradient, p.outputs.strain) {
        let e: Vec<[f64; 3]> = g.iter().map(|g| crate::elasticity::stress::strain(*g)).collect();
        for (k, name) in ["eps_xx", "eps_yy", "eps_xy"].iter().enumerate() {
            f.push(scalar(name, e.iter().map(|e| e[k])));
        }
    }
    if let Some((s, szz, vm)) = stress {
        if p.outputs.stress {
            for (k, name) in ["sigma_xx", "sigma_yy", "sigma_xy"].iter().enumerate() {
                f.push(scalar(name, s.iter().map(|s| s[k])));
            }
            if p.material.plane == crate::elasticity::material::PlaneModel::Strain {
                f.push(scalar("sigma_zz", szz.iter().copied()));
            }
        }
        if p.outputs.von_mises {
            f.push(scalar("von_mises", vm.iter().copied()));
        }
    }
    f
}

/// Point-data arrays of the requested outputs.
fn fields(p: &Problem, sol: &Solution) -> Vec<PointField> {
    let n = sol.nodes.len();
    let nb = sol.nodes.boundary.len();
    let mut f = vec![vector("displacement", sol.displacement.iter().copied())];
    f.extend(stress_fields(p, &sol.gradient, &sol.stress));
    let kinds = (0..n).map(|i| if i < nb { node_kind(&sol.boundary_equations[i]) } else { 0 });
    f.push(PointField { name: "node_kind".into(), components: 1, values: FieldValues::I32(kinds.collect()) });
    let parts = (0..n).map(|i| if i < nb { sol.nodes.boundary[i].touches[0].0 as i32 } else { -1 });
    f.push(PointField { name: "boundary_part".into(), components: 1, values: FieldValues::I32(parts.collect()) });
    f.push(vector("normal", (0..n).map(|i| if i < nb { sol.nodes.normal(i) } else { [0.0, 0.0] })));
    if let (true, Some((ue, se))) = (p.outputs.error, &sol.exact) {
        f.push(vector("exact_displacement", ue.iter().copied()));
        f.push(vector("error_displacement", sol.displacement.iter().zip(ue).map(|(a, b)| [a[0] - b[0], a[1] - b[1]])));
        if let Some((s, _, _)) = &sol.stress {
            let d: Vec<f64> = s.iter().zip(se).flat_map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]]).collect();
            f.push(PointField { name: "error_stress".into(), components: 3, values: FieldValues::F64(d) });
        }
    }
    f
}

fn write_run(p: &Problem, sol: &mut Solution, dir: &Path, t0: Instant) -> Result<(), AppError> {
    let t = Instant::now();
    create_dir(dir)?;
    write_points_vtu(&dir.join("solution.vtu"), &sol.nodes.positions, &p.domain, &fields(p, sol))?;
    sol.timings.output = t.elapsed().as_secs_f64();
    let total = t0.elapsed().as_secs_f64();
    output::write_json(&dir.join("summary.json"), &summary(p, sol, total))?;
    Ok(())
}

/// One row of a convergence table.
#[derive(Serialize)]
struct Level {
    nodes: usize,
    h: f64,
    spacing: f64,
    e_inf_u: f64,
    e_inf_sigma: Option<f64>,
    rel_l2_u: f64,
    order_e_inf_u: Option<f64>,
    order_e_inf_sigma: Option<f64>,
    seconds: f64,
}

#[derive(Serialize)]
struct ConvergenceTable<'a> {
    scene: &'a str,
    levels: Vec<Level>,
    fitted_order_e_inf_u: Option<f64>,
    fitted_order_e_inf_sigma: Option<f64>,
}

fn convergence(p: &Problem, levels: usize, dir: &Path, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    if levels > 8 {
        return Err(AppError::Usage(format!("--levels {levels}: at most 8 halvings (each multiplies the node count by 4)")));
    }
    // Refuse an unaffordable finest level before solving the coarse ones.
    p.with_spacing(p.fill.spacing / 2f64.powi(levels as i32))?;
    let area = p.domain.area_estimate(400);
    let mut rows: Vec<Level> = Vec::new();
    let mut hs = Vec::new();
    let mut eu = Vec::new();
    let mut es = Vec::new();
    for k in 0..=levels {
        let spacing = p.fill.spacing / 2f64.powi(k as i32);
        if !quiet {
            eprintln!("level {k}: spacing {spacing:.4e}");
        }
        let t0 = Instant::now();
        let sol = run::solve(&p.with_spacing(spacing)?, term)?;
        let e = sol.errors.expect("exact solution present");
        // Effective spacing from the node count, so that scattered fills are compared fairly.
        let h = (area / sol.nodes.len() as f64).sqrt();
        let order = |prev: Option<f64>, cur: Option<f64>| match (rows.last(), prev, cur) {
            (Some(last), Some(a), Some(b)) if a > 0.0 && b > 0.0 => Some((a / b).ln() / (last.h / h).ln()),
            _ => None,
        };
        let level = Level {
            nodes: sol.nodes.len(),
            h,
            spacing,
            e_inf_u: e.e_inf_u,
            e_inf_sigma: e.e_inf_sigma,
            rel_l2_u: e.rel_l2_u,
            order_e_inf_u: order(rows.last().map(|r| r.e_inf_u), Some(e.e_inf_u)),
            order_e_inf_sigma: order(rows.last().and_then(|r| r.e_inf_sigma), e.e_inf_sigma),
            seconds: t0.elapsed().as_secs_f64(),
        };
        hs.push(h);
        eu.push(e.e_inf_u);
        es.push(e.e_inf_sigma.unwrap_or(f64::NAN));
        rows.push(level);
    }
    let table = ConvergenceTable {
        scene: &p.name,
        fitted_order_e_inf_u: observed_order(&hs, &eu),
        fitted_order_e_inf_sigma: if es.iter().all(|e| e.is_finite()) { observed_order(&hs, &es) } else { None },
        levels: rows,
    };
    create_dir(dir)?;
    let nan = |o: Option<f64>| o.unwrap_or(f64::NAN);
    let csv: Vec<Vec<f64>> = table
        .levels
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
                l.seconds,
            ]
        })
        .collect();
    output::write_csv(
        &dir.join("convergence.csv"),
        &["nodes", "h", "spacing", "e_inf_u", "e_inf_sigma", "rel_l2_u", "order_e_inf_u", "order_e_inf_sigma", "seconds"],
        &csv,
    )?;
    output::write_json(&dir.join("convergence.json"), &table)?;
    if !quiet {
        println!("{:>9} {:>11} {:>11} {:>11} {:>11} {:>7} {:>7}", "nodes", "h", "e_inf_u", "e_inf_sig", "rel_l2_u", "p_u", "p_sig");
        let f = |o: Option<f64>| o.map_or("-".to_string(), |v| format!("{v:.2}"));
        for l in &table.levels {
            println!(
                "{:>9} {:>11.3e} {:>11.3e} {:>11} {:>11.3e} {:>7} {:>7}",
                l.nodes,
                l.h,
                l.e_inf_u,
                l.e_inf_sigma.map_or("-".into(), |v| format!("{v:.3e}")),
                l.rel_l2_u,
                f(l.order_e_inf_u),
                f(l.order_e_inf_sigma)
            );
        }
        println!("fitted order: e_inf(u) {}  e_inf(sigma) {}", f(table.fitted_order_e_inf_u), f(table.fitted_order_e_inf_sigma));
        println!("written: {}", dir.join("convergence.csv").display());
    }
    Ok(())
}
