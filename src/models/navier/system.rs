//! Assembly of the collocation system `A u = r`: one row per unknown, written node by
//! node in parallel by the [`RowWriter`].
//!
//! Interior nodes carry the Navier rows; boundary nodes their boundary rows and,
//! when they have a ghost, also the Navier rows: then the node's own rows hold the
//! Navier equation and the ghost's rows the tractions, so that both have a large
//! diagonal entry (the centre weight of a first derivative on a symmetric stencil is
//! ~0), which incomplete factorisations without pivoting and the multigrid's
//! smoother need; a displacement component keeps its row and gives the ghost's row
//! to the Navier equation ([`Discretisation::row_nodes`]).

use super::discrete::Discretisation;
use super::equations::{resolve, ComponentEquation};
use super::rows::{Entries, RowWriter};
use crate::physics::case::{Case, Loads};
use crate::physics::elasticity::conditions::Value;
use crate::physics::elasticity::dofs::{Unknowns, PRESSURE};
use crate::physics::exact::{self, ExactSolution};
use crate::linalg::row_assembly::{RowAssembler, RowFragment};
use crate::linalg::Csr;
use crate::stages::RunError;
use rayon::prelude::*;

/// Nodes whose rows are written into one block of entries.
const BLOCK_NODES: usize = 4096;

/// Blocks written in parallel per thread before they are appended to the rows (on two
/// threads, with 13-node supports, about 30 MB of entries in flight).
const WAVE_BLOCKS_PER_THREAD: usize = 4;

