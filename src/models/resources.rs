//! Memory a run will need, estimated from the scene before any heavy stage, against
//! the memory the machine has available.
//!
//! The model (bytes), with `n` nodes (the fill's prediction,
//! `Problem::expected_nodes`), `k` unknowns per node, support `s`, `N = k n`:
//!
//! ```text
//! nonzeros   Z = (k^2 - k + 2) n s        (Navier rows couple k unknowns of s nodes; u-p continuity rows 2)
//! shapes       = n s (5 * 8 + 4)          (five operators of f64 and the support of u32)
//! assembly     = shapes + 12 Z + min(12 Z, 24 MB)   (the rows, and the fragments in flight)
//! solve, LU    = 16 Z + 5.5 Z^1.2 N^0.164 (the equilibrated columns, which replace the
//!                                          rows, and faer's factors: `linalg::lu_factor_bytes`)
//! solve, BiCGSTAB = 84 Z                  (the equilibrated matrix and its ILUT)
//! solve, GMRES = 12 Z + 12 Z_mg + (restart + 6) 8 N   (the rows, the multigrid's levels,
//!                                          the Krylov basis; Z_mg = Z, or 2 Z 12 / s on the
//!                                          low-order operator of large stencils)
//! static run   = max(assembly, solve + 16 n s if RBF-FD keeps the gradient's shapes)
//! peak         = max(run, higher-degree reference run) + 12 MB
//! ```
//!
//! A run is estimated twice. Before it, for the memory check ([`check`], [`of`]):
//! the solver `auto` will choose, no fallback, and the estimate `estimate.method`
//! asks for (`auto`: the defect estimate, which reuses the run's solver and adds no
//! peak; `higher-degree`: the reference run). After it, for the summary
//! ([`of_static_run`]): the path it took ([`StaticPath`]: LU after a GMRES that failed,
//! the reference that `auto` took where the defect estimate cannot be trusted, and
//! that reference's own solver). A fallback is checked when it is chosen: LU only
//! where its factors take at most half the available memory
//! (`SolverKind::auto_fallback`).
//!
//! For peridynamics `n = area / h^2`, `pi m^2` bonds per node (32 B each),
//! `Z = 4 n (pi m^2 + 1)`, the same solver terms with `N = 2 n`; a static run's
//! families and rows are released before its solve. The linear peridynamic solid adds
//! its dilatation (20 B per bond), and `4 Z` where its dilatation is assembled.
//!
//! Measured against the peak the kernel reports (`/usr/bin/time`) on every shipped
//! scene, preset and solver path: 0.77-1.28 (benches/memory_estimate.sh,
//! BENCHMARKS.md "What the memory estimate misses"; tests/resources.rs checks 1.5x).

use crate::physics::case::Case;
use crate::linalg::{lu_factor_bytes, SolverKind};
use crate::models::navier::discrete::keeps_gradient_shapes;
use crate::models::navier::dynamic_estimate::richardson_applies;
use crate::models::navier::estimate::{reference_approximation, EstimateMethod};
use crate::models::navier::NavierParams;
use crate::output::{available_memory, available_memory_bytes};
use crate::models::peridynamics::{PdParams, PointSet, Quadrature};
use crate::scene::problem::{Problem, ProblemError};
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

/// How a system is solved, as far as its memory goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SolverPath {
    /// Sparse LU (faer): the equilibrated columns and the factors.
    Lu,
    /// BiCGSTAB with an incomplete factorisation.
    Bicgstab,
    /// GMRES (in process or PETSc) keeping `restart` Krylov vectors, with multigrid.
    Gmres(usize),
}

