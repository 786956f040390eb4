//! The static system of a peridynamic run over the free unknowns,
//! `(K_b + K_dil) u = f`, and its solve.
//!
//! `K_b` (the bonds) is always assembled. The dilatation of the linear peridynamic
//! solid, `K_dil = beta D_h^T diag(V) D_h` ([`super::dilatation`]), is either assembled
//! with it ([`DilatationPart::Assembled`]: its rows read the nodes within `2 delta`,
//! 3.6x the bonds' nonzeros at m = 3) or applied by its product ([`DilatationPart::Applied`]:
//! `theta = D_h u`, then `-V_k (L_dil u)_k` per free node, two passes over the bonds),
//!
//! ```text
//! (K_dil u)_k = -V_k beta sum_j xi_kj (w_kj theta_k + (V_j / V_k) w_jk theta_j),
//! ```
//!
//! with the fictitious nodes' values `E u` from the extension and the collar's zero in
//! the product, their known parts (`F t`, the prescribed collar values) moved to the
//! right-hand side. The applied form is solved by GMRES preconditioned with the
//! multigrid of `K_b` ([`crate::linalg::addition`]), chosen whenever the solver
//! would run GMRES with the multigrid on the assembled system; if it fails, the whole
//! system is assembled and solved as any other.

use super::assembly::{chunks, compressed, NodeRows, RowBuilder};
use super::dilatation::Dilatation;
use super::solve::Discretisation;
use crate::linalg::{self, Csr, SolveError, SolveReport, SolverParams};
use crate::parallel::distributed;
use crate::stages::{RunError, SolveProgress};
use rayon::prelude::*;
use std::borrow::Cow;

/// The nonzeros of the linear peridynamic solid's assembled stiffness, estimated from the
/// bonds plus nodes (each node's diagonal block): 16 per bond, two rows and two columns per
/// node read, the nodes within `2 delta`, `(2 delta / delta)^2 = 4` times the bonds' (3.6x
/// measured at m = 3).
pub fn assembled_solid_nonzeros(bonds_and_nodes: f64) -> f64 {
    16.0 * bonds_and_nodes
}

/// How the stiffness carries the dilatation of the linear peridynamic solid (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DilatationPart {
    /// In the matrix.
    Assembled,
    /// Out of the matrix, applied by its product ([`Discretisation::dilatation_product`]).
    Applied,
}

impl Discretisation {
    /// The stiffness over the free unknowns of this process's rows and its right-hand
    /// side for the body force densities `body_force` and the traction parts of the
    /// fictitious nodes `traction_parts` ([`super::extension::Extension::traction_parts`]):
    /// the bonds' and, for the linear peridynamic solid, the dilatation's as `part` says
    /// (its known parts in the right-hand side either way), with the fictitious nodes'
    /// columns condensed ([`super::assembly`]); `Err` is the first node with a
    /// coefficient that is not finite.
    pub fn stiffness(&self, body_force: &[[f64; 2]], traction_parts: &[[f64; 2]], part: DilatationPart) -> Result<(Csr, Vec<f64>), usize> {
        let assembled_dilatation = self.dilatation.as_ref().filter(|_| part == DilatationPart::Assembled);
        let (matrix, mut rhs) = if assembled_dilatation.is_none() && self.extension.is_none() {
            self.bonds().stiffness_rows(body_force, |i| self.owns(i))?
        } else {
            self.condensed_rows(body_force, traction_parts, assembled_dilatation)?
        };
        if let (Some(d), DilatationPart::Applied) = (&self.dilatation, part) {
            // The known parts: the collar's prescribed values and the fictitious nodes' F t.
            let nodes = &self.nodes;
            let mut known = vec![[0.0; 2]; nodes.free];
            known.extend_from_slice(&nodes.prescribed[..nodes.fictitious - nodes.free]);
            known.extend_from_slice(traction_parts);
            let forces = self.dilatation_forces(d, &known);
            if let Some(bad) = forces.iter().position(|f| !f[0].is_finite() || !f[1].is_finite()) {
                return Err(bad);
            }
            rhs.iter_mut().zip(forces.as_flattened()).for_each(|(r, f)| *r += f);
        }
        Ok((matrix, rhs))
    }

