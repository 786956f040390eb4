//! The time-dependent peridynamic run: nodes, families and weights
//! ([`super::Discretisation`]), the semi-discrete system ([`super::dynamics::PdDynamics`])
//! integrated from the scene's initial conditions, snapshots (with the damage where bonds
//! break, [`super::fracture`]), the energy history and what broke.

use super::dynamics::{PdDynamics, VaryingLoads};
use super::fracture::Breaking;
use super::loads::LoadLayer;
use super::pairs::Pairs;
use super::solve::Discretisation;
use super::PdParams;
use crate::models::dynamics::driver::{integrate, is_snapshot, time_grid, DynamicReport, EnergyRow, Snapshot, TimeGrid};
use crate::models::dynamics::history::TimeSamples;
use crate::models::dynamics::integrators::Integrator;
use crate::models::dynamics::{DynamicsParams, State};
use crate::physics::case::Case;
use crate::physics::elasticity::conditions::Value;
use crate::stages::{Progress, RunError, Stage, StageTimer, StageTimings};
use std::collections::BTreeMap;

/// The force loop's layout ([`Pairs`]): the weights' symmetry checked.
pub const PAIRS: Stage = Stage::new("pairs");

/// The result of a time-dependent peridynamic run.
pub struct Simulation {
    /// The discretisation (nodes, families, weights).
    pub discretisation: Discretisation,
    /// Final displacement of the free nodes.
    pub u: Vec<[f64; 2]>,
    /// Final velocity of the free nodes.
    pub v: Vec<[f64; 2]>,
    /// Integration report.
    pub report: DynamicReport,
    /// Energy history.
    pub energies: Vec<EnergyRow>,
    /// Bond updates per second per thread in the time loop.
    pub bond_updates_per_second_per_thread: f64,
    /// The states kept for an error estimate, `(t, displacement of the free nodes)`
    /// ([`crate::models::dynamics::driver::history_steps`]); empty unless asked for.
    pub history: Vec<(f64, Vec<[f64; 2]>)>,
    /// What broke, when the scene has `[peridynamics.fracture]`.
    pub fracture: Option<FractureReport>,
    /// Stage timings.
    pub timings: StageTimings,
}

/// What broke in a dynamic run with `[peridynamics.fracture]`.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct FractureReport {
    /// The critical stretch `s0` (given or from `G0`); `None` with pre-cracks only.
    pub critical_stretch: Option<f64>,
    /// Bonds broken from the start by the pre-cracks (both directions counted).
    pub precracked_bonds: usize,
    /// Bonds broken during the run (both directions counted).
    pub broken_bonds: usize,
    /// The elastic energy those bonds held when they broke (J per unit thickness).
    pub released_energy: f64,
    /// Free nodes with some damage at the end.
    pub damaged_nodes: usize,
    /// The largest damage at the end.
    pub largest_damage: f64,
}

/// Run `case` (with `dynamics`) with peridynamics `params`, calling `snapshot` (free
/// nodes) at the snapshot steps.
pub fn simulate(
    case: &Case,
    params: &PdParams,
    dynamics: &DynamicsParams,
    progress: &dyn Progress,
    snapshot: impl FnMut(Snapshot) -> Result<(), RunError>,
) -> Result<Simulation, RunError> {
    simulate_sampled(case, params, dynamics, progress, false, snapshot)
}

