//! `mlsm run` with the peridynamic model: solution.vtu and summary.json.

use super::{create_dir, scalar, stress_fields, vector, write_points_vtu, AppError, MaterialSummary};
use crate::output::{self, FieldValues, PointField};
use crate::peridynamics::solve::{PdSolution, PdTimings, WeightsSummary};
use crate::peridynamics::{Micromodulus, PdParams};
use crate::post::ErrorNorms;
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