impl SolverPath {
    /// The path of the solver `kind` resolves to for `unknowns` and `nonzeros` (`auto`
    /// as `SolverKind::choose` will choose, before any fallback).
    fn chosen(kind: &SolverKind, unknowns: f64, nonzeros: f64, saddle_point: bool) -> SolverPath {
        match kind.choose(unknowns, nonzeros, saddle_point, available_memory_bytes()).primary {
            SolverKind::Bicgstab(..) => SolverPath::Bicgstab,
            SolverKind::Gmres { restart, .. } | SolverKind::Petsc { restart, .. } => SolverPath::Gmres(restart),
            _ => SolverPath::Lu,
        }
    }

    /// The path of a solve that reported `method` (`SolverKind::label`, e.g. `"lu"`
    /// after a GMRES that failed, `"bicgstab+ilu0"`, `"gmres(30)+amg [...]"`).
    pub fn of_method(method: &str) -> SolverPath {
        let restart = |m: &str| m.split_once('(').and_then(|(_, r)| r.split(')').next()?.parse().ok()).unwrap_or(crate::linalg::GMRES_RESTART);
        match method.strip_prefix("petsc:").unwrap_or(method) {
            m if m.starts_with("lu") || m.contains("mumps") => SolverPath::Lu,
            m if m.starts_with("bicgstab") => SolverPath::Bicgstab,
            m => SolverPath::Gmres(restart(m)),
        }
    }

    /// Bytes of the solve of a system of `nonzeros` entries and `unknowns` rows: the
    /// matrix and the factors or preconditioner; `low_order` the share of `nonzeros`
    /// that a multigrid built on the low-order operator holds (`None`: built on the
    /// system itself).
    fn bytes(self, unknowns: f64, nonzeros: f64, low_order: Option<f64>) -> f64 {
        match self {
            // The equilibrated matrix, which replaces the assembled one
            // (`linalg::solve_nodal`), and an ILUT of about four times its size
            // (0.74-1.3x of the measured peaks at 72 B: benches/memory_estimate.sh).
            SolverPath::Bicgstab => 84.0 * nonzeros,
            // The rows as assembled (12 B per entry), equilibrated in place and kept as the
            // multigrid's finest level, the coarse levels and single-precision transfers
            // (about 9 B per fine entry), slack, and the Krylov basis (checked at 1e6 nodes:
            // docs/notebook/round2-target-error.md, "Rows assembled in node order").
            // On the low-order operator the finest level is its own rows (12 B per
            // entry) and the levels are 12 B per entry of those.
            SolverPath::Gmres(restart) => {
                let multigrid = low_order.map_or(12.0 * nonzeros, |share| 24.0 * share * nonzeros);
                12.0 * nonzeros + multigrid + (restart as f64 + 6.0) * 8.0 * unknowns
            }
            // The rows (12 B per entry) become the equilibrated columns (16 B) and are freed;
            // then the columns and the factors.
            SolverPath::Lu => 16.0 * nonzeros + lu_factor_bytes(nonzeros, unknowns),
        }
    }
}

/// The solvers a static Navier run took, as far as its memory goes: the run's own
/// and, when its estimate solved the higher-degree reference, the reference's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticPath {
    /// The run's solve (after any fallback).
    pub run: SolverPath,
    /// The higher-degree reference's solve, when the estimate made one.
    pub reference: Option<SolverPath>,
}

/// Bytes of the solver for `nonzeros` and `unknowns`: assembly and matrix, plus
/// factors or preconditioner (`auto` resolved as the solve will resolve it, with its
/// longer GMRES on the saddle point of the displacement-pressure form).
fn solver_bytes(kind: &SolverKind, unknowns: f64, nonzeros: f64, saddle_point: bool) -> f64 {
    SolverPath::chosen(kind, unknowns, nonzeros, saddle_point).bytes(unknowns, nonzeros, None)
}

/// Process, code and small arrays: the peak of the smallest shipped runs (13-16 MB,
/// benches/memory_estimate.sh) less their arrays.
const BASE_BYTES: f64 = 12e6;

