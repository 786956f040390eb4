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
use crate::linalg::row_assembly::{RowAssembler, RowFragment};
use crate::linalg::Csr;
use crate::pipeline::RunError;
use rayon::prelude::*;

/// Nodes whose rows are written into one block of entries.
const BLOCK_NODES: usize = 4096;

/// Blocks written in parallel per thread before they are appended to the rows (on two
/// threads, with 13-node supports, about 30 MB of entries in flight).
const WAVE_BLOCKS_PER_THREAD: usize = 4;

/// The right-hand sides `(row, value)` of one node: at most two boundary rows and
/// two Navier rows (no allocation per node).
#[derive(Debug, Clone, Copy, Default)]
struct NodeLoads {
    entries: [(usize, f64); 4],
    len: usize,
}

impl NodeLoads {
    fn push(&mut self, row: usize, value: f64) {
        self.entries[self.len] = (row, value);
        self.len += 1;
    }
}

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
    /// Append the coefficients of the rows of node `i` to `e` (module docs).
    fn node_rows(&self, writer: &RowWriter, i: usize, e: &mut Entries) {
        let disc = self.disc;
        if disc.nodes.is_boundary(i) {
            let bc_rows = disc.ghost[i].unwrap_or(i);
            for (c, eq) in disc.boundary_equations[i].iter().enumerate() {
                match *eq {
                    ComponentEquation::Displacement { .. } => writer.displacement(i, bc_rows, c, e),
                    ComponentEquation::Traction { normal, .. } => writer.traction(i, bc_rows, c, normal, e),
                }
            }
        }
        if disc.has_navier_row(i) {
            writer.navier(i, i, e);
        }
        if disc.dofs.unknowns() == Unknowns::DisplacementPressure {
            writer.continuity(i, e);
            if let Some(g) = disc.ghost.get(i).copied().flatten() {
                writer.continuity_normal_derivative(i, g, disc.nodes.normal(i), e);
            }
        }
    }

    /// Right-hand sides `(row, value)` of node `i` under `loads`: the prescribed
    /// value of each boundary row (in the rows of its ghost, if any), `-f` in the
    /// Navier rows (`L u = -f`); the continuity rows have none (zero).
    fn node_loads(&self, loads: &Loads, i: usize) -> NodeLoads {
        let (disc, dofs) = (self.disc, self.disc.dofs);
        let mut rhs = NodeLoads::default();
        if disc.nodes.is_boundary(i) {
            let bc_rows = disc.ghost[i].unwrap_or(i);
            for (c, eq) in resolve(&disc.nodes.boundary[i], &loads.conditions, self.exact).iter().enumerate() {
                let value = match *eq {
                    ComponentEquation::Displacement { value } | ComponentEquation::Traction { value, .. } => value,
                };
                rhs.push(dofs.dof(bc_rows, c), value);
            }
        }
        if disc.has_navier_row(i) {
            let p = disc.nodes.positions[i];
            let f = exact::value(&loads.body_force, p, self.exact, |e| e.body_force(p));
            rhs.push(dofs.dof(i, 0), -f[0]);
            rhs.push(dofs.dof(i, 1), -f[1]);
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
        let per_node: Vec<NodeLoads> = nodes.par_iter().map(|&i| self.node_loads(loads, i)).collect();
        for (&i, r) in nodes.iter().zip(&per_node) {
            let r = &r.entries[..r.len];
            if r.iter().any(|v| !v.1.is_finite()) {
                return Err(RunError::not_finite_at(i, self.disc.nodes.positions[i]));
            }
            for &(row, v) in r {
                rhs[row] = v;
            }
        }
        Ok(())
    }

    /// Rows of every node this rank owns ([`Discretisation::owns`]: all of them unless
    /// the solve is distributed), in compressed rows, and the right-hand side of the
    /// case's loads (zero in the rows of other ranks); or the first node whose
    /// equations hold a non-finite number.
    ///
    /// Blocks of nodes are written in parallel, a wave of blocks at a time, and appended
    /// in node order ([`RowAssembler`]): a node's rows are its own, and the ghosts'
    /// rows (written by their boundary nodes) come after all nodes', so they are kept
    /// aside and appended last. The peak is the matrix plus one wave.
    pub fn assemble(&self) -> Result<(Csr, Vec<f64>), RunError> {
        let (disc, dofs) = (self.disc, self.disc.dofs);
        let material = &self.case.material;
        let writer = RowWriter {
            dofs,
            lame: material.lame(),
            pressure_weights: material.pressure_weights(),
            supports: &disc.supports,
            shapes: &disc.shapes,
        };
        let n = disc.nodes.len();
        let node_rows_end = dofs.dof(n, 0);
        let mut rows = RowAssembler::new(dofs.len(), dofs.len());
        let mut ghost_rows = Entries::new();
        let (blocks, wave_blocks) = (n.div_ceil(BLOCK_NODES), WAVE_BLOCKS_PER_THREAD * rayon::current_num_threads());
        for wave in (0..blocks).step_by(wave_blocks) {
            let written: Vec<Result<(RowFragment, Entries), usize>> = (wave..blocks.min(wave + wave_blocks))
                .into_par_iter()
                .map(|b| {
                    let mut block = Entries::new();
                    for i in (b * BLOCK_NODES..n.min((b + 1) * BLOCK_NODES)).filter(|&i| disc.owns(i)) {
                        let from = block.len();
                        self.node_rows(&writer, i, &mut block);
                        if block[from..].iter().any(|e| !e.2.is_finite()) {
                            return Err(i);
                        }
                    }
                    let mut own = RowFragment::new(block);
                    let ghosts = own.split_off_rows(node_rows_end);
                    Ok((own, ghosts))
                })
                .collect();
            for w in written {
                let (own, ghosts) = w.map_err(|i| RunError::not_finite_at(i, disc.nodes.positions[i]))?;
                rows.append(own)?;
                ghost_rows.extend(ghosts);
            }
        }
        rows.append(RowFragment::new(ghost_rows))?;
        let rhs = self.right_hand_side(&self.case.loads())?;
        Ok((rows.finish(), rhs))
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
            let (rows, rhs) = System { case: &case, disc: &disc, exact: Some(exact.as_ref()) }.assemble().unwrap();
            let u = disc.dofs.from_displacements(|i| exact.displacement(disc.point(i)));
            let (mut au, mut scale) = (vec![0.0; rhs.len()], vec![0.0; rhs.len()]);
            for (row, col, val) in rows.entries() {
                au[row] += val * u[col];
                scale[row] += (val * u[col]).abs();
            }
            let worst = (0..rhs.len()).map(|k| (au[k] - rhs[k]).abs() / (scale[k] + rhs[k].abs())).fold(0.0, f64::max);
            assert!(worst < 1e-12, "{fill:?}: worst relative row residual {worst:.1e}");
        }
    }
}
