//! Tests of [`super`]: which shapes each node gets, and which outlive the assembly.

use super::*;
use crate::domain::FillKind;
use crate::mlsm::Basis;
use crate::models::navier::test_case::quadratic_plate;
use crate::stages::{Silent, StageTimer};

/// The operators of each node are those of the table in the module docs: before
/// the solve those of its rows; after it ([`Discretisation::restore_gradient_shapes`])
/// the first derivatives at every node when the gradient is an output.
#[test]
fn each_node_gets_exactly_the_operators_its_rows_need() {
    let (mut case, params) = quadratic_plate(FillKind::Grid, 0.1);
    for gradient in [false, true] {
        case.outputs.stress = gradient;
        let exact = case.exact_solution();
        let mut disc = Discretisation::new(&case, &params, exact.as_deref(), &mut StageTimer::new(&Silent)).unwrap();
        let d1 = OpSet::EMPTY;
        for i in 0..disc.dofs.nodes() {
            let got = disc.shapes.computed_at(i);
            let want = if i >= disc.nodes.len() {
                OpSet::EMPTY
            } else if !disc.nodes.is_boundary(i) {
                d1 | OpSet::D2
            } else if disc.ghost[i].is_some() {
                OpSet::D1 | OpSet::D2
            } else if disc.boundary_equations[i].iter().any(ComponentEquation::is_traction) {
                OpSet::D1
            } else {
                d1
            };
            assert_eq!(got, want, "node {i} (gradient output {gradient})");
        }
        let every_d1 = disc.operators_computed.iter().find(|(name, _)| name == "d/dx").map_or(0, |(_, count)| *count);
        assert_eq!(every_d1 == disc.nodes.len(), gradient, "d/dx counted at every node exactly when the gradient is an output");
        disc.release_row_shapes();
        disc.restore_gradient_shapes(&params.approximation).unwrap();
        for i in 0..disc.dofs.nodes() {
            let want = if i < disc.nodes.len() { OpSet::D1 } else { OpSet::EMPTY };
            assert_eq!(disc.shapes.computed_at(i), want, "node {i} after the solve");
        }
        // Left edge (displacement): no ghosts, no Navier rows; the traction edges'
        // interior nodes have ghosts and Navier rows.
        let left: Vec<usize> = (0..disc.nodes.boundary.len()).filter(|&i| disc.nodes.positions[i][0] == 0.0).collect();
        assert!(!left.is_empty() && left.iter().all(|&i| disc.ghost[i].is_none() && !disc.has_navier_row(i)));
        assert!((0..disc.nodes.boundary.len()).any(|i| disc.ghost[i].is_some() && disc.has_navier_row(i)));
    }
}

/// Under RBF-FD the gradient's shapes are made with the rows and survive the
/// release, at every node (none at ghosts), with exactly the weights a second round
/// of local solves gives; least squares releases them (the test above).
#[test]
fn rbf_fd_keeps_the_gradient_shapes_it_made_with_the_rows() {
    let (mut case, mut params) = quadratic_plate(FillKind::Scattered, 0.1);
    params.approximation = Approximation {
        basis: Basis::RbfFd { radial: crate::mlsm::Radial::Phs { order: 3 }, degree: 2 },
        weight: params.approximation.weight,
        support: 12,
        ghost_nodes: true,
    };
    case.outputs.stress = true;
    let exact = case.exact_solution();
    let mut disc = Discretisation::new(&case, &params, exact.as_deref(), &mut StageTimer::new(&Silent)).unwrap();
    assert!(disc.gradient_kept);
    disc.release_row_shapes();
    let n = disc.nodes.len();
    for i in 0..disc.dofs.nodes() {
        assert_eq!(disc.shapes.computed_at(i), if i < n { OpSet::D1 } else { OpSet::EMPTY }, "node {i} after the release");
    }
    let kept = disc.shapes.clone();
    disc.restore_gradient_shapes(&params.approximation).unwrap();
    disc.gradient_kept = false;
    disc.restore_gradient_shapes(&params.approximation).unwrap();
    for i in 0..n {
        for op in OpSet::D1.iter() {
            assert_eq!(kept.get(i, op), disc.shapes.get(i, op), "node {i}, {op:?}");
        }
    }
}
