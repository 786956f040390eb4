//! Explicit MLSM elastodynamics: `rho u_tt = (lambda + mu) grad div u + mu lap u + f`
//! at the nodes that carry a Navier row, with the boundary rows (traction,
//! displacement; at ghost nodes and ghost-free boundary nodes) kept as algebraic
//! constraints at every instant.
//!
//! The static system `A u = r` of the discretisation (one row per unknown, see
//! `run::System::assemble`) is split into dynamic unknowns D (rows holding the Navier
//! equation, `A_D u = -f`) and algebraic ones A (boundary rows). Then
//!
//! ```text
//! u_A = A_AA^-1 (r_A - A_AD u_D),     u_D'' = (A_DD u_D + A_DA u_A - r_D) / rho,
//! ```
//!
//! with `A_AA` factorised once (sparse LU). The stable step of the central-difference
//! schemes, `2 / sqrt(|mu_max|)`, uses the largest eigenvalue magnitude of the
//! condensed operator, estimated by 60 power iterations (a lower bound, so the result
//! is multiplied by a 0.9 margin; a collocation operator is not symmetric, and any
//! eigenvalue with a positive real part makes every explicit run grow).

use super::SecondOrderSystem;
use crate::linalg::{lu::SparseLu, SolveError, SparseMatrix};
use rayon::prelude::*;

/// Compressed rows, for parallel products.
struct Rows {
    ptr: Vec<usize>,
    idx: Vec<usize>,
    val: Vec<f64>,
}

impl Rows {
    fn from_entries(n_rows: usize, mut e: Vec<(usize, usize, f64)>) -> Rows {
        e.sort_unstable_by_key(|x| (x.0, x.1));
        let mut ptr = vec![0; n_rows + 1];
        for x in &e {
            ptr[x.0 + 1] += 1;
        }
        for i in 0..n_rows {
            ptr[i + 1] += ptr[i];
        }
        Rows { ptr, idx: e.iter().map(|x| x.1).collect(), val: e.iter().map(|x| x.2).collect() }
    }

    /// `y += A x`.
    fn mul_add(&self, x: &[f64], y: &mut [f64]) {
        y.par_iter_mut().enumerate().for_each(|(r, y)| {
            *y += (self.ptr[r]..self.ptr[r + 1]).map(|k| self.val[k] * x[self.idx[k]]).sum::<f64>();
        });
    }
}

/// The condensed MLSM system of one discretisation.
pub struct NavierDynamics {
    /// Global unknown of each dynamic unknown (state order).
    pub dynamic: Vec<usize>,
    /// Global unknown of each algebraic unknown.
    pub algebraic: Vec<usize>,
    a_dd: Rows,
    a_da: Rows,
    a_ad: Rows,
    lu_aa: SparseLu,
    r_d: Vec<f64>,
    r_a: Vec<f64>,
    density: f64,
}

