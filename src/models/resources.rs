//! Memory a run will need, estimated from the scene before any heavy stage, against
//! the memory the machine has available.
//!
//! The model (bytes), with `n` nodes, `k` unknowns per node, support `s`:
//!
//! ```text
//! nonzeros   Z = (k^2 - k + 2) n s        (Navier rows couple k unknowns of s nodes; u-p continuity rows 2)
//! shapes       = n s (5 * 8 + 4)          (five operators of f64 and the support of u32; a static
//!                                          run frees them after assembly: max(shapes + 12 Z, solve),
//!                                          RBF-FD keeps the gradient's 16 n s through the solve)
//! solve, LU    = Z (16 + 34 N^0.26)       (the equilibrated columns, 16 B per nonzero, which
//!                                          replace the rows; the LU factors of faer, fitted: see below)
//! solve, BiCGSTAB = Z (24 + 48)           (the equilibrated matrix, which replaces the
//!                                          assembled one, and an ILU of about three times its size)
//! solve, GMRES = 24 Z + (restart + 6) 8 N  (the rows as assembled, 12 B, equilibrated in
//!                                          place, the AMG levels and the Krylov basis)
//! solve, auto  = LU or GMRES as `SolverKind::resolve` will choose
//! peak         = max(run, error-estimate reference) + 16 MB
//! ```
//!
//! and for peridynamics `n = area / h^2`, `pi m^2` bonds per node (32 B each),
//! `Z = 4 n (pi m^2 + 1)`, the same solver terms with `N = 2 n`. The LU term was fitted
//! on the Kirsch plate (PHS p = 4) at two sizes (docs/notebook/2026-11-27-auto-by-time.md,
//! "From the code comments"); the test `memory_estimate_tracks_the_measured_peak`
//! checks the whole model within 2x on three sizes.

use crate::physics::case::Case;
use crate::linalg::{lu_factor_bytes, SolverKind};
use crate::models::navier::discrete::keeps_gradient_shapes;
use crate::models::navier::dynamic_estimate::richardson_applies;
use crate::models::navier::estimate::{reference_approximation, EstimateMethod};
use crate::models::navier::NavierParams;
use crate::output::{available_memory, available_memory_bytes};
use crate::models::peridynamics::PdParams;
use crate::scene::problem::{validate, Problem, ProblemError};
use serde::Serialize;

/// The estimate of one run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MemoryEstimate {
    /// Nodes.
    pub nodes: f64,
    /// Unknowns.
    pub unknowns: f64,
    /// Nonzeros of the system matrix.
    pub nonzeros: f64,
    /// Bonds (peridynamics).
    pub bonds: Option<f64>,
    /// Peak resident memory, bytes.
    pub peak_bytes: f64,
    /// The scene setting that drives it.
    #[serde(skip)]
    pub driver: &'static str,
}

/// Bytes of the solver for `nonzeros` and `unknowns`: assembly and matrix, plus
/// factors or preconditioner (`auto` resolved as the solve will resolve it, with its
/// longer GMRES on the saddle point of the displacement-pressure form).
fn solver_bytes(kind: &SolverKind, unknowns: f64, nonzeros: f64, saddle_point: bool) -> f64 {
    match kind.choose(unknowns, nonzeros, saddle_point, available_memory_bytes()).primary {
        // The assembled matrix is freed once equilibrated (`linalg::solve_nodal`).
        SolverKind::Bicgstab(..) => 72.0 * nonzeros,
        // The rows as assembled (12 B per entry), equilibrated in place and kept as the
        // multigrid's finest level, the coarse levels and single-precision transfers
        // (about 9 B per fine entry), slack, and the Krylov basis (checked at 1e6 nodes:
        // docs/notebook/round2-target-error.md, "Rows assembled in node order").
        SolverKind::Gmres { restart, .. } | SolverKind::Petsc { restart, .. } => 24.0 * nonzeros + (restart as f64 + 6.0) * 8.0 * unknowns,
        // The rows (12 B per entry) become the equilibrated columns (16 B) and are freed;
        // then the columns and the factors.
        _ => 16.0 * nonzeros + lu_factor_bytes(nonzeros, unknowns),
    }
}

/// Process, code and small arrays.
const BASE_BYTES: f64 = 16e6;

