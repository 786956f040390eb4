//! Explicit MLSM elastodynamics: `rho u_tt = (lambda + mu) grad div u + mu lap u + f`
//! at the nodes that carry a Navier row, with the boundary rows (traction,
//! displacement; at ghost nodes and ghost-free boundary nodes) kept as algebraic
//! constraints at every instant.
//!
//! The static system `A u = r` of the discretisation (one row per unknown, see
//! `navier::system`) is split into dynamic unknowns D (rows holding the Navier
//! equation, `A_D u = -f`) and algebraic ones A (boundary rows). Then
//!
//! ```text
//! u_A = A_AA^-1 (r_A - A_AD u_D),     u_D'' = (A_DD u_D + A_DA u_A - r_D) / rho,
//! ```
//!
//! with `A_AA` factorised once (sparse LU). Loads that depend on time make `r` a
//! function of `t`, re-evaluated at every force evaluation; the velocities of the
//! algebraic unknowns then follow from the constraints' time derivative,
//! `v_A = A_AA^-1 (r_A' - A_AD v_D)` (`r'` from the symbolic `d/dt` of the formulas).
//! The stable step of the central-difference
//! schemes, `2 / sqrt(|mu_max|)`, uses the largest eigenvalue magnitude of the
//! condensed operator, estimated by 60 power iterations (a lower bound, so the result
//! is multiplied by a 0.9 margin; a collocation operator is not symmetric, and any
//! eigenvalue with a positive real part makes every explicit run grow).

use super::discrete::Discretisation;
use super::estimate::Estimate;
use super::system::System;
use super::NavierParams;
use crate::physics::case::{Case, Loads};
use crate::domain::cells::{cells_inside, nodal_areas};
use crate::models::dynamics::driver::{integrate, is_snapshot, time_grid, DynamicReport, EnergyRow, Snapshot};
use crate::models::dynamics::history::TimeSamples;
use crate::models::dynamics::{DynamicsParams, SecondOrderSystem, State};
use crate::physics::elasticity::conditions::Value;
use crate::physics::elasticity::dofs::DofMap;
use crate::physics::elasticity::material::Lame;
use crate::physics::elasticity::stress::{strain, StressField};
use crate::physics::exact::{self, ExactSolution};
use crate::linalg::{lu::SparseLu, mul_add, row_matrix, RowMatrix, SolveError, SparseMatrix};
use crate::stages::{stage, RunError, StageTimer, StageTimings};
use std::borrow::Cow;
use std::collections::BTreeMap;

/// The condensed MLSM system of one discretisation.
pub struct NavierDynamics<'a> {
    /// Global unknown of each dynamic unknown (state order).
    pub dynamic: Vec<usize>,
    /// Global unknown of each algebraic unknown.
    pub algebraic: Vec<usize>,
    a_dd: RowMatrix,
    a_da: RowMatrix,
    a_ad: RowMatrix,
    lu_aa: SparseLu,
    r_d: Vec<f64>,
    r_a: Vec<f64>,
    density: f64,
    /// The right-hand side at any time, when a load depends on time.
    varying: Option<VaryingLoads<'a>>,
}

/// Loads that depend on time: the right-hand side of the system and its time
/// derivative at any instant.
pub struct VaryingLoads<'a> {
    /// The rows of the discretisation.
    pub system: System<'a>,
    /// The loads as functions of `t`.
    pub loads: Loads,
    /// Their time derivatives.
    pub rates: Loads,
    /// The nodes whose loads vary: the boundary nodes, or every node when the body
    /// force depends on time.
    pub nodes: Vec<usize>,
    /// The right-hand side at t = 0 (the rows of the other nodes keep it).
    pub initial: Vec<f64>,
}

