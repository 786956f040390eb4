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
use super::fracture::{Breaking, Live};
use super::laws::{bond_stretch_energy, bond_stretch_force, bond_stretch_law, linear_energy, linear_law};
use super::loads::LoadLayer;
use super::nodes::PdNodes;
use super::operator::Bonds;
use super::pairs::{Flagged, PairState, Pairs};
use super::{strain, BondForce};
use crate::models::dynamics::driver::Energies;
use crate::models::dynamics::{SecondOrderSystem, State};
use crate::physics::case::Case;
use crate::physics::elasticity::dofs::DofMap;
use crate::physics::elasticity::material::Material;
use crate::physics::elasticity::stress::StressField;
use crate::physics::exact::{self, ExactSolution};
use crate::stages::RunError;
use rayon::prelude::*;
use std::borrow::Cow;
use std::ops::Range;

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
    /// Whether each force evaluation also sums the elastic energy, kept for the energy
    /// history: for integrators whose last evaluation of a step is of the step's state
    /// (Verlet), whose history then costs no pass over the bonds.
    pub energy_in_loop: bool,
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
    /// bond [`PdDynamics::bond_energy`] finds at `s0` is left out. And the bonds' elastic
    /// energy ([`Pairs::energy`]'s sum) where [`PdDynamics::energy_in_loop`], else 0.
    fn bond_forces(&self, u: &[f64], loads: &Instant, live: Option<&Live>) -> (Vec<[f64; 2]>, Vec<Flagged>, f64) {
        let pairs = self.pairs;
        let nodes = self.nodes();
        let (x, volumes, families) = (&nodes.positions, &nodes.volumes, self.bonds.families);
        let c = live.map_or(self.bonds.coefficients, |l| &l.coefficients);
        let breaking = self.breaking.filter(|b| b.critical_stretch.is_finite());
        let s0 = breaking.map_or(f64::INFINITY, |b| b.critical_stretch * (1.0 - 1e-12));
        let at = PairState { positions: x, u, prescribed: &loads.prescribed, coefficients: c, volumes };
        let (linear, bond_stretch) = (Layout::Fused, Layout::Columns);
        match (self.force, breaking.is_some(), self.energy_in_loop) {
            (BondForce::Linear, false, false) => pairs.sum(families, &at, (linear_law::<false, false>(s0), linear)),
            (BondForce::Linear, false, true) => pairs.sum(families, &at, (linear_law::<false, true>(s0), linear)),
            (BondForce::Linear, true, false) => pairs.sum(families, &at, (linear_law::<true, false>(s0), linear)),
            (BondForce::Linear, true, true) => pairs.sum(families, &at, (linear_law::<true, true>(s0), linear)),
            (BondForce::BondStretch, _, false) => pairs.sum(families, &at, (bond_stretch_law::<false>(s0), bond_stretch)),
            (BondForce::BondStretch, _, true) => pairs.sum(families, &at, (bond_stretch_law::<true>(s0), bond_stretch)),
        }
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
            BondForce::BondStretch => {
                let (g, at, _) = bond_stretch_force(c, xi, eta, s0);
                (g, at)
            }
        }
    }

    /// The damage of every free node where bonds break ([`Breaking::damage`], each pair
    /// read from the bond the force loop visits when it visits each pair once).
    pub fn damage(&self) -> Option<Vec<f64>> {
        let breaking = self.breaking?;
        let upper = |i: usize| self.pairs.upper(self.bonds.families, i);
        let visited: Option<&(dyn Fn(usize) -> Range<usize> + Sync)> = (!self.pairs.directed()).then_some(&upper);
        Some(breaking.damage(&self.nodes().volumes, self.bonds.families, visited))
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
                dilatation.as_ref().map_or(0.0, |b| b[i])
                    + families
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
        // Kept by the evaluation of this state (Verlet's last), else a pass over the bonds.
        let el = self.pairs.kept_energy(t, u).unwrap_or_else(|| {
            let c = live.as_deref().map_or(self.bonds.coefficients, |l| &l.coefficients);
            let at = PairState { positions: &nodes.positions, u, prescribed: &loads.prescribed, coefficients: c, volumes: &nodes.volumes };
            let bonds = match self.force {
                BondForce::Linear => self.pairs.energy(self.bonds.families, &at, |c, xi, eta| linear_energy(c, xi, eta).0),
                BondForce::BondStretch => self.pairs.energy(self.bonds.families, &at, |c, xi, eta| bond_stretch_energy(c, xi, eta).0),
            };
            bonds + self.theta(u, &loads).map_or(0.0, |theta| self.dilatation.map_or(0.0, |d| d.energy(nodes, &theta)))
        });
        let (broken, released) = self.breaking.map_or((0, 0.0), |b| b.released());
        [kin, el, ext, released, broken as f64]
    }
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
        let (forces, reached, energy) = self.bond_forces(u, &loads, live.as_deref());
        drop(live);
        if let Some(breaking) = self.breaking.filter(|_| !reached.is_empty()) {
            breaking.record(reached, t, u);
        }
        if self.energy_in_loop {
            let dilatation = self.dilatation.zip(theta.as_deref()).map_or(0.0, |(d, theta)| d.energy(self.nodes(), theta));
            self.pairs.keep_energy(t, u, energy + dilatation);
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
        let (nodes, dofs, s0) = (self.nodes(), self.dofs(), breaking.critical_stretch);
        // What the loop read holds when it evaluated this state (Verlet, RK4); else (emu)
        // each bond is read again at `state`.
        let again = (!fresh).then(|| self.loads(state.t));
        let once = !self.pairs.directed();
        let State { t, u, a, .. } = state;
        let (broken, released) = breaking.break_each(&candidates, |f| {
            let (i, j, c) = (f.node, f.neighbour, f.coefficient);
            let (xi, eta) = again.as_ref().map_or((f.xi, f.eta), |loads| bond_vectors(&nodes.positions, u, &loads.prescribed, i, j));
            let (w, s) = self.bond_energy(c, xi, eta);
            if s < s0 {
                return None;
            }
            let (g, _) = self.bond_force(c, xi, eta, f64::INFINITY);
            a[dofs.dof(i, 0)] -= g[0] / self.density;
            a[dofs.dof(i, 1)] -= g[1] / self.density;
            let vi = nodes.volumes[i];
            if once && j < nodes.free {
                // The pair's force on j, `-V_i f_ij / V_j`, leaves with it, and the energy
                // it held (`V_i w_ij`, both halves).
                let share = vi / nodes.volumes[j];
                a[dofs.dof(j, 0)] += share * g[0] / self.density;
                a[dofs.dof(j, 1)] += share * g[1] / self.density;
                Some((vi * w, 2))
            } else {
                Some((0.5 * vi * w, 1))
            }
        });
        // The energy the evaluation kept held these bonds' (the same shares).
        self.pairs.change_kept_energy(*t, u, -released);
        broken > 0
    }

    fn energies_from_evaluation(&self) -> bool {
        self.energy_in_loop
    }

    fn explain(&self, t0: f64, t1: f64) -> Option<RunError> {
        let v = self.varying.as_ref()?;
        [t0, 0.5 * (t0 + t1), t1].into_iter().find_map(|t| v.at(self.nodes(), t).err())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::peridynamics::fracture::{CriticalStretch, Fracture};
    use crate::models::peridynamics::test_case::plate_bonds;
    use std::collections::HashSet;

    /// On the clamped plate with symmetric weights, a displacement that stretches the
    /// bonds across `x = 1/2` past `s0`: the loop that visits each pair once and the loop
    /// that visits every bond from both ends (the same weights, the pairs told they are
    /// not symmetric) break the same bonds (the same count, the same damage) and release
    /// the same energy, and leave the same acceleration, that of evaluating again without
    /// the broken bonds, and the elastic energy of a pass over the live bonds in what the
    /// evaluation kept, each to round-off (1e-12: sums of about 30 terms in another order).
    #[test]
    fn both_loops_break_the_same_bonds() {
        let (domain, nodes, families, c, skewed) = plate_bonds();
        let (x, free) = (&nodes.positions, nodes.free);
        let once = Pairs::new(&nodes, &families, &c);
        let both = Pairs::new(&nodes, &families, &skewed);
        assert!(!once.directed() && both.directed());
        let body_force = vec![[0.0; 2]; free];
        let u: Vec<f64> = x[..free].iter().flat_map(|p| [1e-2 * ((p[0] - 0.5) / 0.05).tanh(), 1e-3 * p[1]]).collect();
        let fracture = Fracture::new(Some(CriticalStretch::Given(2e-2)), &[]).unwrap();
        let run = |pairs: &Pairs, force: BondForce| {
            let breaking = Breaking::new(x, &families, &c, &fracture.cuts(&domain), 2e-2);
            let system = PdDynamics {
                bonds: Bonds { nodes: &nodes, families: &families, coefficients: &c },
                body_force: &body_force,
                density: 1.0,
                force,
                dilatation: None,
                varying: None,
                breaking: Some(&breaking),
                pairs,
                energy_in_loop: true,
            };
            let mut state = State::new(&system, 0.0, u.clone(), vec![0.0; u.len()]);
            assert!(system.settle(&mut state));
            // The energy the evaluation kept, less the broken bonds', is a pass's over the
            // live bonds (a copy of `u`: not the state the evaluation kept).
            let kept = system.energies(0.0, &state.u, &state.v)[1];
            let pass = system.energies(0.0, &state.u.clone(), &state.v)[1];
            assert!(kept > 0.0 && (kept - pass).abs() <= 1e-12 * pass, "{force:?}: kept {kept:e}, pass {pass:e}");
            // Settling is evaluating again without the broken bonds.
            let mut again = vec![0.0; u.len()];
            system.acceleration(0.0, &state.u, &mut again);
            let largest = again.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            assert!(again.iter().zip(&state.a).all(|(p, q)| (p - q).abs() <= 1e-12 * largest), "{force:?}: settled and evaluated again");
            let (count, released) = breaking.released();
            (state.a, count, released, system.damage().unwrap())
        };
        for force in [BondForce::Linear, BondForce::BondStretch] {
            let (a1, n1, e1, d1) = run(&once, force);
            let (a2, n2, e2, d2) = run(&both, force);
            assert!(n1 > 0 && n1 < families.bonds() / 4, "{force:?}: {n1} of {} bonds broke", families.bonds());
            assert_eq!(n1, n2, "{force:?}: bonds broken");
            assert!((e1 - e2).abs() <= 1e-12 * e1, "{force:?}: released {e1} and {e2}");
            let largest = a1.iter().fold(0.0f64, |m, a| m.max(a.abs()));
            assert!(a1.iter().zip(&a2).all(|(p, q)| (p - q).abs() <= 1e-12 * largest), "{force:?}: accelerations");
            assert!(d1.iter().zip(&d2).all(|(p, q)| (p - q).abs() <= 1e-14), "{force:?}: damage");
        }
    }

    /// Pairs broken by their visited bond alone (the loop visits each pair once) give
    /// every node the damage of the pairs counted from both ends, `sum_{pair broken} V_j /
    /// sum_j V_j`, on the clamped plate with every third visited bond broken.
    #[test]
    fn damage_reads_each_pair_from_its_visited_bond() {
        let (domain, nodes, families, c, _) = plate_bonds();
        let (x, v, free) = (&nodes.positions, &nodes.volumes, nodes.free);
        let pairs = Pairs::new(&nodes, &families, &c);
        let fracture = Fracture::new(Some(CriticalStretch::Given(1.0)), &[]).unwrap();
        let breaking = Breaking::new(x, &families, &c, &fracture.cuts(&domain), 1.0);
        let body_force = vec![[0.0; 2]; free];
        let system = PdDynamics {
            bonds: Bonds { nodes: &nodes, families: &families, coefficients: &c },
            body_force: &body_force,
            density: 1.0,
            force: BondForce::Linear,
            dilatation: None,
            varying: None,
            breaking: Some(&breaking),
            pairs: &pairs,
            energy_in_loop: false,
        };
        let marked: Vec<Flagged> = (0..free)
            .flat_map(|i| pairs.upper(&families, i).map(move |b| (i, b)))
            .step_by(3)
            .map(|(i, b)| {
                let j = families.neighbour(b) as usize;
                Flagged { node: i, bond: b, neighbour: j, coefficient: c[b], xi: [0.0; 2], eta: [0.0; 2] }
            })
            .collect();
        assert!(breaking.break_each(&marked, |_| Some((0.0, 2))).0 > 0);
        let gone: HashSet<(usize, usize)> = marked.iter().map(|f| (f.node, f.neighbour)).collect();
        let damage = system.damage().unwrap();
        assert!(damage.iter().any(|&d| d > 0.3) && damage.iter().all(|&d| d < 1.0));
        for (i, d) in damage.iter().enumerate() {
            let (all, lost) = families.of(i).iter().fold((0.0, 0.0), |(all, lost), &j| {
                let j = j as usize;
                (all + v[j], lost + if gone.contains(&(i.min(j), i.max(j))) { v[j] } else { 0.0 })
            });
            assert!((d - lost / all).abs() <= 1e-14, "node {i}: {d} against {}", lost / all);
        }
    }
}