/// Bytes per matrix entry of a dynamic Navier run (measured, see [`navier`]).
const DYNAMIC_BYTES_PER_NONZERO: f64 = 100.0;

/// A static or dynamic Navier run of `case` with `params` on about `nodes` nodes.
pub fn navier(case: &Case, params: &NavierParams, nodes: f64) -> MemoryEstimate {
    let k = params.formulation.unknowns(&case.material).per_node() as f64;
    let dynamic = case.dynamics.is_some();
    let one = |support: usize, nodes: f64| {
        let s = support as f64;
        // Navier rows couple k unknowns of s nodes (u-p: the continuity row only 2; its
        // stabilisation's pressure Laplacian, s more, is not counted: it adds little to
        // the measured peak, which the estimate still exceeds;
        // docs/notebook/round2-pressure-stabilisation.md).
        let nonzeros = (k * k - (k - 2.0)) * nodes * s;
        // Dynamic: the triplets, the matrix, its split into dynamic and algebraic
        // blocks and the boundary block's factors, 100 B per entry (chosen from the
        // measured peaks of steel_plate_dynamic: docs/notebook/round1-explicit-dynamics-1e5.md).
        let solve =
            if dynamic { DYNAMIC_BYTES_PER_NONZERO * nonzeros } else { solver_bytes(&params.solver.kind, k * nodes, nonzeros, k > 2.0) };
        // A static run releases its shapes once the rows are assembled (they and the
        // rows, 12 B per entry, are the assembly's peak), except the gradient's under
        // RBF-FD (two operators of f64); a dynamic one keeps them all.
        let shapes = nodes * s * 44.0;
        let kept = if case.outputs.needs_gradient() && keeps_gradient_shapes(&params.approximation.basis) { nodes * s * 16.0 } else { 0.0 };
        (nonzeros, if dynamic { shapes + solve } else { (shapes + 12.0 * nonzeros).max(solve + kept) })
    };
    let (nonzeros, mut bytes) = one(params.approximation.support, nodes);
    if params.estimate.method.static_navier_estimates() && !dynamic {
        if let Ok(reference) = reference_approximation(&params.approximation, params.fill.kind, nodes as usize) {
            bytes = bytes.max(one(reference.support, nodes).1);
        }
    }
    if let Some(d) = case.dynamics.as_ref().filter(|_| params.estimate.method.dynamic_navier_estimates()) {
        // The reference runs while the run's system is held: Richardson's a quarter of
        // the nodes, the refined one four times them.
        let method = params.estimate.method;
        let richardson = method != EstimateMethod::Refined && richardson_applies(params, d.integrator).is_ok();
        bytes += one(params.approximation.support, if richardson { 0.25 } else { 4.0 } * nodes).1;
    }
    let driver = if params.approximation.support > 100 { "approximation.support" } else { "nodes.spacing" };
    MemoryEstimate { nodes, unknowns: k * nodes, nonzeros, bonds: None, peak_bytes: bytes + BASE_BYTES, driver }
}

/// A peridynamic run with `params` on the domain of `case`.
pub fn peridynamics(case: &Case, params: &PdParams) -> MemoryEstimate {
    let h = params.horizon / params.ratio;
    let nodes = case.domain.area_estimate(400) / (h * h);
    let per_node = std::f64::consts::PI * params.ratio * params.ratio;
    let bonds = nodes * per_node;
    let nonzeros = 4.0 * nodes * (per_node + 1.0);
    let peak_bytes = bonds * 32.0 + solver_bytes(&params.solver.kind, 2.0 * nodes, nonzeros, false) + BASE_BYTES;
    MemoryEstimate { nodes, unknowns: 2.0 * nodes, nonzeros, bonds: Some(bonds), peak_bytes, driver: "peridynamics.horizon" }
}

