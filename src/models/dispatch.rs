//! Model dispatch: the one place that decides which pipeline runs a problem, static
//! or time-dependent (the scene's `[dynamics]` table) × Navier or peridynamics (the
//! scene's `model`, or `--model`). `mlsm run`, `mlsm compare` and the comparison's
//! local reference all go through [`solve`].

use crate::scene::choice::Choice;
use crate::domain::Point;
use crate::models::dynamics::driver::Snapshot;
use crate::models::navier;
use crate::models::peridynamics;
use crate::stages::{Progress, RunError, StageTimings};
use crate::scene::problem::{ModelParams, Problem};

/// What a run of one problem produced.
#[allow(clippy::large_enum_variant, reason = "one outcome per run, moved once")]
pub enum Outcome {
    /// A static Navier (MLSM) solve.
    NavierStatic(navier::Solution),
    /// MLSM elastodynamics to `end_time`.
    NavierDynamic(navier::Simulation),
    /// A static peridynamic solve.
    PdStatic(peridynamics::PdSolution),
    /// Peridynamic dynamics to `end_time`.
    PdDynamic(peridynamics::Simulation),
}

/// Run `problem` with its model: static, or integrated in time when it has a
/// `[dynamics]` table, then `snapshot` is called at the snapshot steps.
pub fn solve(
    problem: &Problem,
    progress: &dyn Progress,
    snapshot: impl FnMut(Snapshot) -> Result<(), RunError>,
) -> Result<Outcome, RunError> {
    let case = &problem.case;
    match &problem.model {
        ModelParams::Navier { .. } => match &case.dynamics {
            None => navier::solve(case, &problem.navier, progress).map(Outcome::NavierStatic),
            Some(d) => navier::simulate(case, &problem.navier, d, progress, snapshot).map(Outcome::NavierDynamic),
        },
        ModelParams::Peridynamics(params) => {
            match &case.dynamics {
                None => peridynamics::solve(case, params, progress).map(Outcome::PdStatic),
                Some(d) => {
                    let keep = problem.navier.estimate.method.peridynamics_estimates();
                    peridynamics::simulate_sampled(case, params, d, progress, keep, snapshot).map(Outcome::PdDynamic)
                }
            }
        }
    }
}

/// What [`solve`] will run, in one line (printed before it starts).
pub fn announce(problem: &Problem) -> String {
    let p = problem;
    match (&p.model, &p.case.dynamics) {
        (ModelParams::Navier { .. }, None) => format!("{}: solving", p.name),
        (ModelParams::Navier { .. }, Some(d)) => format!("{}: MLSM elastodynamics ({}, t_end = {:.3e} s)", p.name, d.integrator.name(), d.end_time),
        (ModelParams::Peridynamics(pd), None) => format!("{}: solving (peridynamics, {})", p.name, pd.quadrature.name()),
        (ModelParams::Peridynamics(pd), Some(d)) => {
            format!("{}: peridynamic dynamics ({}, {}, t_end = {:.3e} s)", p.name, pd.quadrature.name(), d.integrator.name(), d.end_time)
        }
    }
}

impl Outcome {
    /// The nodes the solution lives on (peridynamics: the free nodes).
    pub fn positions(&self) -> &[Point] {
        match self {
            Outcome::NavierStatic(s) => &s.nodes.positions,
            Outcome::NavierDynamic(s) => &s.positions,
            Outcome::PdStatic(s) => &s.nodes.positions[..s.nodes.free],
            Outcome::PdDynamic(s) => &s.discretisation.nodes.positions[..s.discretisation.nodes.free],
        }
    }

    /// Displacement at [`Outcome::positions`] (static, or at `end_time`).
    pub fn displacement(&self) -> &[[f64; 2]] {
        match self {
            Outcome::NavierStatic(s) => &s.displacement,
            Outcome::NavierDynamic(s) => &s.u,
            Outcome::PdStatic(s) => &s.displacement[..s.nodes.free],
            Outcome::PdDynamic(s) => &s.u,
        }
    }