impl VaryingLoads<'_> {
    /// The right-hand side of the loads at time `t` (with `rate`, of their time
    /// derivatives: zero outside the varying nodes), or the formula (else the node)
    /// that is not finite.
    fn at(&self, t: f64, rate: bool) -> Result<Vec<f64>, RunError> {
        let instant = if rate { &self.rates } else { &self.loads }.at_time(t);
        let mut rhs = if rate { vec![0.0; self.initial.len()] } else { self.initial.clone() };
        self.system.update_right_hand_side(&instant, &self.nodes, &mut rhs).map_err(|e| match e {
            RunError::NotFinite { x, y, .. } => instant.non_finite_at([x, y], t).unwrap_or(e),
            other => other,
        })?;
        Ok(rhs)
    }
}

impl<'a> NavierDynamics<'a> {
    /// Split `matrix`/`rhs` by `is_dynamic` (per global unknown) and factorise `A_AA`.
    pub fn new(matrix: &SparseMatrix, rhs: &[f64], is_dynamic: &[bool], density: f64) -> Result<Self, SolveError> {
        let n = rhs.len();
        let (mut local, mut dynamic, mut algebraic) = (vec![0usize; n], Vec::new(), Vec::new());
        for g in 0..n {
            if is_dynamic[g] {
                local[g] = dynamic.len();
                dynamic.push(g);
            } else {
                local[g] = algebraic.len();
                algebraic.push(g);
            }
        }
        let (mut dd, mut da, mut ad, mut aa) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for col in 0..n {
            for (&row, &v) in matrix.symbolic().row_idx_of_col_raw(col).iter().zip(matrix.val_of_col(col)) {
                let e = (local[row], local[col], v);
                match (is_dynamic[row], is_dynamic[col]) {
                    (true, true) => dd.push(e),
                    (true, false) => da.push(e),
                    (false, true) => ad.push(e),
                    (false, false) => aa.push(faer::sparse::Triplet::new(e.0, e.1, e.2)),
                }
            }
        }
        let (nd, na) = (dynamic.len(), algebraic.len());
        let a_aa = SparseMatrix::try_new_from_triplets(na, na, &aa)
            .map_err(|e| SolveError::Dimension { detail: format!("boundary block: {e:?}") })?;
        let lu_aa = SparseLu::factor(&a_aa)?;
        Ok(NavierDynamics {
            a_dd: row_matrix(nd, nd, &dd)?,
            a_da: row_matrix(nd, na, &da)?,
            a_ad: row_matrix(na, nd, &ad)?,
            lu_aa,
            r_d: dynamic.iter().map(|&g| rhs[g]).collect(),
            r_a: algebraic.iter().map(|&g| rhs[g]).collect(),
            dynamic,
            algebraic,
            density,
            varying: None,
        })
    }

    /// The same system with loads that depend on time.
    pub fn with_varying(self, varying: VaryingLoads<'a>) -> Self {
        NavierDynamics { varying: Some(varying), ..self }
    }

    /// `(r_D, r_A)` of a full right-hand side.
    fn split(&self, rhs: &[f64]) -> (Vec<f64>, Vec<f64>) {
        (self.dynamic.iter().map(|&g| rhs[g]).collect(), self.algebraic.iter().map(|&g| rhs[g]).collect())
    }

    /// `(r_D, r_A)` at time `t` (of the loads, or with `rate` of their time
    /// derivatives; zero for fixed loads); NaN where a formula is not finite (the
    /// driver stops and asks [`SecondOrderSystem::explain`]).
    fn loads(&self, t: f64, rate: bool) -> (Cow<'_, [f64]>, Cow<'_, [f64]>) {
        let n = self.dynamic.len() + self.algebraic.len();
        match (&self.varying, rate) {
            (None, false) => (Cow::Borrowed(&self.r_d), Cow::Borrowed(&self.r_a)),
            (None, true) => (Cow::Owned(vec![0.0; self.dynamic.len()]), Cow::Owned(vec![0.0; self.algebraic.len()])),
            (Some(v), _) => {
                let rhs = v.at(t, rate).unwrap_or_else(|_| vec![f64::NAN; n]);
                let (d, a) = self.split(&rhs);
                (Cow::Owned(d), Cow::Owned(a))
            }
        }
    }

