//! The static peridynamic run: nodes -> families -> bond weights -> stiffness ->
//! solve -> post-processing (nonlocal strain, errors against an exact solution on
//! the whole plate and on the interior region at distance >= delta from the boundary).

use super::family::Families;
use super::kernel::{fourth_moment, Micromodulus};
use super::nodes::{self, Body, PdNodes};
use super::operator::Bonds;
use super::weights::{bond_coefficients, search_radius, BondWeights};
use super::{loads, strain, PdParams};
use crate::elasticity::stress;
use crate::exact::ExactSolution;
use crate::linalg::{self, SolveReport};
use crate::post::{masked_errors, ErrorNorms};
use crate::problem::Problem;
use crate::run::{exact_solution, timed, Progress, RunError, Stage};
use rayon::prelude::*;
use serde::Serialize;

/// Wall-clock seconds per stage of a peridynamic run.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct PdTimings {
    /// Node layout (cells, collar).
    pub nodes: f64,
    /// Family search.
    pub families: f64,
    /// Bond weights (quadrature, correction, compatible weights).
    pub weights: f64,
    /// Loads and stiffness assembly.
    pub assembly: f64,
    /// Linear solve.
    pub solve: f64,
    /// Strain, stress, errors.
    pub post: f64,
    /// Writing files (filled by the caller).
    pub output: f64,
}

/// Everything a static peridynamic run computed.
pub struct PdSolution {
    /// The parameters used.
    pub params: PdParams,
    /// Nodes (free first, then the constrained collar).
    pub nodes: PdNodes,
    /// Displacement of every node (prescribed values on the collar).
    pub displacement: Vec<[f64; 2]>,
    /// Body force density at the free nodes (tractions included).
    pub body_force: Vec<[f64; 2]>,
    /// Free nodes at distance >= delta from the boundary.
    pub interior: Vec<bool>,
    /// Free nodes carrying a traction layer load.
    pub layer_nodes: usize,
    /// Bonds (both directions counted).
    pub bonds: usize,
    /// Bond weighting report.
    pub weights: WeightsSummary,
    /// Unknowns and nonzeros.
    pub unknowns: usize,
    /// Nonzeros of the stiffness.
    pub nonzeros: usize,
    /// Nonlocal displacement gradient, when outputs need it.
    pub gradient: Option<Vec<[[f64; 2]; 2]>>,
    /// Stress `[sxx, syy, sxy]`, `sigma_zz`, von Mises, from the gradient.
    pub stress: Option<(Vec<[f64; 3]>, Vec<f64>, Vec<f64>)>,
    /// Exact displacement at the free nodes.
    pub exact: Option<Vec<[f64; 2]>>,
    /// Errors on the whole plate and on the interior region.
    pub errors: Option<(ErrorNorms, Option<ErrorNorms>)>,
    /// Calibrated micromodulus.
    pub micromodulus: Micromodulus,
    /// Solver report.
    pub solver: SolveReport,
    /// Stage timings.
    pub timings: PdTimings,
}

/// Counts from the weighting stage.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct WeightsSummary {
    /// Free nodes with a complete family.
    pub complete_families: usize,
    /// Rows with asymptotically compatible weights.
    pub compatible_rows: usize,
    /// Complete rows whose moment problem was singular (base weights kept).
    pub compatible_failures: usize,
}

/// The discrete peridynamic operator of a scene: nodes, families, bond weights.
pub struct Discretisation {
    /// Nodes (free first, then the constrained collar).
    pub nodes: PdNodes,
    /// Families of the free nodes.
    pub families: Families,
    /// Bond coefficients.
    pub weights: BondWeights,
    /// Calibrated micromodulus.
    pub micromodulus: Micromodulus,
}

impl Discretisation {
    /// Build the nodes, families and bond weights of `problem` with `params` (`exact`:
    /// the scene's exact solution, for prescribed values), timing each stage into `t`.
    pub fn new(
        problem: &Problem,
        params: &PdParams,
        exact: Option<&dyn ExactSolution>,
        progress: &dyn Progress,
        t: &mut PdTimings,
    ) -> Result<Self, RunError> {
        let body = Body::new(&problem.domain, &problem.conditions, exact, params);
        let nodes = timed(progress, Stage::Nodes, &mut t.nodes, || {
            let n = nodes::generate(&body, params);
            let note = format!("{} free nodes, {} constrained, h = {:.3e}", n.free, n.constrained(), n.spacing);
            Ok((n, note))
        })?;
        let families = timed(progress, Stage::Families, &mut t.families, || {
            let f = Families::within(&nodes.positions, nodes.free, search_radius(params));
            let note = format!("{} bonds, {:.1} per node", f.bonds(), f.bonds() as f64 / nodes.free.max(1) as f64);
            Ok((f, note))
        })?;
        let moment = fourth_moment(&problem.material);
        let micromodulus = Micromodulus::calibrated(params.kernel, params.horizon, moment);
        let weights = timed(progress, Stage::Weights, &mut t.weights, || {
            let w = bond_coefficients(&body, &nodes, &families, &micromodulus, params, moment);
            let note = format!("{} complete families, {} compatible rows", w.complete_families, w.compatible_rows);
            Ok((w, note))
        })?;
        Ok(Discretisation { nodes, families, weights, micromodulus })
    }

