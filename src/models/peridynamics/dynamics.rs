//! Peridynamic elastodynamics: `rho u_tt = L_h u + b` (linear law) or the nonlinear
//! bond-stretch law, integrated explicitly from the scene's initial conditions.
//!
//! Unknowns are the free nodes' displacements (interleaved x, y); constrained collar
//! nodes keep their prescribed values. Bond forces, for `eta = u_j - u_i`:
//!
//! ```text
//! linear:        f_ij = c_ij (xi ⊗ xi) eta
//! bond-stretch:  f_ij = c_ij |xi|^3 s (xi + eta) / |xi + eta|,   s = (|xi + eta| - |xi|) / |xi|
//! ```
//!
//! (the second linearises to the first). Energies (seed 000, definition 4.1.5):
//! `E_kin = sum_i rho V_i |v_i|^2 / 2`, `E_el = 1/2 sum_i V_i sum_j w_ij` with
//! `w = c_ij (xi . eta)^2 / 2` (linear) or `c_ij |xi|^4 s^2 / 2`, `E_ext = -sum_i V_i b_i . u_i`;
//! the linear peridynamic solid adds its dilatation force and energy
//! `(beta / 2) sum_i V_i theta_i^2` ([`super::dilatation`]).
//!
//! Stable step (Silling & Askari 2005, central differences; Gershgorin bound on the
//! largest eigenvalue of the linear operator):
//! `dt_stable = sqrt(2 rho / max_i sum_j |c_ij| |xi_ij|^2)`, times
//! [`crate::models::dynamics::Integrator::stability_factor`].

use super::block::{bond_vectors, Layout};
use super::dilatation::Dilatation;
use super::family::Families;
use super::loads::LoadLayer;
use super::nodes::PdNodes;
use super::operator::Bonds;
use super::pairs::{Flagged, PairState, Pairs};
use super::{strain, BondForce};
use crate::physics::case::Case;
use super::fracture::{Breaking, Live, SERIAL_BELOW};
use crate::models::dynamics::driver::Energies;
use crate::models::dynamics::{SecondOrderSystem, State};
use crate::physics::elasticity::dofs::DofMap;
use crate::physics::elasticity::material::Material;
use crate::physics::elasticity::stress::StressField;
use crate::physics::exact::{self, ExactSolution};
use crate::stages::RunError;
use rayon::prelude::*;
use std::borrow::Cow;

/// The semi-discrete peridynamic system of one discretisation.
#[derive(Clone, Copy)]
pub struct PdDynamics<'a> {
    /// Bonds and their coefficients.
    pub bonds: Bonds<'a>,
    /// Body force density at the free nodes (tractions included) at t = 0.
    pub body_force: &'a [[f64; 2]],
    /// Mass density.
    pub density: f64,
    /// Force law.
    pub force: BondForce,
    /// The dilatation term of the linear peridynamic solid (linear law only).
    pub dilatation: Option<&'a Dilatation>,
    /// The loads at any time, when a load depends on time.
    pub varying: Option<VaryingLoads<'a>>,
    /// Bonds that break and pre-cracks ([`super::fracture`]), when the scene has them.
    pub breaking: Option<&'a Breaking>,
    /// The force loop: each bond once where the weights are symmetric
    /// ([`super::pairs`]).
    pub pairs: &'a Pairs,
}

/// Loads that depend on time: the body force densities of the free nodes and the
/// prescribed displacements of the collar, evaluated at every force evaluation.
#[derive(Clone, Copy)]
pub struct VaryingLoads<'a> {
    /// The case (body force, boundary conditions).
    pub case: &'a Case,
    /// Where the tractions act.
    pub layer: &'a LoadLayer,
    /// The exact solution, for `"exact"` values.
    pub exact: Option<&'a dyn ExactSolution>,
}

/// The loads of one instant: body force density of the free nodes, displacement of
/// the collar nodes (borrowed when the loads are fixed).
struct Instant<'a> {
    body_force: Cow<'a, [[f64; 2]]>,
    prescribed: Cow<'a, [[f64; 2]]>,
}