    /// The rows gathered node by node ([`RowBuilder`]): the bonds, and `dilatation`'s when given.
    fn condensed_rows(
        &self,
        body_force: &[[f64; 2]],
        traction_parts: &[[f64; 2]],
        dilatation: Option<&Dilatation>,
    ) -> Result<(Csr, Vec<f64>), usize> {
        let nodes = &self.nodes;
        let x = &nodes.positions;
        let row = |builder: &mut RowBuilder, k: usize| -> NodeRows {
            if !self.owns(k) {
                return (Vec::new(), Vec::new(), Vec::new(), [0.0; 2]);
            }
            let v = nodes.volumes[k];
            builder.load([v * body_force[k][0], v * body_force[k][1]]);
            for (b, &j) in self.families.range(k).zip(self.families.of(k)) {
                let j = j as usize;
                let xi = [x[j][0] - x[k][0], x[j][1] - x[k][1]];
                let c = v * self.weights.coefficients[b];
                let kb = [c * xi[0] * xi[0], c * xi[0] * xi[1], c * xi[1] * xi[0], c * xi[1] * xi[1]];
                builder.add(k, kb);
                builder.add(j, kb.map(|e| -e));
            }
            if let Some(d) = dilatation {
                d.row(nodes, k, &mut |l, blk| builder.add(l, blk));
            }
            builder.finish()
        };
        // One builder (a block and a mark per node) per chunk of rows, a few chunks per
        // thread: a builder per rayon job would allocate and clear them thousands of times.
        let rows: Vec<NodeRows> = chunks(nodes.free)
            .into_par_iter()
            .flat_map_iter(|range| {
                let mut builder = RowBuilder::new(nodes, Some((self.extension.as_ref(), traction_parts)));
                range.map(|k| row(&mut builder, k)).collect::<Vec<_>>()
            })
            .collect();
        if let Some(bad) = rows.iter().position(|r| r.1.iter().chain(&r.2).chain(&r.3).any(|v| !v.is_finite())) {
            return Err(bad);
        }
        Ok(compressed(rows))
    }

    /// `V_k (L_dil u)_k` at every free node `k` for the displacement `u` of every node
    /// (`-(K_dil u)_k`, module docs).
    fn dilatation_forces(&self, d: &Dilatation, u: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let nodes = &self.nodes;
        let theta = d.theta(nodes, u);
        (0..nodes.free)
            .into_par_iter()
            .map(|k| {
                let f = d.force_at(nodes, &theta, k);
                [nodes.volumes[k] * f[0], nodes.volumes[k] * f[1]]
            })
            .collect()
    }

    /// `y ← K_dil x` over the free unknowns (interleaved, module docs): the collar at
    /// zero, the fictitious nodes at their extension of `x` without its traction part.
    /// Zero without the dilatation.
    pub fn dilatation_product(&self, x: &[f64], y: &mut [f64]) {
        let Some(d) = &self.dilatation else {
            y.fill(0.0);
            return;
        };
        let nodes = &self.nodes;
        let mut u: Vec<[f64; 2]> = x.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        u.resize(nodes.fictitious, [0.0; 2]);
        if let Some(e) = &self.extension {
            let ghosts = e.values(&u[..nodes.free], &vec![[0.0; 2]; nodes.fictitious_count()]);
            u.extend(ghosts);
        }
        let forces = self.dilatation_forces(d, &u);
        y.par_iter_mut().zip(forces.as_flattened().par_iter()).for_each(|(y, f)| *y = -f);
    }

    /// How this run's stiffness carries the dilatation, and the GMRES settings and
    /// `auto`'s reason when it is applied: [`DilatationPart::Applied`] for the linear
    /// peridynamic solid in one process whenever `solver` would run GMRES with the
    /// multigrid on the assembled system (its nonzeros estimated as 16 per bond: two
    /// rows, two columns per node, nodes within `2 delta`, `(2 delta / delta)^2` the
    /// bonds'), else [`DilatationPart::Assembled`].
    fn dilatation_part(&self, solver: &SolverParams) -> (DilatationPart, Option<Applied>) {
        if self.dilatation.is_none() || self.share.is_split() {
            return (DilatationPart::Assembled, None);
        }
        let assembled_nonzeros = assembled_solid_nonzeros((self.families.bonds() + self.nodes.free) as f64);
        match linalg::takes_addition(solver, 2 * self.nodes.free, assembled_nonzeros) {
            Some(settings) => (DilatationPart::Applied, Some(settings)),
            None => (DilatationPart::Assembled, None),
        }
    }

