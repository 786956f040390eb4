//! What a finished run reports as doubtful: a run never ends with a wrong answer and
//! nothing said. Each check turns one symptom into a [`Warning`] that names the
//! symptom, the number behind it and what to try; `summary.json` lists them under
//! `warnings`, the terminal prints them, and `mlsm run --strict` exits with code 4
//! when there is any.
//!
//! Static Navier checks ([`navier_static`]):
//! * the error estimate (`navier::estimate`) above `estimate.threshold` (relative
//!   e_inf of u, and of sigma when stress is computed), with the node where it is
//!   largest;
//! * no estimate possible (too few nodes, degree at the limit, reference failed);
//! * the error against the scene's exact solution above the same threshold;
//! * nu close to 1/2, where the displacement form loses accuracy (said together with
//!   the estimate);
//! * global equilibrium (`navier::equilibrium`): reactions + applied tractions + body
//!   force above the threshold, relative to the force through the boundary;
//! * the linear solve: a relative residual of the solved (row-equilibrated) system
//!   above [`RESIDUAL_LIMIT`], a
//!   condition estimate `κ₁ ε` above [`DIGITS_LIMIT`] (fewer than about 6 digits
//!   certain), unknowns that underflowed, and an iterative solver's own error above
//!   [`SOLVER_ERROR_SHARE`] of the run's error in u (`solver-error`).
//!
//! Dynamic runs ([`dynamic`]): the `richardson` or `refined` estimate over the history (Navier) above
//! the threshold, the drift of the total energy above the threshold.
//!
//! Peridynamic runs ([`peridynamics_static`], [`dynamic`]): `m < 3`; the `local-model`
//! estimate above the threshold is a note (the model difference of the horizon), and a
//! Navier reference too coarse to judge it is warned.
//!
//! Singular corners: where a clamped part (displacement on both components) meets a
//! part with a traction component, and at re-entrant corners, the exact stress of a
//! scene without a closed-form solution is unbounded, so no discretisation makes
//! e_inf(sigma) small there. The stress check then skips the nodes within
//! [`SINGULAR_RADIUS`] local spacings of such corners and says so in a note, with the
//! estimate there. Scenes with an exact solution have no singular corners (their
//! exact solutions are smooth). The reactions there are integrals of a singular
//! stress, which the boundary quadrature integrates slowly (steel plate: relative
//! imbalance 1.9e-2, 1.1e-2, 6.7e-3, 4.0e-3 at h = 0.02, 0.01, 0.005, 0.0025, about
//! `h^0.75`), so with singular corners the imbalance is a note up to
//! [`SINGULAR_EQUILIBRIUM_FACTOR`] times the threshold and a warning above.
//!
//! Submodules: [`peridynamics`] (the checks of a peridynamic run) and [`time`] (of a
//! time-dependent run: estimate, energy drift, loads against the step).

mod peridynamics;
mod time;

pub use peridynamics::{
    discretisation as pd_discretisation, near_incompressible as pd_near_incompressible, peridynamics_static, LOCAL_REFERENCE_MARGIN,
    PD_LAMBDA_OVER_MU, PD_MIN_RATIO,
};
pub use time::{dynamic, energy_drift, load_time_resolution};

use crate::domain::Point;
use crate::linalg::SolveReport;
use crate::mlsm::Basis;
use crate::models::navier::equilibrium::Equilibrium;
use crate::models::navier::formulation::AUTO_FROM_POISSON;
use crate::models::navier::{ErrorEstimate, Estimate, NavierParams, Solution};
use crate::models::resources;
use crate::physics::case::Case;
pub use crate::physics::case::{singular_corners, SingularCorner, SINGULAR_RADIUS};
use crate::physics::elasticity::dofs::Unknowns;
use crate::physics::elasticity::material::{Material, PlaneModel};
use crate::scene::problem::Problem;
use serde::Serialize;

/// Factor the estimated displacement error counts for, against the threshold and
/// against `--target-error`, where the scene has singular corners: there the
/// higher-degree reference gains no order (its stencils meet the same singularity)
/// and is about as wrong as the run: against finite elements on the L bracket and the
/// bracket the estimate of e_inf(u) was about half the true error
/// (docs/guide/estimate-and-warnings.md;
/// docs/notebook/2026-11-27-singular-corners-count-double.md).
pub const SINGULAR_ESTIMATE_FACTOR: f64 = 2.0;

/// [`SINGULAR_ESTIMATE_FACTOR`] when `corners` is not empty, else 1.
pub fn displacement_estimate_factor(corners: &[SingularCorner]) -> f64 {
    if corners.is_empty() {
        1.0
    } else {
        SINGULAR_ESTIMATE_FACTOR
    }
}

