//! The static Navier run, stage by stage (no printing; stages report to the timer's
//! observer): nodes -> supports -> shapes -> assembly -> solve -> post-processing
//! (gradients, strain, stress, von Mises, errors against the exact solution).

use super::discrete::Discretisation;
use super::equations::ComponentEquation;
use super::system::System;
use super::NavierParams;
use crate::case::Case;
use crate::domain::NodeSet;
use crate::elasticity::stress::{Gradient, StressField};
use crate::linalg::{self, SolveReport};
use crate::pipeline::{stage, Progress, RunError, StageTimer, StageTimings};
use crate::post::{ErrorNorms, ExactFields};

/// Everything a static Navier run computed.
pub struct Solution {
    /// Nodes.
    pub nodes: NodeSet,
    /// Equations of each boundary node (x and y).
    pub boundary_equations: Vec<[ComponentEquation; 2]>,
    /// Nodal displacements.
    pub displacement: Vec<[f64; 2]>,
    /// Displacement gradients, when post-processing needed them.
    pub gradient: Option<Vec<Gradient>>,
    /// Stresses, when gradients exist.
    pub stress: Option<StressField>,
    /// Exact displacement and stress at the nodes, when an exact solution is known.
    pub exact: Option<ExactFields>,
    /// Error norms, when an exact solution is known.
    pub errors: Option<ErrorNorms>,
    /// Number of ghost nodes.
    pub ghost_nodes: usize,
    /// Supports widened to determine an RBF-FD polynomial part.
    pub widened_supports: usize,
    /// Number of unknowns.
    pub unknowns: usize,
    /// Nonzeros of the assembled matrix.
    pub nonzeros: usize,
    /// Operators computed, with the number of nodes each was computed at.
    pub operators_computed: Vec<(String, usize)>,
    /// Solver report.
    pub solver: SolveReport,
    /// Stage timings.
    pub timings: StageTimings,
}

/// Run every stage of `case` with `params`.
pub fn solve(case: &Case, params: &NavierParams, progress: &dyn Progress) -> Result<Solution, RunError> {
    let mut timer = StageTimer::new(progress);
    let exact = case.exact_solution();
    let exact = exact.as_deref();
    let disc = Discretisation::new(case, params, exact, &mut timer)?;
    let (matrix, rhs) = timer.run(stage::ASSEMBLY, || {
        let (triplets, rhs) = System { case, disc: &disc, exact }.assemble()?;
        let m = linalg::assemble(&triplets)?;
        let note = format!("{} unknowns, {} nonzeros", disc.dofs.len(), m.compute_nnz());
        Ok(((m, rhs), note))
    })?;
    let nonzeros = matrix.compute_nnz();
    let (x, report) = timer.run(stage::SOLVE, || {
        let (x, report) = linalg::solve(&matrix, &rhs, &params.solver)?;
        let note = format!("{}: {} iterations, relative residual {:.1e}", report.method, report.iterations, report.relative_residual);
        Ok(((x, report), note))
    })?;
    drop(matrix);

    let n = disc.nodes.len();
    let (displacement, gradient, stress, exact_fields, errors) = timer.run(stage::POST, || {
        let displacement = disc.dofs.displacements(&x, n);
        let gradient = case.outputs.needs_gradient().then(|| disc.gradients(&x));
        let stress = gradient.as_ref().map(|g| StressField::from_gradients(&case.material, g));
        let exact_fields = exact.map(|e| ExactFields::at(e, &disc.nodes.positions, true));
        let errors = exact_fields.as_ref().map(|ef| ErrorNorms::against(&displacement, stress.as_ref(), ef));
        let note = match &errors {
            Some(e) => format!("e_inf(u) = {:.3e}", e.e_inf_u),
            None => String::new(),
        };
        Ok(((displacement, gradient, stress, exact_fields, errors), note))
    })?;

    let ghost_nodes = disc.ghost_count();
    let widened_supports = disc.widened_supports;
    let unknowns = disc.dofs.len();
    let Discretisation { nodes, boundary_equations, operators_computed, .. } = disc;
    Ok(Solution {
        nodes,
        boundary_equations,
        displacement,
        gradient,
        stress,
        exact: exact_fields,
        errors,
        ghost_nodes,
        widened_supports,
        unknowns,
        nonzeros,
        operators_computed,
        solver: report,
        timings: timer.finish(),
    })
}