    /// `u_A = A_AA^-1 (r_A - A_AD u_D)`.
    fn algebraic_part(&self, u_d: &[f64], r_a: &[f64]) -> Vec<f64> {
        let mut b = r_a.to_vec();
        let mut t = vec![0.0; b.len()];
        mul_add(&self.a_ad, u_d, &mut t);
        b.iter_mut().zip(&t).for_each(|(b, t)| *b -= t);
        self.lu_aa.solve(&b)
    }

    /// All unknowns (global order) at time `t` from the dynamic ones: displacements,
    /// or with `rate` velocities (the constraints differentiated in time).
    pub fn expand(&self, t: f64, u_d: &[f64], rate: bool) -> Vec<f64> {
        let mut u = vec![0.0; self.dynamic.len() + self.algebraic.len()];
        for (k, &g) in self.dynamic.iter().enumerate() {
            u[g] = u_d[k];
        }
        let loads = self.loads(t, rate);
        for (k, v) in self.algebraic_part(u_d, &loads.1).into_iter().enumerate() {
            u[self.algebraic[k]] = v;
        }
        u
    }

    /// The condensed operator `(A_DD u_D + A_DA u_A(u_D) - r_D) / rho` under the loads
    /// `(r_D, r_A)` (zero: the homogeneous operator).
    fn operator(&self, u_d: &[f64], out: &mut [f64], (r_d, r_a): (&[f64], &[f64])) {
        out.iter_mut().for_each(|v| *v = 0.0);
        mul_add(&self.a_dd, u_d, out);
        let u_a = self.algebraic_part(u_d, r_a);
        mul_add(&self.a_da, &u_a, out);
        out.iter_mut().zip(r_d).for_each(|(o, r)| *o -= r);
        out.iter_mut().for_each(|v| *v /= self.density);
    }

    /// Largest stable step of the central-difference schemes (module docs).
    pub fn stable_time_step(&self) -> f64 {
        let n = self.dynamic.len();
        let mut x: Vec<f64> = (0..n).map(|i| 1.0 + ((i * 7919) % 101) as f64 / 101.0).collect();
        let mut y = vec![0.0; n];
        let mut lambda = 0.0;
        let (zero_d, zero_a) = (vec![0.0; n], vec![0.0; self.algebraic.len()]);
        for _ in 0..60 {
            let norm = crate::linalg::scaled_norm(&x);
            x.iter_mut().for_each(|v| *v /= norm);
            self.operator(&x, &mut y, (&zero_d, &zero_a));
            lambda = crate::linalg::scaled_norm(&y);
            std::mem::swap(&mut x, &mut y);
        }
        0.9 * 2.0 / lambda.sqrt()
    }
}

impl SecondOrderSystem for NavierDynamics<'_> {
    fn len(&self) -> usize {
        self.dynamic.len()
    }

    fn acceleration(&self, t: f64, u: &[f64], a: &mut [f64]) {
        let loads = self.loads(t, false);
        self.operator(u, a, (&loads.0, &loads.1));
    }

    fn explain(&self, t0: f64, t1: f64) -> Option<RunError> {
        let v = self.varying.as_ref()?;
        [t0, 0.5 * (t0 + t1), t1].into_iter().find_map(|t| v.at(t, false).err())
    }
}

/// The result of a time-dependent MLSM run.
pub struct Simulation {
    /// Node positions (ghosts excluded).
    pub positions: Vec<[f64; 2]>,
    /// Final displacement at the nodes.
    pub u: Vec<[f64; 2]>,
    /// Final velocity at the nodes.
    pub v: Vec<[f64; 2]>,
    /// Integration report.
    pub report: DynamicReport,
    /// Energy history (empty for a reference run, [`Sampling::Times`]).
    pub energies: Vec<EnergyRow>,
    /// Ghost nodes.
    pub ghost_nodes: usize,
    /// Dynamic and algebraic unknowns.
    pub unknowns: (usize, usize),
    /// Error estimate over the history (`estimate.method`; module `estimate`).
    pub estimate: Estimate,
    /// The states kept for an error estimate, `(t, displacement at the nodes)`
    /// ([`Sampling`]); empty without one.
    pub history: Vec<(f64, Vec<[f64; 2]>)>,
    /// Stage timings (assembly includes the split and the boundary factorisation).
    pub timings: StageTimings,
    /// The re-entrant corners and holes with traction edges, none of them balanced
    /// (the sector balances are not imposed in time, `super::sector`).
    pub unbalanced: Vec<super::sector::Unbalanced>,
}

