//! `mlsm run --export-system DIR`: the assembled system of a static Navier run, for
//! other solvers (`output::write_system`), with what each unknown is:
//!
//! * `matrix.mtx`, `rhs.mtx`, `solution.mtx` (MatrixMarket) and `matrix.petsc`,
//!   `rhs.petsc` (PETSc binary): `A`, `b` as assembled, before the solver's row
//!   equilibration, and our solution `x`;
//! * `unknowns.csv`: per unknown its node, component (0 = x, 1 = y, 2 = pressure / mu),
//!   the node's position and whether it is a ghost (the coordinates give the
//!   rigid-body modes, the near-null space of multigrid); a run with sector balances
//!   (re-entrant corners, free holes) has their multipliers last, node -1, component
//!   3, 4, 5 (force x, force y, moment), at the balance's centre: the system is then
//!   bordered, `[A G; C 0]` (`linalg::border`);
//! * `system.json`: sizes, layout and the relative residual `‖b − A x‖₂ / ‖b‖₂` of our
//!   solution on this system.

use super::{create_dir, AppError};
use crate::linalg::{relative_residual, SolveReport};
use crate::models::navier::solve::LinearSystem;
use crate::output::{self, ColumnMatrix};
use serde::Serialize;
use std::path::Path;

/// `system.json`.
#[derive(Serialize)]
struct SystemSummary<'a> {
    unknowns: usize,
    multipliers: usize,
    nonzeros: usize,
    nodes: usize,
    ghost_nodes: usize,
    formulation: &'static str,
    rows: &'static str,
    relative_residual: f64,
    solver: &'a str,
}

/// Write `system` into `dir` (module docs).
pub(super) fn write(dir: &Path, system: &LinearSystem, report: &SolveReport) -> Result<(), AppError> {
    create_dir(dir)?;
    let a = &system.matrix;
    let n = a.nrows();
    let column = ColumnMatrix { n, column_starts: a.symbolic().col_ptr(), rows: a.symbolic().row_idx(), values: a.val() };
    output::write_system(dir, &column, &system.rhs, &system.x)?;
    let field = n - system.multipliers.len();
    let rows: Vec<Vec<f64>> = (0..n)
        .map(|dof| match dof.checked_sub(field) {
            None => {
                let (node, c) = system.dofs.location(dof);
                let p = system.points[node];
                vec![dof as f64, node as f64, c as f64, p[0], p[1], f64::from(u8::from(node >= system.nodes))]
            }
            // A multiplier: no node, component 3 + (0 force x, 1 force y, 2 moment),
            // at its balance's centre.
            Some(m) => {
                let p = system.multipliers[m];
                vec![dof as f64, -1.0, (3 + m % 3) as f64, p[0], p[1], 0.0]
            }
        })
        .collect();
    output::write_csv(&dir.join("unknowns.csv"), &["unknown", "node", "component", "x", "y", "ghost"], &rows)?;
    let summary = SystemSummary {
        unknowns: n,
        multipliers: system.multipliers.len(),
        nonzeros: a.compute_nnz(),
        nodes: system.nodes,
        ghost_nodes: system.points.len() - system.nodes,
        formulation: system.dofs.unknowns().name(),
        rows: "as assembled (not equilibrated); unknowns ordered node by node: x, y[, pressure / mu]; then the \
               multipliers of the sector balances (force x, force y, moment each), whose rows are the balances",
        relative_residual: relative_residual(a, &system.x, &system.rhs),
        solver: &report.method,
    };
    Ok(output::write_json(&dir.join("system.json"), &summary)?)
}