    /// Solver iterations (static runs) or time steps (dynamic runs).
    pub fn iterations(&self) -> usize {
        match self {
            Outcome::NavierStatic(s) => s.solver.iterations,
            Outcome::PdStatic(s) => s.solver.iterations,
            Outcome::NavierDynamic(s) => s.report.steps,
            Outcome::PdDynamic(s) => s.report.steps,
        }
    }

    /// Seconds per stage.
    pub fn timings(&self) -> &StageTimings {
        match self {
            Outcome::NavierStatic(s) => &s.timings,
            Outcome::NavierDynamic(s) => &s.timings,
            Outcome::PdStatic(s) => &s.timings,
            Outcome::PdDynamic(s) => &s.timings,
        }
    }

    /// One line saying what was computed, for tables.
    pub fn describe(&self, problem: &Problem) -> String {
        match self {
            Outcome::NavierStatic(s) => match s.estimate.done() {
                Some(e) => format!(
                    "MLSM solution ({} nodes, spacing {:.3e}, estimated e_inf(u) ~ {:.1e})",
                    s.nodes.len(),
                    s.nodes.spacing,
                    e.norms.e_inf_u
                ),
                None => format!("MLSM solution ({} nodes, spacing {:.3e})", s.nodes.len(), s.nodes.spacing),
            },
            Outcome::NavierDynamic(s) => {
                let t = s.energies.last().map_or(0.0, |e| e[0]);
                format!(
                    "MLSM elastodynamics at t = {t:.3e} s ({} nodes, spacing {:.3e}, {} steps)",
                    s.positions.len(),
                    problem.navier.fill.spacing,
                    s.report.steps
                )
            }
            Outcome::PdStatic(s) => format!("peridynamics ({} free nodes, horizon {:.3e})", s.nodes.free, s.params.horizon),
            Outcome::PdDynamic(s) => {
                format!("peridynamic dynamics ({} free nodes, {} steps)", s.discretisation.nodes.free, s.report.steps)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::problem::Model;
    use crate::stages::Silent;
    use std::path::Path;

    fn shipped(name: &str) -> Problem {
        Problem::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("problems").join(name)).unwrap()
    }

    /// Each (model, static/dynamic) pair runs its own pipeline; only the time-dependent
    /// runs take snapshots; positions and displacements match in length.
    #[test]
    fn each_model_and_time_setting_runs_its_pipeline() {
        let fixed = shipped("pd_tension.toml");
        let mut moving = shipped("steel_plate_dynamic.toml");
        if let Some(d) = moving.case.dynamics.as_mut() {
            d.end_time = 2e-6;
        }
        let cases = [(fixed, false), (moving, true)];
        for (problem, dynamic) in cases {
            for model in [Model::Navier, Model::Peridynamics] {
                let p = Problem { model: problem.model.running(model).unwrap(), ..problem.clone() };
                let mut snapshots = 0;
                let outcome = solve(&p, &Silent, |_| {
                    snapshots += 1;
                    Ok(())
                })
                .unwrap();
                let kind = match (&outcome, dynamic) {
                    (Outcome::NavierStatic(_), false) | (Outcome::NavierDynamic(_), true) => Model::Navier,
                    (Outcome::PdStatic(_), false) | (Outcome::PdDynamic(_), true) => Model::Peridynamics,
                    _ => panic!("{model:?}, dynamic {dynamic}: wrong pipeline"),
                };
                assert_eq!(kind, model);
                assert_eq!(snapshots > 0, dynamic, "{model:?}: {snapshots} snapshots");
                assert_eq!(outcome.positions().len(), outcome.displacement().len());
                assert!(outcome.timings().get(crate::stages::stage::NODES) > 0.0);
                assert!(!outcome.describe(&p).is_empty());
            }
        }
    }
}
