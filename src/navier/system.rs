//! Assembly of the collocation system `A u = r`: one row per unknown, written node by
//! node in parallel by the [`RowWriter`].
//!
//! Interior nodes carry the Navier rows; boundary nodes their boundary rows and,
//! when they have a ghost, also the Navier rows: then the node's own rows hold the
//! Navier equation and the ghost's rows the tractions, so that both have a large
//! diagonal entry (the centre weight of a first derivative on a symmetric stencil is
//! ~0), which incomplete factorisations without pivoting need.

use super::discrete::Discretisation;
use super::equations::{resolve, ComponentEquation};
use super::rows::{Entries, RowWriter};
use crate::case::{Case, Loads};
use crate::elasticity::dofs::Unknowns;
use crate::exact::{self, ExactSolution};
use crate::linalg::Triplets;
use crate::pipeline::RunError;
use rayon::prelude::*;

/// Everything the equation rows of one discretisation need.
pub struct System<'a> {
    /// The case (material, body force).
    pub case: &'a Case,
    /// Nodes, equations, ghosts, supports, shapes, unknowns.
    pub disc: &'a Discretisation,
    /// Exact solution for `"exact"` values.
    pub exact: Option<&'a dyn ExactSolution>,
}

impl System<'_> {
    /// Coefficients of the rows of node `i` (module docs).
    fn node_rows(&self, writer: &RowWriter, i: usize) -> Entries {
        let disc = self.disc;
        let mut e = Entries::with_capacity(8 * disc.supports.of(i).len());
        if disc.nodes.is_boundary(i) {
            let bc_rows = disc.ghost[i].unwrap_or(i);
            for (c, eq) in disc.boundary_equations[i].iter().enumerate() {
                match *eq {
                    ComponentEquation::Displacement { .. } => writer.displacement(i, bc_rows, c, &mut e),
                    ComponentEquation::Traction { normal, .. } => writer.traction(i, bc_rows, c, normal, &mut e),
                }
            }
        }
        if disc.has_navier_row(i) {
            writer.navier(i, i, &mut e);
        }
        if disc.dofs.unknowns() == Unknowns::DisplacementPressure {
            writer.continuity(i, &mut e);
            if let Some(g) = disc.ghost.get(i).copied().flatten() {
                writer.continuity_normal_derivative(i, g, disc.nodes.normal(i), &mut e);
            }
        }
        e
    }

    /// Right-hand sides `(row, value)` of node `i` under `loads`: the prescribed
    /// value of each boundary row (in the rows of its ghost, if any), `-f` in the
    /// Navier rows (`L u = -f`); the continuity rows have none (zero).
    fn node_loads(&self, loads: &Loads, i: usize) -> Vec<(usize, f64)> {
        let (disc, dofs) = (self.disc, self.disc.dofs);
        let mut rhs = Vec::with_capacity(4);
        if disc.nodes.is_boundary(i) {
            let bc_rows = disc.ghost[i].unwrap_or(i);
            for (c, eq) in resolve(&disc.nodes.boundary[i], &loads.conditions, self.exact).iter().enumerate() {
                let value = match *eq {
                    ComponentEquation::Displacement { value } | ComponentEquation::Traction { value, .. } => value,
                };
                rhs.push((dofs.dof(bc_rows, c), value));
            }
        }
        if disc.has_navier_row(i) {
            let p = disc.nodes.positions[i];
            let f = exact::value(&loads.body_force, p, self.exact, |e| e.body_force(p));
            rhs.extend([(dofs.dof(i, 0), -f[0]), (dofs.dof(i, 1), -f[1])]);
        }
        rhs
    }

    /// The right-hand side of every row this rank owns under `loads` (the case's own,
    /// or those of one instant of a time-dependent run), zero in the rows of other
    /// ranks; or the first node whose loads are not finite.
    pub fn right_hand_side(&self, loads: &Loads) -> Result<Vec<f64>, RunError> {
        let mut rhs = vec![0.0; self.disc.dofs.len()];
        let owned: Vec<usize> = (0..self.disc.nodes.len()).filter(|&i| self.disc.owns(i)).collect();
        self.update_right_hand_side(loads, &owned, &mut rhs)?;
        Ok(rhs)
    }

    /// Overwrite the right-hand sides of the rows of `nodes` in `rhs` with those of
    /// `loads` (a time-dependent run rewrites only the nodes whose loads vary).
    pub fn update_right_hand_side(&self, loads: &Loads, nodes: &[usize], rhs: &mut [f64]) -> Result<(), RunError> {
        let per_node: Vec<Vec<(usize, f64)>> = nodes.par_iter().map(|&i| self.node_loads(loads, i)).collect();
        for (&i, r) in nodes.iter().zip(per_node) {
            if r.iter().any(|v| !v.1.is_finite()) {
                let p = self.disc.nodes.positions[i];
                return Err(RunError::NotFinite { node: i, x: p[0], y: p[1] });
            }
            for (row, v) in r {
                rhs[row] = v;
            }
        }
        Ok(())
    }

    /// Rows of every node this rank owns ([`Discretisation::owns`]: all of them unless
    /// the solve is distributed), in parallel; returns the triplets and the right-hand
    /// side of the case's loads (zero in the rows of other ranks), or the first node
    /// whose equations hold a non-finite number.
    pub fn assemble(&self) -> Result<(Triplets, Vec<f64>), RunError> {
        let (disc, dofs) = (self.disc, self.disc.dofs);
        let material = &self.case.material;
        let writer = RowWriter {
            dofs,
            lame: material.lame(),
            pressure_weights: material.pressure_weights(),
            supports: &disc.supports,
            shapes: &disc.shapes,
        };
        let per_node: Vec<Entries> = (0..disc.nodes.len())
            .into_par_iter()
            .map(|i| if disc.owns(i) { self.node_rows(&writer, i) } else { Default::default() })
            .collect();
        let total: usize = per_node.iter().map(|e| e.len()).sum();
        let mut triplets = Triplets::with_capacity(dofs.len(), total);
        for (i, entries) in per_node.into_iter().enumerate() {
            if entries.iter().any(|e| !e.2.is_finite()) {
                let p = disc.nodes.positions[i];
                return Err(RunError::NotFinite { node: i, x: p[0], y: p[1] });
            }
            for (row, col, v) in entries {
                triplets.push(row, col, v);
            }
        }
        let rhs = self.right_hand_side(&self.case.loads())?;
        Ok((triplets, rhs))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::FillKind;
    use crate::navier::test_case::quadratic_plate;
    use crate::pipeline::{Silent, StageTimer};

    /// Every row is exact for a quadratic field with degree-2 shapes, so the nodal
    /// values of the exact solution (ghosts included: the polynomial extends outside)
    /// satisfy the assembled system row by row, up to the round-off of the local
    /// solves: `|(A u - r)_k| <= 1e-12 sum_j |a_kj u_j|` (measured 4e-16 on the grid and
    /// the scattered fill; one wrong coefficient, sign or normal gives O(1)).
    #[test]
    fn exact_quadratic_satisfies_every_row() {
        for fill in [FillKind::Grid, FillKind::Scattered] {
            let (case, params) = quadratic_plate(fill, 0.05);
            let exact = case.exact_solution().unwrap();
            let disc = Discretisation::new(&case, &params, Some(exact.as_ref()), &mut StageTimer::new(&Silent)).unwrap();
            assert!(disc.ghost_count() > 0, "{fill:?}: the traction edges have ghosts");
            let (triplets, rhs) = System { case: &case, disc: &disc, exact: Some(exact.as_ref()) }.assemble().unwrap();
            let u = disc.dofs.from_displacements(|i| exact.displacement(disc.point(i)));
            let (mut au, mut scale) = (vec![0.0; rhs.len()], vec![0.0; rhs.len()]);
            for t in triplets.entries() {
                au[t.row] += t.val * u[t.col];
                scale[t.row] += (t.val * u[t.col]).abs();
            }
            let worst = (0..rhs.len()).map(|k| (au[k] - rhs[k]).abs() / (scale[k] + rhs[k].abs())).fold(0.0, f64::max);
            assert!(worst < 1e-12, "{fill:?}: worst relative row residual {worst:.1e}");
        }
    }
}
