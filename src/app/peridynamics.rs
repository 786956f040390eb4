//! `mlsm run` with the peridynamic model: solution.vtu and summary.json.

use super::{create_dir, scalar, stress_fields, vector, write_points_vtu, AppError, MaterialSummary, Terminal};
use crate::dynamics::State;
use crate::output::{self, FieldValues, PointField};
use super::dynamics::Series;
use crate::dynamics::driver::{time_grid, DynamicReport, EnergyRow};
use crate::peridynamics::dynamics::PdDynamics;
use crate::peridynamics::loads;
use crate::peridynamics::solve::Discretisation;
use crate::peridynamics::solve::{PdSolution, PdTimings, WeightsSummary};
use crate::peridynamics::{Micromodulus, PdParams};
use crate::post::ErrorNorms;
use crate::problem::DynamicsParams;
use crate::problem::Problem;

use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// `summary.json` of a peridynamic run.
#[derive(Serialize)]
struct PdSummary<'a> {
    scene: &'a str,
    source: String,
    version: &'static str,
    model: &'static str,
    nodes: usize,
    constrained_nodes: usize,
    loaded_layer_nodes: usize,
    unknowns: usize,
    nonzeros: usize,
    bonds: usize,
    bonds_per_node: f64,
    peridynamics: PdParams,
    spacing: f64,
    micromodulus: Micromodulus,
    weights: WeightsSummary,
    material: MaterialSummary,
    timings_s: Timings,
    solver: &'a crate::linalg::SolveReport,
    errors: Option<ErrorNorms>,
    errors_interior: Option<ErrorNorms>,
    outputs: crate::problem::Outputs,
    peak_memory_bytes: Option<u64>,
    threads: usize,
}

#[derive(Serialize)]
struct Timings {
    #[serde(flatten)]
    stages: PdTimings,
    total: f64,
}

/// Point-data arrays of a peridynamic solution (free nodes only).
pub(super) fn pd_fields(p: &Problem, sol: &PdSolution) -> Vec<PointField> {
    let n = sol.nodes.free;
    let mut f = vec![vector("displacement", sol.displacement[..n].iter().copied())];
    f.extend(stress_fields(p, &sol.gradient, &sol.stress));
    f.push(vector("body_force", sol.body_force.iter().copied()));
    f.push(PointField {
        name: "interior".into(),
        components: 1,
        values: FieldValues::I32(sol.interior.iter().map(|&b| b as i32).collect()),
    });
    f.push(scalar("volume", sol.nodes.volumes[..n].iter().copied()));
    if let (true, Some(ue)) = (p.outputs.error, &sol.exact) {
        f.push(vector("exact_displacement", ue.iter().copied()));
        f.push(vector("error_displacement", sol.displacement.iter().zip(ue).map(|(a, b)| [a[0] - b[0], a[1] - b[1]])));
    }
    f
}

/// Write `solution.vtu` (free nodes, Delaunay cells inside the solid) and `summary.json`.
pub(super) fn write_pd_run(p: &Problem, sol: &mut PdSolution, dir: &Path, t0: Instant) -> Result<(), AppError> {
    let t = Instant::now();
    create_dir(dir)?;
    write_points_vtu(&dir.join("solution.vtu"), &sol.nodes.positions[..sol.nodes.free], &p.domain, &pd_fields(p, sol))?;
    sol.timings.output = t.elapsed().as_secs_f64();
    let summary = PdSummary {
        scene: &p.name,
        source: p.source.display().to_string(),
        version: env!("CARGO_PKG_VERSION"),
        model: "peridynamics",
        nodes: sol.nodes.free,
        constrained_nodes: sol.nodes.constrained(),
        loaded_layer_nodes: sol.layer_nodes,
        unknowns: sol.unknowns,
        nonzeros: sol.nonzeros,
        bonds: sol.bonds,
        bonds_per_node: sol.bonds as f64 / sol.nodes.free.max(1) as f64,
        peridynamics: sol.params,
        spacing: sol.nodes.spacing,
        micromodulus: sol.micromodulus,
        weights: sol.weights,
        material: MaterialSummary::of(&p.material),
        timings_s: Timings { stages: sol.timings, total: t0.elapsed().as_secs_f64() },
        solver: &sol.solver,
        errors: sol.errors.map(|e| e.0),
        errors_interior: sol.errors.and_then(|e| e.1),
        outputs: p.outputs,
        peak_memory_bytes: output::peak_memory_bytes(),
        threads: rayon::current_num_threads(),
    };
    output::write_json(&dir.join("summary.json"), &summary)?;
    Ok(())
}

/// Terminal lines after a peridynamic run.
pub(super) fn print_pd_result(sol: &PdSolution) {
    println!(
        "nodes {} (+{} constrained)  bonds {}  unknowns {}  nonzeros {}",
        sol.nodes.free,
        sol.nodes.constrained(),
        sol.bonds,
        sol.unknowns,
        sol.nonzeros
    );
    println!("solver {}: relative residual {:.2e}", sol.solver.method, sol.solver.relative_residual);
    if let Some((w, i)) = &sol.errors {
        print!("e_inf(u) = {:.4e}  rel_l2(u) = {:.4e}", w.e_inf_u, w.rel_l2_u);
        if let Some(i) = i {
            print!("  interior: e_inf(u) = {:.4e}  rel_l2(u) = {:.4e}", i.e_inf_u, i.rel_l2_u);
        }
        println!();
    }
}

