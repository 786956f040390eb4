//! The MLSM discretisation of a case, ready for assembly: nodes, the boundary
//! equations of each boundary node, ghost nodes, supports, and the shape functions of
//! exactly the operators each node needs:
//!
//! | node | rows it carries | operators |
//! |---|---|---|
//! | interior | Navier | `d2` |
//! | boundary with a ghost (all-traction; RBF-FD: any traction) | Navier + boundary rows (in the ghost's rows) | `d1`, `d2` |
//! | boundary with a traction component | tractions, displacements | `d1` |
//! | boundary, all-displacement | displacements | none |
//!
//! plus `d1` everywhere when post-processing needs the gradient. Ghost nodes are
//! nodes `n..` of the supports and shapes; they carry no operators of their own.
//! In the displacement-pressure form every node carries a continuity row, so every
//! node needs `d1`.

use super::cloud::{cloud, shape_needs, widen_degenerate, Cloud};
pub use super::cloud::keeps_gradient_shapes;
use super::equations::{resolve, ComponentEquation};
use super::NavierParams;
use crate::physics::case::Case;
use crate::domain::{self, neighbors::Supports, NodeSet, Point};
use crate::physics::elasticity::dofs::{DofMap, Unknowns, PRESSURE};
use crate::physics::elasticity::material::Material;
use crate::physics::elasticity::stress::{Gradient, StressField};
use crate::physics::exact::ExactSolution;
use crate::parallel::distributed::agree;
use crate::parallel::share::Share;
use crate::mlsm::{compute_shapes, Approximation, Op, OpSet, Shapes};
use crate::stages::{stage, RunError, Stage, StageTimer};

/// Ghost placement and support search.
pub const SUPPORTS: Stage = Stage::new("supports");
/// Shape functions.
pub const SHAPES: Stage = Stage::new("shapes");
use rayon::prelude::*;

/// Everything the rows of the Navier model are written from (module docs).
pub struct Discretisation {
    /// Nodes of the solid (ghosts are not in it).
    pub nodes: NodeSet,
    /// Equations of each boundary node.
    pub boundary_equations: Vec<[ComponentEquation; 2]>,
    /// Ghost node of each node, if it has one (ghosts are nodes `n..`).
    pub ghost: Vec<Option<usize>>,
    /// Positions of the ghosts (ghost `n + k` at `ghost_positions[k]`).
    pub ghost_positions: Vec<Point>,
    /// Supports over nodes and ghosts.
    pub supports: Supports,
    /// Supports widened because they could not determine an RBF-FD polynomial part.
    pub widened_supports: usize,
    /// Shape functions over nodes and ghosts.
    pub shapes: Shapes,
    /// Whether the gradient's shapes were made with those of the rows and outlive the
    /// assembly ([`keeps_gradient_shapes`]).
    pub gradient_kept: bool,
    /// Operators computed, with the number of nodes each was computed at.
    pub operators_computed: Vec<(String, usize)>,
    /// Unknown layout over nodes and ghosts.
    pub dofs: DofMap,
    /// `tau` of the continuity rows' pressure stabilisation (`navier::formulation`;
    /// used by the displacement-pressure form only).
    pub pressure_stabilisation: f64,
    /// The nodes and ghosts this process works on: all of them, or when the solve is
    /// distributed over MPI ranks (`solver.kind = "petsc"`) the shapes and rows of its
    /// own nodes only (a ghost belongs to its node's rank).
    pub share: Share,
    /// The re-entrant corners and holes with traction edges, and which of them the
    /// assembly balances (`super::sector`).
    pub survey: super::sector::Survey,
}

impl Discretisation {
    /// Nodes, ghosts, supports and shapes of `case` with `params`, each stage timed
    /// by `timer`; `exact` gives the values of `"exact"` boundary conditions.
    pub fn new(case: &Case, params: &NavierParams, exact: Option<&dyn ExactSolution>, timer: &mut StageTimer) -> Result<Self, RunError> {
        let nodes = timer.run(stage::NODES, || {
            let nodes = domain::generate(&case.domain, &params.fill);
            let note = format!("{} nodes ({} on the boundary)", nodes.len(), nodes.boundary.len());
            Ok((nodes, note))
        })?;
        Self::on_nodes(case, params, nodes, exact, timer)
    }