/// Bytes per bond of the linear peridynamic solid's dilatation, kept from its stage to
/// the end of the run: family index (4 B), weight and reverse weight (8 + 8 B)
/// (measured 16 B: 4.12 GB against bond-based's 3.67 GB at 1e6 nodes, m = 3).
const DILATATION_BYTES_PER_BOND: f64 = 20.0;

/// The most that the assembly holds beside its rows and shapes ([`navier`]).
const ASSEMBLY_IN_FLIGHT_BYTES: f64 = 24e6;

/// Nodes of a stencil of the low-order operator (`low_order::approximation`).
const LOW_ORDER_SUPPORT: f64 = 12.0;

/// Bytes per matrix entry of a dynamic Navier run (measured, see [`navier`]).
const DYNAMIC_BYTES_PER_NONZERO: f64 = 100.0;

/// A static or dynamic Navier run of `case` with `params` on about `nodes` nodes, as
/// it is expected to go: its solver as `auto` chooses it (no fallback), and a static
/// run's estimate as `estimate.method` asks (`auto`: the defect estimate, made with
/// the run's own solver).
pub fn navier(case: &Case, params: &NavierParams, nodes: f64) -> MemoryEstimate {
    navier_on(case, params, nodes, None)
}

/// [`navier`] for the solvers a static run took ([`StaticPath`]): the estimate of
/// the memory of the run as it went, for comparison with its measured peak.
pub fn navier_taken(case: &Case, params: &NavierParams, nodes: f64, path: StaticPath) -> MemoryEstimate {
    navier_on(case, params, nodes, Some(path))
}

/// [`navier`] and [`navier_taken`].
fn navier_on(case: &Case, params: &NavierParams, nodes: f64, taken: Option<StaticPath>) -> MemoryEstimate {
    let k = params.formulation.unknowns(&case.material).per_node() as f64;
    let dynamic = case.dynamics.is_some();
    let one = |support: usize, nodes: f64, path: Option<SolverPath>| {
        let s = support as f64;
        // Navier rows couple k unknowns of s nodes (u-p: the continuity row only 2; its
        // stabilisation's pressure Laplacian, s more, is not counted: it adds little to
        // the measured peak, which the estimate still exceeds;
        // docs/notebook/round2-pressure-stabilisation.md).
        let nonzeros = (k * k - (k - 2.0)) * nodes * s;
        // Dynamic: the triplets, the matrix, its split into dynamic and algebraic
        // blocks and the boundary block's factors, 100 B per entry (chosen from the
        // measured peaks of steel_plate_dynamic: docs/notebook/round1-explicit-dynamics-1e5.md).
        let path = path.unwrap_or_else(|| SolverPath::chosen(&params.solver.kind, k * nodes, nonzeros, k > 2.0));
        // A multigrid on the low-order operator holds its 12-node stencils' share.
        let low_order = params.multigrid.low_order(support).then(|| LOW_ORDER_SUPPORT / s);
        let solve = if dynamic { DYNAMIC_BYTES_PER_NONZERO * nonzeros } else { path.bytes(k * nodes, nonzeros, low_order) };
        // A static run releases its shapes once the rows are assembled (they and the
        // rows, 12 B per entry, are the assembly's peak), except the gradient's under
        // RBF-FD (two operators of f64); a dynamic one keeps them all.
        let shapes = nodes * s * 44.0;
        let kept = if case.outputs.needs_gradient() && keeps_gradient_shapes(&params.approximation.basis) { nodes * s * 16.0 } else { 0.0 };
        // The assembly holds the shapes, the rows (12 B per entry) and the fragments
        // of rows in flight with the threads' allocator arenas: up to about 24 MB
        // measured (mt, md, flamant, Kirsch, the dam with PHS degree 6;
        // docs/notebook/2026-11-29-memory-estimate.md).
        let assembly = shapes + 12.0 * nonzeros + (12.0 * nonzeros).min(ASSEMBLY_IN_FLIGHT_BYTES);
        (nonzeros, if dynamic { shapes + solve } else { assembly.max(solve + kept) })
    };
    let (nonzeros, mut bytes) = one(params.approximation.support, nodes, taken.map(|t| t.run));
    // The higher-degree reference runs after the run's solver is released: asked for,
    // or taken by `auto` where the defect estimate cannot be trusted.
    let reference = match taken {
        Some(t) => t.reference.map(Some),
        None => (params.estimate.method == EstimateMethod::HigherDegree).then_some(None),
    };
    if let (Some(path), false) = (reference, dynamic) {
        if let Ok(reference) = reference_approximation(&params.approximation, params.fill.kind, nodes as usize) {
            bytes = bytes.max(one(reference.support, nodes, path).1);
        }
    }
    if let Some(d) = case.dynamics.as_ref().filter(|_| params.estimate.method.dynamic_navier_estimates()) {
        // The reference runs while the run's system is held: Richardson's a quarter of
        // the nodes, the refined one four times them.
        let method = params.estimate.method;
        let richardson = method != EstimateMethod::Refined && richardson_applies(params, d.integrator).is_ok();
        bytes += one(params.approximation.support, if richardson { 0.25 } else { 4.0 } * nodes, None).1;
    }
    let driver = if params.approximation.support > 100 { "approximation.support" } else { "nodes.spacing" };
    MemoryEstimate { nodes, unknowns: k * nodes, nonzeros, bonds: None, peak_bytes: bytes + BASE_BYTES, driver }
}

