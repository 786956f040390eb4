//! One run of one scene, stage by stage (no printing; stages are reported to a
//! [`Progress`] observer):
//! nodes -> supports -> shapes (only the operators each node needs) -> assembly ->
//! solve -> post-processing (gradients, strain, stress, von Mises, errors).

use crate::domain::{self, neighbors::Supports, NodeSet};
use crate::elasticity::conditions::{resolve, ComponentEquation};
use crate::elasticity::dofs::DofMap;
use crate::elasticity::rows::{Entries, RowWriter};
use crate::elasticity::stress;
use crate::exact::{self, ExactSolution};
use crate::linalg::{self, SolveError, SolveReport, Triplets};
use crate::mlsm::{compute_shapes, OpSet, ShapeError, Shapes};
use crate::post::{relative_errors, ErrorNorms};
use crate::problem::{Problem, Value};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Stages of a run, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Node generation.
    Nodes,
    /// Support search.
    Supports,
    /// Shape functions.
    Shapes,
    /// Peridynamic families (bonds within the horizon).
    Families,
    /// Peridynamic bond weights.
    Weights,
    /// Matrix assembly.
    Assembly,
    /// Linear solve.
    Solve,
    /// Explicit time integration.
    Integrate,
    /// Stresses and errors.
    Post,
}

impl Stage {
    /// Name as used in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Nodes => "nodes",
            Stage::Supports => "supports",
            Stage::Shapes => "shapes",
            Stage::Families => "families",
            Stage::Weights => "weights",
            Stage::Assembly => "assembly",
            Stage::Solve => "solve",
            Stage::Integrate => "integrate",
            Stage::Post => "post",
        }
    }
}

/// Observer of stage starts and ends (the CLI shows progress with it).
pub trait Progress: Sync {
    /// A stage begins.
    fn start(&self, stage: Stage);
    /// A stage ended after `seconds`, with a short note (sizes).
    fn finish(&self, stage: Stage, seconds: f64, note: &str);
    /// `done` of `total` steps of the current stage are complete (long stages only).
    fn advance(&self, _done: u64, _total: u64) {}
}

/// A progress observer that does nothing.
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _: Stage) {}
    fn finish(&self, _: Stage, _: f64, _: &str) {}
}

/// Why a run failed after validation.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// A fixed time step above the stability limit of the scheme.
    #[error("time step {given:.3e} s exceeds the stable step {limit:.3e} s of the {integrator} scheme (central-difference bound sqrt(2 rho / max_i sum_j |c_ij| |xi|^2)); use a smaller dynamics.time_step or leave it out")]
    UnstableTimeStep { given: f64, limit: f64, integrator: &'static str },
    /// The solution became non-finite during time integration.
    #[error("the solution became non-finite at step {step} (t = {t:.4e} s): the time integration diverged")]
    Diverged { step: usize, t: f64 },
    /// Too few nodes for the support size.
    #[error("the node set has {nodes} nodes, fewer than the support size {support}; use a smaller nodes.spacing")]
    TooFewNodes { nodes: usize, support: usize },
    /// A local least-squares problem is rank deficient.
    #[error(transparent)]
    Shape(#[from] ShapeError),
    /// The linear solver failed.
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
    /// A non-finite coefficient in a row.
    #[error("non-finite coefficient in the equations of node {node} at ({x:.6e}, {y:.6e})")]
    NotFinite { node: usize, x: f64, y: f64 },
}

/// Wall-clock seconds per stage.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Timings {
    /// Node generation.
    pub nodes: f64,
    /// Support search.
    pub supports: f64,
    /// Shape functions.
    pub shapes: f64,
    /// Assembly.
    pub assembly: f64,
    /// Linear solve (including factorisation / preconditioner).
    pub solve: f64,
    /// Post-processing.
    pub post: f64,
    /// Writing files (filled by the caller).
    pub output: f64,
}

