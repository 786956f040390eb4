//! `summary.json` (and the headers of `compare.json` and `convergence.json`): one
//! [`Header`] shared by every command (version, scene, seed, threads, peak memory,
//! timings keyed by stage), followed by what each kind of run reports.

use super::extremes::Extremes;
use crate::physics::case::Outputs;
use crate::scene::choice::Choice;
use crate::models::dynamics::driver::{DynamicReport, EnergyRow};
use crate::models::dynamics::DynamicsParams;
use crate::physics::elasticity::material::{Material, PlaneModel};
use crate::linalg::SolveReport;
use crate::mlsm::Approximation;
use crate::models::navier;
use crate::models::resources::MemoryEstimate;
use crate::output;
use crate::models::peridynamics::solve::WeightsSummary;
use crate::models::peridynamics::{Micromodulus, PdParams, PdSolution};
use crate::stages::{StagePeaks, StageTimings};
use crate::quality::post::probe::ProbeValue;
use crate::quality::post::ErrorNorms;
use crate::scene::problem::Problem;
use crate::quality::warnings::Checks;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// What every summary starts with.
#[derive(Serialize)]
pub(super) struct Header<'a> {
    scene: &'a str,
    source: String,
    version: &'static str,
    seed: u64,
    threads: usize,
    peak_memory_bytes: Option<u64>,
    /// The memory model (`resources`) of the run as it went (the solvers it took,
    /// after any fallback), for comparison with the peak.
    estimated_peak_memory_bytes: f64,
    /// The estimate the memory check made before the run (the expected path).
    checked_peak_memory_bytes: f64,
    /// The node count both estimates assume (the Navier run's, or the peridynamic
    /// grid's), predicted from the scene before any node is placed.
    estimated_nodes: f64,
    /// Peak resident memory of each stage.
    peak_memory_by_stage_bytes: StagePeaks<'a>,
    timings_s: Timings<'a>,
}

/// Seconds per stage and in total.
#[derive(Serialize)]
struct Timings<'a> {
    #[serde(flatten)]
    stages: &'a StageTimings,
    total: f64,
}

impl<'a> Header<'a> {
    /// The header of a command on `p` that started at `t0`, with its stage timings.
    pub(super) fn new(p: &'a Problem, timings: &'a StageTimings, t0: Instant) -> Self {
        let checked = crate::models::resources::of(p);
        Header::taken(p, timings, t0, checked.peak_bytes.round(), &checked)
    }

    /// [`Header::new`] with the memory model of the path the run took (`taken`) and of
    /// the one the check expected (`checked`), bytes.
    fn taken(p: &'a Problem, timings: &'a StageTimings, t0: Instant, taken: f64, checked: &MemoryEstimate) -> Self {
        Header {
            scene: &p.name,
            source: p.source.display().to_string(),
            version: env!("CARGO_PKG_VERSION"),
            seed: p.navier.fill.seed,
            threads: rayon::current_num_threads(),
            peak_memory_bytes: output::peak_memory_bytes(),
            estimated_peak_memory_bytes: taken,
            checked_peak_memory_bytes: checked.peak_bytes.round(),
            estimated_nodes: checked.nodes.round(),
            peak_memory_by_stage_bytes: timings.peaks(),
            timings_s: Timings { stages: timings, total: t0.elapsed().as_secs_f64() },
        }
    }
}

/// Elastic constants as given and as they enter the planar equations.
#[derive(Serialize)]
pub(super) struct MaterialSummary {
    young: f64,
    poisson: f64,
    plane: PlaneModel,
    lambda: f64,
    mu: f64,
}

impl MaterialSummary {
    pub(super) fn of(m: &Material) -> Self {
        let lame = m.lame();
        MaterialSummary { young: m.elastic.young, poisson: m.elastic.poisson, plane: m.plane, lambda: lame.lambda, mu: lame.mu }
    }
}

#[derive(Serialize)]
struct SolverSummary<'a> {
    kind: &'static str,
    #[serde(flatten)]
    report: &'a SolveReport,
}

/// `summary.json` of a static Navier run.
#[derive(Serialize)]
pub(super) struct NavierSummary<'a> {
    #[serde(flatten)]
    header: Header<'a>,
    nodes: usize,
    boundary_nodes: usize,
    ghost_nodes: usize,
    widened_supports: usize,
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    sector_balances: &'a [navier::sector::SectorSummary],
    unbalanced: &'a [navier::sector::Unbalanced],
    unknowns: usize,
    formulation: &'static str,
    nonzeros: usize,
    spacing: f64,
    fill: crate::domain::FillKind,
    relax_iterations: usize,
    approximation: Approximation,
    material: MaterialSummary,
    operators_computed: BTreeMap<String, usize>,
    solver: SolverSummary<'a>,
    errors: Option<ErrorNorms>,
    estimated_errors: &'a navier::Estimate,
    /// The largest displacement and von Mises stress, and where they are.
    extremes: Option<Extremes>,
    equilibrium: Option<navier::equilibrium::Equilibrium>,
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    probes: &'a [ProbeValue],
    #[serde(flatten)]
    checks: &'a Checks,
    outputs: Outputs,
    /// The history of `--target-error`, when it was set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) target: Option<&'a super::target::TargetReport>,
    /// The trial run of a `balanced` or `accurate` preset, when one was made.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) preset_trial: Option<&'a super::preset_trial::TrialReport>,
}