    /// The operator `L_h` over these bonds.
    pub fn bonds(&self) -> Bonds<'_> {
        Bonds { nodes: &self.nodes, families: &self.families, coefficients: &self.weights.coefficients }
    }
}

/// Whether each point lies in the interior region, at distance >= `horizon` from the
/// boundary (where the comparisons and errors are also reported separately).
pub fn interior_flags(domain: &crate::domain::Domain, points: &[crate::domain::Point], horizon: f64) -> Vec<bool> {
    points.par_iter().map(|p| domain.signed_distance(*p) <= -horizon).collect()
}

/// Solve the static peridynamic problem of `problem` with `params`.
pub fn solve(problem: &Problem, params: &PdParams, progress: &dyn Progress) -> Result<PdSolution, RunError> {
    let mut t = PdTimings::default();
    let exact = exact_solution(problem);
    let exact = exact.as_deref();
    let mut slot = 0.0;
    let Discretisation { nodes, families, weights, micromodulus } = Discretisation::new(problem, params, exact, progress, &mut t)?;
    let bonds = Bonds { nodes: &nodes, families: &families, coefficients: &weights.coefficients };

    let (matrix, rhs, body_force, layer_nodes) = timed(progress, Stage::Assembly, &mut slot, || {
        let (b, layer) = loads::body_forces(&problem.domain, &problem.conditions, problem.body_force, exact, &nodes);
        let (m, rhs) = bonds.stiffness(&b).map_err(|node| {
            let p = nodes.positions[node];
            RunError::NotFinite { node, x: p[0], y: p[1] }
        })?;
        let note = format!("{} unknowns, {} nonzeros, {layer} nodes in loaded layers", rhs.len(), m.compute_nnz());
        Ok(((m, rhs, b, layer), note))
    })?;
    t.assembly = slot;
    let nonzeros = matrix.compute_nnz();
    let (x, report) = timed(progress, Stage::Solve, &mut slot, || {
        let (x, report) = linalg::solve(&matrix, &rhs, &params.solver)?;
        let note = format!("{}: relative residual {:.1e}", report.method, report.relative_residual);
        Ok(((x, report), note))
    })?;
    t.solve = slot;
    drop(matrix);

    let (displacement, interior, gradient, stress, exact_u, errors) = timed(progress, Stage::Post, &mut slot, || {
        let mut u: Vec<[f64; 2]> = (0..nodes.free).map(|i| [x[2 * i], x[2 * i + 1]]).collect();
        u.extend_from_slice(&nodes.prescribed);
        let interior = interior_flags(&problem.domain, &nodes.positions[..nodes.free], params.horizon);
        let gradient = problem.outputs.needs_gradient().then(|| strain::gradients(&nodes, &families, &u));
        let stress = gradient.as_ref().map(|g| stress::stresses(&problem.material, g));
        let exact_u: Option<Vec<[f64; 2]>> = exact.map(|e| nodes.positions[..nodes.free].par_iter().map(|p| e.displacement(*p)).collect());
        let errors = exact_u.as_ref().map(|ue| {
            let whole = masked_errors(&u, ue, |_| true).expect("at least one free node");
            (whole, masked_errors(&u, ue, |i| interior[i]))
        });
        let note = match &errors {
            Some((w, i)) => format!("e_inf(u) = {:.3e} (interior {})", w.e_inf_u, i.map_or("-".into(), |i| format!("{:.3e}", i.e_inf_u))),
            None => String::new(),
        };
        Ok(((u, interior, gradient, stress, exact_u, errors), note))
    })?;
    t.post = slot;

    Ok(PdSolution {
        params: *params,
        unknowns: 2 * nodes.free,
        bonds: families.bonds(),
        weights: WeightsSummary {
            complete_families: weights.complete_families,
            compatible_rows: weights.compatible_rows,
            compatible_failures: weights.compatible_failures,
        },
        nodes,
        displacement,
        body_force,
        interior,
        layer_nodes,
        nonzeros,
        gradient,
        stress,
        exact: exact_u,
        errors,
        micromodulus,
        solver: report,
        timings: t,
    })
}