/// Everything a run computed.
pub struct Solution {
    /// Nodes.
    pub nodes: NodeSet,
    /// Equations of each boundary node (x and y).
    pub boundary_equations: Vec<[ComponentEquation; 2]>,
    /// Nodal displacements.
    pub displacement: Vec<[f64; 2]>,
    /// Displacement gradients, when post-processing needed them.
    pub gradient: Option<Vec<[[f64; 2]; 2]>>,
    /// Stress `[sxx, syy, sxy]`, `sigma_zz`, von Mises, when gradients exist.
    pub stress: Option<(Vec<[f64; 3]>, Vec<f64>, Vec<f64>)>,
    /// Exact displacement and stress at the nodes, when an exact solution is known.
    pub exact: Option<(Vec<[f64; 2]>, Vec<[f64; 3]>)>,
    /// Error norms, when an exact solution is known.
    pub errors: Option<ErrorNorms>,
    /// Number of ghost nodes.
    pub ghost_nodes: usize,
    /// Number of unknowns.
    pub unknowns: usize,
    /// Nonzeros of the assembled matrix.
    pub nonzeros: usize,
    /// Operators computed, with the number of nodes each was computed at.
    pub operators_computed: Vec<(String, usize)>,
    /// Solver report.
    pub solver: SolveReport,
    /// Stage timings.
    pub timings: Timings,
}

pub(crate) fn timed<T>(
    progress: &dyn Progress,
    stage: Stage,
    slot: &mut f64,
    f: impl FnOnce() -> Result<(T, String), RunError>,
) -> Result<T, RunError> {
    progress.start(stage);
    let t0 = Instant::now();
    let (v, note) = f()?;
    *slot = t0.elapsed().as_secs_f64();
    progress.finish(stage, *slot, &note);
    Ok(v)
}

/// The exact solution of a problem, if it names one.
pub fn exact_solution(problem: &Problem) -> Option<Box<dyn ExactSolution>> {
    problem.exact.as_ref().map(|k| exact::from_kind(k, problem.material).expect("validated exact solution parameters"))
}

/// The MLSM discretisation of a problem: nodes, ghosts, supports, shape functions and
/// the boundary equations, ready for assembly.
pub struct Discrete {
    /// Nodes of the solid.
    pub nodes: NodeSet,
    /// Equations of each boundary node.
    pub boundary_equations: Vec<[ComponentEquation; 2]>,
    /// Ghost node of each node (`usize::MAX`: none); ghosts are nodes `n..`.
    pub ghost: Vec<usize>,
    /// Supports over nodes and ghosts.
    pub supports: Supports,
    /// Shape functions over nodes and ghosts.
    pub shapes: Shapes,
    /// Operators computed, with the number of nodes each was computed at.
    pub operators_computed: Vec<(String, usize)>,
    /// Unknown layout over nodes and ghosts.
    pub dofs: DofMap,
}

impl Discrete {
    /// Nodes, ghosts, supports and shapes of `problem`, each stage timed into `t`.
    pub fn new(problem: &Problem, progress: &dyn Progress, t: &mut Timings) -> Result<Discrete, RunError> {
        let exact = exact_solution(problem);
        let exact = exact.as_deref();
        let n_support = problem.approximation.support;
        let nodes = timed(progress, Stage::Nodes, &mut t.nodes, || {
            let nodes = domain::generate(&problem.domain, &problem.fill);
            if nodes.len() < n_support {
                return Err(RunError::TooFewNodes { nodes: nodes.len(), support: n_support });
            }
            let note = format!("{} nodes ({} on the boundary)", nodes.len(), nodes.boundary.len());
            Ok((nodes, note))
        })?;
        let n = nodes.len();

        let boundary_equations: Vec<[ComponentEquation; 2]> =
            nodes.boundary.iter().map(|b| resolve(b, &problem.conditions, exact)).collect();
        let has_traction =
            |i: usize| i < nodes.boundary.len() && boundary_equations[i].iter().any(|e| matches!(e, ComponentEquation::Traction { .. }));
        // Ghost nodes (positions n..) only where both equations are tractions: on mixed
        // (symmetry) nodes an extra Navier row made scattered-node runs unstable (measured
        // on kirsch.toml: e_inf(sigma) 1.4e-2 at h = 0.005 with them, 3.1e-4 without).
        // Placing them is part of building the point cloud, so it is timed with the supports.
        let all_traction = |i: usize| boundary_equations[i].iter().all(|e| matches!(e, ComponentEquation::Traction { .. }));
        let (positions, ghost, supports) = timed(progress, Stage::Supports, &mut t.supports, || {
            let candidates: Vec<usize> = if problem.approximation.ghost_nodes {
                (0..nodes.boundary.len()).filter(|&i| all_traction(i)).collect()
            } else {
                Vec::new()
            };
            let ghosts = crate::domain::ghost::place_ghosts(&problem.domain, &nodes, &candidates);
            let mut positions = nodes.positions.clone();
            positions.extend(ghosts.iter().map(|g| g.1));
            let mut ghost = vec![usize::MAX; n];
            for (k, g) in ghosts.iter().enumerate() {
                ghost[g.0] = n + k;
            }
            let supports = Supports::nearest(&positions, n_support);
            let note = format!("{n_support} nearest, {} ghost nodes", ghosts.len());
            Ok(((positions, ghost, supports), note))
        })?;
        let n_all = positions.len();

        let gradient_needed = problem.outputs.needs_gradient();
        let needs: Vec<OpSet> = (0..n_all)
            .map(|i| {
                if i >= n {
                    return OpSet::EMPTY;
                }
                let mut ops = if gradient_needed { OpSet::D1 } else { OpSet::EMPTY };
                if has_traction(i) {
                    ops |= OpSet::D1;
                }
                if i >= nodes.boundary.len() || ghost[i] != usize::MAX {
                    ops |= OpSet::D2;
                }
                ops
            })
            .collect();

        let shapes = timed(progress, Stage::Shapes, &mut t.shapes, || {
            let s = compute_shapes(&positions, &supports, &problem.approximation, &needs)?;
            let note = format!("{} shape functions", s.count());
            Ok((s, note))
        })?;
        let operators_computed = crate::mlsm::Op::ALL
            .iter()
            .filter(|op| shapes.operators().contains(**op))
            .map(|op| (OpSet::from(*op).names()[0].to_string(), (0..n).filter(|&i| shapes.computed_at(i).contains(*op)).count()))
            .collect();

        let dofs = DofMap::new(n_all);
        Ok(Discrete { nodes, boundary_equations, ghost, supports, shapes, operators_computed, dofs })
    }

