//! A posteriori error estimate of a static Navier run, with or without an exact
//! solution: the same case is solved again on the **same nodes** with a basis two
//! polynomial degrees higher (RBF-FD, PHS `r^3` plus monomials of total degree
//! `p + 2`, its default stencil), and the difference is taken as the error of the run:
//!
//! ```text
//! est e_inf(u)     = max_{i,c} |u_h - u_ref| / max_{i,c} |u_ref|
//! est rel_l2(u)    = sqrt(sum |u_h - u_ref|^2 / sum |u_ref|^2)
//! ```
//!
//! and the same for the stress components. When the reference is much more accurate
//! than the run (`e_ref << e_h`, the normal case in the asymptotic range: two degrees
//! buy about two orders of `h`), the estimate equals the true error to within
//! `e_ref / e_h`. Measured effectivities (estimate / true error) on the shipped scenes
//! and the near-incompressible Lame ring: docs/verification.md, "The error estimate:
//! measured effectivities".
//!
//! Why this estimator: a residual or recovery indicator of a collocation scheme is not
//! a bound on the error (a residual of 1e-12 proves nothing), and Richardson
//! extrapolation on scattered nodes needs a second, unrelated node set and an
//! interpolation between them. The higher-degree solve reuses the nodes, needs no
//! assumption on the order, and its per-node difference points at where the error is.
//!
//! Per node, the indicator is `max_c |u_h - u_ref|_i / max |u_ref|` (and the same for
//! the stress): written to `solution.vtu` as `estimated_error` (and
//! `estimated_error_stress`).

use crate::domain::{FillKind, Point};
use crate::mlsm::{default_rbf_fd_support, Approximation, Basis, Radial, Weight};
use crate::physics::elasticity::stress::StressField;
use crate::quality::post::{ErrorNorms, ExactFields};
use crate::scene::choice::{choice, Choice};
use crate::stages::{RunError, Stage, StageTimer};
use serde::Serialize;
use std::time::Instant;

/// The estimate's stage in the timings.
pub const ESTIMATE: Stage = Stage::new("estimate");

/// Highest polynomial degree a reference is built with (the scene's degree limit).
pub const MAX_REFERENCE_DEGREE: u32 = 8;

choice! {
    /// How a static Navier run estimates its error (`estimate.method`).
    pub enum EstimateMethod("estimate.method", default Some(EstimateMethod::Auto), serde "kebab-case") {
        /// `defect` for a static Navier run (`higher-degree` where it cannot be trusted), `richardson` (else `refined`) for a dynamic one, `local-model` for a peridynamic one.
        Auto = "auto" => "defect for a static Navier run, and higher-degree where the defect estimate is unavailable, reaches the warning threshold (or 1e-2) or the scene has singular corners; richardson for a dynamic run (refined where it does not apply), local-model for a peridynamic run",
        /// Difference to a solution two degrees higher on the same nodes.
        HigherDegree = "higher-degree" => "static Navier runs: difference to the solution with RBF-FD (PHS r^3 + monomials of degree p + 2) on the same nodes, solved afresh; the certificate, 0.5-3x the cost of the run (BENCHMARKS.md, \"What the error estimate costs\")",
        /// The run's truncation error on local fits of its solution, mapped by its own operator.
        Defect = "defect" => "static Navier runs: the run's truncation error measured on local fits of degree p + 2 of its own solution, mapped to an error by one loose solve with the run's own factors or preconditioner (no second discretisation or solver)",
        /// Richardson's extrapolation from a run at twice the spacing and a longer step.
        Richardson = "richardson" => "dynamic Navier runs of basis degree <= 2 and verlet or rk4: (u - u_2h) / sqrt 3, u_2h the run on nodes at twice the spacing with the time step doubled (x sqrt 2 for rk4); 1/8 of the run's nodes x steps (0.18 with rk4)",
        /// Difference to a run on nodes at half the spacing with a finer time step.
        Refined = "refined" => "dynamic Navier runs: difference to the run on nodes at half the spacing with the time step halved (quartered for emu); 8x the nodes x steps of the run (16x with emu): 3-4x its time on the shipped scenes, 6x at 1.2e4 nodes",
        /// Difference to the local (Navier) model's solution of the same scene.
        LocalModel = "local-model" => "peridynamic runs: difference to the Navier model's solution of the same scene on its [nodes] (with its own estimate when static), interpolated to the peridynamic nodes by moving least squares; the peridynamic error as the exact-solution errors measure it, against the local model",
        /// No estimate.
        None = "none" => "no estimate (saves the second solve); the run is then reported as unestimated",
    }
}