impl NavierDynamics {
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
        let na = algebraic.len();
        let a_aa = SparseMatrix::try_new_from_triplets(na, na, &aa)
            .map_err(|e| SolveError::Dimension { detail: format!("boundary block: {e:?}") })?;
        let lu_aa = SparseLu::factor(&a_aa)?;
        Ok(NavierDynamics {
            a_dd: Rows::from_entries(dynamic.len(), dd),
            a_da: Rows::from_entries(dynamic.len(), da),
            a_ad: Rows::from_entries(na, ad),
            lu_aa,
            r_d: dynamic.iter().map(|&g| rhs[g]).collect(),
            r_a: algebraic.iter().map(|&g| rhs[g]).collect(),
            dynamic,
            algebraic,
            density,
        })
    }

    /// `u_A = A_AA^-1 (r_A - A_AD u_D)`; with `homogeneous`, without `r_A`.
    fn algebraic_part(&self, u_d: &[f64], homogeneous: bool) -> Vec<f64> {
        let mut b: Vec<f64> = if homogeneous { vec![0.0; self.r_a.len()] } else { self.r_a.clone() };
        let mut t = vec![0.0; b.len()];
        self.a_ad.mul_add(u_d, &mut t);
        b.iter_mut().zip(&t).for_each(|(b, t)| *b -= t);
        self.lu_aa.solve(&b)
    }

    /// All unknowns (global order) from the dynamic ones; with `homogeneous` the
    /// constraints without their right-hand side (for velocities: the prescribed
    /// boundary values do not change in time).
    pub fn expand(&self, u_d: &[f64], homogeneous: bool) -> Vec<f64> {
        let mut u = vec![0.0; self.dynamic.len() + self.algebraic.len()];
        for (k, &g) in self.dynamic.iter().enumerate() {
            u[g] = u_d[k];
        }
        for (k, v) in self.algebraic_part(u_d, homogeneous).into_iter().enumerate() {
            u[self.algebraic[k]] = v;
        }
        u
    }

    /// The condensed operator `M u_D = (A_DD u_D + A_DA u_A(u_D)) / rho` (no loads).
    fn operator(&self, u_d: &[f64], out: &mut [f64], homogeneous: bool) {
        out.iter_mut().for_each(|v| *v = 0.0);
        self.a_dd.mul_add(u_d, out);
        let u_a = self.algebraic_part(u_d, homogeneous);
        self.a_da.mul_add(&u_a, out);
        if !homogeneous {
            out.iter_mut().zip(&self.r_d).for_each(|(o, r)| *o -= r);
        }
        out.iter_mut().for_each(|v| *v /= self.density);
    }

    /// Largest stable step of the central-difference schemes (module docs).
    pub fn stable_time_step(&self) -> f64 {
        let n = self.dynamic.len();
        let mut x: Vec<f64> = (0..n).map(|i| 1.0 + ((i * 7919) % 101) as f64 / 101.0).collect();
        let mut y = vec![0.0; n];
        let mut lambda = 0.0;
        for _ in 0..60 {
            let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            x.iter_mut().for_each(|v| *v /= norm);
            self.operator(&x, &mut y, true);
            lambda = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            std::mem::swap(&mut x, &mut y);
        }
        0.9 * 2.0 / lambda.sqrt()
    }
}

impl SecondOrderSystem for NavierDynamics {
    fn len(&self) -> usize {
        self.dynamic.len()
    }

    fn acceleration(&self, _t: f64, u: &[f64], a: &mut [f64]) {
        self.operator(u, a, false);
    }
}

/// The result of a time-dependent MLSM run.
pub struct NavierSimulation {
    /// Node positions (ghosts excluded).
    pub positions: Vec<[f64; 2]>,
    /// Final displacement and velocity at the nodes.
    pub u: Vec<[f64; 2]>,
    /// Final velocity at the nodes.
    pub v: Vec<[f64; 2]>,
    /// Integration report.
    pub report: super::driver::DynamicReport,
    /// Energy history.
    pub energies: Vec<super::driver::EnergyRow>,
    /// Ghost nodes.
    pub ghost_nodes: usize,
    /// Dynamic and algebraic unknowns.
    pub unknowns: (usize, usize),
    /// Stage timings (assembly includes the split and the boundary factorisation).
    pub timings: crate::run::Timings,
}

/// Lumped nodal areas: a third of every Delaunay triangle (inside the solid) at each corner.
pub fn nodal_areas(points: &[[f64; 2]], triangles: &[[usize; 3]]) -> Vec<f64> {
    let mut a = vec![0.0; points.len()];
    for t in triangles {
        let (p, q, r) = (points[t[0]], points[t[1]], points[t[2]]);
        let area = 0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1])).abs();
        for &k in t {
            a[k] += area / 3.0;
        }
    }
    a
}