    /// The rows of every equation (see [`System::assemble`]).
    pub fn system<'a>(&'a self, problem: &'a Problem, exact: Option<&'a dyn ExactSolution>) -> System<'a> {
        System {
            problem,
            nodes: &self.nodes,
            supports: &self.supports,
            shapes: &self.shapes,
            equations: &self.boundary_equations,
            ghost: &self.ghost,
            exact,
            dofs: self.dofs,
        }
    }
}

/// Run every stage of `problem`.
pub fn solve(problem: &Problem, progress: &dyn Progress) -> Result<Solution, RunError> {
    let mut t = Timings::default();
    let exact = exact_solution(problem);
    let exact = exact.as_deref();
    let disc = Discrete::new(problem, progress, &mut t)?;
    let gradient_needed = problem.outputs.needs_gradient();
    let (matrix, rhs) = timed(progress, Stage::Assembly, &mut t.assembly, || {
        let system = disc.system(problem, exact);
        let (triplets, rhs) = system.assemble()?;
        let m = linalg::assemble(&triplets)?;
        let note = format!("{} unknowns, {} nonzeros", disc.dofs.len(), m.compute_nnz());
        Ok(((m, rhs), note))
    })?;
    let Discrete { nodes, boundary_equations, ghost: _, supports, shapes, operators_computed, dofs } = disc;
    let n = nodes.len();
    let ghost_count = dofs.len() / 2 - n;
    let nonzeros = matrix.compute_nnz();

    let (x, report) = timed(progress, Stage::Solve, &mut t.solve, || {
        let (x, report) = linalg::solve(&matrix, &rhs, &problem.solver)?;
        let note = format!("{}: {} iterations, relative residual {:.1e}", report.method, report.iterations, report.relative_residual);
        Ok(((x, report), note))
    })?;
    drop(matrix);

    let (displacement, gradient, stress, exact_fields, errors) = timed(progress, Stage::Post, &mut t.post, || {
        let displacement: Vec<[f64; 2]> = (0..n).map(|i| dofs.displacement(&x, i)).collect();
        let gradient = gradient_needed.then(|| stress::gradients(&dofs, &supports, &shapes, &x, n));
        let stress = gradient.as_ref().map(|g| stress::stresses(&problem.material, g));
        let exact_fields = exact.map(|e| {
            let u: Vec<[f64; 2]> = nodes.positions.par_iter().map(|p| e.displacement(*p)).collect();
            let s: Vec<[f64; 3]> = nodes.positions.par_iter().map(|p| e.stress(*p)).collect();
            (u, s)
        });
        let errors = exact_fields.as_ref().map(|(ue, se)| {
            let (e_inf_u, rel_l2_u) = relative_errors(&displacement, ue);
            let sig = stress.as_ref().map(|(s, _, _)| relative_errors(s, se));
            ErrorNorms { e_inf_u, e_inf_sigma: sig.map(|s| s.0), rel_l2_u, rel_l2_sigma: sig.map(|s| s.1) }
        });
        let note = match &errors {
            Some(e) => format!("e_inf(u) = {:.3e}", e.e_inf_u),
            None => String::new(),
        };
        Ok(((displacement, gradient, stress, exact_fields, errors), note))
    })?;

    Ok(Solution {
        nodes,
        boundary_equations,
        displacement,
        gradient,
        stress,
        exact: exact_fields,
        errors,
        ghost_nodes: ghost_count,
        unknowns: dofs.len(),
        nonzeros,
        operators_computed,
        solver: report,
        timings: t,
    })
}

