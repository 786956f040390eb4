//! The point cloud of a Navier discretisation: ghost nodes placed beside the
//! boundary nodes, the supports of nodes and ghosts (widened where an RBF-FD stencil's
//! polynomial part is degenerate), and the operators each point's shapes must carry.

use super::equations::ComponentEquation;
use super::NavierParams;
use crate::physics::case::Case;
use crate::domain::{self, ghost::place_ghosts, neighbors::Supports, NodeSet, Point};
use crate::physics::elasticity::dofs::Unknowns;
use crate::parallel::distributed::agree;
use crate::parallel::share::Share;
use crate::mlsm::{degenerate_supports, Basis, OpSet, ShapeError};
use crate::stages::RunError;

/// Whether a static run makes the gradient's shapes together with the rows' and keeps
/// them through the solve, instead of making them again after it: yes for RBF-FD,
/// whose cost is the LU of the `(s + m)`-square local system, shared by every operator
/// of the node (two more right-hand sides are nearly free, a second round of LUs
/// doubled the shapes' time); no for least squares, whose local solves are cheap and
/// whose 16 s bytes per node then stay out of the solve's peak
/// (docs/notebook/2026-11-26-up-form-iterative-solvers.md, "RBF-FD keeps the
/// gradient's shapes").
pub fn keeps_gradient_shapes(basis: &Basis) -> bool {
    matches!(basis, Basis::RbfFd { .. })
}

/// The node of each of the `count` ghosts (ghost `n + k` belongs to `parents[k]`).
pub(super) fn ghost_parents(ghost: &[Option<usize>], count: usize) -> Vec<usize> {
    let n = ghost.len();
    let mut parents = vec![0; count];
    for (i, g) in ghost.iter().enumerate() {
        if let Some(g) = g {
            parents[g - n] = i;
        }
    }
    parents
}

/// What the supports stage makes: node and ghost positions, each node's ghost, the
/// how they are shared among MPI ranks, the supports, the operators each point needs
/// (all of them, and those made now), whether the gradient's shapes are made now, and
/// the number of supports widened.
pub(super) struct Cloud {
    /// Nodes, then ghosts.
    pub positions: Vec<Point>,
    /// The ghost of each node, if it has one.
    pub ghost: Vec<Option<usize>>,
    /// The points this process works on (all of them unless distributed).
    pub share: Share,
    /// The supports of nodes and ghosts.
    pub supports: Supports,
    /// Every operator each point's shapes carry over the run.
    pub every: Vec<OpSet>,
    /// Those made now (the gradient's may come after the solve).
    pub needs: Vec<OpSet>,
    /// Whether the gradient's shapes are made now.
    pub gradient_kept: bool,
    /// Supports widened.
    pub widened: usize,
}

/// The supports stage of [`Discretisation::on_nodes`]: ghosts placed, supports found
/// (and widened where an RBF-FD polynomial part is degenerate), with the stage's note.
pub(super) fn cloud(
    case: &Case,
    params: &NavierParams,
    nodes: &NodeSet,
    boundary_equations: &[[ComponentEquation; 2]],
    survey: &super::sector::Survey,
) -> Result<(Cloud, String), RunError> {
    let n_support = params.approximation.support;
    let unknowns = params.formulation.unknowns(&case.material);
    let distributed = Share::splits(&params.solver);
    let (positions, ghost) = ghosts(case, params, nodes, boundary_equations, (distributed, survey));
    // Distributed: a rank finds the supports and makes the shapes of its own
    // nodes and ghosts only (their supports reach into the others' halo).
    let share = Share::of(&nodes.positions, &params.solver).with_followers(&ghost_parents(&ghost, positions.len() - nodes.len()));
    let own = |i: usize| share.owns(i);
    // Supports are widened for every shape the run will make, the gradient's
    // included; a static least-squares run makes the gradient's shapes only
    // after its solve (`restore_gradient_shapes`), RBF-FD makes them with the
    // rows (`keeps_gradient_shapes`), explicit dynamics reads them at every snapshot.
    let gradient = case.outputs.needs_gradient();
    let only_own = |mut ops: Vec<OpSet>| {
        ops.iter_mut().enumerate().filter(|(i, _)| !own(*i)).for_each(|(_, o)| *o = OpSet::EMPTY);
        ops
    };
    let every = only_own(shape_needs(nodes, boundary_equations, &ghost, positions.len(), (unknowns, gradient)));
    let (supports, widened) = agree(
        widen_degenerate(Supports::nearest_where(&positions, n_support, own), &positions, &params.approximation.basis, &every)
            .map_err(RunError::from),
    )?;
    let now = gradient && (case.dynamics.is_some() || keeps_gradient_shapes(&params.approximation.basis));
    let needs = if now == gradient {
        every.clone()
    } else {
        only_own(shape_needs(nodes, boundary_equations, &ghost, positions.len(), (unknowns, now)))
    };
    // Each rank widened its own nodes' supports; the count is of all of them.
    let mut count = [widened as f64];
    share.sum(&mut count, "the widened supports");
    let widened = count[0] as usize;
    let mine = if share.is_split() { " of this rank's nodes" } else { "" };
    let note = format!("{n_support} nearest{mine}, {} ghost nodes, {widened} supports widened", positions.len() - nodes.len());
    Ok((Cloud { positions, ghost, share, supports, every, needs, gradient_kept: now, widened }, note))
}