/// Default `estimate.threshold`: a run whose estimated relative error exceeds it is
/// warned.
pub const DEFAULT_THRESHOLD: f64 = 1e-2;

/// `[estimate]` of a scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EstimateParams {
    /// Estimator.
    pub method: EstimateMethod,
    /// Relative e_inf (of u, and of sigma when computed) above which the run is warned.
    pub threshold: f64,
}

impl Default for EstimateParams {
    fn default() -> Self {
        EstimateParams { method: EstimateMethod::Auto, threshold: DEFAULT_THRESHOLD }
    }
}

impl EstimateMethod {
    /// Whether a static Navier run estimates its error (`auto`, `higher-degree` or `defect`).
    pub fn static_navier_estimates(self) -> bool {
        matches!(self, EstimateMethod::Auto | EstimateMethod::HigherDegree | EstimateMethod::Defect)
    }

    /// Whether a static Navier run makes the `defect` estimate in its own stages
    /// (`defect`, and `auto`, which takes it where it can be trusted:
    /// [`super::run::solve`]).
    pub fn makes_defect(self) -> bool {
        matches!(self, EstimateMethod::Auto | EstimateMethod::Defect)
    }

    /// Whether a dynamic Navier run estimates its error (`auto`, `richardson` or `refined`).
    pub fn dynamic_navier_estimates(self) -> bool {
        matches!(self, EstimateMethod::Auto | EstimateMethod::Richardson | EstimateMethod::Refined)
    }

    /// Whether a peridynamic run estimates its error (`auto` or `local-model`).
    pub fn peridynamics_estimates(self) -> bool {
        matches!(self, EstimateMethod::Auto | EstimateMethod::LocalModel)
    }
}

/// Estimated errors of one run, and where they are largest.
#[derive(Debug, Clone, Serialize)]
pub struct ErrorEstimate {
    /// `"higher-degree"` or `"local-model"`.
    pub method: &'static str,
    /// The reference: its basis and stencil (and time step, model).
    pub reference: String,
    /// The reference's polynomial degree.
    pub reference_degree: u32,
    /// The reference's own estimated e_inf(u), where it has one (`local-model` of a
    /// static run): the estimate holds while this is well below it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_estimated_e_inf_u: Option<f64>,
    /// Estimated norms (same definitions as the errors against an exact solution).
    #[serde(flatten)]
    pub norms: ErrorNorms,
    /// Node where the displacement indicator is largest.
    pub largest_u_at: Point,
    /// Time at which it is largest (a dynamic run's estimate over its history).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub largest_u_time: Option<f64>,
    /// Node where the stress indicator is largest (when stress is computed).
    pub largest_sigma_at: Option<Point>,
    /// Wall-clock seconds of the reference (nodes reused; supports, shapes, assembly,
    /// solve, gradients).
    pub seconds: f64,
    /// Unknowns and matrix nonzeros of the reference system.
    pub reference_unknowns: usize,
    /// Nonzeros of the reference matrix.
    pub reference_nonzeros: usize,
    /// The solver that solved the reference system (`higher-degree`: e.g. `"lu"`
    /// after a failed GMRES), for the memory the run took (`resources::navier_taken`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_solver: Option<String>,
    /// Per-node displacement indicator `max_c |u_h - u_ref| / max |u_ref|`.
    #[serde(skip)]
    pub per_node_u: Vec<f64>,
    /// Per-node stress indicator, when stress is computed.
    #[serde(skip)]
    pub per_node_sigma: Option<Vec<f64>>,
}

