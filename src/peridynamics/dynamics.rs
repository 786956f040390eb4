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
//! `w = c_ij (xi . eta)^2 / 2` (linear) or `c_ij |xi|^4 s^2 / 2`, `E_ext = -sum_i V_i b_i . u_i`.
//!
//! Stable step (Silling & Askari 2005, central differences; Gershgorin bound on the
//! largest eigenvalue of the linear operator):
//! `dt_stable = sqrt(2 rho / max_i sum_j |c_ij| |xi_ij|^2)`, times
//! [`crate::dynamics::Integrator::stability_factor`].

use super::operator::Bonds;
use super::BondForce;
use crate::dynamics::SecondOrderSystem;
use rayon::prelude::*;
use serde::Serialize;

/// The semi-discrete peridynamic system of one discretisation.
pub struct PdDynamics<'a> {
    /// Bonds and their coefficients.
    pub bonds: Bonds<'a>,
    /// Body force density at the free nodes (tractions included), constant in time.
    pub body_force: &'a [[f64; 2]],
    /// Mass density.
    pub density: f64,
    /// Force law.
    pub force: BondForce,
}

impl PdDynamics<'_> {
    fn nodes(&self) -> &super::nodes::PdNodes {
        self.bonds.nodes
    }

    /// Displacement of node `j` (free: from `u`, constrained: prescribed).
    fn displacement(&self, u: &[f64], j: usize) -> [f64; 2] {
        let free = self.nodes().free;
        if j < free {
            [u[2 * j], u[2 * j + 1]]
        } else {
            self.nodes().prescribed[j - free]
        }
    }

    /// Force density and micropotential sum of the bonds of free node `i`.
    fn bond_sums(&self, u: &[f64], i: usize) -> ([f64; 2], f64) {
        let x = &self.nodes().positions;
        let ui = self.displacement(u, i);
        let (mut f, mut w) = ([0.0, 0.0], 0.0);
        let families = self.bonds.families;
        for (b, &j) in families.range(i).zip(families.of(i)) {
            let j = j as usize;
            let c = self.bonds.coefficients[b];
            let xi = [x[j][0] - x[i][0], x[j][1] - x[i][1]];
            let uj = self.displacement(u, j);
            let eta = [uj[0] - ui[0], uj[1] - ui[1]];
            match self.force {
                BondForce::Linear => {
                    let p = xi[0] * eta[0] + xi[1] * eta[1];
                    f[0] += c * p * xi[0];
                    f[1] += c * p * xi[1];
                    w += 0.5 * c * p * p;
                }
                BondForce::BondStretch => {
                    let r = xi[0].hypot(xi[1]);
                    let y = [xi[0] + eta[0], xi[1] + eta[1]];
                    let ry = y[0].hypot(y[1]);
                    let s = (ry - r) / r;
                    let k = c * r * r * r * s / ry;
                    f[0] += k * y[0];
                    f[1] += k * y[1];
                    w += 0.5 * c * r.powi(4) * s * s;
                }
            }
        }
        (f, w)
    }

    /// Largest stable time step of the central-difference schemes (module docs).
    pub fn stable_time_step(&self) -> f64 {
        let x = &self.nodes().positions;
        let families = self.bonds.families;
        let worst = (0..self.nodes().free)
            .into_par_iter()
            .map(|i| {
                families
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

    /// `(E_kin, E_el, E_ext)` of a state.
    pub fn energies(&self, u: &[f64], v: &[f64]) -> (f64, f64, f64) {
        let nodes = self.nodes();
        (0..nodes.free)
            .into_par_iter()
            .map(|i| {
                let vol = nodes.volumes[i];
                let kin = 0.5 * self.density * vol * (v[2 * i].powi(2) + v[2 * i + 1].powi(2));
                let (_, w) = self.bond_sums(u, i);
                let b = self.body_force[i];
                (kin, 0.5 * vol * w, -vol * (b[0] * u[2 * i] + b[1] * u[2 * i + 1]))
            })
            .reduce(|| (0.0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2))
    }
}

impl SecondOrderSystem for PdDynamics<'_> {
    fn len(&self) -> usize {
        2 * self.nodes().free
    }

    fn acceleration(&self, _t: f64, u: &[f64], a: &mut [f64]) {
        a.par_chunks_mut(2).enumerate().for_each(|(i, a)| {
            let (f, _) = self.bond_sums(u, i);
            let b = self.body_force[i];
            a[0] = (f[0] + b[0]) / self.density;
            a[1] = (f[1] + b[1]) / self.density;
        });
    }
}

/// What a dynamic run did.
#[derive(Debug, Clone, Serialize)]
pub struct DynamicReport {
    /// Scheme.
    pub integrator: crate::dynamics::Integrator,
    /// Step used.
    pub time_step: f64,
    /// Stable step of the central-difference schemes.
    pub stable_time_step: f64,
    /// Steps taken.
    pub steps: usize,
    /// Force evaluations (including the initial one).
    pub force_evaluations: usize,
    /// Bond force evaluations (`force_evaluations x bonds`).
    pub bond_updates: f64,
    /// Wall-clock seconds of the time loop (snapshots excluded).
    pub seconds: f64,
    /// Bond updates per second per thread.
    pub bond_updates_per_second_per_thread: f64,
}

/// One line of the energy history: `(t, E_kin, E_el, E_ext)`.
pub type EnergyRow = [f64; 4];

/// The step and step count of a run, checked against the stability limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeGrid {
    /// Step.
    pub dt: f64,
    /// Number of steps to `end_time`.
    pub steps: usize,
    /// Stable step of the central-difference schemes.
    pub stable: f64,
}