/// `summary.json` of a dynamic peridynamic run.
#[derive(Serialize)]
struct DynamicSummary<'a> {
    scene: &'a str,
    source: String,
    version: &'static str,
    model: &'static str,
    nodes: usize,
    constrained_nodes: usize,
    bonds: usize,
    peridynamics: PdParams,
    spacing: f64,
    micromodulus: Micromodulus,
    weights: WeightsSummary,
    dynamics: crate::problem::DynamicsParams,
    integration: &'a DynamicReport,
    bond_updates_per_second_per_thread: f64,
    energy_first: EnergyRow,
    energy_last: EnergyRow,
    material: MaterialSummary,
    timings_s: DynamicTimings,
    peak_memory_bytes: Option<u64>,
    threads: usize,
}

#[derive(Serialize)]
struct DynamicTimings {
    #[serde(flatten)]
    stages: PdTimings,
    integrate: f64,
    total: f64,
}

/// A time-dependent peridynamic run: snapshots (`snapshots/step_<k>.vtu` and
/// `series.pvd`), `energies.csv`, the final `solution.vtu` and `summary.json`.
pub(super) fn run_pd_dynamic(
    p: &Problem,
    params: &PdParams,
    dynamics: &DynamicsParams,
    dir: &Path,
    term: &Terminal,
    quiet: bool,
) -> Result<(), AppError> {
    let t0 = Instant::now();
    if !quiet {
        eprintln!(
            "{}: peridynamic dynamics ({}, {}, t_end = {:.3e} s)",
            p.name,
            params.quadrature.name(),
            dynamics.integrator.name(),
            dynamics.end_time
        );
    }
    let mut timings = PdTimings::default();
    let disc = Discretisation::new(p, params, term, &mut timings)?;
    let exact = crate::run::exact_solution(p);
    let (body_force, _) = loads::body_forces(&p.domain, &p.conditions, p.body_force, exact.as_deref(), &disc.nodes);
    let system = PdDynamics { bonds: disc.bonds(), body_force: &body_force, density: dynamics.density, force: params.force };
    let free = &disc.nodes.positions[..disc.nodes.free];
    let flat = |f: &crate::problem::Affine| -> Vec<f64> { free.iter().flat_map(|x| f.at(*x)).collect() };
    let grid = time_grid(system.stable_time_step(), dynamics)?;
    let mut state = State::new(&system, 0.0, flat(&dynamics.initial_displacement), flat(&dynamics.initial_velocity));
    let mut series = Series::new(dir, free, &p.domain)?;
    let started = Instant::now();
    let energy = |s: &State| system.energies(&s.u, &s.v);
    let pairs = |v: &[f64]| v.chunks_exact(2).map(|c| [c[0], c[1]]).collect::<Vec<[f64; 2]>>();
    let (report, energies) = series.run(&system, &energy, &mut state, grid, dynamics, term, |s| (pairs(&s.u), pairs(&s.v)))?;
    let integrate_seconds = started.elapsed().as_secs_f64();
    let throughput = report.force_evaluations as f64 * disc.families.bonds() as f64 / report.seconds.max(1e-12) / rayon::current_num_threads() as f64;
    let summary = DynamicSummary {
        scene: &p.name,
        source: p.source.display().to_string(),
        version: env!("CARGO_PKG_VERSION"),
        model: "peridynamics",
        nodes: disc.nodes.free,
        constrained_nodes: disc.nodes.constrained(),
        bonds: disc.families.bonds(),
        peridynamics: *params,
        spacing: disc.nodes.spacing,
        micromodulus: disc.micromodulus,
        weights: WeightsSummary {
            complete_families: disc.weights.complete_families,
            compatible_rows: disc.weights.compatible_rows,
            compatible_failures: disc.weights.compatible_failures,
        },
        dynamics: *dynamics,
        integration: &report,
        bond_updates_per_second_per_thread: throughput,
        energy_first: energies[0],
        energy_last: *energies.last().expect("initial energy recorded"),
        material: MaterialSummary::of(&p.material),
        timings_s: DynamicTimings { stages: timings, integrate: integrate_seconds, total: t0.elapsed().as_secs_f64() },
        peak_memory_bytes: output::peak_memory_bytes(),
        threads: rayon::current_num_threads(),
    };
    output::write_json(&dir.join("summary.json"), &summary)?;
    if !quiet {
        let (e0, e1) = (energies[0], energies.last().unwrap());
        println!(
            "nodes {}  bonds {}  steps {}  dt {:.3e} s (stable {:.3e} s)",
            disc.nodes.free,
            disc.families.bonds(),
            report.steps,
            report.time_step,
            report.stable_time_step
        );
        println!(
            "energy at t = 0: kinetic {:.6e}, elastic {:.6e}; at t = {:.3e}: kinetic {:.6e}, elastic {:.6e}, total drift {:.2e}",
            e0[1],
            e0[2],
            e1[0],
            e1[1],
            e1[2],
            ((e1[1] + e1[2] + e1[3]) - (e0[1] + e0[2] + e0[3])) / (e0[1] + e0[2] + e0[3]).abs().max(1e-300)
        );
        println!(
            "throughput {:.2e} bond updates per second per thread; written: {}",
            throughput,
            dir.display()
        );
    }
    Ok(())
}