/// The estimate for the model `p` runs.
pub fn of(p: &Problem) -> MemoryEstimate {
    match &p.model {
        crate::scene::problem::ModelParams::Peridynamics(pd) => {
            let mut e = peridynamics(&p.case, pd);
            // The local-model estimate's Navier run comes after the nonlocal one.
            if p.navier.estimate.method.peridynamics_estimates() {
                e.peak_bytes = e.peak_bytes.max(of(&p.local_reference()).peak_bytes);
                // The discretisation estimate: the run at twice m (four times the nodes
                // and the bonds per node), after the run: a static run's, and a dynamic
                // one's below m = 6 (from m = 6 it takes the run at m / 2).
                if p.case.dynamics.is_none() || pd.ratio < 6.0 {
                    let fine = PdParams { ratio: 2.0 * pd.ratio, ..*pd };
                    e.peak_bytes = e.peak_bytes.max(peridynamics(&p.case, &fine).peak_bytes);
                }
            }
            e
        }
        _ => {
            let nodes = validate::expected_nodes(&p.case.domain, &p.navier.fill, p.case.domain.area_estimate(400));
            navier(&p.case, &p.navier, nodes)
        }
    }
}

/// The estimate of `p`, or a refusal naming the setting that drives it and the limit
/// that is the smallest ([`available_memory`]: `MLSM_MEMORY_LIMIT`, `MemAvailable`,
/// the cgroup's, `ulimit -v`) when it exceeds the available memory (or naming
/// `MLSM_MEMORY_LIMIT` when it is set to something other than a positive number of
/// bytes).
pub fn check(p: &Problem) -> Result<MemoryEstimate, ProblemError> {
    check_estimate(p, || of(p))
}

/// [`check`] of the Navier run of `p` on about `nodes` nodes, a count the caller already
/// has (`convergence`: its first level's times 4 per halving), so that a graded fill's
/// node count is not integrated again at the finest spacing (16 s for Kirsch at 1/32 of
/// its spacing).
pub fn check_navier_nodes(p: &Problem, nodes: f64) -> Result<MemoryEstimate, ProblemError> {
    check_estimate(p, || navier(&p.case, &p.navier, nodes))
}

/// The refusal of [`check`] for the estimate `estimate` makes.
fn check_estimate(p: &Problem, estimate: impl FnOnce() -> MemoryEstimate) -> Result<MemoryEstimate, ProblemError> {
    if let Ok(v) = std::env::var("MLSM_MEMORY_LIMIT") {
        if !v.trim().parse::<f64>().is_ok_and(|x| x > 0.0 && x.is_finite()) {
            return Err(ProblemError {
                file: p.source.clone(),
                field: "MLSM_MEMORY_LIMIT".into(),
                reason: format!("the environment variable is {v:?}, not a positive number of bytes (e.g. 4e9)"),
                kind: crate::scene::problem::ProblemErrorKind::Invalid,
            });
        }
    }
    let e = estimate();
    match available_memory() {
        Some(limit) if e.peak_bytes > limit.bytes => Err(ProblemError {
            file: p.source.clone(),
            field: e.driver.into(),
            reason: format!(
                "the run needs about {} ({}), more than the {} available ({}); {}",
                gigabytes(e.peak_bytes),
                describe(&e),
                gigabytes(limit.bytes),
                limit.source.describe(),
                match e.driver {
                    "approximation.support" => "use a smaller support",
                    "peridynamics.horizon" => "use a larger horizon or a smaller m",
                    _ => "use a larger spacing, solver.kind = \"auto\" or \"bicgstab\" (no factors), or [estimate] method = \"none\" (its reference solve has the larger stencils)",
                }
            ),
            kind: crate::scene::problem::ProblemErrorKind::Invalid,
        }),
        _ => Ok(e),
    }
}

/// `bytes` in GB, with two decimals below 1 GB (so that small limits do not read
/// "0.0 GB").
pub fn gigabytes(bytes: f64) -> String {
    if bytes < 1e9 {
        format!("{:.2} GB", bytes / 1e9)
    } else {
        format!("{:.1} GB", bytes / 1e9)
    }
}

/// `N nodes, U unknowns, Z nonzeros[, B bonds]`.
pub fn describe(e: &MemoryEstimate) -> String {
    let bonds = e.bonds.map(|b| format!(", {b:.1e} bonds")).unwrap_or_default();
    format!("{:.1e} nodes, {:.1e} unknowns, {:.1e} nonzeros{bonds}", e.nodes, e.unknowns, e.nonzeros)
}

/// Whether `e` needs more than half the available memory (a warning).
pub fn above_half(e: &MemoryEstimate) -> Option<f64> {
    available_memory_bytes().filter(|a| e.peak_bytes > 0.5 * a)
}
