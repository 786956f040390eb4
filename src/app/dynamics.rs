//! Time series output shared by the dynamic runs: snapshots (`snapshots/step_<k>.vtu`
//! with displacement and velocity), `series.pvd`, `energies.csv` and the final
//! `solution.vtu`, with the integration shown as a progress bar.

use super::{create_dir, vector, AppError, Terminal};
use crate::domain::Domain;
use crate::dynamics::driver::{integrate, DynamicReport, EnergyRow, IntegrateError, TimeGrid};
use crate::dynamics::{SecondOrderSystem, State};
use crate::output;
use crate::problem::DynamicsParams;
use crate::run::{Progress, Stage};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where and on which points a time series is written.
pub(super) struct Series<'a> {
    dir: PathBuf,
    points: &'a [[f64; 2]],
    triangles: Vec<[usize; 3]>,
    entries: Vec<(f64, String)>,
}

impl<'a> Series<'a> {
    /// Create `dir/snapshots` and triangulate `points` once for every snapshot.
    pub(super) fn new(dir: &Path, points: &'a [[f64; 2]], domain: &Domain) -> Result<Self, AppError> {
        create_dir(&dir.join("snapshots"))?;
        Ok(Series { dir: dir.to_path_buf(), points, triangles: output::triangulate(points, |c| domain.contains(c)), entries: Vec::new() })
    }

    fn write(&self, name: &str, u: &[[f64; 2]], v: &[[f64; 2]]) -> Result<(), AppError> {
        let fields = vec![vector("displacement", u.iter().copied()), vector("velocity", v.iter().copied())];
        Ok(output::write_vtu(&self.dir.join(name), self.points, &self.triangles, &fields)?)
    }

    /// Integrate (see [`integrate`]) with snapshots of the nodal fields `fields(state)`,
    /// then write `series.pvd`, `energies.csv` and `solution.vtu`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run(
        &mut self,
        system: &dyn SecondOrderSystem,
        energy: &dyn Fn(&State) -> (f64, f64, f64),
        state: &mut State,
        grid: TimeGrid,
        params: &DynamicsParams,
        term: &Terminal,
        fields: impl Fn(&State) -> (Vec<[f64; 2]>, Vec<[f64; 2]>),
    ) -> Result<(DynamicReport, Vec<EnergyRow>), AppError> {
        term.start(Stage::Integrate);
        let started = Instant::now();
        let result = integrate(system, energy, state, grid, params, term, |step, s| {
            let name = format!("snapshots/step_{step:06}.vtu");
            let (u, v) = fields(s);
            self.write(&name, &u, &v)?;
            self.entries.push((s.t, name));
            Ok::<(), AppError>(())
        });
        let (report, energies) = result.map_err(|e| match e {
            IntegrateError::Run(r) => AppError::Run(r),
            IntegrateError::Output(o) => o,
        })?;
        term.finish(
            Stage::Integrate,
            started.elapsed().as_secs_f64(),
            &format!("{} steps of {:.3e} s (stable {:.3e} s)", report.steps, report.time_step, report.stable_time_step),
        );
        output::write_pvd(&self.dir.join("series.pvd"), &self.entries)?;
        let rows: Vec<Vec<f64>> = energies.iter().map(|e| vec![e[0], e[1], e[2], e[3], e[1] + e[2] + e[3]]).collect();
        output::write_csv(&self.dir.join("energies.csv"), &["t", "kinetic", "elastic", "external", "total"], &rows)?;
        let (u, v) = fields(state);
        self.write("solution.vtu", &u, &v)?;
        Ok((report, energies))
    }
}

/// `summary.json` of a dynamic MLSM run.
#[derive(serde::Serialize)]
struct NavierDynamicSummary<'a> {
    scene: &'a str,
    source: String,
    version: &'static str,
    model: &'static str,
    nodes: usize,
    ghost_nodes: usize,
    dynamic_unknowns: usize,
    algebraic_unknowns: usize,
    spacing: f64,
    approximation: crate::mlsm::Approximation,
    dynamics: DynamicsParams,
    integration: &'a DynamicReport,
    seconds_per_step_per_node: f64,
    energy_first: EnergyRow,
    energy_last: EnergyRow,
    material: super::MaterialSummary,
    timings_s: NavierTimings,
    peak_memory_bytes: Option<u64>,
    threads: usize,
}

#[derive(serde::Serialize)]
struct NavierTimings {
    #[serde(flatten)]
    stages: crate::run::Timings,
    integrate: f64,
    total: f64,
}

/// Lumped nodal areas: a third of every Delaunay triangle (inside the solid) at each corner.
fn nodal_areas(points: &[[f64; 2]], triangles: &[[usize; 3]]) -> Vec<f64> {
    let mut a = vec![0.0; points.len()];
    for t in triangles {
        let (p, q, r) = (points[t[0]], points[t[1]], points[t[2]]);
        let area = 0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1])).abs();
        for &k in t {
            a[k] += area / 3.0;
        }
    }
    a
}