    /// The run's system for `body_force` and `traction_parts` with `solver`: the
    /// dilatation applied where [`Discretisation::dilatation_part`] says so.
    pub fn system(&self, body_force: &[[f64; 2]], traction_parts: &[[f64; 2]], solver: &SolverParams) -> Result<System, RunError> {
        let (part, applied) = self.dilatation_part(solver);
        let assembled =
            self.stiffness(body_force, traction_parts, part).map_err(|node| RunError::not_finite_at(node, self.nodes.positions[node]));
        let (matrix, rhs) = distributed::agree(assembled)?;
        Ok(System { matrix, rhs, applied })
    }

    /// Solve `system` (module docs) with `solver`, reporting to `watch`: the free
    /// nodes' displacements (interleaved) and the report. An applied dilatation whose
    /// GMRES fails is assembled (for `body_force` and `traction_parts`) and solved again,
    /// and the report says why.
    pub fn solve_system(
        &self,
        system: System,
        (body_force, traction_parts): (&[[f64; 2]], &[[f64; 2]]),
        solver: &SolverParams,
        watch: &SolveProgress,
    ) -> Result<(Vec<f64>, SolveReport), RunError> {
        let free_positions = &self.nodes.positions[..self.nodes.free];
        let layout = linalg::NodeLayout { per_node: 2, positions: free_positions, multipliers: 0 };
        let System { matrix, rhs, applied } = system;
        let (matrix, rhs, retried) = match applied {
            Some(settings) => {
                let product = |x: &[f64], y: &mut [f64]| self.dilatation_product(x, y);
                match linalg::solve_nodal_with_addition(matrix, &product, &rhs, settings, solver.equilibrate, layout, watch) {
                    Ok(done) => return Ok(done),
                    Err(e) => {
                        let assembled = self.stiffness(body_force, traction_parts, DilatationPart::Assembled);
                        let (matrix, rhs) = assembled.map_err(|node| RunError::not_finite_at(node, self.nodes.positions[node]))?;
                        (matrix, rhs, Some(e.without_hint()))
                    }
                }
            }
            None => (matrix, rhs, None),
        };
        let why = retried.as_ref().map(|e| format!("the dilatation applied without its matrix failed ({e}): assembled and solved again"));
        let (x, mut report) = if self.share.is_split() {
            self.share.solve(2, matrix.entries(), &rhs, free_positions, solver)?
        } else {
            linalg::solve_nodal(Cow::Owned(matrix), &rhs, solver, Some(layout), None, watch).map_err(|e| match retried {
                // Both failures: the first says what the applied form met.
                Some(first) => SolveError::FallbackFailed {
                    first: Box::new(first),
                    retry_method: "the dilatation assembled into the matrix".into(),
                    retry: Box::new(e),
                },
                None => e,
            })?
        };
        if let Some(why) = why {
            report.choice = Some(match report.choice {
                Some(c) => format!("{why}; {c}"),
                None => why,
            });
        }
        Ok((x, report))
    }
}

/// The GMRES settings and `auto`'s reason for a system whose dilatation is applied.
type Applied = (linalg::gmres::GmresSettings, Option<String>);

/// A peridynamic run's system over the free unknowns: this process's rows of the
/// assembled part and the right-hand side; `applied` when the dilatation is applied by
/// its product (module docs), with the GMRES that solves it.
pub struct System {
    /// The assembled rows.
    pub matrix: Csr,
    /// The right-hand side.
    pub rhs: Vec<f64>,
    applied: Option<Applied>,
}

impl System {
    /// Whether the dilatation is applied by its product, out of the matrix.
    pub fn dilatation_applied(&self) -> bool {
        self.applied.is_some()
    }
}
