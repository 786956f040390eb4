//! The estimates of the runs that have no higher-degree reference: a peridynamic run
//! against the local (Navier) model (`local-model`), and a dynamic Navier run against
//! itself on other nodes and time steps (`richardson`, `refined`), each against the
//! true error. Bands (issue 11): effectivity = estimate / true error in [0.5, 2] for
//! e_inf(u).

mod common;

use common::{f, s, scene};
use mlsm::models::navier::Estimate;
use mlsm::stages::Silent;
use mlsm::scene::problem::Problem;
use std::path::Path;

/// `local-model` on the shipped peridynamic scenes with an exact solution, at their
/// horizon and at half of it: the estimate is the difference to an MLSM solution of
/// the same scene (PHS r^3 + degree 4 on the scene's nodes, interpolated at degree 4;
/// its own estimated error 2e-13 to 3e-6), so it tracks the true (model plus
/// quadrature) error of 9e-4 to 0.15 closely. Measured effectivities 1.00-1.01.
#[test]
fn local_model_tracks_the_peridynamic_error() {
    for name in ["pd_manufactured", "pd_trig", "pd_tension"] {
        let base = scene(name, &[]).model.peridynamics().copied().expect("[peridynamics]").horizon;
        for horizon in [base, base / 2.0] {
            let p = scene(name, &[("model", s("peridynamics")), ("peridynamics.horizon", f(horizon))]);
            let params = p.model.peridynamics().copied().expect("[peridynamics]");
            let sol = mlsm::models::peridynamics::solve(&p.case, &params, &Silent).unwrap_or_else(|e| panic!("{name}: {e}"));
            let n = sol.nodes.free;
            let estimate =
                mlsm::quality::compare::estimate::local_model(&p, &sol.nodes.positions[..n], (&sol.displacement[..n], sol.stress.as_ref()), &[]);
            let est = estimate.done().unwrap_or_else(|| panic!("{name}: no estimate: {estimate:?}"));
            let e = sol.errors.expect("exact solution").0.e_inf_u;
            let own = est.reference_estimated_e_inf_u.expect("a static reference estimates itself");
            eprintln!(
                "{name} delta = {horizon}: e_inf(u) {e:.2e}, estimated {:.2e} (effectivity {:.3}), reference's own {own:.1e}, {:.2} s",
                est.norms.e_inf_u,
                est.norms.e_inf_u / e,
                est.seconds
            );
            assert!((0.5..=2.0).contains(&(est.norms.e_inf_u / e)), "{name} delta = {horizon}: effectivity {}", est.norms.e_inf_u / e);
            assert!(own * mlsm::quality::warnings::LOCAL_REFERENCE_MARGIN < est.norms.e_inf_u, "{name}: the reference is too coarse to judge it");
        }
    }
}

/// A Navier reference on nodes too coarse to judge the peridynamic run (spacing 0.1,
/// own estimate 3.8e-4 against a difference of 1.9e-3 measured there, effectivity
/// 2.0) is refined: at spacing 0.05 the estimate is back in the band (1.03 measured).
#[test]
fn a_coarse_local_reference_is_refined() {
    let p = scene("pd_manufactured", &[("model", s("peridynamics")), ("nodes.spacing", f(0.1)), ("peridynamics.horizon", f(0.05))]);
    let params = p.model.peridynamics().copied().expect("[peridynamics]");
    let sol = mlsm::models::peridynamics::solve(&p.case, &params, &Silent).unwrap();
    let n = sol.nodes.free;
    let estimate = mlsm::quality::compare::estimate::local_model(&p, &sol.nodes.positions[..n], (&sol.displacement[..n], sol.stress.as_ref()), &[]);
    let est = estimate.done().unwrap_or_else(|| panic!("no estimate: {estimate:?}"));
    let e = sol.errors.unwrap().0.e_inf_u;
    eprintln!("coarse reference: e_inf(u) {e:.2e}, estimated {:.2e} against {}", est.norms.e_inf_u, est.reference);
    assert_eq!(est.reference_unknowns, 2 * 21 * 21, "refined once, to spacing 0.05: {}", est.reference);
    assert!((0.5..=2.0).contains(&(est.norms.e_inf_u / e)), "effectivity {}", est.norms.e_inf_u / e);
}