/// Bytes per bond of an explicit peridynamic run's peak (the weights stage or the time
/// loop): family index (4 B), coefficient (8 B) and the weights' working copy, measured
/// 17-19 B per bond (full-area at 2e7 bonds, the Delaunay interior-3 rule at 3.8e8:
/// docs/notebook/2026-11-29-bond-pairs.md); the compatible rule's moment fits hold
/// more (35 B measured).
const DYNAMIC_BYTES_PER_BOND: f64 = 20.0;

/// [`DYNAMIC_BYTES_PER_BOND`] of the compatible rule.
const DYNAMIC_COMPATIBLE_BYTES_PER_BOND: f64 = 36.0;

/// Bytes per bond that breaking adds: the live coefficients and the broken flags
/// ([`crate::models::peridynamics::fracture::Breaking`]).
const BREAKING_BYTES_PER_BOND: f64 = 9.0;

/// Points of a Delaunay set of spacing `h` per point of the lattice rule with the
/// same triangle rule: measured 0.86 on the plate with a hole (21 930 of 25 500 at m = 6,
/// 245 592 of 283 800 at m = 10; the fill makes fewer than two triangles per `h^2`).
const DELAUNAY_DENSITY: f64 = 0.87;

/// A peridynamic run with `params` on the domain of `case`: `nodes_per_cell / h^2`
/// nodes per unit area (the rule's points in a lattice cell of side `h = delta / m`;
/// [`DELAUNAY_DENSITY`] of it on a Delaunay set), each with `pi m^2` cells' worth of
/// bonds.
pub fn peridynamics(case: &Case, params: &PdParams) -> MemoryEstimate {
    let h = params.horizon / params.ratio;
    let delaunay = if params.points == PointSet::Delaunay { DELAUNAY_DENSITY } else { 1.0 };
    let density = params.nodes_per_cell() as f64 * delaunay;
    let nodes = case.domain.area_estimate(400) / (h * h) * density;
    let per_node = std::f64::consts::PI * params.ratio * params.ratio * density;
    let bonds = nodes * per_node;
    let bond_nonzeros = 4.0 * nodes * (per_node + 1.0);
    // The solid's dilatation is applied by its product when the solver runs GMRES with
    // the multigrid, else assembled: its rows then read the nodes within 2 delta, four
    // times the bonds' entries (peridynamics::stiffness).
    let assembled = crate::models::peridynamics::stiffness::assembled_solid_nonzeros(bonds + nodes);
    let applied = params.has_dilatation() && crate::linalg::takes_addition(&params.solver, 2 * nodes as usize, assembled).is_some();
    let nonzeros = if params.has_dilatation() && !applied { assembled } else { bond_nonzeros };
    let dilatation = if params.has_dilatation() { bonds * DILATATION_BYTES_PER_BOND } else { 0.0 };
    let solve = solver_bytes(&params.solver.kind, 2.0 * nodes, nonzeros, false);
    // A static run's families (32 B per bond) and rows (12 B per entry) are the
    // assembly's peak and are released before the solve (the run at twice m of
    // pd_manufactured: 152 MB measured, 230 MB when they were counted with the
    // solver); a dynamic run keeps its families through the time loop. The
    // dilatation's stay through both.
    // An explicit run solves nothing: its peak is its bonds'.
    let run = if case.dynamics.is_some() {
        let per_bond = if params.quadrature == Quadrature::Compatible { DYNAMIC_COMPATIBLE_BYTES_PER_BOND } else { DYNAMIC_BYTES_PER_BOND };
        let breaking = if params.fracture.is_some() { BREAKING_BYTES_PER_BOND } else { 0.0 };
        bonds * (per_bond + breaking)
    } else {
        (bonds * 32.0 + 12.0 * nonzeros).max(solve)
    };
    let peak_bytes = run + dilatation + BASE_BYTES;
    MemoryEstimate { nodes, unknowns: 2.0 * nodes, nonzeros, bonds: Some(bonds), peak_bytes, driver: "peridynamics.horizon" }
}