impl VaryingLoads<'_> {
    /// The loads at time `t`, or the first formula that is not finite where it is used.
    fn at(&self, nodes: &PdNodes, t: f64) -> Result<Instant<'static>, RunError> {
        let loads = self.case.loads_at(t);
        // The formula that fails at the node; else (a traction read near the node, an
        // exact value) the node itself.
        let bad = |node: usize| {
            let p = nodes.positions[node];
            loads.non_finite_at(p, t).unwrap_or(RunError::not_finite_at(node, p))
        };
        let body_force = self.layer.forces(&loads.body_force, &loads.conditions, self.exact, nodes).map_err(|e| match e {
            RunError::NotFinite { node, .. } => bad(node),
            other => other,
        })?;
        let collar = &nodes.positions[nodes.free..];
        let prescribed: Vec<[f64; 2]> = collar
            .par_iter()
            .zip(&nodes.collar_part)
            .map(|(&p, &part)| exact::value(&loads.conditions[part].value, p, self.exact, |e| e.displacement(p)))
            .collect();
        match prescribed.iter().position(|u| !u[0].is_finite() || !u[1].is_finite()) {
            Some(k) => Err(bad(nodes.free + k)),
            None => Ok(Instant { body_force: Cow::Owned(body_force), prescribed: Cow::Owned(prescribed) }),
        }
    }
}