/// Outcome of the estimate stage.
#[derive(Debug, Clone)]
pub enum Estimate {
    /// The estimate was computed.
    Done(Box<ErrorEstimate>),
    /// `estimate.method = "none"`.
    Off,
    /// No estimate could be computed by the method (its name), and why.
    Unavailable(&'static str, String),
}

/// `summary.json`: the estimate's object, `{"method": ..., "unavailable": reason}`,
/// or `null` when off.
impl Serialize for Estimate {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Unavailable<'a> {
            method: &'static str,
            unavailable: &'a str,
        }
        match self {
            Estimate::Done(e) => e.serialize(s),
            Estimate::Off => s.serialize_none(),
            Estimate::Unavailable(method, why) => Unavailable { method, unavailable: why }.serialize(s),
        }
    }
}

impl Estimate {
    /// One line for the stage's timing: the estimated e_inf of u (and sigma), or why
    /// there is none.
    pub fn note(&self) -> String {
        match self {
            Estimate::Done(e) => match e.norms.e_inf_sigma {
                Some(s) => format!("e_inf(u) ~ {:.1e}, e_inf(sigma) ~ {s:.1e}", e.norms.e_inf_u),
                None => format!("e_inf(u) ~ {:.1e}", e.norms.e_inf_u),
            },
            Estimate::Unavailable(_, why) => format!("unavailable: {why}"),
            Estimate::Off => "off".into(),
        }
    }

    /// The estimate, if computed.
    pub fn done(&self) -> Option<&ErrorEstimate> {
        match self {
            Estimate::Done(e) => Some(e),
            _ => None,
        }
    }
}

/// The estimate stage of a Navier run: `compute` timed as [`ESTIMATE`] when
/// `estimates` (the method fits the run), `Off` for `none`, and unavailable for a
/// method that estimates another kind of run (refused by the validation before).
pub fn stage(
    method: EstimateMethod,
    estimates: bool,
    timer: &mut StageTimer,
    compute: impl FnOnce() -> Estimate,
) -> Result<Estimate, RunError> {
    match method {
        EstimateMethod::None => Ok(Estimate::Off),
        _ if estimates => timer.run(ESTIMATE, || {
            let e = compute();
            let note = e.note();
            Ok((e, note))
        }),
        other => Ok(Estimate::Unavailable(other.name(), "the method estimates another kind of run (estimate.method)".into())),
    }
}

/// The approximation of the reference solve for a run with `run` on `nodes` nodes, or
/// why there is none: PHS `r^3` with degree `p + 2` (or `p + 1` when the node set is
/// too small for `p + 2`), its default stencil capped at the node count.
pub fn reference_approximation(run: &Approximation, fill: FillKind, nodes: usize) -> Result<Approximation, String> {
    let p = run.basis.polynomial_degree();
    for degree in [p + 2, p + 1] {
        if degree > MAX_REFERENCE_DEGREE {
            continue;
        }
        let basis = Basis::RbfFd { radial: Radial::Phs { order: 3 }, degree };
        let m = basis.size();
        let support = default_rbf_fd_support(m, fill).min(nodes);
        // Fewer than 1.5 m nodes leave an RBF-FD stencil too close to a polynomial
        // interpolation to be more accurate than the run.
        if 2 * support >= 3 * m {
            return Ok(Approximation { basis, weight: Weight::None, support, ghost_nodes: run.ghost_nodes });
        }
    }
    if p + 1 > MAX_REFERENCE_DEGREE {
        Err(format!("the run's degree {p} leaves no higher degree for a reference (at most {MAX_REFERENCE_DEGREE})"))
    } else {
        Err(format!(
            "{nodes} nodes are too few for a reference of degree {} (needs at least {})",
            p + 1,
            3 * Basis::RbfFd { radial: Radial::Phs { order: 3 }, degree: p + 1 }.size() / 2
        ))
    }
}