impl<'a> NavierSummary<'a> {
    pub(super) fn new(p: &'a Problem, sol: &'a navier::Solution, checks: &'a Checks, t0: Instant) -> Self {
        let checked = crate::models::resources::of(p);
        let taken = crate::models::resources::of_static_run(p, sol, checked.nodes).map_or(checked.peak_bytes, |e| e.peak_bytes).round();
        NavierSummary {
            header: Header::taken(p, &sol.timings, t0, taken, &checked),
            nodes: sol.nodes.len(),
            boundary_nodes: sol.nodes.boundary.len(),
            ghost_nodes: sol.ghost_nodes,
            widened_supports: sol.widened_supports,
            sector_balances: &sol.sector_balances,
            unbalanced: &sol.unbalanced,
            unknowns: sol.unknowns,
            formulation: sol.formulation.name(),
            nonzeros: sol.nonzeros,
            spacing: p.navier.fill.spacing,
            fill: p.navier.fill.kind,
            relax_iterations: p.navier.fill.relax_iterations,
            approximation: p.navier.approximation,
            material: MaterialSummary::of(&p.case.material),
            operators_computed: sol.operators_computed.iter().cloned().collect(),
            solver: SolverSummary { kind: p.navier.solver.kind.method().name(), report: &sol.solver },
            errors: sol.errors,
            estimated_errors: &sol.estimate,
            extremes: navier_extremes(sol),
            equilibrium: sol.equilibrium,
            probes: &sol.probes,
            checks,
            outputs: p.case.outputs,
            target: None,
            preset_trial: None,
        }
    }
}

/// `summary.json` of a static peridynamic run.
#[derive(Serialize)]
pub(super) struct PdSummary<'a> {
    #[serde(flatten)]
    header: Header<'a>,
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
    solver: &'a SolveReport,
    errors: Option<ErrorNorms>,
    errors_interior: Option<ErrorNorms>,
    estimated_errors: &'a navier::Estimate,
    /// The estimated discretisation error at this horizon (`null` when not asked for,
    /// `{"unavailable": why}` when it failed).
    discretisation_estimate: Option<DiscretisationField<'a>>,
    /// The largest displacement and von Mises stress of the free nodes, and where they are.
    extremes: Option<Extremes>,
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    probes: &'a [ProbeValue],
    #[serde(flatten)]
    checks: &'a Checks,
    outputs: Outputs,
}

/// `summary.json`'s `discretisation_estimate` of a static or dynamic peridynamic run.
#[derive(Serialize)]
#[serde(untagged)]
enum DiscretisationField<'a> {
    Done(&'a crate::models::peridynamics::solve::DiscretisationEstimate),
    Unavailable { unavailable: &'a str },
}

impl<'a> DiscretisationField<'a> {
    /// The estimate, or why there is none.
    fn of(d: &'a Result<crate::models::peridynamics::solve::DiscretisationEstimate, String>) -> Self {
        match d {
            Ok(d) => DiscretisationField::Done(d),
            Err(why) => DiscretisationField::Unavailable { unavailable: why },
        }
    }
}

impl<'a> PdSummary<'a> {
    pub(super) fn new(p: &'a Problem, sol: &'a PdSolution, estimate: &'a navier::Estimate, checks: &'a Checks, t0: Instant) -> Self {
        PdSummary {
            header: Header::new(p, &sol.timings, t0),
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
            material: MaterialSummary::of(&p.case.material),
            solver: &sol.solver,
            errors: sol.errors.map(|e| e.0),
            errors_interior: sol.errors.and_then(|e| e.1),
            estimated_errors: estimate,
            discretisation_estimate: sol.discretisation.as_ref().map(DiscretisationField::of),
            extremes: pd_extremes(sol),
            probes: &sol.probes,
            checks,
            outputs: p.case.outputs,
        }
    }
}

/// What the peridynamic model adds to a dynamic summary.
#[derive(Serialize)]
pub(super) struct PdDynamicPart<'a> {
    model: &'static str,
    constrained_nodes: usize,
    bonds: usize,
    spacing: f64,
    peridynamics: PdParams,
    micromodulus: Micromodulus,
    bond_updates_per_second_per_thread: f64,
    /// The estimated discretisation error at the horizon over the history (`null` when
    /// not asked for, `{"unavailable": why}` when it failed).
    discretisation_estimate: Option<DiscretisationField<'a>>,
    /// What broke (`null` without `[peridynamics.fracture]`).
    fracture: Option<crate::models::peridynamics::simulation::FractureReport>,
}

