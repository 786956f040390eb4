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
//! * the linear solve: a residual of the unscaled system above [`RESIDUAL_LIMIT`], a
//!   condition estimate `κ₁ ε` above [`DIGITS_LIMIT`] (fewer than about 6 digits
//!   certain), and unknowns that underflowed.
//!
//! Dynamic runs ([`dynamic`]): the `refined` estimate at the end time (Navier) above
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

use crate::case::Case;
use crate::choice::Choice;
use crate::domain::corner::corners;
use crate::domain::{NodeSet, Point};
use crate::dynamics::driver::EnergyRow;
use crate::dynamics::integrators::Integrator;
use crate::elasticity::conditions::ComponentCondition;
use crate::elasticity::conditions::Value;
use crate::elasticity::dofs::Unknowns;
use crate::elasticity::material::{Material, PlaneModel};
use crate::linalg::SolveReport;
use crate::mlsm::Basis;
use crate::navier::equilibrium::Equilibrium;
use crate::navier::formulation::AUTO_FROM_POISSON;
use crate::navier::{ErrorEstimate, Estimate, NavierParams, Solution};
use crate::peridynamics::PdSolution;
use crate::problem::Problem;
use crate::resources;
use rayon::prelude::*;
use serde::Serialize;

/// Radius of the neighbourhood of a singular corner that the stress check skips, in
/// local node spacings (on the steel plate, h = 0.01, the estimated stress error falls
/// from 0.36 at the clamped corners to 2.2e-3 at ten spacings).
pub const SINGULAR_RADIUS: f64 = 10.0;

/// With singular corners, the equilibrium imbalance warns above this multiple of the
/// threshold (module docs).
pub const SINGULAR_EQUILIBRIUM_FACTOR: f64 = 10.0;

/// Relative residual of the unscaled system above which a solution is doubtful
/// (healthy shipped scenes: 3e-14 to 7e-9 with LU and equilibration).
pub const RESIDUAL_LIMIT: f64 = 1e-6;

/// `κ₁ ε` above which fewer than about six digits of the solution are certain
/// (healthy shipped scenes: κ₁ from 1.2e3 to 6.0e7, `κ₁ ε` <= 1.3e-8).
pub const DIGITS_LIMIT: f64 = 1e-6;

/// A corner where the stress is singular.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SingularCorner {
    /// Position.
    pub at: Point,
    /// Why: `re-entrant` or `clamped meets traction`.
    pub reason: &'static str,
    /// Radius skipped by the stress check.
    pub radius: f64,
}

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