/// Why a dynamic run balances no corner or hole (`Simulation::unbalanced`).
pub const UNBALANCED_IN_TIME: &str = "dynamic runs impose no sector balance";

/// The condensed system of `disc`: assembled, split and factorised (module docs),
/// with its loads re-evaluated in time when they depend on it.
fn condensed<'a>(
    case: &'a Case,
    disc: &'a Discretisation,
    exact: Option<&'a dyn ExactSolution>,
    density: f64,
) -> Result<NavierDynamics<'a>, RunError> {
    let system = System { case, disc, exact };
    let (rows, rhs) = system.assemble()?;
    let matrix = crate::linalg::csr::columns_of(rows);
    let is_dynamic: Vec<bool> = (0..rhs.len())
        .map(|g| {
            let (node, c) = disc.dofs.location(g);
            c < 2 && disc.navier_row_is_own(node, c)
        })
        .collect();
    let condensed = NavierDynamics::new(&matrix, &rhs, &is_dynamic, density)?;
    let loads = case.loads();
    if !loads.depend_on_time() {
        return Ok(condensed);
    }
    let rates = loads.time_derivative().map_err(|(field, why)| RunError::Formula {
        field,
        reason: format!("{why}; the MLSM model needs d/dt of a load in t (the velocity the boundary rows impose)"),
    })?;
    let nodes: Vec<usize> =
        if loads.body_force.depends_on_time() { (0..disc.nodes.len()).collect() } else { (0..disc.nodes.boundary.len()).collect() };
    Ok(condensed.with_varying(VaryingLoads { system, loads, rates, nodes, initial: rhs }))
}

/// `(E_kin, E_el, E_ext)` of a state (see [`simulate`]), `E_ext` with the body force
/// `body_force` bound at the state's time once.
fn energies(
    system: &NavierDynamics,
    disc: &Discretisation,
    (body_force, exact): (&Value, Option<&dyn ExactSolution>),
    areas: &[f64],
    lame: Lame,
    density: f64,
    s: &State,
) -> (f64, f64, f64) {
    let (u, v) = (system.expand(s.t, &s.u, false), system.expand(s.t, &s.v, true));
    let grads = disc.gradients(&u);
    let (mut kin, mut el, mut ext) = (0.0, 0.0, 0.0);
    let force = body_force.at_time(s.t);
    for (i, area) in areas.iter().enumerate() {
        let p = disc.nodes.positions[i];
        let body = exact::value(&force, p, exact, |e| e.body_force(p));
        let (ui, vi) = (disc.dofs.displacement(&u, i), disc.dofs.displacement(&v, i));
        kin += 0.5 * density * area * (vi[0].powi(2) + vi[1].powi(2));
        let (sg, e) = (lame.stress(grads[i]), strain(grads[i]));
        el += 0.5 * area * (sg[0] * e[0] + sg[1] * e[1] + 2.0 * sg[2] * e[2]);
        ext -= area * (body[0] * ui[0] + body[1] * ui[1]);
    }
    (kin, el, ext)
}

/// The states a simulation keeps in [`Simulation::history`].
#[derive(Debug, Clone, Copy)]
pub enum Sampling<'a> {
    /// Those of its own error estimate ([`crate::models::dynamics::driver::history_steps`]), when `estimate.method`
    /// makes one.
    Estimate,
    /// The states at these times (a run's history, for its reference, which keeps no
    /// energies): a step's own
    /// where its time equals `t` to 1e-9 of the end time, else interpolated between
    /// the two steps around `t` ([`TimeSamples`]).
    Times(&'a [f64]),
}