/// The estimate for the model `p` runs.
pub fn of(p: &Problem) -> MemoryEstimate {
    match &p.model {
        crate::scene::problem::ModelParams::Peridynamics(pd) => {
            let mut e = peridynamics(&p.case, pd);
            // The local-model estimate's Navier run comes after the nonlocal one (none
            // where bonds break: such runs have no estimate).
            if p.navier.estimate.method.peridynamics_estimates() && pd.fracture.is_none() {
                let local = of(&p.local_reference()).peak_bytes;
                // The discretisation estimate: the run at twice m (four times the nodes
                // and the bonds per node): a static run's, and a dynamic one's below
                // m = 6 (from m = 6 it takes the run at m / 2).
                let ratio = if p.case.dynamics.is_none() || pd.ratio < 6.0 { 2.0 * pd.ratio } else { 0.5 * pd.ratio };
                let discretisation = peridynamics(&p.case, &PdParams { ratio, ..*pd }).peak_bytes;
                // Each runs after the other while the run's own arrays are still held
                // (measured: the explicit steel plate at delta = 0.05, 25 MB through the
                // time loop and 40 MB with the local model's run beside it).
                e.peak_bytes += local.max(discretisation) - BASE_BYTES;
            }
            e
        }
        _ => {
            navier(&p.case, &p.navier, p.expected_nodes())
        }
    }
}

/// The estimate of the static Navier run `p` on `nodes` (the check's prediction,
/// [`of`]) as it went ([`navier_taken`]): the solver it took, and the higher-degree
/// reference's when its estimate made one; `None` for another kind of run.
pub fn of_static_run(p: &Problem, solution: &crate::models::navier::Solution, nodes: f64) -> Option<MemoryEstimate> {
    if p.case.dynamics.is_some() || !matches!(p.model, crate::scene::problem::ModelParams::Navier { .. }) {
        return None;
    }
    let reference = match &solution.estimate {
        crate::models::navier::estimate::Estimate::Done(e) => e.reference_solver.as_deref().map(SolverPath::of_method),
        _ => None,
    };
    let path = StaticPath { run: SolverPath::of_method(&solution.solver.method), reference };
    Some(navier_taken(&p.case, &p.navier, nodes, path))
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