/// The right-hand sides `(row, value)` of one node: at most two boundary rows, two
/// Navier rows and a continuity row (no allocation per node).
#[derive(Debug, Clone, Copy, Default)]
struct NodeLoads {
    entries: [(usize, f64); 5],
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
    /// The writer of this system's rows.
    fn writer(&self) -> RowWriter<'_> {
        let material = &self.case.material;
        RowWriter {
            dofs: self.disc.dofs,
            lame: material.lame(),
            pressure_weights: material.pressure_weights(),
            supports: &self.disc.supports,
            shapes: &self.disc.shapes,
            stabilisation: self.disc.pressure_stabilisation,
            local_spacing: &self.disc.nodes.local_spacing,
        }
    }

    /// Append the coefficients of the rows of node `i` to `e` (module docs).
    fn node_rows(&self, writer: &RowWriter, i: usize, e: &mut Entries) {
        let disc = self.disc;
        if disc.nodes.is_boundary(i) {
            for (c, eq) in disc.boundary_equations[i].iter().enumerate() {
                let row_node = disc.row_nodes(i, c).1;
                match *eq {
                    ComponentEquation::Displacement { .. } => writer.displacement(i, row_node, c, e),
                    ComponentEquation::Traction { normal, .. } => writer.traction(i, row_node, c, normal, e),
                }
            }
        }
        if let (Some(x), Some(y)) = (disc.row_nodes(i, 0).0, disc.row_nodes(i, 1).0) {
            writer.navier(i, [x, y], e);
        }
        if disc.dofs.unknowns() == Unknowns::DisplacementPressure {
            writer.continuity(i, e);
            if let Some(g) = disc.ghost.get(i).copied().flatten() {
                writer.continuity_normal_derivative(i, g, disc.nodes.normal(i), e);
            }
        }
    }

    /// The coefficients of the rows of `nodes` (each node's own and its ghost's), in
    /// the order written: a few rows read where the discretisation has shapes at
    /// those nodes only ([`Discretisation::with_approximation_at`]).
    pub fn rows_of(&self, nodes: &[usize]) -> Entries {
        let writer = self.writer();
        let mut e = Entries::new();
        for &i in nodes {
            self.node_rows(&writer, i, &mut e);
        }
        e
    }

    /// Right-hand sides `(row, value)` of node `i` under `loads`: the prescribed
    /// value of each boundary row (in the rows of its ghost, if any), `-f` in the
    /// Navier rows (`L u = -f`); the continuity row that of its stabilisation
    /// ([`RowWriter::continuity_load`]) from `forces`, the body force at every node
    /// and ghost ([`Self::continuity_forces`]), when there is one.
    fn node_loads(&self, writer: &RowWriter, loads: &Loads, forces: Option<&[[f64; 2]]>, i: usize) -> NodeLoads {
        let (disc, dofs) = (self.disc, self.disc.dofs);
        let mut rhs = NodeLoads::default();
        if disc.nodes.is_boundary(i) {
            for (c, eq) in resolve(&disc.nodes.boundary[i], &loads.conditions, self.exact).iter().enumerate() {
                let value = match *eq {
                    ComponentEquation::Displacement { value } | ComponentEquation::Traction { value, .. } => value,
                };
                rhs.push(dofs.dof(disc.row_nodes(i, c).1, c), value);
            }
        }
        if disc.has_navier_row(i) {
            let p = disc.nodes.positions[i];
            let f = exact::value(&loads.body_force, p, self.exact, |e| e.body_force(p));
            for (c, f) in f.into_iter().enumerate() {
                if let Some(row_node) = disc.row_nodes(i, c).0 {
                    rhs.push(dofs.dof(row_node, c), -f);
                }
            }
        }
        if let Some(forces) = forces {
            rhs.push(dofs.dof(i, PRESSURE), writer.continuity_load(i, |j| forces[j]));
        }
        rhs
    }

    /// The body force of `loads` at every node and ghost, which the stabilised
    /// continuity rows differentiate (each over its support, so evaluated once here);
    /// `None` outside the displacement-pressure form and under a constant body force,
    /// whose divergence is zero.
    fn continuity_forces(&self, loads: &Loads) -> Option<Vec<[f64; 2]>> {
        let disc = self.disc;
        (disc.dofs.unknowns() == Unknowns::DisplacementPressure && !matches!(loads.body_force, Value::Constant(_))).then(|| {
            (0..disc.dofs.nodes())
                .into_par_iter()
                .map(|j| {
                    let p = disc.point(j);
                    exact::value(&loads.body_force, p, self.exact, |e| e.body_force(p))
                })
                .collect()
        })
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
        let (writer, forces) = (self.writer(), self.continuity_forces(loads));
        let per_node: Vec<NodeLoads> = nodes.par_iter().map(|&i| self.node_loads(&writer, loads, forces.as_deref(), i)).collect();
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
        let writer = self.writer();
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
    use crate::physics::elasticity::conditions::ComponentCondition;
    use crate::mlsm::{Basis, Radial, Weight};
    use crate::models::navier::test_case::quadratic_plate;
    use crate::models::navier::NavierParams;
    use crate::stages::{Silent, StageTimer};

    /// The quadratic plate on scattered nodes with RBF-FD of degree 2 and a symmetry-like
    /// bottom edge (traction in x, displacement in y), whose mixed nodes get a ghost.
    fn mixed_rbf_fd_plate() -> (Case, NavierParams) {
        let (mut case, mut params) = quadratic_plate(FillKind::Scattered, 0.05);
        case.conditions[0].components = [ComponentCondition::Traction, ComponentCondition::Displacement];
        params.approximation.basis = Basis::RbfFd { radial: Radial::Phs { order: 3 }, degree: 2 };
        params.approximation.weight = Weight::None;
        (case, params)
    }

    /// Every row is exact for a quadratic field with degree-2 shapes, so the nodal
    /// values of the exact solution (ghosts included: the polynomial extends outside)
    /// satisfy the assembled system row by row, up to the round-off of the local
    /// solves: `|(A u - r)_k| <= 1e-12 sum_j |a_kj u_j|` (measured 4e-16 on the grid and
    /// the scattered fill; one wrong coefficient, sign or normal gives O(1)). The mixed
    /// plate checks the rows a displacement component hands to its ghost.
    #[test]
    fn exact_quadratic_satisfies_every_row() {
        let plates = [quadratic_plate(FillKind::Grid, 0.05), quadratic_plate(FillKind::Scattered, 0.05), mixed_rbf_fd_plate()];
        for (case, params) in plates {
            let fill = (params.fill.kind, params.approximation.basis);
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

    /// No row leaves a zero on the diagonal, and a displacement row holds its 1 there:
    /// a displacement written in its ghost's row (the layout before
    /// [`Discretisation::row_nodes`]) had no entry in the ghost's column, and the
    /// multigrid's smoother stalled on every scene with a symmetry edge. The threshold
    /// 1e-3 of the row's largest entry: the ghost's weight in a Navier row is 0.3-0.9
    /// of it (measured on Kirsch), a missing entry is exactly 0.
    #[test]
    fn every_row_has_a_diagonal_and_displacements_keep_theirs() {
        let (case, params) = mixed_rbf_fd_plate();
        let exact = case.exact_solution().unwrap();
        let disc = Discretisation::new(&case, &params, Some(exact.as_ref()), &mut StageTimer::new(&Silent)).unwrap();
        let mixed = (0..disc.nodes.boundary.len())
            .filter(|&i| disc.ghost[i].is_some() && matches!(disc.boundary_equations[i][1], ComponentEquation::Displacement { .. }))
            .count();
        assert!(mixed > 0, "the bottom edge's nodes have ghosts");
        let (rows, rhs) = System { case: &case, disc: &disc, exact: Some(exact.as_ref()) }.assemble().unwrap();
        let (mut diagonal, mut largest) = (vec![0.0f64; rhs.len()], vec![0.0f64; rhs.len()]);
        for (row, col, val) in rows.entries() {
            largest[row] = largest[row].max(val.abs());
            if row == col {
                diagonal[row] = val;
            }
        }
        for k in 0..rhs.len() {
            assert!(
                diagonal[k].abs() >= 1e-3 * largest[k],
                "row {k} ({:?}): diagonal {:.1e} of {:.1e}",
                disc.dofs.location(k),
                diagonal[k],
                largest[k]
            );
        }
        for i in 0..disc.nodes.boundary.len() {
            for c in 0..2 {
                if matches!(disc.boundary_equations[i][c], ComponentEquation::Displacement { .. }) {
                    assert_eq!(diagonal[disc.dofs.dof(i, c)], 1.0, "node {i}, component {c}");
                }
            }
        }
    }
}