    /// The same on a given node set (`params.fill` is not used): ghosts, supports and
    /// shapes of `params.approximation` on `nodes`.
    pub fn on_nodes(
        case: &Case,
        params: &NavierParams,
        nodes: NodeSet,
        exact: Option<&dyn ExactSolution>,
        timer: &mut StageTimer,
    ) -> Result<Self, RunError> {
        let n_support = params.approximation.support;
        let unknowns = params.formulation.unknowns(&case.material);
        if nodes.len() < n_support {
            return Err(RunError::TooFewNodes { nodes: nodes.len(), support: n_support });
        }
        let on_parts: Vec<(Point, usize)> =
            nodes.boundary.iter().flat_map(|b| b.touches.iter().map(|&(part, _)| (b.position, part))).collect();
        case.check_formulas(&nodes.positions, &on_parts)?;
        let boundary_equations: Vec<[ComponentEquation; 2]> = nodes.boundary.iter().map(|b| resolve(b, &case.conditions, exact)).collect();
        let survey = super::sector::survey(case, &nodes);
        // Placing ghosts is part of building the point cloud, so it is timed with the supports.
        let Cloud { positions, ghost, share, supports, every, needs, gradient_kept, widened } =
            timer.run(SUPPORTS, || cloud(case, params, &nodes, &boundary_equations, &survey))?;
        let shapes = timer.run(SHAPES, || {
            let s = agree(compute_shapes(&positions, &supports, &params.approximation, &needs).map_err(RunError::from))?;
            let note = format!("{} shape functions", s.count());
            Ok((s, note))
        })?;
        let n = nodes.len();
        // Every shape the run makes, those of the gradient after the solve included.
        let stored = every.iter().fold(OpSet::EMPTY, |a, &b| a | b);
        let operators_computed = Op::ALL
            .iter()
            .filter(|op| stored.contains(**op))
            .map(|op| (OpSet::from(*op).names()[0].to_string(), (0..n).filter(|&i| every[i].contains(*op)).count()))
            .collect();
        let dofs = DofMap::new(positions.len(), unknowns);
        let ghost_positions = positions[n..].to_vec();
        Ok(Discretisation {
            nodes,
            boundary_equations,
            ghost,
            ghost_positions,
            supports,
            widened_supports: widened,
            gradient_kept,
            pressure_stabilisation: params.pressure_stabilisation,
            shapes,
            operators_computed,
            dofs,
            share,
            survey,
        })
    }

    /// `assemble` run on this discretisation with the supports and shapes of
    /// `approximation` in place of the scene's (those of the rows only, no gradient),
    /// on the same nodes and ghosts: the same unknowns and row layout, other
    /// coefficients ([`crate::models::navier::low_order`]). The scene's supports and shapes are
    /// back in place afterwards. In-process runs only (not distributed).
    pub fn with_approximation<T>(&mut self, approximation: &Approximation, assemble: impl FnOnce(&Self) -> T) -> Result<T, RunError> {
        self.with_approximation_at(approximation, None, OpSet::EMPTY, assemble)
    }

    /// [`Discretisation::with_approximation`] with supports and shapes only at the
    /// nodes `at` picks (all when `None`; the others get none, so only their rows may
    /// be read), each with the operators `extra` as well as those of its rows.
    pub fn with_approximation_at<T>(
        &mut self,
        approximation: &Approximation,
        at: Option<&[bool]>,
        extra: OpSet,
        assemble: impl FnOnce(&Self) -> T,
    ) -> Result<T, RunError> {
        let positions: Vec<Point> = (0..self.dofs.nodes()).map(|i| self.point(i)).collect();
        let picked = |i: usize| at.is_none_or(|a| a.get(i).copied().unwrap_or(false));
        let mut needs = shape_needs(&self.nodes, &self.boundary_equations, &self.ghost, positions.len(), (self.dofs.unknowns(), false));
        for (i, ops) in needs.iter_mut().enumerate() {
            *ops = if !picked(i) {
                OpSet::EMPTY
            } else if i < self.nodes.len() {
                *ops | extra
            } else {
                *ops
            };
        }
        let size = approximation.support.min(positions.len());
        let supports = Supports::nearest_where(&positions, size, picked);
        let (supports, _) = widen_degenerate(supports, &positions, &approximation.basis, &needs)?;
        let shapes = compute_shapes(&positions, &supports, approximation, &needs)?;
        let scene_supports = std::mem::replace(&mut self.supports, supports);
        let scene_shapes = std::mem::replace(&mut self.shapes, shapes);
        let out = assemble(self);
        self.supports = scene_supports;
        self.shapes = scene_shapes;
        Ok(out)
    }

    /// Give back the memory of the rows' shapes once the rows are assembled: the solve
    /// is the peak of a large run. The first derivatives that post-processing needs
    /// are kept when they were made with the rows ([`keeps_gradient_shapes`]), else
    /// made again after the solve ([`Discretisation::restore_gradient_shapes`]: a lower
    /// peak for some more post-processing;
    /// docs/notebook/2026-11-26-up-form-iterative-solvers.md, "The smoothed transfers in
    /// one fused product, the gradient's shapes after the solve").
    pub fn release_row_shapes(&mut self) {
        self.shapes.retain(if self.gradient_kept { OpSet::D1 } else { OpSet::EMPTY });
    }

    /// The first-derivative shapes of `approximation` (the one the discretisation was
    /// built with) at every node this rank owns, ghosts excluded, on the supports in
    /// place: what [`Discretisation::gradients`] reads. The same local solves as the
    /// first time, so the same weights. Nothing to do when they were kept.
    pub fn restore_gradient_shapes(&mut self, approximation: &Approximation) -> Result<(), RunError> {
        if self.gradient_kept {
            return Ok(());
        }
        let positions: Vec<Point> = (0..self.dofs.nodes()).map(|i| self.point(i)).collect();
        let n = self.nodes.len();
        let needs: Vec<OpSet> = (0..positions.len()).map(|i| if i < n && self.owns(i) { OpSet::D1 } else { OpSet::EMPTY }).collect();
        self.shapes = compute_shapes(&positions, &self.supports, approximation, &needs)?;
        Ok(())
    }