impl PdDynamics<'_> {
    fn nodes(&self) -> &PdNodes {
        self.bonds.nodes
    }

    fn dofs(&self) -> DofMap {
        self.nodes().dofs()
    }

    /// The loads at time `t`: the fixed ones, or those of [`VaryingLoads`] (NaN where a
    /// formula is not finite: the driver stops and asks [`SecondOrderSystem::explain`]).
    fn loads(&self, t: f64) -> Instant<'_> {
        let nodes = self.nodes();
        match &self.varying {
            None => Instant { body_force: Cow::Borrowed(self.body_force), prescribed: Cow::Borrowed(&nodes.prescribed) },
            Some(v) => v.at(nodes, t).unwrap_or_else(|_| Instant {
                body_force: Cow::Owned(vec![[f64::NAN; 2]; nodes.free]),
                prescribed: Cow::Owned(vec![[f64::NAN; 2]; nodes.constrained()]),
            }),
        }
    }

    /// Displacement of node `j` (free: from `u`, constrained: prescribed at the instant
    /// of `loads`).
    fn displacement(&self, u: &[f64], loads: &Instant, j: usize) -> [f64; 2] {
        let free = self.nodes().free;
        if j < free {
            self.dofs().displacement(u, j)
        } else {
            loads.prescribed[j - free]
        }
    }

    /// `V_i` times the bond force density at every free node ([`Pairs::sum`]), over the
    /// `live` bonds where bonds break, recording the bonds at the critical stretch
    /// ([`super::fracture`]): the loop flags them without a branch by
    /// [`PdDynamics::bond_force`]'s test. The test is a little wide (1e-12), so that no
    /// bond [`PdDynamics::bond_energy`] finds at `s0` is left out.
    fn bond_forces(&self, u: &[f64], loads: &Instant, live: Option<&Live>) -> (Vec<[f64; 2]>, Vec<Flagged>) {
        let pairs = self.pairs;
        let nodes = self.nodes();
        let (x, volumes, families) = (&nodes.positions, &nodes.volumes, self.bonds.families);
        let c = live.map_or(self.bonds.coefficients, |l| &l.coefficients);
        let breaking = self.breaking.filter(|b| b.critical_stretch.is_finite());
        let s0 = breaking.map_or(f64::INFINITY, |b| b.critical_stretch * (1.0 - 1e-12));
        let at = PairState { positions: x, u, prescribed: &loads.prescribed, coefficients: c, volumes };
        let (forces, reached) = match (self.force, breaking) {
            (BondForce::Linear, None) => pairs.sum(
                families,
                &at,
                (
                    |c, xi: [f64; 2], eta: [f64; 2], vi| {
                        let vcp = vi * c * (xi[0] * eta[0] + xi[1] * eta[1]);
                        ([vcp * xi[0], vcp * xi[1]], false)
                    },
                    Layout::Fused,
                ),
            ),
            (BondForce::Linear, Some(_)) => pairs.sum(
                families,
                &at,
                (
                    |c, xi: [f64; 2], eta: [f64; 2], vi| {
                        let p = xi[0] * eta[0] + xi[1] * eta[1];
                        let cp = c * p;
                        // Live and at s0 (a broken bond, c = 0, stays stretched: not flagged).
                        ([vi * cp * xi[0], vi * cp * xi[1]], (cp != 0.0) & (p >= s0 * (xi[0] * xi[0] + xi[1] * xi[1])))
                    },
                    Layout::Fused,
                ),
            ),
            (BondForce::BondStretch, _) => pairs.sum(
                families,
                &at,
                (
                    |c, xi, eta, vi| {
                        let (g, at) = bond_stretch_force(c, xi, eta, s0);
                        ([vi * g[0], vi * g[1]], at)
                    },
                    Layout::Columns,
                ),
            ),
        };
        (forces, reached)
    }

    /// The force of one bond with coefficient `c` on its node (module docs), and whether
    /// it is live (`c != 0`) and at the critical stretch `s0` ([`super::fracture`]; the
    /// linearised stretch under the linear law), tested without a division
    /// (`xi . eta >= s0 |xi|^2`, `|xi + eta| - |xi| >= s0 |xi|`).
    #[inline]
    fn bond_force(&self, c: f64, xi: [f64; 2], eta: [f64; 2], s0: f64) -> ([f64; 2], bool) {
        let r2 = xi[0] * xi[0] + xi[1] * xi[1];
        match self.force {
            BondForce::Linear => {
                let p = xi[0] * eta[0] + xi[1] * eta[1];
                ([c * p * xi[0], c * p * xi[1]], (c != 0.0) & (p >= s0 * r2))
            }
            BondForce::BondStretch => bond_stretch_force(c, xi, eta, s0),
        }
    }

    /// The micropotential `w` of a bond with coefficient `c` (module docs), and its stretch.
    fn bond_energy(&self, c: f64, xi: [f64; 2], eta: [f64; 2]) -> (f64, f64) {
        match self.force {
            BondForce::Linear => linear_energy(c, xi, eta),
            BondForce::BondStretch => bond_stretch_energy(c, xi, eta),
        }
    }

    /// Every node's displacement (the free ones from `u`, the collar's of `loads`) and
    /// the dilatation of every node, when the solid has the dilatation term.
    fn theta(&self, u: &[f64], loads: &Instant) -> Option<Vec<f64>> {
        let d = self.dilatation?;
        let all: Vec<[f64; 2]> = (0..self.nodes().len()).map(|j| self.displacement(u, loads, j)).collect();
        Some(d.theta(self.nodes(), &all))
    }

    /// Largest stable time step of the central-difference schemes (module docs; with
    /// the dilatation term, its rows' Gershgorin bounds are added).
    pub fn stable_time_step(&self) -> f64 {
        let x = &self.nodes().positions;
        let families = self.bonds.families;
        let dilatation = self.dilatation.map(|d| d.row_bounds(self.nodes()));
        let worst = (0..self.nodes().free)
            .into_par_iter()
            .map(|i| {
                dilatation.as_ref().map_or(0.0, |b| b[i]) + families
                    .range(i)
                    .zip(families.of(i))
                    .map(|(b, &j)| {
                        let j = j as usize;
                        self.bonds.coefficients[b].abs() * ((x[j][0] - x[i][0]).powi(2) + (x[j][1] - x[i][1]).powi(2))
                    })
                    .sum::<f64>()
            })
            .reduce(|| 0.0, f64::max);
        (2.0 * self.density / worst).sqrt()
    }

    /// The nonlocal stress at every free node ([`strain::gradients`] over `families`)
    /// of the free nodes' displacements `u` at time `t`, the collar at its prescribed
    /// values of `t`.
    pub fn stress(&self, material: &Material, families: &Families, t: f64, u: &[[f64; 2]]) -> StressField {
        let all: Vec<[f64; 2]> = u.iter().chain(self.loads(t).prescribed.iter()).copied().collect();
        StressField::from_gradients(material, &strain::gradients(self.nodes(), families, &all, |_| true))
    }

    /// `(E_kin, E_el, E_ext, E_released, broken bonds)` of a state at time `t` (`E_ext`
    /// with the loads of `t`; the last two since the start, [`Breaking::released`]).
    pub fn energies(&self, t: f64, u: &[f64], v: &[f64]) -> Energies {
        let (nodes, dofs) = (self.nodes(), self.dofs());
        let loads = self.loads(t);
        let live = self.breaking.map(Breaking::live);
        let (kin, ext) = (0..nodes.free)
            .into_par_iter()
            .map(|i| {
                let vol = nodes.volumes[i];
                let (ui, vi) = (dofs.displacement(u, i), dofs.displacement(v, i));
                let kin = 0.5 * self.density * vol * (vi[0].powi(2) + vi[1].powi(2));
                let b = loads.body_force[i];
                (kin, -vol * (b[0] * ui[0] + b[1] * ui[1]))
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        let c = live.as_deref().map_or(self.bonds.coefficients, |l| &l.coefficients);
        let at = PairState { positions: &nodes.positions, u, prescribed: &loads.prescribed, coefficients: c, volumes: &nodes.volumes };
        let el = match self.force {
            BondForce::Linear => self.pairs.energy(self.bonds.families, &at, |c, xi, eta| linear_energy(c, xi, eta).0),
            BondForce::BondStretch => self.pairs.energy(self.bonds.families, &at, |c, xi, eta| bond_stretch_energy(c, xi, eta).0),
        };
        let dilatation = self.theta(u, &loads).map_or(0.0, |theta| self.dilatation.map_or(0.0, |d| d.energy(nodes, &theta)));
        let (broken, released) = self.breaking.map_or((0, 0.0), |b| b.released());
        [kin, el + dilatation, ext, released, broken as f64]
    }

    /// Break the bonds whose stretch at `state` is at least the critical one, both
    /// directions at once, among the `candidates` the last force evaluation found there
    /// ([`super::fracture`]); the energy a pair held (`V_i w_ij / 2 + V_j w_ji / 2`, its
    /// share of `E_el`) is released. What the loop read of each bond is used when
    /// `fresh` (it evaluated this state: Verlet and RK4 end on it); else each bond is read
    /// again at `state`. A bond is read at most once: its reverse is `(-xi, -eta)` (the
    /// laws' `w` are even, their forces odd). The bonds broken, each seen from its node:
    /// `(node, coefficient, xi, eta)`.
    fn break_bonds(&self, breaking: &Breaking, (candidates, fresh): (&[Flagged], bool), state: &State) -> Vec<(usize, f64, [f64; 2], [f64; 2])> {
        let (nodes, families) = (self.nodes(), self.bonds.families);
        let s0 = breaking.critical_stretch;
        // Per bond at s0: its two ends `(node, bond, xi, eta)`, the reverse when `j` is free.
        type End = (usize, usize, [f64; 2], [f64; 2]);
        let ends: Vec<End> = {
            let again = (!fresh).then(|| (breaking.live(), self.loads(state.t)));
            let ends_of = |f: &Flagged| {
                let (i, j) = (f.node, f.neighbour);
                let (c, (xi, eta)) = match &again {
                    None => (f.coefficient, (f.xi, f.eta)),
                    Some((live, loads)) => (live.coefficients[f.bond], bond_vectors(&nodes.positions, &state.u, &loads.prescribed, i, j)),
                };
                let at = c != 0.0 && self.bond_energy(c, xi, eta).1 >= s0;
                let reverse = (at && j < nodes.free)
                    .then(|| families.of(j).binary_search(&(i as u32)).ok())
                    .flatten()
                    .map(|p| (j, families.range(j).start + p, [-xi[0], -xi[1]], [-eta[0], -eta[1]]));
                at.then_some((i, f.bond, xi, eta)).into_iter().chain(reverse)
            };
            if candidates.len() < SERIAL_BELOW {
                candidates.iter().flat_map(ends_of).collect()
            } else {
                candidates.par_iter().flat_map_iter(ends_of).collect()
            }
        };
        let bonds: Vec<(usize, usize)> = ends.iter().map(|e| (e.0, e.1)).collect();
        let held = |k: usize, c: f64| {
            let (n, _, xi, eta) = ends[k];
            0.5 * nodes.volumes[n] * self.bond_energy(c, xi, eta).0
        };
        let coefficients = breaking.break_bonds(&bonds, &held);
        ends.iter().zip(coefficients).filter_map(|(&(n, _, xi, eta), c)| c.map(|c| (n, c, xi, eta))).collect()
    }
}

/// The bond-stretch force `c |xi|^3 s (xi + eta) / |xi + eta|` (module docs) and whether
/// the bond is live and at `s0` or beyond (`|xi + eta| - |xi| >= s0 |xi|`).
#[inline(always)]
fn bond_stretch_force(c: f64, xi: [f64; 2], eta: [f64; 2], s0: f64) -> ([f64; 2], bool) {
    let r2 = xi[0] * xi[0] + xi[1] * xi[1];
    let r = r2.sqrt();
    let y = [xi[0] + eta[0], xi[1] + eta[1]];
    let ry = (y[0] * y[0] + y[1] * y[1]).sqrt();
    // c |xi|^3 s / |xi + eta|, s = (|xi + eta| - |xi|) / |xi|.
    let k = c * r2 * (ry - r) / ry;
    ([k * y[0], k * y[1]], (c != 0.0) & (ry - r >= s0 * r))
}

/// The linear law's micropotential `c (xi . eta)^2 / 2` (module docs) and the linearised
/// stretch `xi . eta / |xi|^2`.
#[inline(always)]
fn linear_energy(c: f64, xi: [f64; 2], eta: [f64; 2]) -> (f64, f64) {
    let p = xi[0] * eta[0] + xi[1] * eta[1];
    (0.5 * c * p * p, p / (xi[0] * xi[0] + xi[1] * xi[1]))
}

/// The bond-stretch micropotential `c |xi|^4 s^2 / 2` (module docs) and the stretch `s`.
#[inline(always)]
fn bond_stretch_energy(c: f64, xi: [f64; 2], eta: [f64; 2]) -> (f64, f64) {
    let r = (xi[0] * xi[0] + xi[1] * xi[1]).sqrt();
    let s = (((xi[0] + eta[0]).powi(2) + (xi[1] + eta[1]).powi(2)).sqrt() - r) / r;
    (0.5 * c * r.powi(4) * s * s, s)
}


impl SecondOrderSystem for PdDynamics<'_> {
    fn len(&self) -> usize {
        self.dofs().len()
    }

    fn acceleration(&self, t: f64, u: &[f64], a: &mut [f64]) {
        if let Some(breaking) = self.breaking {
            breaking.start_evaluation();
        }
        let loads = self.loads(t);
        let theta = self.theta(u, &loads);
        let live = self.breaking.map(Breaking::live);
        let (forces, reached) = self.bond_forces(u, &loads, live.as_deref());
        if let Some(breaking) = self.breaking.filter(|_| !reached.is_empty()) {
            breaking.record(reached, t, u);
        }
        let volumes = &self.nodes().volumes;
        a.par_chunks_mut(2).enumerate().for_each(|(i, a)| {
            let mut f = [forces[i][0] / volumes[i], forces[i][1] / volumes[i]];
            if let (Some(d), Some(theta)) = (self.dilatation, theta.as_deref()) {
                let g = d.force_at(self.nodes(), theta, i);
                f = [f[0] + g[0], f[1] + g[1]];
            }
            let b = loads.body_force[i];
            a[0] = (f[0] + b[0]) / self.density;
            a[1] = (f[1] + b[1]) / self.density;
        });
    }

    /// Bonds that reached the critical stretch break, and their forces leave `state.a`
    /// (the same as evaluating it again, for the broken bonds' work only).
    fn settle(&self, state: &mut State) -> bool {
        let Some(breaking) = self.breaking else { return false };
        let (candidates, fresh) = breaking.candidates(state.t, &state.u);
        if candidates.is_empty() {
            return false;
        }
        let dofs = self.dofs();
        let broken = self.break_bonds(breaking, (&candidates, fresh), state);
        for &(k, c, xi, eta) in &broken {
            let (g, _) = self.bond_force(c, xi, eta, f64::INFINITY);
            state.a[dofs.dof(k, 0)] -= g[0] / self.density;
            state.a[dofs.dof(k, 1)] -= g[1] / self.density;
        }
        !broken.is_empty()
    }

    fn explain(&self, t0: f64, t1: f64) -> Option<RunError> {
        let v = self.varying.as_ref()?;
        [t0, 0.5 * (t0 + t1), t1].into_iter().find_map(|t| v.at(self.nodes(), t).err())
    }
}