/// [`simulate`], keeping the states of its history for an error estimate when
/// `keep_history`.
pub fn simulate_sampled(
    case: &Case,
    params: &PdParams,
    dynamics: &DynamicsParams,
    progress: &dyn Progress,
    keep_history: bool,
    mut snapshot: impl FnMut(Snapshot) -> Result<(), RunError>,
) -> Result<Simulation, RunError> {
    let mut timer = StageTimer::new(progress);
    let (finish, discretisation) = with_system(case, params, dynamics, &mut timer, |system, disc, mut state, grid, timer| {
        let breaking = system.breaking;
        let dofs = disc.nodes.dofs();
        let free = &disc.nodes.positions[..disc.nodes.free];
        let nodal = |x: &[f64]| dofs.displacements(x, dofs.nodes());
        let energy = |s: &State| system.energies(s.t, &s.u, &s.v);
        let samples = if keep_history { TimeSamples::own(grid.steps, grid.dt) } else { TimeSamples::none() };
        let mut kept = BTreeMap::new();
        let (report, energies) = integrate(system, &energy, &mut state, (grid, &samples.steps), dynamics, timer, |step, s| {
            let (u, v) = (nodal(&s.u), nodal(&s.v));
            if is_snapshot(step, grid.steps, dynamics) {
                let stress =
                    (case.outputs.stress || case.outputs.von_mises).then(|| system.stress(&case.material, &disc.families, s.t, &u));
                let damage = system.damage();
                snapshot(Snapshot { step, t: s.t, positions: free, u: &u, v: &v, stress: stress.as_ref(), damage: damage.as_deref() })?;
            }
            if samples.keeps(step) {
                kept.insert(step, (s.t, u, v));
            }
            Ok(())
        })?;
        let history = samples.states(&kept);
        drop(kept);
        let throughput = report.force_evaluations as f64 * disc.families.bonds() as f64
            / report.seconds.max(1e-12)
            / rayon::current_num_threads() as f64;
        let (u, v) = (nodal(&state.u), nodal(&state.v));
        let fracture = breaking.as_ref().map(|b| {
            let damage = system.damage().unwrap_or_default();
            let (broken, released) = b.released();
            FractureReport {
                critical_stretch: b.critical_stretch.is_finite().then_some(b.critical_stretch),
                precracked_bonds: b.precracked,
                broken_bonds: broken,
                released_energy: released,
                damaged_nodes: damage.iter().filter(|&&d| d > 0.0).count(),
                largest_damage: damage.iter().copied().fold(0.0, f64::max),
            }
        });
        Ok(move |discretisation| Simulation {
            discretisation,
            u,
            v,
            report,
            energies,
            bond_updates_per_second_per_thread: throughput,
            history,
            fracture,
            timings: StageTimings::default(),
        })
    })?;
    Ok(Simulation { timings: timer.finish(), ..finish(discretisation) })
}

/// Build what a time-dependent run integrates (the discretisation, the loads, the bonds
/// that break, the force loop's pairs; each a stage of `timer`) and hand `run` the
/// system, its discretisation, the initial state and the time grid; `run`'s result and
/// the discretisation back.
pub fn with_system<R>(
    case: &Case,
    params: &PdParams,
    dynamics: &DynamicsParams,
    timer: &mut StageTimer,
    run: impl FnOnce(&PdDynamics, &Discretisation, State, TimeGrid, &mut StageTimer) -> Result<R, RunError>,
) -> Result<(R, Discretisation), RunError> {
    let exact = case.exact_solution();
    let disc = Discretisation::new(case, params, exact.as_deref(), timer)?;
    let layer = LoadLayer::new(&case.domain, &case.conditions, &disc.nodes);
    let body_force = layer.forces(&case.body_force, &case.conditions, exact.as_deref(), &disc.nodes)?;
    let varying = case.loads().depend_on_time().then_some(VaryingLoads { case, layer: &layer, exact: exact.as_deref() });
    let breaking = params.fracture.map(|f| {
        let s0 = f.critical_stretch(&disc.micromodulus).unwrap_or(f64::INFINITY);
        Breaking::new(&disc.nodes.positions, &disc.families, &disc.weights.coefficients, &f.cuts(&case.domain), s0)
    });
    let pairs = timer.run(PAIRS, || {
        let pairs = Pairs::new(&disc.nodes, &disc.families, &disc.weights.coefficients);
        let note = if pairs.directed() {
            "each bond from both ends: the weights are not symmetric"
        } else {
            "each bond once: the weights are symmetric"
        };
        Ok((pairs, note.to_string()))
    })?;
    let system = PdDynamics {
        bonds: disc.bonds(),
        body_force: &body_force,
        density: dynamics.density,
        force: params.force,
        dilatation: disc.dilatation.as_ref(),
        varying,
        breaking: breaking.as_ref(),
        pairs: &pairs,
        energy_in_loop: dynamics.integrator == Integrator::Verlet,
    };
    let free = &disc.nodes.positions[..disc.nodes.free];
    let dofs = disc.nodes.dofs();
    let flat = |f: &Value| {
        dofs.from_displacements(|i| f.explicit_at(free[i]).expect("validated: an initial state is a constant or an expression"))
    };
    let grid = time_grid(system.stable_time_step(), dynamics)?;
    let state = State::new(&system, 0.0, flat(&dynamics.initial_displacement), flat(&dynamics.initial_velocity));
    let result = run(&system, &disc, state, grid, timer)?;
    Ok((result, disc))
}