    /// Whether this rank computes node `i`'s shapes and rows (always, unless distributed).
    pub fn owns(&self, i: usize) -> bool {
        self.share.owns(i)
    }

    /// Position of node or ghost `i`.
    pub fn point(&self, i: usize) -> Point {
        let n = self.nodes.len();
        if i < n {
            self.nodes.positions[i]
        } else {
            self.ghost_positions[i - n]
        }
    }

    /// Number of ghost nodes.
    pub fn ghost_count(&self) -> usize {
        self.dofs.nodes() - self.nodes.len()
    }

    /// Whether node `i` carries the Navier equation (interior, or boundary with a ghost).
    pub fn has_navier_row(&self, i: usize) -> bool {
        i < self.nodes.len() && (!self.nodes.is_boundary(i) || self.ghost[i].is_some())
    }

    /// The nodes whose row `c` holds component `c` of node `i`'s Navier equation and
    /// of its boundary equation, `(navier, boundary)` (`navier` is `None` on a node
    /// without a Navier row). A node with a ghost has two rows per component:
    /// a traction goes in the ghost's row and the Navier equation in the node's own;
    /// a displacement, whose only coefficient is the node's own unknown, stays in the
    /// node's row (diagonal 1) and the Navier equation goes to the ghost's row.
    /// Writing a displacement in the ghost's row left a zero diagonal there, which
    /// stalled the multigrid on every scene with a symmetry edge
    /// (docs/notebook/2026-11-25-multigrid-symmetry-edges.md).
    pub fn row_nodes(&self, i: usize, c: usize) -> (Option<usize>, usize) {
        match (self.ghost.get(i).copied().flatten(), self.nodes.is_boundary(i)) {
            (None, false) => (Some(i), i),
            (None, true) => (None, i),
            (Some(g), _) => match self.boundary_equations[i][c] {
                ComponentEquation::Displacement { .. } => (Some(g), i),
                ComponentEquation::Traction { .. } => (Some(i), g),
            },
        }
    }

    /// Whether unknown `c` of node `i` (a node or a ghost) is the one whose row holds
    /// `i`'s own Navier equation of component `c`: the dynamic unknowns of an
    /// explicit run (`dynamics`).
    pub fn navier_row_is_own(&self, i: usize, c: usize) -> bool {
        i < self.nodes.len() && self.row_nodes(i, c).0 == Some(i)
    }

    /// Nodal pressures `p = -lambda div u` (nodes, ghosts excluded) from the global
    /// vector `x`, in the displacement-pressure form (whose unknown is `p / mu`, `rows`).
    pub fn pressure(&self, material: &Material, x: &[f64]) -> Option<Vec<f64>> {
        let mu = material.mu();
        (self.dofs.unknowns() == Unknowns::DisplacementPressure)
            .then(|| (0..self.nodes.len()).map(|i| mu * x[self.dofs.dof(i, PRESSURE)]).collect())
    }

    /// Stress at every node from the gradients and, in the displacement-pressure form,
    /// the pressures of `x` (`sigma = -p I + mu (g + g^T)`, finite at `nu = 1/2`).
    pub fn stress(&self, material: &Material, gradients: &[Gradient], x: &[f64]) -> StressField {
        match self.pressure(material, x) {
            Some(p) => StressField::from_gradients_and_pressure(material, gradients, &p),
            None => StressField::from_gradients(material, gradients),
        }
    }

    /// Displacement gradient `[[u_x, u_y], [v_x, v_y]]` at every node (ghosts
    /// excluded) from the global vector `x`; needs first-derivative shapes everywhere.
    ///
    /// Distributed: each rank computes its own nodes' and the sum over ranks fills in
    /// the rest.
    pub fn gradients(&self, x: &[f64]) -> Vec<Gradient> {
        let mut g: Vec<Gradient> = (0..self.nodes.len())
            .into_par_iter()
            .map(|i| if self.owns(i) { self.gradient_at(i, x) } else { [[0.0; 2]; 2] })
            .collect();
        self.share.sum(g.as_flattened_mut().as_flattened_mut(), "the gradients over the ranks");
        g
    }

    /// Displacement gradient at node `i` from `x`, `g[c][d] = sum_k D^d_ik u_c(x_jk)`
    /// over its support; needs its first-derivative shapes.
    pub fn gradient_at(&self, i: usize, x: &[f64]) -> Gradient {
        let (dx, dy) = (self.shapes.get(i, Op::Dx), self.shapes.get(i, Op::Dy));
        let mut g = [[0.0; 2]; 2];
        for (k, &j) in self.supports.of(i).iter().enumerate() {
            let u = self.dofs.displacement(x, j as usize);
            for c in 0..2 {
                g[c][0] += dx[k] * u[c];
                g[c][1] += dy[k] * u[c];
            }
        }
        g
    }
}

#[cfg(test)]
#[path = "discrete_tests.rs"]
mod tests;