/// The singular corners of `case` on `nodes` (module docs).
pub fn singular_corners(case: &Case, nodes: &NodeSet) -> Vec<SingularCorner> {
    if case.exact.is_some() {
        return Vec::new();
    }
    let clamped = |part: usize| case.conditions[part].components.iter().all(|c| *c == ComponentCondition::Displacement);
    let traction = |part: usize| case.conditions[part].components.contains(&ComponentCondition::Traction);
    corners(&case.domain, nodes)
        .into_iter()
        .filter_map(|c| {
            let [a, b] = c.parts;
            let reason = if c.reentrant {
                "re-entrant"
            } else if (clamped(a) && traction(b)) || (clamped(b) && traction(a)) {
                "clamped meets traction"
            } else {
                return None;
            };
            Some(SingularCorner { at: c.position, reason, radius: SINGULAR_RADIUS * nodes.local_spacing[c.node] })
        })
        .collect()
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
                 (README, \"Near-incompressible solids\")",
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

/// Doubts about the linear solve: the residual of the unscaled system and the
/// condition estimate (module docs).
fn linear_solve(report: &SolveReport) -> Vec<Warning> {
    let mut out = Vec::new();
    let r = report.original_relative_residual;
    if exceeds(r, RESIDUAL_LIMIT) {
        out.push(Warning {
            check: "residual",
            message: format!(
                "the unscaled system is satisfied only to a relative residual {r:.1e} (limit {RESIDUAL_LIMIT:.0e}; the \
                 equilibrated one to {:.1e}); try solver.kind = \"lu\" or a smaller solver.tolerance",
                report.relative_residual
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
            "{what}: the reactions at the singular corners converge slowly (README, \"Error estimate and warnings\"); below the warning level {limit:.0e}"
        ));
    }
}

/// The checks of a static Navier run (module docs).
pub fn navier_static(sol: &Solution, params: &NavierParams, case: &Case) -> Checks {
    let threshold = params.estimate.threshold;
    let material = &case.material;
    let mut checks = Checks { singular_corners: singular_corners(case, &sol.nodes), ..Checks::default() };
    let near_singular = |p: Point| checks.singular_corners.iter().any(|c| (p[0] - c.at[0]).hypot(p[1] - c.at[1]) <= c.radius);
    match &sol.estimate {
        Estimate::Done(e) => {
            let mut over = Vec::new();
            if exceeds(e.norms.e_inf_u, threshold) {
                over.push(format!(
                    "e_inf(u) ~ {:.1e} (largest at ({:.4e}, {:.4e}))",
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

/// Horizon-to-spacing ratio `m = delta / h` below which the bond-based quadrature
/// is too coarse to approximate the nonlocal integral (README, "Peridynamics at
/// m < 3": the error no longer falls with the horizon).
pub const PD_MIN_RATIO: f64 = 3.0;

/// The checks of a static peridynamic run: `m < 3` is warned (a discretisation that
/// cannot approximate the nonlocal integral), and the `local-model` estimate is read by
/// [`estimate_of_peridynamics`]. The difference to an exact *local* solution is a
/// note, not a warning: at `m >= 3` it is mostly the model difference of the finite
/// horizon, which the user chose.
pub fn peridynamics_static(sol: &PdSolution, estimate: &Estimate, threshold: f64) -> Checks {
    let mut checks = Checks { warnings: linear_solve(&sol.solver), ..Checks::default() };
    let m = sol.params.ratio;
    if m < PD_MIN_RATIO {
        checks.warnings.push(Warning {
            check: "pd-horizon-ratio",
            message: format!(
                "peridynamics.m = {m} is below {PD_MIN_RATIO}: a horizon spans too few nodes for the bond quadrature, \
                 and errors of order 0.1 to 0.5 are to be expected whatever the horizon (README, \"Peridynamics at m < 3\"); \
                 use m >= 3"
            ),
        });
    }
    if let Some(e) = sol.errors.map(|e| e.0).filter(|e| exceeds(e.e_inf_u, threshold)) {
        checks.notes.push(format!(
            "the nonlocal solution differs from the exact local one by e_inf(u) = {:.2e} (above {threshold:.0e}); \
             at m >= 3 this is mostly the model difference of the horizon {:.3e}, which shrinks with it",
            e.e_inf_u, sol.params.horizon
        ));
    }
    // With an exact solution, its note above says what the estimate's would.
    estimate_of_peridynamics(estimate, threshold, sol.params.horizon, sol.errors.is_none(), &mut checks);
    checks
}

/// How much closer to the local solution than the peridynamic run the Navier reference
/// of a `local-model` estimate must be (by its own estimate) for the estimate to be
/// trusted: its own estimate misses the interpolation to the peridynamic nodes and may
/// itself be low on coarse nodes (pd_manufactured, Navier spacing 0.1, delta = 0.05:
/// own estimate 3.8e-4, estimate 1.9e-3 against a true 9.3e-4; a margin of 3 let it
/// pass).
pub const LOCAL_REFERENCE_MARGIN: f64 = 10.0;

/// The checks of a peridynamic run's `local-model` estimate: above `threshold` a note
/// when `note_above` (the model difference of the horizon, like the exact error); a Navier reference
/// whose own estimated error is not [`LOCAL_REFERENCE_MARGIN`] times below the
/// estimate is warned (`estimate-reference`); no estimate is warned (`no-estimate`).
fn estimate_of_peridynamics(estimate: &Estimate, threshold: f64, horizon: f64, note_above: bool, checks: &mut Checks) {
    let Some(e) = unestimated(estimate, checks) else { return };
    let est = e.norms.e_inf_u;
    if note_above && exceeds(est, threshold) {
        checks.notes.push(format!(
            "the nonlocal solution is estimated to differ from the local model by e_inf(u) ~ {est:.1e} (above {threshold:.0e}, \
             largest at ({:.4e}, {:.4e})); at m >= 3 this is mostly the model difference of the horizon {horizon:.3e}, which shrinks with it",
            e.largest_u_at[0], e.largest_u_at[1]
        ));
    }
    if let Some(own) = e.reference_estimated_e_inf_u.filter(|own| exceeds(own * LOCAL_REFERENCE_MARGIN, est)) {
        checks.warnings.push(Warning {
            check: "estimate-reference",
            message: format!(
                "the local-model estimate e_inf(u) ~ {est:.1e} is uncertain: the Navier reference's own estimated error is {own:.1e}, \
                 not {LOCAL_REFERENCE_MARGIN} times smaller; refine the Navier nodes (nodes.spacing) for a better reference"
            ),
        });
    }
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

/// The largest change of the total energy (kinetic + elastic + external) over the
/// history, relative to the largest sum of the magnitudes of its three parts: the
/// integrators conserve it up to their time-discretisation error (there is no
/// damping, and the external part is the potential of the loads).
pub fn energy_drift(energies: &[EnergyRow]) -> f64 {
    let total = |e: &EnergyRow| e[1] + e[2] + e[3];
    let Some(first) = energies.first() else { return 0.0 };
    let scale = energies.iter().map(|e| e[1].abs() + e[2].abs() + e[3].abs()).fold(0.0, f64::max);
    let change = energies.iter().map(|e| (total(e) - total(first)).abs()).fold(0.0, f64::max);
    if scale > 0.0 {
        change / scale
    } else {
        0.0
    }
}

/// The checks of a time-dependent run: the estimate at `end_time` (a Navier run's
/// `higher-degree` estimate above `threshold` is warned; a peridynamic run's
/// `local-model` one, with its `horizon`, is read by [`estimate_of_peridynamics`]),
/// and the energy drift ([`energy_drift`]) above `threshold` is warned, unless
/// `loads_vary` (loads that depend on time do work, so the total is not conserved: a
/// note says the check was not made).
pub fn dynamic(energies: &[EnergyRow], threshold: f64, loads_vary: bool, estimate: &Estimate, horizon: Option<f64>) -> Checks {
    let mut checks = Checks::default();
    match horizon {
        Some(horizon) => estimate_of_peridynamics(estimate, threshold, horizon, true, &mut checks),
        None => {
            if let Some(e) = unestimated(estimate, &mut checks).filter(|e| exceeds(e.norms.e_inf_u, threshold)) {
                checks.warnings.push(Warning {
                    check: "estimate",
                    message: format!(
                        "estimated error at the end time above the threshold {threshold:.0e}: e_inf(u) ~ {:.1e} (largest at \
                         ({:.4e}, {:.4e}); space and time, against {}); try a smaller nodes.spacing, a higher \
                         approximation.degree or a smaller dynamics.time_step",
                        e.norms.e_inf_u, e.largest_u_at[0], e.largest_u_at[1], e.reference
                    ),
                });
            }
        }
    }
    if loads_vary {
        checks.notes.push(
            "no energy check (only load-time-resolution): the loads depend on t, so their work changes the total energy \
             (energies.csv; its external part is -b(t).u)"
                .into(),
        );
        return checks;
    }
    let drift = energy_drift(energies);
    if exceeds(drift, threshold) {
        checks.warnings.push(Warning {
            check: "energy-drift",
            message: format!(
                "the total energy changed by up to {drift:.1e} of its scale over the run (threshold {threshold:.0e}): \
                 the time integration is inaccurate; try dynamics.integrator = \"rk4\" or a smaller dynamics.time_step"
            ),
        });
    }
    checks.notes.push(format!("the total energy is conserved to {drift:.1e} (energies.csv)"));
    checks
}

/// Instants at which [`load_time_resolution`] samples the loads over the run.
const LOAD_SAMPLE_TIMES: usize = 2000;

/// Boundary samples per part at most at which [`load_time_resolution`] reads a load
/// (every k-th sample of the run's spacing beyond that).
const LOAD_SAMPLE_POINTS: usize = 2000;

/// Where [`load_time_resolution`] reads each load: the boundary sampled at the run's
/// `spacing` (a boundary value on the samples of its part, where it acts; the body
/// force on all of them), and a 5 x 5 lattice over the bounding box for the body force
/// inside. A narrow load (a spot, a moving front) acts between the lattice's points,
/// where its value may underflow to zero, but never between the nodes that carry it.
struct LoadPoints {
    lattice: Vec<Point>,
    /// Boundary samples of each part (strided to [`LOAD_SAMPLE_POINTS`]).
    parts: Vec<Vec<Point>>,
}

impl LoadPoints {
    fn new(case: &Case, spacing: f64) -> Self {
        let (lo, hi) = case.domain.bounding_box();
        let lattice =
            (0..25).map(|k| [lo[0] + (hi[0] - lo[0]) * (k % 5) as f64 / 4.0, lo[1] + (hi[1] - lo[1]) * (k / 5) as f64 / 4.0]).collect();
        let samples = crate::domain::boundary::discretise_boundary(&case.domain, spacing);
        let parts = (0..case.conditions.len())
            .map(|part| {
                let on: Vec<Point> = samples.iter().filter(|s| s.touches.iter().any(|(p, _)| *p == part)).map(|s| s.position).collect();
                let stride = on.len().div_ceil(LOAD_SAMPLE_POINTS).max(1);
                on.into_iter().step_by(stride).collect()
            })
            .collect();
        LoadPoints { lattice, parts }
    }

    /// The points of the body force: the lattice and every part's samples.
    fn body(&self) -> Vec<Point> {
        self.lattice.iter().chain(self.parts.iter().flatten()).copied().collect()
    }
}

/// The time scale of one load formula in `t`: `tau = max |g| / max |dg/dt|` over the
/// sampled `times` and `points` (both maxima over the components; `1 / omega` for
/// `g = A sin(omega t)`, `T / pi` for the pulse `A sin(pi t / T)^2`). `None` for a load
/// that does not vary in time or that is zero or non-finite at every sample.
fn time_scale(value: &Value, points: &[Point], times: &[f64]) -> Option<f64> {
    if !value.depends_on_time() {
        return None;
    }
    let rate = value.time_derivative().ok()?;
    let largest = |v: &Value, t: f64| {
        let at = v.at_time(t);
        points.iter().filter_map(|&p| at.explicit_at(p)).flatten().filter(|x| x.is_finite()).fold(0.0f64, |m, x| m.max(x.abs()))
    };
    let (g, r) =
        times.par_iter().map(|&t| (largest(value, t), largest(&rate, t))).reduce(|| (0.0f64, 0.0f64), |a, b| (a.0.max(b.0), a.1.max(b.1)));
    (g > 0.0 && r > 0.0).then(|| g / r)
}

/// A load formula in `t` that the time step resolves poorly: its time scale `tau`
/// ([`time_scale`], sampled over the run) against the step `dt`, judged by the
/// integrator's error per radian for an oscillation on that time scale,
/// [`Integrator::error_per_radian`] at `h = dt / tau`. Warned above `threshold` (the
/// estimate's, default 1e-2: RK4 from 1.05 steps per time scale, Verlet from 2.0,
/// `emu` from 50), naming the load, its time scale and a step that would do (half the
/// threshold). Measured on plate_pulse with a 10x shorter pulse (tests/time_loads.rs).
/// The loads are read at [`LoadPoints`] for the run's node `spacing`.
pub fn load_time_resolution(
    case: &Case,
    spacing: f64,
    time_step: f64,
    end_time: f64,
    integrator: Integrator,
    threshold: f64,
) -> Option<Warning> {
    let loads = case.loads();
    let at = LoadPoints::new(case, spacing);
    let body = at.body();
    let times: Vec<f64> = (0..LOAD_SAMPLE_TIMES).map(|k| end_time * k as f64 / (LOAD_SAMPLE_TIMES - 1) as f64).collect();
    let fields = std::iter::once(("body_force".to_string(), &loads.body_force, &body[..]))
        .chain(loads.conditions.iter().enumerate().map(|(k, c)| (format!("boundary[{k}].value"), &c.value, &at.parts[k][..])));
    let (field, tau) = fields
        .filter_map(|(field, v, points)| {
            let name = match v {
                Value::Expression(e) if !e.origin.is_empty() => e.origin.clone(),
                _ => field,
            };
            time_scale(v, points, &times).map(|tau| (name, tau))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let error = integrator.error_per_radian(time_step / tau);
    exceeds(error, threshold).then(|| Warning {
        check: "load-time-resolution",
        message: format!(
            "the load {field} varies on a time scale of {tau:.2e} s (max |g| / max |dg/dt| over the run), {:.2} steps of \
             dt = {time_step:.2e} s: {} integrates an oscillation on that scale with an error of {error:.1e} per radian, \
             above {threshold:.0e}; the response to this load is poorly resolved in time: try dynamics.time_step = {:.2e} \
             or smaller",
            tau / time_step,
            integrator.name(),
            tau * integrator.step_for_error(threshold / 2.0)
        ),
    })
}

/// A run whose memory estimate exceeds half the available memory (`resources`).
pub fn memory(p: &Problem) -> Option<Warning> {
    let e = resources::of(p);
    resources::above_half(&e).map(|available| Warning {
        check: "memory",
        message: format!(
            "the run was estimated at {:.1} GB ({}), more than half of the {:.1} GB available; \
             a larger problem would not fit (see {})",
            e.peak_bytes / 1e9,
            resources::describe(&e),
            available / 1e9,
            e.driver
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Energy exchanged between kinetic and elastic at constant total: no drift; a total
    /// that wanders by 3 % of the scale at one row: drift 0.03, warned at 1e-2, except
    /// when the loads depend on time (their work changes the total; a note says so).
    #[test]
    fn energy_drift_is_the_largest_change_of_the_total() {
        let conserved: Vec<EnergyRow> =
            (0..50).map(|k| (k as f64 * 0.1).sin()).map(|s| [0.0, 100.0 * s * s, 100.0 * (1.0 - s * s), 0.0]).collect();
        assert!(energy_drift(&conserved) < 1e-14);
        let off = Estimate::Off;
        assert!(dynamic(&conserved, 1e-2, false, &off, None).warnings.is_empty());
        let mut wandering = conserved.clone();
        wandering[20][1] += 3.0;
        assert!((energy_drift(&wandering) - 3.0 / 103.0).abs() < 1e-3 * 0.03, "{}", energy_drift(&wandering));
        assert_eq!(dynamic(&wandering, 1e-2, false, &off, None).warnings[0].check, "energy-drift");
        let varying = dynamic(&wandering, 1e-2, true, &off, None);
        assert!(varying.warnings.is_empty() && varying.notes.iter().any(|n| n.contains("no energy check")), "{:?}", varying.notes);
    }
}