/// Positions of nodes and ghosts, and the ghost of each node.
///
/// Which boundary nodes get a ghost depends on the basis (measured: docs/limits.md,
/// docs/methods/rbf-fd.md):
/// * weighted least squares: nodes whose two equations are tractions. On mixed
///   (symmetry) nodes an extra Navier row made scattered-node runs unstable;
/// * RBF-FD: every node with a traction equation, symmetry nodes included. Without
///   them the one-sided RBF-FD stencils where a symmetry edge meets a curved free
///   edge went unstable.
fn ghosts(
    case: &Case,
    params: &NavierParams,
    nodes: &NodeSet,
    equations: &[[ComponentEquation; 2]],
    (distributed, survey): (bool, &super::sector::Survey),
) -> (Vec<Point>, Vec<Option<usize>>) {
    let rbf_fd = matches!(params.approximation.basis, Basis::RbfFd { .. });
    let wants_ghost = |eq: &[ComponentEquation; 2]| {
        if rbf_fd {
            eq.iter().any(ComponentEquation::is_traction)
        } else {
            eq.iter().all(ComponentEquation::is_traction)
        }
    };
    let candidates: Vec<usize> = if params.approximation.ghost_nodes {
        (0..nodes.boundary.len()).filter(|&i| wants_ghost(&equations[i])).collect()
    } else {
        Vec::new()
    };
    // Ghost-free around re-entrant corners (`domain::ghost`), except where the sector
    // balance of a static in-process solve takes the corner's spurious load
    // (`super::sector`; dynamics assembles without it, PETSc's rows have no border).
    let mut ghost_free = domain::corner::reentrant_corners(&case.domain, nodes);
    if !distributed && case.dynamics.is_none() {
        let balanced = survey.balanced_corners();
        ghost_free.retain(|c| !balanced.contains(c));
    }
    let placed = place_ghosts(&case.domain, nodes, &candidates, &ghost_free);
    let n = nodes.len();
    let mut positions = nodes.positions.clone();
    positions.extend(placed.iter().map(|g| g.1));
    let mut ghost = vec![None; n];
    for (k, g) in placed.iter().enumerate() {
        ghost[g.0] = Some(n + k);
    }
    (positions, ghost)
}

/// RBF-FD only: supports that cannot determine the polynomial part of the basis
/// (one-sided lattice stencils at high degree) are widened by half, at most three
/// times; returns the supports and how many were widened, or the first support still
/// degenerate after that (the shapes of RBF-FD do not test the rank again).
pub(super) fn widen_degenerate(
    mut supports: Supports,
    positions: &[Point],
    basis: &Basis,
    needs: &[OpSet],
) -> Result<(Supports, usize), ShapeError> {
    if !matches!(basis, Basis::RbfFd { .. }) {
        return Ok((supports, 0));
    }
    let mut widened = std::collections::BTreeSet::new();
    let mut size = supports.requested();
    let mut bad = degenerate_supports(positions, &supports, basis, needs);
    for _ in 0..3 {
        if bad.is_empty() {
            break;
        }
        size += size / 2;
        let nodes: Vec<usize> = bad.iter().map(|&(i, _)| i).collect();
        supports = supports.widened(positions, &nodes, size);
        widened.extend(nodes);
        bad = degenerate_supports(positions, &supports, basis, needs);
    }
    match bad.first() {
        None => Ok((supports, widened.len())),
        Some(&(node, ratio)) => Err(ShapeError {
            node,
            x: positions[node][0],
            y: positions[node][1],
            basis_size: basis.size(),
            support: supports.of(node).len(),
            ratio,
        }),
    }
}

/// The operators each of the `total` nodes and ghosts needs (module docs); `d1` at
/// every node only with `gradient_needed`.
pub(super) fn shape_needs(
    nodes: &NodeSet,
    equations: &[[ComponentEquation; 2]],
    ghost: &[Option<usize>],
    total: usize,
    (unknowns, gradient_needed): (Unknowns, bool),
) -> Vec<OpSet> {
    // The displacement-pressure form has a continuity row (div u) at every node and ghost.
    let pressure = unknowns == Unknowns::DisplacementPressure;
    if pressure {
        let ops = |i: usize| match (i < nodes.len(), !nodes.is_boundary(i) || ghost[i].is_some()) {
            (false, _) => OpSet::EMPTY,
            (true, true) => OpSet::D1 | OpSet::D2,
            (true, false) => OpSet::D1,
        };
        return (0..total).map(ops).collect();
    }
    let has_traction = |i: usize| nodes.is_boundary(i) && equations[i].iter().any(ComponentEquation::is_traction);
    (0..total)
        .map(|i| {
            if i >= nodes.len() {
                return OpSet::EMPTY;
            }
            let mut ops = if gradient_needed { OpSet::D1 } else { OpSet::EMPTY };
            if has_traction(i) {
                ops |= OpSet::D1;
            }
            if !nodes.is_boundary(i) || ghost[i].is_some() {
                ops |= OpSet::D2;
            }
            ops
        })
        .collect()
}
