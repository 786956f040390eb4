//! The truncation error of the rows near singular corners, for the `defect` estimate
//! ([`super::defect`]), measured with the higher-degree operator instead of local fits.
//!
//! A fit of the solution is a polynomial, and near a singular corner the solution is
//! not (`u ~ r^lambda`, `lambda < 1`): the fits there see a smooth field and the
//! estimate misses the corner's error. So the rows of the nodes within a corner's
//! radius ([`SingularCorner::radius`]) take `tau_r ~ ((A - A_H) x)_r`, `A_H` the rows
//! of the higher-degree reference's approximation written at those nodes only: since
//! `A_H u* ~ b`, `tau = A u* - b ~ (A - A_H) u*`, and the run's `x` stands for `u*`
//! (defect correction with the higher-degree operator on those rows). The
//! correction's solve then takes `A_H`'s rows in place of `A`'s there: the reference
//! solves `A_H u = b` on those rows and `A u = b + tau` elsewhere. With `A`'s rows
//! (one step of defect correction, `e ~ A^-1 (b - A_H x)`) the steel plate's e_inf(u)
//! came out 15 times the higher-degree reference's (3.3e-2 against 2.2e-3); with
//! `A_H`'s, 2.24e-3. It is solved by GMRES preconditioned by the run's own solver
//! ([`crate::linalg::Retained::solve_replaced`]). The gradient's truncation error
//! likewise, `tau_G ~ (G - G_H) x`. A few hundred rows per corner: none of the
//! reference's solve, supports or shapes elsewhere.

use super::discrete::Discretisation;
use super::system::System;
use crate::linalg::Csr;
use crate::mlsm::{Approximation, OpSet};
use crate::physics::case::{Case, SingularCorner};
use crate::physics::elasticity::stress::Gradient;
use std::collections::BTreeMap;

/// The rows of the nodes near singular corners, as the run assembled them.
pub struct CornerRows {
    /// Nodes within a corner's radius.
    nodes: Vec<usize>,
    /// Their rows (a node's own and its ghost's), each with its coefficients
    /// `(column, value)` in the run's matrix before the solver scaled it.
    rows: Vec<(usize, Vec<(u32, f64)>)>,
}

/// What [`CornerRows::measure`] finds: the truncation error of each corner row and the
/// row of the higher-degree operator that replaces it in the correction's solve, both
/// in the solved rows' scale, and the higher-degree gradient `G_H x` at each corner
/// node.
pub struct CornerTruncation {
    /// `(row, D_r ((A - A_H) x)_r)`, `D_r` the solver's scale of row `r`.
    pub tau: Vec<(usize, f64)>,
    /// `(row, D_r A_H[r] (and the run's multiplier columns of a bordered row)`,
    /// sorted by column.
    pub rows: Vec<(usize, Vec<(u32, f64)>)>,
    /// `(node, G_H x)`.
    pub gradients: Vec<(usize, Gradient)>,
}

impl CornerRows {
    /// The nodes of `disc` within the radius of one of `corners` and their rows in the
    /// run's `matrix` (unscaled, as assembled; a bordered matrix's multiplier rows are
    /// not among them); `None` without corners.
    pub fn of(disc: &Discretisation, corners: &[SingularCorner], matrix: &Csr) -> Option<CornerRows> {
        if corners.is_empty() {
            return None;
        }
        let nodes: Vec<usize> = (0..disc.nodes.len()).filter(|&i| corners.iter().any(|c| c.covers(disc.nodes.positions[i]))).collect();
        let per_node = disc.dofs.unknowns().per_node();
        let rows = nodes
            .iter()
            .flat_map(|&i| std::iter::once(i).chain(disc.ghost[i]))
            .flat_map(|k| (0..per_node).map(move |c| (k, c)))
            .map(|(k, c)| {
                let r = disc.dofs.dof(k, c);
                let row = matrix.row(r);
                (r, row.col_indices().iter().copied().zip(row.values().iter().copied()).collect())
            })
            .collect();
        Some(CornerRows { nodes, rows })
    }

    /// Number of corner nodes.
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }

    /// The truncation error of the corner rows for the run's solution `x` (unknowns,
    /// no multipliers) with `approximation` as the higher-degree operator, scaled as
    /// the `solved` rows `D A` are; and `G_H x` at the corner nodes (module docs).
    pub fn measure(
        &self,
        case: &Case,
        disc: &mut Discretisation,
        approximation: &Approximation,
        solved: &Csr,
        x: &[f64],
    ) -> Result<CornerTruncation, String> {
        let mut at = vec![false; disc.dofs.nodes()];
        self.nodes.iter().for_each(|&i| at[i] = true);
        let (entries, gradients) = disc
            .with_approximation_at(approximation, Some(&at), OpSet::D1, |d| {
                let entries = System { case, disc: d, exact: None }.rows_of(&self.nodes);
                let gradients: Vec<(usize, Gradient)> = self.nodes.iter().map(|&i| (i, d.gradient_at(i, x))).collect();
                (entries, gradients)
            })
            .map_err(|e| format!("the higher-degree rows at the singular corners: {e}"))?;
        let unknowns = x.len();
        let times_x = |(c, v): (u32, f64)| if (c as usize) < unknowns { v * x[c as usize] } else { 0.0 };
        let mut high: BTreeMap<usize, BTreeMap<u32, f64>> = BTreeMap::new();
        for &(r, c, v) in &entries {
            *high.entry(r as usize).or_default().entry(c).or_default() += v;
        }
        let (mut tau, mut rows) = (Vec::with_capacity(self.rows.len()), Vec::with_capacity(self.rows.len()));
        for (r, run) in &self.rows {
            let d = row_scale(solved, *r, run);
            let high = high.remove(r).unwrap_or_default();
            let own: f64 = run.iter().map(|&e| times_x(e)).sum();
            let high_x: f64 = high.iter().map(|(&c, &v)| times_x((c, v))).sum();
            tau.push((*r, d * (own - high_x)));
            // The multipliers' columns of a bordered row stay as the solver scaled them.
            let solved_row = solved.row(*r);
            let multipliers = solved_row.col_indices().iter().zip(solved_row.values()).filter(|(&c, _)| c as usize >= unknowns);
            let mut row: Vec<(u32, f64)> = high.into_iter().filter(|&(c, _)| (c as usize) < unknowns).map(|(c, v)| (c, d * v)).collect();
            row.extend(multipliers.map(|(&c, &v)| (c, v)));
            rows.push((*r, row));
        }
        Ok(CornerTruncation { tau, rows, gradients })
    }
}

/// The solver's scale `D_r` of row `r`: its largest coefficient in the `solved` rows
/// over the same coefficient as assembled (`run`); 1 for an empty row.
fn row_scale(solved: &Csr, r: usize, run: &[(u32, f64)]) -> f64 {
    let Some(&(col, value)) = run.iter().max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())) else {
        return 1.0;
    };
    let row = solved.row(r);
    row.col_indices().iter().position(|&c| c == col).map_or(1.0, |k| row.values()[k] / value)
}