impl<'a> PdDynamicPart<'a> {
    pub(super) fn of(
        p: &Problem,
        sim: &crate::models::peridynamics::Simulation,
        discretisation: Option<&'a Result<crate::models::peridynamics::solve::DiscretisationEstimate, String>>,
    ) -> Self {
        let disc = &sim.discretisation;
        PdDynamicPart {
            model: "peridynamics",
            constrained_nodes: disc.nodes.constrained(),
            bonds: disc.bond_count,
            spacing: disc.nodes.spacing,
            peridynamics: p.model.peridynamics().copied().expect("peridynamic run"),
            micromodulus: disc.micromodulus,
            bond_updates_per_second_per_thread: sim.bond_updates_per_second_per_thread,
            discretisation_estimate: discretisation.map(DiscretisationField::of),
            fracture: sim.fracture,
        }
    }
}

/// What the Navier model adds to a dynamic summary.
#[derive(Serialize)]
pub(super) struct NavierDynamicPart {
    model: &'static str,
    ghost_nodes: usize,
    dynamic_unknowns: usize,
    algebraic_unknowns: usize,
    spacing: f64,
    approximation: Approximation,
    /// The corners and holes with traction edges (none balanced in time).
    unbalanced: Vec<navier::sector::Unbalanced>,
}

impl NavierDynamicPart {
    pub(super) fn of(p: &Problem, sim: &navier::Simulation) -> Self {
        NavierDynamicPart {
            model: "navier",
            ghost_nodes: sim.ghost_nodes,
            dynamic_unknowns: sim.unknowns.0,
            algebraic_unknowns: sim.unknowns.1,
            spacing: p.navier.fill.spacing,
            approximation: p.navier.approximation,
            unbalanced: sim.unbalanced.clone(),
        }
    }
}

/// What every time-dependent run reports.
#[derive(Clone, Copy)]
pub(super) struct Dynamic<'a> {
    pub nodes: usize,
    pub report: &'a DynamicReport,
    pub energies: &'a [EnergyRow],
    pub timings: &'a StageTimings,
    /// The error estimate (Navier: over the history; peridynamics: at the end time).
    pub estimate: &'a navier::Estimate,
    /// The re-entrant corners and holes left unbalanced (Navier), for the note.
    pub unbalanced: &'a [navier::sector::Unbalanced],
    /// The largest displacement of the final state, and where it is.
    pub extremes: Option<Extremes>,
}

/// `summary.json` of a time-dependent run.
#[derive(Serialize)]
pub(super) struct DynamicSummary<'a, M: Serialize> {
    #[serde(flatten)]
    header: Header<'a>,
    nodes: usize,
    dynamics: &'a DynamicsParams,
    integration: &'a DynamicReport,
    /// The stability limit of the scheme (s): `integration.stable_time_step`, the
    /// central-difference limit, times the scheme's factor (RK4: sqrt 2).
    time_step_limit: f64,
    seconds_per_step_per_node: f64,
    energy_first: EnergyRow,
    energy_last: EnergyRow,
    material: MaterialSummary,
    estimated_errors: &'a navier::Estimate,
    /// The largest displacement of the final state, and where it is.
    extremes: Option<Extremes>,
    #[serde(flatten)]
    model: M,
    #[serde(flatten)]
    checks: &'a Checks,
}

impl<'a, M: Serialize> DynamicSummary<'a, M> {
    pub(super) fn new(p: &'a Problem, d: &Dynamic<'a>, model: M, checks: &'a Checks, t0: Instant) -> Self {
        let Dynamic { nodes, report, energies, timings, estimate, extremes, .. } = *d;
        DynamicSummary {
            header: Header::new(p, timings, t0),
            nodes,
            dynamics: p.case.dynamics.as_ref().expect("dynamic run"),
            integration: report,
            time_step_limit: stability_limit(report),
            seconds_per_step_per_node: report.seconds / report.steps.max(1) as f64 / nodes.max(1) as f64,
            energy_first: energies[0],
            energy_last: *energies.last().expect("initial energy recorded"),
            material: MaterialSummary::of(&p.case.material),
            estimated_errors: estimate,
            extremes,
            model,
            checks,
        }
    }
}

/// The extremes of a static Navier run at its nodes.
pub(super) fn navier_extremes(sol: &navier::Solution) -> Option<Extremes> {
    Extremes::of(&sol.nodes.positions, &sol.displacement, sol.stress.as_ref().map(|s| s.von_mises.as_slice()))
}

/// The extremes of a static peridynamic run at its free nodes.
pub(super) fn pd_extremes(sol: &PdSolution) -> Option<Extremes> {
    let n = sol.nodes.free;
    Extremes::of(&sol.nodes.positions[..n], &sol.displacement[..n], sol.stress.as_ref().map(|s| s.von_mises.as_slice()))
}

/// The stability limit of a dynamic run's scheme (s): the central-difference limit
/// `2 / omega_max` times the scheme's factor (1; RK4 sqrt 2).
pub(super) fn stability_limit(r: &DynamicReport) -> f64 {
    r.stable_time_step * r.integrator.stability_factor()
}