/// The note of a report whose displacement estimates count
/// [`SINGULAR_ESTIMATE_FACTOR`] times (`what`: "the estimated e_inf(u) counts", ...).
pub fn singular_estimate_note(what: &str) -> String {
    format!(
        "the scene has singular corners: {what} x{SINGULAR_ESTIMATE_FACTOR} \
         (the reference is about as wrong as the run there; docs/guide/estimate-and-warnings.md)"
    )
}

/// With singular corners, the equilibrium imbalance warns above this multiple of the
/// threshold (module docs).
pub const SINGULAR_EQUILIBRIUM_FACTOR: f64 = 10.0;

/// Relative residual `‖D b − D A x‖ / ‖D b‖` of the row-equilibrated system above
/// which a solution is doubtful. That of the unscaled system is not used: its rows
/// carry the units of their equations (Navier `~ E/h^2`, displacement `~ 1`), so it
/// reflects the largest rows only: the Kirsch plate with displacements on its outer
/// edges solved by LU to 8.8e-16 gave 0.19 there, with correct errors.
pub const RESIDUAL_LIMIT: f64 = 1e-6;

/// `κ₁ ε` above which fewer than about six digits of the solution are certain
/// (healthy shipped scenes: κ₁ from 1.2e3 to 6.0e7, `κ₁ ε` <= 1.3e-8).
pub const DIGITS_LIMIT: f64 = 1e-6;

/// Share of a run's error (estimated, or exact where the scene has one) above which
/// the iterative solver's own error ([`SolveReport::solver_error`]) is warned: at 0.1 it
/// adds at most 10 % to the error the run reports.
pub const SOLVER_ERROR_SHARE: f64 = 0.1;

/// The checks of one run: warnings (something is doubtful) and notes (something the
/// user should know to read the result).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Checks {
    /// Doubtful results, with what to try.
    pub warnings: Vec<Warning>,
    /// Remarks that do not make the run doubtful.
    pub notes: Vec<String>,
    /// Corners where the stress is singular.
    pub singular_corners: Vec<SingularCorner>,
}

/// One doubtful aspect of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Warning {
    /// Which check fired (`estimate`, `no-estimate`, `exact-error`).
    pub check: &'static str,
    /// What is doubtful, the number behind it, and what to try.
    pub message: String,
}

/// `x > threshold`, or `x` is NaN (an error that could not be measured is not small).
fn exceeds(x: f64, threshold: f64) -> bool {
    x.is_nan() || x > threshold
}

/// What to try when the error of a static Navier run is too large.
fn advice(params: &NavierParams, material: &Material) -> String {
    let p = params.approximation.basis.polynomial_degree();
    let mut s = format!("try a smaller nodes.spacing (now {:.3e}) or a higher approximation.degree (now {p})", params.fill.spacing);
    let nu = material.elastic.poisson;
    if nu >= AUTO_FROM_POISSON && material.plane == PlaneModel::Strain {
        match params.formulation.unknowns(material) {
            Unknowns::Displacement => s.push_str(&format!(
                "; nu = {nu} is near the incompressible limit, where the displacement form loses accuracy: \
                 try approximation.formulation = \"displacement-pressure\""
            )),
            Unknowns::DisplacementPressure if !matches!(params.approximation.basis, Basis::RbfFd { degree: 3.., .. }) => s.push_str(
                "; near the incompressible limit the displacement-pressure form needs basis = \"phs\" with degree >= 3 \
                 (docs/methods/incompressible.md)",
            ),
            Unknowns::DisplacementPressure => {}
        }
    }
    s
}

/// The warning `check` for the norms in `over` (none when empty): `what` above the
/// threshold, and what to try.
fn above_threshold(
    check: &'static str,
    what: &str,
    over: &[String],
    threshold: f64,
    params: &NavierParams,
    material: &Material,
) -> Option<Warning> {
    (!over.is_empty()).then(|| Warning {
        check,
        message: format!("{what} above the threshold {threshold:.0e}: {}; {}", over.join(", "), advice(params, material)),
    })
}

/// Unknowns that underflowed to subnormal numbers (the loads are tiny against the
/// moduli in these units).
fn underflow(report: &SolveReport) -> Option<Warning> {
    (report.subnormal_unknowns > 0).then(|| Warning {
        check: "underflow",
        message: format!(
            "{} unknowns are below the smallest normal double (2.2e-308) and keep fewer than 15 digits; \
             rescale the units (loads against moduli)",
            report.subnormal_unknowns
        ),
    })
}

