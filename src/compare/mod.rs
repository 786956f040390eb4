//! Nonlocal-to-local comparison: the local (Navier) displacement as a field that can
//! be evaluated at the peridynamic nodes, either the scene's exact solution or an MLSM
//! solution interpolated by moving least squares ([`interpolate`]); difference norms
//! on the interior region and the whole plate are [`crate::post::masked_errors`], and
//! observed orders in delta are [`crate::post::observed_order`] (least-squares slope).

pub mod interpolate;

use crate::domain::Point;
use crate::exact::ExactSolution;
use crate::problem::Problem;
use crate::run::{self, Progress, RunError, Solution};

/// The local solution the peridynamic runs are compared with.
pub enum LocalReference {
    /// The scene's closed-form solution.
    Exact(Box<dyn ExactSolution>),
    /// An MLSM solution of the scene, interpolated with value shapes.
    Mlsm(Box<Solution>),
}

impl LocalReference {
    /// The exact solution if the scene has one, else an MLSM solve of `problem`.
    pub fn build(problem: &Problem, progress: &dyn Progress) -> Result<LocalReference, RunError> {
        match run::exact_solution(problem) {
            Some(e) => Ok(LocalReference::Exact(e)),
            None => Ok(LocalReference::Mlsm(Box::new(run::solve(problem, progress)?))),
        }
    }

    /// Short description for tables.
    pub fn describe(&self) -> String {
        match self {
            LocalReference::Exact(e) => format!("exact solution ({})", e.name()),
            LocalReference::Mlsm(s) => format!("MLSM solution ({} nodes, spacing {:.3e})", s.nodes.len(), s.nodes.spacing),
        }
    }

    /// Displacement at `points` (which must lie in the solid).
    pub fn displacement_at(&self, points: &[Point]) -> Result<Vec<[f64; 2]>, RunError> {
        match self {
            LocalReference::Exact(e) => Ok(points.iter().map(|p| e.displacement(*p)).collect()),
            LocalReference::Mlsm(s) => Ok(interpolate::mls_values(&s.nodes.positions, &s.displacement, points)?),
        }
    }
}