/// A static Navier scene with `local-model` or `richardson`, a peridynamic one with
/// `higher-degree` or `richardson` and a dynamic Navier one with `higher-degree` are
/// refused, naming `estimate.method`.
#[test]
fn an_estimate_of_the_other_model_is_refused() {
    for (name, edits) in [
        ("lame", vec![("estimate.method", s("local-model"))]),
        ("lame", vec![("estimate.method", s("richardson"))]),
        ("pd_trig", vec![("estimate.method", s("richardson"))]),
        ("pd_trig", vec![("estimate.method", s("higher-degree"))]),
        ("steel_plate_dynamic", vec![("model", s("navier")), ("estimate.method", s("higher-degree"))]),
    ] {
        let r = std::panic::catch_unwind(|| scene(name, &edits));
        let why = r.err().and_then(|p| p.downcast_ref::<String>().cloned()).unwrap_or_else(|| panic!("{name}: accepted"));
        assert!(why.contains("estimate.method"), "{name}: {why}");
    }
}

/// A standing compression wave in a plane-strain plate, `rho u_tt = (lambda + 2 mu)
/// u_x,xx`:
///
/// ```text
/// u = (a sin(pi x) cos(w t), 0),   w = pi sqrt((lambda + 2 mu) / rho)
/// ```
///
/// on `[0, 1] x [0, 0.5]` with the displacement prescribed on every side (in `t`),
/// starting from rest; E = 1, nu = 0.25 (lambda + 2 mu = 1.2), rho = 1, so w = 3.44
/// and t = 0.8 is 0.44 of a period. The error has a spatial and a time part.
fn standing_wave(spacing: f64, integrator: &str) -> Problem {
    let side =
        |part: &str| format!("[[boundary]]\npart = \"{part}\"\nkind = \"displacement\"\nvalue = [\"a * sin(pi * x) * cos(w * t)\", 0]\n");
    let text = format!(
        r#"
name = "standing_wave"
[constants]
a = 1e-3
w = {w:e}

[[domain.region]]
shape = "rectangle"
min = [0.0, 0.0]
max = [1.0, 0.5]

[nodes]
spacing = {spacing:e}
fill = "grid"

[approximation]
basis = "tensor"
support = 13

[material]
E = 1.0
nu = 0.25
plane = "strain"

[dynamics]
density = 1.0
end_time = 0.8
integrator = "{integrator}"
initial_displacement = ["a * sin(pi * x)", 0]

{}{}{}{}"#,
        side("left"),
        side("right"),
        side("bottom"),
        side("top"),
        w = WAVE_FREQUENCY,
    );
    Problem::from_str(&text, Path::new("standing_wave.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// `pi sqrt(1.2)`: the standing wave's angular frequency.
const WAVE_FREQUENCY: f64 = std::f64::consts::PI * 1.095_445_115_010_332_2;

/// The dynamic estimates on the standing wave, against the true space-time error over
/// the run's history states (`Simulation::history`, eight evenly spaced times up to
/// the end; the error at the end time alone is printed beside it):
///
/// - `auto` (Richardson's, from the run at twice the spacing) at three spacings and
///   with two integrators: for a second-order error its effectivity tends to
///   3 / sqrt 3 = 1.73 in the asymptotic range (the divisor sqrt 3 keeps any order
///   from 1 to 2 within [0.58, 1.73]); asserted in [0.5, 2];
/// - `auto` where the run at twice the spacing would have fewer than
///   `RICHARDSON_MIN_COARSE_NODES` nodes (h = 0.1: 24): it takes `refined` and says why;
/// - `refined` (half the spacing): 0.75 for a second-order error; in [0.5, 2].
///
/// Measured: the printed lines (docs/verification.md, "The error estimate: measured
/// effectivities").
#[test]
fn dynamic_estimates_track_the_dynamic_error() {
    let cases = [
        (0.05, "rk4", "auto"),
        (0.05, "verlet", "auto"),
        (0.025, "rk4", "auto"),
        (0.025, "verlet", "auto"),
        (0.0125, "verlet", "auto"),
        (0.1, "rk4", "auto"),
        (0.05, "rk4", "refined"),
        (0.05, "verlet", "refined"),
    ];
    for (spacing, integrator, method) in cases {
        let mut p = standing_wave(spacing, integrator);
        p.navier.estimate.method = <mlsm::models::navier::EstimateMethod as mlsm::scene::choice::Choice>::parse(method).unwrap();
        let d = p.case.dynamics.as_ref().unwrap();
        let sim = mlsm::models::navier::simulate(&p.case, &p.navier, d, &Silent, |_| Ok(())).unwrap_or_else(|e| panic!("{e}"));
        let exact_at = |t: f64| -> Vec<[f64; 2]> {
            sim.positions.iter().map(|q| [1e-3 * (std::f64::consts::PI * q[0]).sin() * (WAVE_FREQUENCY * t).cos(), 0.0]).collect()
        };
        assert_eq!(sim.history.len(), mlsm::models::dynamics::driver::HISTORY_SAMPLES.min(sim.report.steps), "h = {spacing}: states kept");
        let (t_end, u_end) = sim.history.last().unwrap();
        assert_eq!(u_end, &sim.u, "the last state kept is the final one");
        // Space-time error over the kept states: all of them side by side.
        let u: Vec<[f64; 2]> = sim.history.iter().flat_map(|(_, u)| u.iter().copied()).collect();
        let exact: Vec<[f64; 2]> = sim.history.iter().flat_map(|(t, _)| exact_at(*t)).collect();
        let (e, _) = mlsm::quality::post::relative_errors(&u, &exact);
        let (e_end, _) = mlsm::quality::post::relative_errors(u_end, &exact_at(*t_end));
        let Estimate::Done(est) = &sim.estimate else { panic!("h = {spacing}: no estimate: {:?}", sim.estimate) };
        let expected = match (method, spacing) {
            ("auto", 0.1) => "refined",
            ("auto", _) => "richardson",
            _ => method,
        };
        assert_eq!(est.method, expected, "h = {spacing} {integrator} {method}: {}", est.reference);
        if (method, spacing) == ("auto", 0.1) {
            assert!(est.reference.contains("auto took it because Richardson's estimate is unavailable"), "{}", est.reference);
        }
        let eff = est.norms.e_inf_u / e;
        eprintln!(
            "standing wave h = {spacing} {integrator} {method}: {} nodes, {} steps, e_inf(u) over the history {e:.2e} (at the end {e_end:.2e}), estimated {:.2e} (effectivity {eff:.2}, largest at t = {:.3}), reference {} in {:.2} s",
            sim.positions.len(),
            sim.report.steps,
            est.norms.e_inf_u,
            est.largest_u_time.unwrap_or(f64::NAN),
            est.reference,
            est.seconds
        );
        assert!(est.reference.contains(&format!("{} states", sim.history.len())), "{}", est.reference);
        assert!((0.5..=2.0).contains(&eff), "h = {spacing} {integrator} {method}: effectivity {eff}");
    }
}

/// `estimate.method = "none"` switches the dynamic estimate off.
#[test]
fn a_dynamic_estimate_can_be_switched_off() {
    let p = scene("steel_plate_dynamic", &[("model", s("navier")), ("estimate.method", s("none")), ("dynamics.end_time", f(1e-5))]);
    let sim = mlsm::models::navier::simulate(&p.case, &p.navier, p.case.dynamics.as_ref().unwrap(), &Silent, |_| Ok(())).unwrap();
    assert!(matches!(sim.estimate, Estimate::Off));
}

/// The default (Richardson's) estimate of the shipped dynamic scenes run by the Navier
/// model at spacing 0.02 (816 nodes), against their true space-time error over the
/// history, taken from the same scene at a quarter of the spacing (12 261 nodes,
/// interpolated to the run's nodes). That reference's own error is 1/16 of the run's
/// for a second-order error and about 1/7 at the order 1.4 the steel plate's fronts
/// show (e_inf(u) 1.97e-2 at h = 0.02, 7.55e-3 at 0.01 against h = 0.0025), so the
/// measured effectivity is within 15 % of the true one. The divisor sqrt 3 keeps every
/// order from 1 to 2 within [0.58, 1.73]: asserted in [0.5, 2]. Measured: steel plate
/// 1.51, plate pulse 1.73.
///
/// `MLSM_DYNAMIC_TRUTH=0.0025` takes the true error from that spacing instead (48 521
/// nodes, about a minute) and adds the runs at h = 0.01 and the `refined` estimate
/// (docs/verification.md: 1.45 / 1.17 and 1.65 / 1.78 at h = 0.02 / 0.01; `refined`
/// 0.78-0.82).
#[test]
fn richardson_tracks_the_shipped_dynamic_scenes() {
    let truth_spacing: f64 = std::env::var("MLSM_DYNAMIC_TRUTH").map(|v| v.parse().expect("MLSM_DYNAMIC_TRUTH: a spacing")).unwrap_or(0.005);
    let (spacings, methods): (&[f64], &[&str]) = if truth_spacing < 0.005 { (&[0.02, 0.01], &["auto", "refined"]) } else { (&[0.02], &["auto"]) };
    for name in ["steel_plate_dynamic", "plate_pulse"] {
        let at = |h: f64, method: &str| scene(name, &[("model", s("navier")), ("nodes.spacing", f(h)), ("estimate.method", s(method))]);
        for &h in spacings {
            for &method in methods {
                let p = at(h, method);
                let d = p.case.dynamics.as_ref().unwrap();
                let sim = mlsm::models::navier::simulate(&p.case, &p.navier, d, &Silent, |_| Ok(())).unwrap_or_else(|e| panic!("{name}: {e}"));
                let Estimate::Done(est) = &sim.estimate else { panic!("{name}: no estimate: {:?}", sim.estimate) };
                assert_eq!(est.method, if method == "auto" { "richardson" } else { method }, "{name}: {}", est.reference);
                let fine = at(truth_spacing, "none");
                let times: Vec<f64> = sim.history.iter().map(|h| h.0).collect();
                let mut timer = mlsm::stages::StageTimer::new(&Silent);
                let sampling = mlsm::models::navier::Sampling::Times(&times);
                let truth = mlsm::models::navier::simulate_sampled(&fine.case, &fine.navier, d, &mut timer, sampling, |_| Ok(()))
                    .unwrap_or_else(|e| panic!("{name} at {truth_spacing}: {e}"));
                let mut exact = Vec::new();
                for (_, u) in &truth.history {
                    exact.extend(mlsm::mlsm::interpolate::mls_values(&truth.positions, u, &sim.positions).unwrap());
                }
                let u: Vec<[f64; 2]> = sim.history.iter().flat_map(|(_, u)| u.iter().copied()).collect();
                let (e, _) = mlsm::quality::post::relative_errors(&u, &exact);
                let eff = est.norms.e_inf_u / e;
                eprintln!(
                    "{name} h = {h} {method}: e_inf(u) over the history {e:.3e} (against h = {truth_spacing}), estimated {:.3e}, effectivity {eff:.2}, in {:.2} s",
                    est.norms.e_inf_u, est.seconds
                );
                assert!((0.5..=2.0).contains(&eff), "{name} h = {h} {method}: effectivity {eff}");
            }
        }
    }
}