/// Doubts about the linear solve: the residual of the solved system and the
/// condition estimate (module docs).
fn linear_solve(report: &SolveReport) -> Vec<Warning> {
    let mut out = Vec::new();
    let r = report.relative_residual;
    if exceeds(r, RESIDUAL_LIMIT) {
        out.push(Warning {
            check: "residual",
            message: format!(
                "the linear system is satisfied only to a relative residual {r:.1e} (limit {RESIDUAL_LIMIT:.0e}); try a \
                 smaller solver.tolerance or solver.kind = \"lu\""
            ),
        });
    }
    if let Some(kappa) = report.condition_estimate.filter(|k| exceeds(k * f64::EPSILON, DIGITS_LIMIT)) {
        out.push(Warning {
            check: "conditioning",
            message: format!(
                "the system's estimated condition number κ₁ ≈ {kappa:.1e} leaves about {:.0} certain digits \
                 (κ₁ ε = {:.1e}); check for nearly coincident nodes, very thin parts or boundary conditions that \
                 barely fix a rigid-body motion",
                -(kappa * f64::EPSILON).log10(),
                kappa * f64::EPSILON
            ),
        });
    }
    out.extend(underflow(report));
    out
}

/// The iterative solver's own error against the run's error in u (`accuracy`: the
/// value and which error it is) or, without one, against `threshold`: a stopped Krylov
/// iteration limits the accuracy the discretisation would give (manufactured_traction
/// with PHS degree 6 at 4.6e4 nodes: e_inf(u) 3.9e-9 at the default tolerance 1e-10,
/// 7.1e-12 at 1e-13).
fn solver_error(report: &SolveReport, accuracy: Option<(f64, &str)>, threshold: f64) -> Option<Warning> {
    let s = report.solver_error?;
    let advice = "lower solver.tolerance (or use solver.kind = \"lu\")";
    let message = match accuracy {
        Some((e, which)) if exceeds(s, SOLVER_ERROR_SHARE * e) => format!(
            "the iterative solver stopped about {s:.1e} of max |u| from the solution of its system, {:.0} % of the \
             {which} e_inf(u) {e:.1e}: the solver's tolerance limits this run's accuracy; {advice}",
            100.0 * s / e
        ),
        None if exceeds(s, SOLVER_ERROR_SHARE * threshold) => {
            format!("the iterative solver stopped about {s:.1e} of max |u| from the solution of its system; {advice}")
        }
        _ => return None,
    };
    Some(Warning { check: "solver-error", message })
}

/// The global force balance against `threshold`: a warning, or a note when singular
/// corners explain it (module docs).
fn equilibrium(q: &Equilibrium, threshold: f64, checks: &mut Checks, params: &NavierParams, material: &Material) {
    let what = format!(
        "relative imbalance {:.1e} of reactions ({:.3e}, {:.3e}), applied tractions ({:.3e}, {:.3e}) and body force ({:.3e}, {:.3e})",
        q.relative, q.reactions[0], q.reactions[1], q.applied[0], q.applied[1], q.body[0], q.body[1]
    );
    let singular = !checks.singular_corners.is_empty();
    let limit = if singular { SINGULAR_EQUILIBRIUM_FACTOR * threshold } else { threshold };
    if exceeds(q.relative, limit) {
        checks.warnings.push(Warning {
            check: "equilibrium",
            message: format!("global equilibrium is violated: {what}, above {limit:.0e}; {}", advice(params, material)),
        });
    } else if singular && q.relative > threshold {
        checks.notes.push(format!(
            "{what}: the reactions at the singular corners converge slowly (docs/guide/estimate-and-warnings.md); below the warning level {limit:.0e}"
        ));
    }
}

/// The note that names the re-entrant corners and holes with traction edges that got
/// no sector balance, grouped by the reason; `None` when there are none.
pub fn unbalanced_note(unbalanced: &[crate::models::navier::sector::Unbalanced]) -> Option<String> {
    if unbalanced.is_empty() {
        return None;
    }
    let mut by_reason: std::collections::BTreeMap<&str, Vec<String>> = std::collections::BTreeMap::new();
    for u in unbalanced {
        let what = match u.around {
            crate::models::navier::sector::Around::Corner => "the re-entrant corner at",
            crate::models::navier::sector::Around::Hole => "the hole around",
        };
        by_reason.entry(&u.reason).or_default().push(format!("{what} ({:.4e}, {:.4e})", u.at[0], u.at[1]));
    }
    let list: Vec<String> = by_reason.into_iter().map(|(why, places)| format!("{} ({why})", places.join(", "))).collect();
    Some(format!(
        "not balanced: {}; the solution may carry a spurious load there, which only the error estimate shows (docs/limits.md, re-entrant corners)",
        list.join("; ")
    ))
}