/// Run `problem` (with a `[dynamics]` table) by explicit MLSM elastodynamics, calling
/// `snapshot(step, t, positions, u, v)` at the snapshot steps. Energies:
/// `E_kin = sum rho A_i |v_i|^2 / 2`, `E_el = sum A_i sigma : eps / 2`,
/// `E_ext = -sum A_i f . u_i` (constant body force), `A_i` lumped Delaunay areas.
pub fn simulate<E>(
    problem: &crate::problem::Problem,
    progress: &dyn crate::run::Progress,
    mut snapshot: impl FnMut(usize, f64, &[[f64; 2]], &[[f64; 2]], &[[f64; 2]]) -> Result<(), E>,
) -> Result<NavierSimulation, super::driver::IntegrateError<E>> {
    use super::driver::{integrate, time_grid, IntegrateError};
    use crate::elasticity::stress;
    use crate::run::RunError;
    let dynamics = problem.dynamics.expect("a [dynamics] table");
    let run_err = |e: RunError| IntegrateError::Run(e);
    // Energies need the displacement gradient at every node.
    let mut q = problem.clone();
    q.outputs.stress = true;
    let mut timings = crate::run::Timings::default();
    let disc = crate::run::Discrete::new(&q, progress, &mut timings).map_err(run_err)?;
    let exact = crate::run::exact_solution(&q);
    let (n, nb) = (disc.nodes.len(), disc.nodes.boundary.len());
    let started = std::time::Instant::now();
    let (triplets, rhs) = disc.system(&q, exact.as_deref()).assemble().map_err(run_err)?;
    let matrix = crate::linalg::assemble(&triplets).map_err(|e| run_err(e.into()))?;
    let is_dynamic: Vec<bool> = (0..rhs.len()).map(|g| g / 2 < n && (g / 2 >= nb || disc.ghost[g / 2] != usize::MAX)).collect();
    let system = NavierDynamics::new(&matrix, &rhs, &is_dynamic, dynamics.density).map_err(|e| run_err(e.into()))?;
    drop(matrix);
    timings.assembly = started.elapsed().as_secs_f64();
    let grid = time_grid(system.stable_time_step(), &dynamics).map_err(run_err)?;
    let points = &disc.nodes.positions;
    let init = |f: &crate::problem::Affine| -> Vec<f64> { system.dynamic.iter().map(|&g| f.at(points[g / 2])[g % 2]).collect() };
    let mut state = super::State::new(&system, 0.0, init(&dynamics.initial_displacement), init(&dynamics.initial_velocity));
    let areas = nodal_areas(points, &crate::output::triangulate(points, |c| problem.domain.contains(c)));
    let lame = q.material.lame();
    let body = match q.body_force {
        crate::problem::Value::Constant(f) => f,
        crate::problem::Value::Exact => [0.0, 0.0],
    };
    let nodal = |x: &[f64]| -> Vec<[f64; 2]> { (0..n).map(|i| [x[2 * i], x[2 * i + 1]]).collect() };
    let energy = |s: &super::State| {
        let (u, v) = (system.expand(&s.u, false), system.expand(&s.v, true));
        let grads = stress::gradients(&disc.dofs, &disc.supports, &disc.shapes, &u, n);
        let (mut kin, mut el, mut ext) = (0.0, 0.0, 0.0);
        for i in 0..n {
            kin += 0.5 * dynamics.density * areas[i] * (v[2 * i].powi(2) + v[2 * i + 1].powi(2));
            let (sg, e) = (lame.stress(grads[i]), stress::strain(grads[i]));
            el += 0.5 * areas[i] * (sg[0] * e[0] + sg[1] * e[1] + 2.0 * sg[2] * e[2]);
            ext -= areas[i] * (body[0] * u[2 * i] + body[1] * u[2 * i + 1]);
        }
        (kin, el, ext)
    };
    let (report, energies) = integrate(&system, &energy, &mut state, grid, &dynamics, progress, |step, s| {
        snapshot(step, s.t, points, &nodal(&system.expand(&s.u, false)), &nodal(&system.expand(&s.v, true)))
    })?;
    Ok(NavierSimulation {
        positions: points.clone(),
        u: nodal(&system.expand(&state.u, false)),
        v: nodal(&system.expand(&state.v, true)),
        report,
        energies,
        ghost_nodes: disc.dofs.len() / 2 - n,
        unknowns: (system.dynamic.len(), system.algebraic.len()),
        timings,
    })
}