/// The step of `params` (fixed, or `safety` times the scheme's limit), refused when a
/// fixed step exceeds the limit.
pub fn time_grid(system: &PdDynamics, params: &crate::problem::DynamicsParams) -> Result<TimeGrid, crate::run::RunError> {
    let stable = system.stable_time_step();
    let limit = stable * params.integrator.stability_factor();
    match params.time_step {
        Some(dt) if dt > limit => Err(crate::run::RunError::UnstableTimeStep { given: dt, limit, integrator: params.integrator.name() }),
        Some(dt) => Ok(TimeGrid { dt, steps: (params.end_time / dt).round().max(1.0) as usize, stable }),
        None => {
            let steps = (params.end_time / (params.safety * limit)).ceil().max(1.0) as usize;
            Ok(TimeGrid { dt: params.end_time / steps as f64, steps, stable })
        }
    }
}

/// Integrate `system` from `state` over `grid` with the scheme of `params`, calling
/// `snapshot` at `params.snapshots` evenly spaced steps (and at the start and the end)
/// and recording the energies at every step (every `ceil(steps / 1000)`-th step for
/// longer runs). Returns the report and the energy history.
pub fn integrate<E>(
    system: &PdDynamics,
    state: &mut crate::dynamics::State,
    grid: TimeGrid,
    params: &crate::problem::DynamicsParams,
    progress: &dyn crate::run::Progress,
    mut snapshot: impl FnMut(usize, &crate::dynamics::State) -> Result<(), E>,
) -> Result<(DynamicReport, Vec<EnergyRow>), IntegrateError<E>> {
    let TimeGrid { dt, steps, stable } = grid;
    let every = (steps / params.snapshots.max(1)).max(1);
    // Energies cost one more pass over the bonds: at most about 1000 rows.
    let energy_every = steps.div_ceil(1000).max(1);
    let mut energies = Vec::with_capacity(steps + 1);
    let record = |s: &crate::dynamics::State, energies: &mut Vec<EnergyRow>| {
        let (k, e, x) = system.energies(&s.u, &s.v);
        energies.push([s.t, k, e, x]);
    };
    record(state, &mut energies);
    snapshot(0, state).map_err(IntegrateError::Output)?;
    let mut looped = 0.0;
    for step in 1..=steps {
        let ts = std::time::Instant::now();
        params.integrator.step(system, state, dt);
        looped += ts.elapsed().as_secs_f64();
        if state.u.iter().any(|v| !v.is_finite()) {
            return Err(IntegrateError::Run(crate::run::RunError::Diverged { step, t: state.t }));
        }
        if step % energy_every == 0 || step == steps {
            record(state, &mut energies);
        }
        if step % every == 0 || step == steps {
            snapshot(step, state).map_err(IntegrateError::Output)?;
        }
        progress.advance(step as u64, steps as u64);
    }
    let evaluations = 1 + steps * params.integrator.evaluations();
    let bond_updates = evaluations as f64 * system.bonds.families.bonds() as f64;
    let report = DynamicReport {
        integrator: params.integrator,
        time_step: dt,
        stable_time_step: stable,
        steps,
        force_evaluations: evaluations,
        bond_updates,
        seconds: looped,
        bond_updates_per_second_per_thread: bond_updates / looped.max(1e-12) / rayon::current_num_threads() as f64,
    };
    Ok((report, energies))
}

/// A failed integration: numerical, or the snapshot writer's own error.
#[derive(Debug)]
pub enum IntegrateError<E> {
    /// Unstable step or divergence.
    Run(crate::run::RunError),
    /// The snapshot callback failed.
    Output(E),
}
