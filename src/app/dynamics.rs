//! Time-dependent runs: snapshots (`snapshots/step_<k>.vtu` with displacement and
//! velocity), `series.pvd`, `energies.csv`, the final `solution.vtu` and
//! `summary.json`, with the integration shown as a progress bar.

use super::{create_dir, vector, AppError, MaterialSummary, Terminal};
use crate::domain::Domain;
use crate::dynamics::driver::{DynamicReport, EnergyRow, IntegrateError};
use crate::output;
use crate::peridynamics::PdParams;
use crate::problem::{DynamicsParams, Problem};
use crate::run::{Progress, Stage};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Snapshot writer of one run (the Delaunay cells are built at the first snapshot).
struct Series<'a> {
    dir: PathBuf,
    domain: &'a Domain,
    triangles: Option<Vec<[usize; 3]>>,
    entries: Vec<(f64, String)>,
}

impl<'a> Series<'a> {
    /// Nothing is created until the first snapshot, which comes after every check.
    fn new(dir: &Path, domain: &'a Domain) -> Result<Self, AppError> {
        Ok(Series { dir: dir.to_path_buf(), domain, triangles: None, entries: Vec::new() })
    }

    fn write(&mut self, name: &str, points: &[[f64; 2]], u: &[[f64; 2]], v: &[[f64; 2]]) -> Result<(), AppError> {
        if self.triangles.is_none() {
            create_dir(&self.dir.join("snapshots"))?;
        }
        let domain = self.domain;
        let tris = self.triangles.get_or_insert_with(|| output::triangulate(points, |c| domain.contains(c)));
        let fields = vec![vector("displacement", u.iter().copied()), vector("velocity", v.iter().copied())];
        Ok(output::write_vtu(&self.dir.join(name), points, tris, &fields)?)
    }

    fn snapshot(&mut self, step: usize, t: f64, points: &[[f64; 2]], u: &[[f64; 2]], v: &[[f64; 2]]) -> Result<(), AppError> {
        let name = format!("snapshots/step_{step:06}.vtu");
        self.write(&name, points, u, v)?;
        self.entries.push((t, name));
        Ok(())
    }

    /// `series.pvd`, `energies.csv` and the final `solution.vtu`.
    fn finish(&mut self, energies: &[EnergyRow], points: &[[f64; 2]], u: &[[f64; 2]], v: &[[f64; 2]]) -> Result<(), AppError> {
        output::write_pvd(&self.dir.join("series.pvd"), &self.entries)?;
        let rows: Vec<Vec<f64>> = energies.iter().map(|e| vec![e[0], e[1], e[2], e[3], e[1] + e[2] + e[3]]).collect();
        output::write_csv(&self.dir.join("energies.csv"), &["t", "kinetic", "elastic", "external", "total"], &rows)?;
        self.write("solution.vtu", points, u, v)
    }
}

/// The error of a time loop whose snapshot writer returns [`AppError`].
pub(super) fn app_error(e: IntegrateError<AppError>) -> AppError {
    match e {
        IntegrateError::Run(r) => AppError::Run(r),
        IntegrateError::Output(o) => o,
    }
}

/// `summary.json` of a dynamic run.
#[derive(Serialize)]
struct DynamicSummary<'a, M: Serialize> {
    scene: &'a str,
    source: String,
    version: &'static str,
    nodes: usize,
    dynamics: DynamicsParams,
    integration: &'a DynamicReport,
    seconds_per_step_per_node: f64,
    energy_first: EnergyRow,
    energy_last: EnergyRow,
    material: MaterialSummary,
    #[serde(flatten)]
    model: M,
    integrate_seconds: f64,
    total_seconds: f64,
    peak_memory_bytes: Option<u64>,
    threads: usize,
}

#[derive(Serialize)]
struct PdPart {
    model: &'static str,
    constrained_nodes: usize,
    bonds: usize,
    spacing: f64,
    peridynamics: PdParams,
    micromodulus: crate::peridynamics::Micromodulus,
    bond_updates_per_second_per_thread: f64,
    timings_s: crate::peridynamics::solve::PdTimings,
}

#[derive(Serialize)]
struct NavierPart {
    model: &'static str,
    ghost_nodes: usize,
    dynamic_unknowns: usize,
    algebraic_unknowns: usize,
    spacing: f64,
    approximation: crate::mlsm::Approximation,
    timings_s: crate::run::Timings,
}

