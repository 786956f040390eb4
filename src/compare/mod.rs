//! Nonlocal-to-local comparison: the local (Navier) displacement as a field that can
//! be evaluated at the peridynamic nodes, either the scene's exact solution or an MLSM
//! solution interpolated by moving least squares ([`interpolate`]); difference norms
//! on the interior region and the whole plate are [`crate::post::masked_errors`], and
//! observed orders in delta are [`crate::post::observed_order`] (least-squares slope).

pub mod interpolate;

use crate::domain::Point;
use crate::exact::ExactSolution;
use crate::problem::Problem;
use crate::run::{self, Progress, RunError};

/// The local solution the peridynamic runs are compared with.
pub enum LocalReference {
    /// The scene's closed-form solution (static scenes).
    Exact(Box<dyn ExactSolution>),
    /// An MLSM solution of the scene (static, or at `end_time` of a dynamic scene),
    /// interpolated with value shapes.
    Mlsm {
        /// What it is.
        description: String,
        /// MLSM nodes.
        positions: Vec<Point>,
        /// Nodal displacement.
        displacement: Vec<[f64; 2]>,
    },
}

impl LocalReference {
    /// The exact solution if a static scene has one, else an MLSM run of `problem`
    /// (explicit elastodynamics to `end_time` when the scene has a `[dynamics]` table).
    pub fn build(problem: &Problem, progress: &dyn Progress) -> Result<LocalReference, RunError> {
        if problem.dynamics.is_some() {
            let sim = crate::dynamics::navier::simulate(problem, progress, |_, _, _, _, _| Ok::<(), ()>(())).map_err(|e| match e {
                crate::dynamics::driver::IntegrateError::Run(r) => r,
                crate::dynamics::driver::IntegrateError::Output(()) => unreachable!("no output"),
            })?;
            let t = sim.energies.last().map_or(0.0, |e| e[0]);
            let description = format!(
                "MLSM elastodynamics at t = {t:.3e} s ({} nodes, spacing {:.3e}, {} steps)",
                sim.positions.len(),
                problem.fill.spacing,
                sim.report.steps
            );
            return Ok(LocalReference::Mlsm { description, positions: sim.positions, displacement: sim.u });
        }
        match run::exact_solution(problem) {
            Some(e) => Ok(LocalReference::Exact(e)),
            None => {
                let s = run::solve(problem, progress)?;
                let description = format!("MLSM solution ({} nodes, spacing {:.3e})", s.nodes.len(), s.nodes.spacing);
                Ok(LocalReference::Mlsm { description, positions: s.nodes.positions, displacement: s.displacement })
            }
        }
    }

    /// Short description for tables.
    pub fn describe(&self) -> String {
        match self {
            LocalReference::Exact(e) => format!("exact solution ({})", e.name()),
            LocalReference::Mlsm { description, .. } => description.clone(),
        }
    }

    /// Displacement at `points` (which must lie in the solid).
    pub fn displacement_at(&self, points: &[Point]) -> Result<Vec<[f64; 2]>, RunError> {
        match self {
            LocalReference::Exact(e) => Ok(points.iter().map(|p| e.displacement(*p)).collect()),
            LocalReference::Mlsm { positions, displacement, .. } => Ok(interpolate::mls_values(positions, displacement, points)?),
        }
    }
}