/// The checks of a static Navier run (module docs).
pub fn navier_static(sol: &Solution, params: &NavierParams, case: &Case) -> Checks {
    let threshold = params.estimate.threshold;
    let material = &case.material;
    let mut checks = Checks { singular_corners: singular_corners(case, &sol.nodes), ..Checks::default() };
    let near_singular = |p: Point| checks.singular_corners.iter().any(|c| c.covers(p));
    match &sol.estimate {
        Estimate::Done(e) => {
            let mut over = Vec::new();
            let factor = displacement_estimate_factor(&checks.singular_corners);
            if exceeds(factor * e.norms.e_inf_u, threshold) {
                let counted = if factor == 1.0 {
                    String::new()
                } else {
                    format!(
                        ", counted as {:.1e} (x{factor}: at the singular corners the reference is about as wrong as the run)",
                        factor * e.norms.e_inf_u
                    )
                };
                over.push(format!(
                    "e_inf(u) ~ {:.1e}{counted} (largest at ({:.4e}, {:.4e}))",
                    e.norms.e_inf_u, e.largest_u_at[0], e.largest_u_at[1]
                ));
            }
            if let (Some(all), Some(per_node)) = (e.norms.e_inf_sigma, &e.per_node_sigma) {
                // Largest stress indicator away from singular corners.
                let away = (0..per_node.len())
                    .filter(|&i| !near_singular(sol.nodes.positions[i]))
                    .max_by(|&i, &j| per_node[i].total_cmp(&per_node[j]));
                if !checks.singular_corners.is_empty() {
                    let list: Vec<String> =
                        checks.singular_corners.iter().map(|c| format!("({:.4e}, {:.4e}) {}", c.at[0], c.at[1], c.reason)).collect();
                    checks.notes.push(format!(
                        "the stress is singular at {} corner(s): {}; the peak stress there is not a converged quantity (estimated e_inf(sigma) ~ {all:.1e} with them); the stress check skips {SINGULAR_RADIUS} local spacings around them",
                        list.len(),
                        list.join(", ")
                    ));
                }
                if let Some(i) = away.filter(|&i| exceeds(per_node[i], threshold)) {
                    let at = sol.nodes.positions[i];
                    over.push(format!("e_inf(sigma) ~ {:.1e} (largest at ({:.4e}, {:.4e}))", per_node[i], at[0], at[1]));
                }
            }
            checks.warnings.extend(above_threshold("estimate", "estimated error", &over, threshold, params, material));
        }
        Estimate::Unavailable(_, why) => checks
            .warnings
            .push(Warning { check: "no-estimate", message: format!("no error estimate: {why}; the accuracy of this run is unknown") }),
        Estimate::Off => checks.notes.push("no error estimate (estimate.method = \"none\")".into()),
    }
    match &sol.equilibrium {
        Some(q) => equilibrium(q, threshold, &mut checks, params, material),
        None => checks.notes.push("no equilibrium check: the scene computes no stress (output.fields)".into()),
    }
    checks.warnings.extend(linear_solve(&sol.solver));
    let accuracy = match (&sol.errors, &sol.estimate) {
        (Some(e), _) => Some((e.e_inf_u, "exact")),
        (None, Estimate::Done(e)) => Some((e.norms.e_inf_u, "estimated")),
        _ => None,
    };
    checks.warnings.extend(solver_error(&sol.solver, accuracy, threshold));
    checks.notes.extend(unbalanced_note(&sol.unbalanced));
    if let Some(e) = &sol.errors {
        let mut over = Vec::new();
        if exceeds(e.e_inf_u, threshold) {
            over.push(format!("e_inf(u) = {:.2e}", e.e_inf_u));
        }
        if let Some(s) = e.e_inf_sigma.filter(|s| exceeds(*s, threshold)) {
            over.push(format!("e_inf(sigma) = {s:.2e}"));
        }
        checks.warnings.extend(above_threshold("exact-error", "error against the exact solution", &over, threshold, params, material));
    }
    checks
}

/// The estimate if it was computed; otherwise a `no-estimate` warning (unavailable) or a
/// note (switched off) is added to `checks`.
fn unestimated<'a>(estimate: &'a Estimate, checks: &mut Checks) -> Option<&'a ErrorEstimate> {
    match estimate {
        Estimate::Done(e) => Some(e),
        Estimate::Unavailable(method, why) => {
            checks.warnings.push(Warning {
                check: "no-estimate",
                message: format!("no error estimate ({method}): {why}; the accuracy of this run is unknown"),
            });
            None
        }
        Estimate::Off => {
            checks.notes.push("no error estimate (estimate.method = \"none\")".into());
            None
        }
    }
}

/// A run whose memory estimate exceeds half the available memory (`resources`).
pub fn memory(p: &Problem) -> Option<Warning> {
    let e = resources::of(p);
    resources::above_half(&e).map(|available| Warning {
        check: "memory",
        message: format!(
            "the run was estimated at {} ({}), more than half of the {} available; \
             a larger problem would not fit (see {})",
            resources::gigabytes(e.peak_bytes),
            resources::describe(&e),
            resources::gigabytes(available),
            e.driver
        ),
    })
}