#[allow(clippy::too_many_arguments)]
fn write_summary<M: Serialize>(
    p: &Problem,
    dir: &Path,
    nodes: usize,
    report: &DynamicReport,
    energies: &[EnergyRow],
    model: M,
    integrate_seconds: f64,
    t0: Instant,
    quiet: bool,
) -> Result<(), AppError> {
    let summary = DynamicSummary {
        scene: &p.name,
        source: p.source.display().to_string(),
        version: env!("CARGO_PKG_VERSION"),
        nodes,
        dynamics: p.dynamics.expect("dynamic run"),
        integration: report,
        seconds_per_step_per_node: report.seconds / report.steps.max(1) as f64 / nodes.max(1) as f64,
        energy_first: energies[0],
        energy_last: *energies.last().expect("initial energy recorded"),
        material: MaterialSummary::of(&p.material),
        model,
        integrate_seconds,
        total_seconds: t0.elapsed().as_secs_f64(),
        peak_memory_bytes: output::peak_memory_bytes(),
        threads: rayon::current_num_threads(),
    };
    output::write_json(&dir.join("summary.json"), &summary)?;
    if !quiet {
        let (e0, e1) = (energies[0], energies.last().expect("recorded"));
        let total = |e: &EnergyRow| e[1] + e[2] + e[3];
        println!("nodes {nodes}  steps {}  dt {:.3e} s (stable {:.3e} s)", report.steps, report.time_step, report.stable_time_step);
        println!(
            "energy at t = 0: kinetic {:.6e}; at t = {:.3e}: kinetic {:.6e}, elastic {:.6e}, total drift {:.2e}",
            e0[1],
            e1[0],
            e1[1],
            e1[2],
            (total(e1) - total(&e0)) / total(&e0).abs().max(1e-300)
        );
        println!("{:.2e} s per step per node; written: {}", summary.seconds_per_step_per_node, dir.display());
    }
    Ok(())
}

/// A time-dependent peridynamic run.
pub(super) fn run_pd_dynamic(p: &Problem, params: &PdParams, dir: &Path, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    let t0 = Instant::now();
    let d = p.dynamics.expect("dynamic run");
    if !quiet {
        eprintln!("{}: peridynamic dynamics ({}, {}, t_end = {:.3e} s)", p.name, params.quadrature.name(), d.integrator.name(), d.end_time);
    }
    let mut series = Series::new(dir, &p.domain)?;
    let started = Instant::now();
    let sim =
        crate::peridynamics::dynamics::simulate(p, params, &Integrating::new(term), |step, t, x, u, v| series.snapshot(step, t, x, u, v))
            .map_err(app_error)?;
    let integrate_seconds = started.elapsed().as_secs_f64();
    let disc = &sim.discretisation;
    let free = &disc.nodes.positions[..disc.nodes.free];
    series.finish(&sim.energies, free, &sim.u, &sim.v)?;
    let part = PdPart {
        model: "peridynamics",
        constrained_nodes: disc.nodes.constrained(),
        bonds: disc.families.bonds(),
        spacing: disc.nodes.spacing,
        peridynamics: *params,
        micromodulus: disc.micromodulus,
        bond_updates_per_second_per_thread: sim.bond_updates_per_second_per_thread,
        timings_s: sim.timings,
    };
    if !quiet {
        println!("throughput {:.2e} bond updates per second per thread", sim.bond_updates_per_second_per_thread);
    }
    write_summary(p, dir, free.len(), &sim.report, &sim.energies, part, integrate_seconds, t0, quiet)
}

/// A time-dependent MLSM run (explicit elastodynamics, see `dynamics::navier`).
pub(super) fn run_navier_dynamic(p: &Problem, dir: &Path, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    let t0 = Instant::now();
    let d = p.dynamics.expect("dynamic run");
    if !quiet {
        eprintln!("{}: MLSM elastodynamics ({}, t_end = {:.3e} s)", p.name, d.integrator.name(), d.end_time);
    }
    let mut series = Series::new(dir, &p.domain)?;
    let started = Instant::now();
    let sim = crate::dynamics::navier::simulate(p, &Integrating::new(term), |step, t, x, u, v| series.snapshot(step, t, x, u, v))
        .map_err(app_error)?;
    let integrate_seconds = started.elapsed().as_secs_f64();
    series.finish(&sim.energies, &sim.positions, &sim.u, &sim.v)?;
    let part = NavierPart {
        model: "navier",
        ghost_nodes: sim.ghost_nodes,
        dynamic_unknowns: sim.unknowns.0,
        algebraic_unknowns: sim.unknowns.1,
        spacing: p.fill.spacing,
        approximation: p.approximation,
        timings_s: sim.timings,
    };
    write_summary(p, dir, sim.positions.len(), &sim.report, &sim.energies, part, integrate_seconds, t0, quiet)
}

/// Stage reports of the preparation, then a progress bar with an estimated time to
/// finish once the time steps start.
struct Integrating<'a>(&'a Terminal, std::sync::Mutex<Option<Instant>>);

impl<'a> Integrating<'a> {
    fn new(term: &'a Terminal) -> Self {
        Integrating(term, std::sync::Mutex::new(None))
    }
}

impl Progress for Integrating<'_> {
    fn start(&self, stage: Stage) {
        self.0.start(stage)
    }

    fn finish(&self, stage: Stage, seconds: f64, note: &str) {
        self.0.finish(stage, seconds, note)
    }

    fn advance(&self, done: u64, total: u64) {
        if done == 1 {
            *self.1.lock().unwrap() = Some(Instant::now());
            self.0.start(Stage::Integrate);
        }
        self.0.advance(done, total);
        if done == total {
            let seconds = self.1.lock().unwrap().map_or(0.0, |t| t.elapsed().as_secs_f64());
            self.0.finish(Stage::Integrate, seconds, &format!("{total} steps"));
        }
    }
}
