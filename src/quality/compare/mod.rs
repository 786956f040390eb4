//! Nonlocal-to-local comparison: the local (Navier) displacement as a field that can
//! be evaluated at the peridynamic nodes, either the scene's exact solution or an MLSM
//! solution interpolated by moving least squares ([`crate::mlsm::interpolate`]); difference norms
//! on the interior region and the whole plate are [`crate::quality::post::masked_errors`], and
//! observed orders in delta are [`crate::quality::post::observed_order`] (least-squares slope).

pub mod estimate;

use crate::domain::Point;
use crate::physics::exact::ExactSolution;
use crate::models::dispatch::{self, Outcome};
use crate::stages::{Progress, RunError};
use crate::scene::problem::{Model, Problem};

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
    /// The exact solution if a static scene has one, else the Navier model's run of
    /// `problem` (explicit elastodynamics to `end_time` when the scene has a
    /// `[dynamics]` table).
    pub fn build(problem: &Problem, progress: &dyn Progress) -> Result<LocalReference, RunError> {
        if problem.case.dynamics.is_none() {
            if let Some(e) = problem.case.exact_solution() {
                return Ok(LocalReference::Exact(e));
            }
        }
        let navier = Problem { model: problem.model.running(Model::Navier).expect("the Navier model always runs"), ..problem.clone() };
        let outcome = dispatch::solve(&navier, progress, |_| Ok(()))?;
        let description = outcome.describe(&navier);
        let (positions, displacement) = match outcome {
            Outcome::NavierStatic(s) => (s.nodes.positions, s.displacement),
            Outcome::NavierDynamic(s) => (s.positions, s.u),
            Outcome::PdStatic(_) | Outcome::PdDynamic(_) => unreachable!("the reference runs the Navier model"),
        };
        Ok(LocalReference::Mlsm { description, positions, displacement })
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
            LocalReference::Mlsm { positions, displacement, .. } => {
                Ok(crate::mlsm::interpolate::mls_values(positions, displacement, points)?)
            }
        }
    }
}