/// The stages of [`super::run::simulate`] timed by `timer`, keeping the states
/// `sampling` picks: the [`Simulation`]'s `estimate` is [`Estimate::Off`] and its
/// `timings` empty until the caller makes the estimate and closes the timer.
pub fn simulate_sampled(
    case: &Case,
    params: &NavierParams,
    dynamics: &DynamicsParams,
    timer: &mut StageTimer,
    sampling: Sampling,
    mut snapshot: impl FnMut(Snapshot) -> Result<(), RunError>,
) -> Result<Simulation, RunError> {
    // Energies need the displacement gradient at every node.
    let snapshot_stress = case.outputs.stress || case.outputs.von_mises;
    let mut case = case.clone();
    case.outputs.stress = true;
    let case = &case;
    let exact = case.exact_solution();
    let disc = Discretisation::new(case, params, exact.as_deref(), timer)?;
    let system = timer.run(stage::ASSEMBLY, || {
        let system = condensed(case, &disc, exact.as_deref(), dynamics.density)?;
        let note = format!("{} dynamic, {} algebraic unknowns", system.dynamic.len(), system.algebraic.len());
        Ok((system, note))
    })?;
    let grid = time_grid(system.stable_time_step(), dynamics)?;
    let points = &disc.nodes.positions;
    let dofs: DofMap = disc.dofs;
    let init = |f: &Value| -> Vec<f64> {
        system
            .dynamic
            .iter()
            .map(|&g| {
                let (node, c) = dofs.location(g);
                f.explicit_at(points[node]).expect("validated: an initial state is a constant or an expression")[c]
            })
            .collect()
    };
    let mut state = State::new(&system, 0.0, init(&dynamics.initial_displacement), init(&dynamics.initial_velocity));
    let areas = nodal_areas(points, &cells_inside(&case.domain, points));
    let n = disc.nodes.len();
    let nodal = |x: &[f64]| dofs.displacements(x, n);
    let body = (&case.body_force, exact.as_deref());
    // A reference run for an estimate (`Sampling::Times`) keeps no energies: they cost
    // one more pass over the operator per step and nobody reads them.
    let reference = matches!(sampling, Sampling::Times(_));
    let energy = |s: &State| {
        if reference {
            [0.0; 5]
        } else {
            let (k, e, x) = energies(&system, &disc, body, &areas, case.material.lame(), dynamics.density, s);
            [k, e, x, 0.0, 0.0]
        }
    };
    let method = params.estimate.method;
    let samples = match sampling {
        Sampling::Estimate if method.dynamic_navier_estimates() => TimeSamples::own(grid.steps, grid.dt),
        Sampling::Estimate => TimeSamples::none(),
        Sampling::Times(times) => TimeSamples::at_times(times, grid.dt, grid.steps, 1e-9 * dynamics.end_time),
    };
    let mut kept = BTreeMap::new();
    let (report, energies) = integrate(&system, &energy, &mut state, (grid, &samples.steps), dynamics, timer, |step, s| {
        let (keep, write) = (samples.keeps(step), is_snapshot(step, grid.steps, dynamics));
        let x = system.expand(s.t, &s.u, false);
        let u = nodal(&x);
        let v = if keep || write { nodal(&system.expand(s.t, &s.v, true)) } else { Vec::new() };
        if write {
            let stress = snapshot_stress.then(|| StressField::from_gradients(&case.material, &disc.gradients(&x)));
            snapshot(Snapshot { step, t: s.t, positions: points, u: &u, v: &v, stress: stress.as_ref(), damage: None })?;
        }
        if keep {
            kept.insert(step, (s.t, u, v));
        }
        Ok(())
    })?;
    let history = samples.states(&kept);
    drop(kept);
    let u = nodal(&system.expand(state.t, &state.u, false));
    Ok(Simulation {
        positions: points.clone(),
        u,
        v: nodal(&system.expand(state.t, &state.v, true)),
        report,
        energies: if reference { Vec::new() } else { energies },
        ghost_nodes: disc.ghost_count(),
        unknowns: (system.dynamic.len(), system.algebraic.len()),
        estimate: Estimate::Off,
        history,
        timings: StageTimings::default(),
        unbalanced: disc.survey.none_balanced(UNBALANCED_IN_TIME),
    })
}