/// `"8 states from t = .. to .. s"`, for an estimate's reference text.
pub fn compared_states(history: &[(f64, Vec<[f64; 2]>)]) -> String {
    match (history.first(), history.last()) {
        (Some(a), Some(b)) => format!("{} states from t = {:.4e} to {:.4e} s", history.len(), a.0, b.0),
        _ => "no state".into(),
    }
}

impl ErrorEstimate {
    /// The estimate of a dynamic run's `history` against the `reference` states at the
    /// same times (same order, already on the run's `positions`): the space-time norms
    /// of the differences over all the states together, the time of the largest, and
    /// each node's largest difference as its indicator. The reference's degree,
    /// unknowns and nonzeros are left 0.
    pub fn over_history(
        method: EstimateMethod,
        reference_description: String,
        positions: &[Point],
        history: &[(f64, Vec<[f64; 2]>)],
        reference: Vec<Vec<[f64; 2]>>,
        t0: Instant,
    ) -> ErrorEstimate {
        debug_assert_eq!(history.len(), reference.len(), "a reference state per state of the run");
        let u_ref: Vec<[f64; 2]> = reference.into_iter().flatten().collect();
        let u: Vec<[f64; 2]> = history.iter().flat_map(|(_, u)| u.iter().copied()).collect();
        let at: Vec<Point> = history.iter().flat_map(|_| positions.iter().copied()).collect();
        let reference = ExactFields { displacement: u_ref, stress: None };
        let mut e = ErrorEstimate::between(method, reference_description, &at, &u, None, &reference, t0);
        let n = positions.len();
        e.largest_u_time = Some(history[argmax(&e.per_node_u) / n].0);
        e.per_node_u = (0..n).map(|i| e.per_node_u.iter().skip(i).step_by(n).fold(0.0, |m: f64, &v| m.max(v))).collect();
        e
    }

    /// The estimate of the run `(displacement, stress)` at `positions` by its
    /// difference to `reference` at the same points, computed by `method` since `t0`
    /// (the reference's degree, unknowns and nonzeros left 0 for the caller).
    pub fn between(
        method: EstimateMethod,
        reference_description: String,
        positions: &[Point],
        displacement: &[[f64; 2]],
        stress: Option<&StressField>,
        reference: &ExactFields,
        t0: Instant,
    ) -> ErrorEstimate {
        let norms = ErrorNorms::against(displacement, stress, reference);
        let per_node_u = per_node(displacement, &reference.displacement);
        let per_node_sigma = stress.zip(reference.stress.as_ref()).map(|(s, r)| per_node(&s.sigma, r));
        let largest = |v: &[f64]| positions[argmax(v)];
        ErrorEstimate {
            method: method.name(),
            reference: reference_description,
            reference_degree: 0,
            reference_estimated_e_inf_u: None,
            norms,
            largest_u_at: largest(&per_node_u),
            largest_u_time: None,
            largest_sigma_at: per_node_sigma.as_deref().map(largest),
            seconds: t0.elapsed().as_secs_f64(),
            reference_unknowns: 0,
            reference_nonzeros: 0,
            reference_solver: None,
            per_node_u,
            per_node_sigma,
        }
    }
}

/// `max_c |a_i - b_i| / max_{j,c} |b_j|` at every node.
fn per_node<const K: usize>(a: &[[f64; K]], b: &[[f64; K]]) -> Vec<f64> {
    let scale = b.iter().flat_map(|v| v.iter()).fold(0.0f64, |m, x| m.max(x.abs()));
    let scale = if scale > 0.0 { scale } else { 1.0 };
    a.iter().zip(b).map(|(x, y)| (0..K).map(|c| (x[c] - y[c]).abs()).fold(0.0, f64::max) / scale).collect()
}

/// Index of the largest entry (NaN counts as largest).
fn argmax(v: &[f64]) -> usize {
    (0..v.len()).max_by(|&i, &j| v[i].abs().total_cmp(&v[j].abs())).unwrap_or(0)
}