/// Everything the equation rows of one discretisation need.
pub struct System<'a> {
    /// The scene.
    pub problem: &'a Problem,
    /// Nodes of the solid (ghosts are not in it).
    pub nodes: &'a NodeSet,
    /// Supports over nodes and ghosts.
    pub supports: &'a Supports,
    /// Shape functions over nodes and ghosts.
    pub shapes: &'a Shapes,
    /// Boundary equations of the boundary nodes.
    pub equations: &'a [[ComponentEquation; 2]],
    /// Ghost node of each node (`usize::MAX`: none).
    pub ghost: &'a [usize],
    /// Exact solution for boundary values and body force.
    pub exact: Option<&'a dyn ExactSolution>,
    /// Unknown layout over nodes and ghosts.
    pub dofs: DofMap,
}

impl System<'_> {
    /// Rows of every node, in parallel; returns the triplets and the right-hand side.
    ///
    /// Interior nodes carry the Navier rows; boundary nodes their boundary rows and,
    /// when they have a ghost, also the Navier rows (then the node's own rows hold
    /// the Navier equation and the ghost's rows the tractions).
    pub fn assemble(&self) -> Result<(Triplets, Vec<f64>), RunError> {
        let (nodes, dofs) = (self.nodes, self.dofs);
        let writer = RowWriter { dofs, lame: self.problem.material.lame(), supports: self.supports, shapes: self.shapes };
        let body_force = |i: usize| match self.problem.body_force {
            Value::Constant(f) => f,
            Value::Exact => self.exact.expect("validated").body_force(nodes.positions[i]),
        };
        let per_node: Vec<(Entries, Vec<(usize, f64)>)> = (0..nodes.len())
            .into_par_iter()
            .map(|i| {
                let mut e = Entries::with_capacity(8 * self.supports.size());
                let mut rhs = Vec::with_capacity(4);
                if i < nodes.boundary.len() {
                    // With a ghost, the node's own rows take the Navier equation and the
                    // ghost's rows the tractions: both then have a large diagonal entry
                    // (the centre weight of a first derivative on a symmetric stencil is
                    // ~0), which incomplete factorisations without pivoting need.
                    let g = self.ghost[i];
                    let bc_rows = if g != usize::MAX { g } else { i };
                    for (c, eq) in self.equations[i].iter().enumerate() {
                        let r = match *eq {
                            ComponentEquation::Displacement { value } => writer.displacement(i, c, value, &mut e),
                            ComponentEquation::Traction { normal, value } => writer.traction(i, bc_rows, c, normal, value, &mut e),
                        };
                        rhs.push((dofs.dof(bc_rows, c), r));
                    }
                    if g != usize::MAX {
                        let r = writer.navier(i, i, body_force(i), &mut e);
                        rhs.extend([(dofs.dof(i, 0), r[0]), (dofs.dof(i, 1), r[1])]);
                    }
                } else {
                    let r = writer.navier(i, i, body_force(i), &mut e);
                    rhs.extend([(dofs.dof(i, 0), r[0]), (dofs.dof(i, 1), r[1])]);
                }
                (e, rhs)
            })
            .collect();
        let total: usize = per_node.iter().map(|(e, _)| e.len()).sum();
        let mut triplets = Triplets::with_capacity(dofs.len(), total);
        let mut rhs = vec![0.0; dofs.len()];
        for (i, (entries, r)) in per_node.into_iter().enumerate() {
            if entries.iter().any(|e| !e.2.is_finite()) || r.iter().any(|v| !v.1.is_finite()) {
                let p = nodes.positions[i];
                return Err(RunError::NotFinite { node: i, x: p[0], y: p[1] });
            }
            for (row, col, v) in entries {
                triplets.push(row, col, v);
            }
            for (row, v) in r {
                rhs[row] = v;
            }
        }
        Ok((triplets, rhs))
    }
}