/// A time-dependent MLSM run (explicit elastodynamics, see `dynamics::navier`).
pub(super) fn run_navier_dynamic(p: &crate::problem::Problem, dynamics: &DynamicsParams, dir: &Path, term: &Terminal, quiet: bool) -> Result<(), AppError> {
    use crate::dynamics::navier::NavierDynamics;
    use crate::elasticity::stress;
    let t0 = Instant::now();
    if !quiet {
        eprintln!("{}: MLSM elastodynamics ({}, t_end = {:.3e} s)", p.name, dynamics.integrator.name(), dynamics.end_time);
    }
    // Energies need the displacement gradient at every node.
    let mut q = p.clone();
    q.outputs.stress = true;
    let mut timings = crate::run::Timings::default();
    let disc = crate::run::Discrete::new(&q, term, &mut timings)?;
    let exact = crate::run::exact_solution(&q);
    let (n, nb) = (disc.nodes.len(), disc.nodes.boundary.len());
    let started = Instant::now();
    let (triplets, rhs) = disc.system(&q, exact.as_deref()).assemble()?;
    let matrix = crate::linalg::assemble(&triplets).map_err(crate::run::RunError::from)?;
    let is_dynamic: Vec<bool> = (0..rhs.len()).map(|g| g / 2 < n && (g / 2 >= nb || disc.ghost[g / 2] != usize::MAX)).collect();
    let system = NavierDynamics::new(&matrix, &rhs, &is_dynamic, dynamics.density).map_err(crate::run::RunError::from)?;
    drop(matrix);
    timings.assembly = started.elapsed().as_secs_f64();
    let grid = crate::dynamics::driver::time_grid(system.stable_time_step(), dynamics)?;
    let points = &disc.nodes.positions;
    let init = |f: &crate::problem::Affine| -> Vec<f64> { system.dynamic.iter().map(|&g| f.at(points[g / 2])[g % 2]).collect() };
    let mut state = State::new(&system, 0.0, init(&dynamics.initial_displacement), init(&dynamics.initial_velocity));
    let mut series = Series::new(dir, points, &p.domain)?;
    let areas = nodal_areas(points, &series.triangles);
    let lame = q.material.lame();
    let body = match q.body_force {
        crate::problem::Value::Constant(f) => f,
        crate::problem::Value::Exact => [0.0, 0.0],
    };
    let nodal = |x: &[f64]| -> Vec<[f64; 2]> { (0..n).map(|i| [x[2 * i], x[2 * i + 1]]).collect() };
    let energy = |s: &State| {
        let (u, v) = (system.expand(&s.u, false), system.expand(&s.v, true));
        let grads = stress::gradients(&disc.dofs, &disc.supports, &disc.shapes, &u, n);
        let (mut kin, mut el, mut ext) = (0.0, 0.0, 0.0);
        for i in 0..n {
            kin += 0.5 * dynamics.density * areas[i] * (v[2 * i].powi(2) + v[2 * i + 1].powi(2));
            let (sg, e) = (lame.stress(grads[i]), stress::strain(grads[i]));
            el += 0.5 * areas[i] * (sg[0] * e[0] + sg[1] * e[1] + 2.0 * sg[2] * e[2]);
            ext -= areas[i] * (body[0] * u[2 * i] + body[1] * u[2 * i + 1]);
        }
        (kin, el, ext)
    };
    let (report, energies) =
        series.run(&system, &energy, &mut state, grid, dynamics, term, |s| (nodal(&system.expand(&s.u, false)), nodal(&system.expand(&s.v, true))))?;
    let summary = NavierDynamicSummary {
        scene: &p.name,
        source: p.source.display().to_string(),
        version: env!("CARGO_PKG_VERSION"),
        model: "navier",
        nodes: n,
        ghost_nodes: disc.dofs.len() / 2 - n,
        dynamic_unknowns: system.dynamic.len(),
        algebraic_unknowns: system.algebraic.len(),
        spacing: p.fill.spacing,
        approximation: p.approximation,
        dynamics: *dynamics,
        integration: &report,
        seconds_per_step_per_node: report.seconds / report.steps.max(1) as f64 / n as f64,
        energy_first: energies[0],
        energy_last: *energies.last().expect("initial energy recorded"),
        material: super::MaterialSummary::of(&p.material),
        timings_s: NavierTimings { stages: timings, integrate: report.seconds, total: t0.elapsed().as_secs_f64() },
        peak_memory_bytes: output::peak_memory_bytes(),
        threads: rayon::current_num_threads(),
    };
    output::write_json(&dir.join("summary.json"), &summary)?;
    if !quiet {
        let (e0, e1) = (energies[0], energies.last().unwrap());
        println!("nodes {n}  steps {}  dt {:.3e} s (stable {:.3e} s)", report.steps, report.time_step, report.stable_time_step);
        println!(
            "energy at t = 0: kinetic {:.6e}; at t = {:.3e}: kinetic {:.6e}, elastic {:.6e}; {:.2e} s per step per node",
            e0[1], e1[0], e1[1], e1[2], summary.seconds_per_step_per_node
        );
    }
    Ok(())
}
