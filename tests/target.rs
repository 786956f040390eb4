//! `mlsm run --target-error`: the loop reaches a target from a coarse start and stops
//! there, the true error then lies within 2x the target (the bound: the
//! estimate's measured effectivities are 0.78..1.13), a target out of reach is warned
//! with the best estimate (exit 4 under --strict), and bad input is refused.
//! (The refinement rule and the grading are unit-tested in src/domain/adapt.rs.)

mod common;

use common::f;
use mlsm::stages::Silent;
use mlsm::tradeoff::hp;
use mlsm::tradeoff::target::{pursue, DegreeRule, Outcome, Refinement, Stop, Target, TargetNorm, MAX_STEPS};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn mlsm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mlsm")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().expect("cannot start mlsm")
}

fn problem(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("problems").join(format!("{name}.toml")).display().to_string()
}

/// A target at the scene's degree (the loop's refinement alone, as before the hp
/// choices).
fn target(tolerance: f64, norm: TargetNorm, refinement: Refinement) -> Target {
    Target { tolerance, norm, refinement, degree: DegreeRule::Scene, budget: None, max_steps: MAX_STEPS }
}

/// The command line's target: degree and refinement chosen by the loop.
fn hp_target(tolerance: f64, norm: TargetNorm) -> Target {
    Target { degree: DegreeRule::Auto, ..target(tolerance, norm, Refinement::Auto) }
}

/// Every step is refined from the one before, the last is reached and the true
/// error of the result is within 2 E.
fn assert_reached(o: &Outcome, e: f64, what: &str) {
    let steps: Vec<(usize, f64, Option<f64>)> = o.history.iter().map(|s| (s.nodes, s.estimate, s.error)).collect();
    assert!(matches!(o.stop, Stop::Reached), "{what}: {:?}, steps {steps:?}", o.stop);
    assert_eq!(o.best + 1, o.history.len(), "{what}: the reached step is the result");
    let last = &o.history[o.best];
    assert!(last.estimate <= e, "{what}: {steps:?}");
    let error = last.error.expect("exact solution");
    assert!(error <= 2.0 * e, "{what}: true error {error:.3e} above 2 x {e:e}; steps {steps:?}");
    assert!(o.history.len() >= 2, "{what}: the coarse start must need refinement; {steps:?}");
    for w in o.history.windows(2) {
        assert!(w[1].nodes > w[0].nodes, "{what}: a step did not refine: {steps:?}");
    }
}

/// The test: `--target-error 1e-3` on Lame meets the target and stops. Started
/// from spacing 1e-3 (estimate about 1e-2), the loop must refine at least once.
#[test]
fn lame_reaches_1e_3_from_a_coarse_start_and_stops() {
    let p = common::scene("lame", &[("nodes.spacing", f(1e-3))]);
    let o = pursue(&p, &target(1e-3, TargetNorm::EInfU, Refinement::Local), &Silent, |_| {}).unwrap();
    assert_reached(&o, 1e-3, "lame e_inf(u) 1e-3");
    assert!(o.notes.iter().any(|n| n.contains("estimate is switched on")), "{:?}", o.notes);
}

/// A stress target in relative L2 on Lame, refined uniformly.
#[test]
fn lame_reaches_a_stress_l2_target_uniformly() {
    let p = common::scene("lame", &[("nodes.spacing", f(1e-3))]);
    let o = pursue(&p, &target(1e-4, TargetNorm::RelL2Sigma, Refinement::Uniform), &Silent, |_| {}).unwrap();
    assert_reached(&o, 1e-4, "lame rel_l2(sigma) 1e-4");
}

/// On a grid (one spacing) the loop refines uniformly and says so; the manufactured
/// scene reaches 1e-5 in e_inf(u).
#[test]
fn manufactured_grid_reaches_1e_5_uniformly() {
    let p = common::scene("manufactured_traction", &[("nodes.spacing", f(0.1))]);
    let o = pursue(&p, &target(1e-5, TargetNorm::EInfU, Refinement::Local), &Silent, |_| {}).unwrap();
    assert_reached(&o, 1e-5, "manufactured_traction e_inf(u) 1e-5");
    assert!(o.notes.iter().any(|n| n.contains("refined uniformly")), "{:?}", o.notes);
}

/// A target out of reach, under the smallest budget (1 ns), which has run out after the
/// first step on any machine: exit 0 with a warning naming the best estimate and why the
/// loop ended, the history in target.csv and summary.json, exit 4 under --strict. (The
/// budget's decision itself is unit-tested with the seconds the test sets in
/// src/tradeoff/target.rs.)
#[test]
fn unreachable_target_is_warned_and_strict_exits_4() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lame");
    let args = ["run", &problem("lame"), "--spacing", "1e-3", "--target-error", "1e-9", "--budget", "1ns", "--out", out.to_str().unwrap()];
    let o = mlsm(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("warning [target]") && err.contains("not reached: the best estimate is"), "{err}");
    assert!(err.contains("the budget ends: the next step would take about") && err.contains("0.0 s are left"), "{err}");
    let summary: Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let target = &summary["target"];
    assert_eq!(target["reached"], false);
    assert_eq!(target["stop"], "budget", "{target}");
    assert_eq!(target["left_s"], 0.0, "{target}");
    assert!(target["predicted_s"].as_f64().unwrap() > 0.0, "{target}");
    assert_eq!(target["steps"].as_array().unwrap().len(), 1, "{target}");
    let csv = std::fs::read_to_string(out.join("target.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2);
    let mut strict = args.to_vec();
    strict.push("--strict");
    assert_eq!(mlsm(&strict).status.code(), Some(4));
}

/// Bad input names the option and the reason, exit 2, nothing written.
#[test]
fn bad_targets_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let o = out.to_str().unwrap();
    for (args, expect) in [
        (vec!["--target-error", "0"], "positive"),
        (vec!["--target-error", "-1e-3"], "positive"),
        (vec!["--target-error", "2"], "(0, 1)"),
        (vec!["--target-error", "1e-3", "--budget", "0"], "positive number of seconds"),
        (vec!["--target-norm", "e_inf_sigma"], "--target-error"),
    ] {
        let mut a = vec!["run", "problems/lame.toml", "--out", o];
        a.extend(args.iter().copied());
        let r = mlsm(&a);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote results");
    }
    let r = mlsm(&["run", &problem("pd_tension"), "--model", "peridynamics", "--target-error", "1e-3", "--out", o]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("--horizon"));
    let r = mlsm(&["run", &problem("steel_plate_dynamic"), "--target-error", "1e-3", "--out", o]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("dynamic"));
}

/// On a scene with singular corners the local step refines them at least as much as
/// the node that asks the most: the bracket from 4 mm. Left to the indicator alone,
/// the clamped base stayed at 4 mm next to 1 mm elsewhere, and the second step's
/// estimate rose from 0.147 to 0.346 (tip 35 % off); with the corners refined it fell
/// to 2.35e-2, and with the corners' ghosts and the square of the factor there to
/// 2.0e-3 (from 5.0e-2). The bound 0.1 lies between. Two steps at most: the test's
/// cost is bounded by its step count, not by the clock (a time budget ran out after
/// one step on a loaded machine).
#[test]
fn local_refinement_refines_the_singular_corners() {
    let p = common::scene("bracket", &[("nodes.spacing", f(4e-3))]);
    let t = Target { max_steps: 2, ..target(1e-2, TargetNorm::EInfU, Refinement::Local) };
    let o = pursue(&p, &t, &Silent, |_| {}).unwrap();
    let steps: Vec<(usize, f64)> = o.history.iter().map(|s| (s.nodes, s.estimate)).collect();
    assert!(steps.len() >= 2, "{steps:?}, {:?}", o.stop);
    assert!(steps[1].1 < 0.1 && steps[1].1 < steps[0].1, "the second step's estimate must fall: {steps:?}");
    // The clamped corner (0, 0) carries the step's smallest spacing.
    let nodes = &o.solution.nodes;
    let smallest = nodes.local_spacing.iter().copied().fold(f64::INFINITY, f64::min);
    let from_corner = |i: usize| nodes.positions[i][0].hypot(nodes.positions[i][1]);
    let corner = (0..nodes.len()).min_by(|&a, &b| from_corner(a).total_cmp(&from_corner(b))).unwrap();
    assert!(nodes.local_spacing[corner] <= 1.01 * smallest, "corner spacing {} against {smallest}", nodes.local_spacing[corner]);
}

/// The bracket from its shipped 2 mm to e_inf(u) 1e-2 (counted double at its singular
/// corners: an estimate of 5e-3). The local loop refines the corners by the square of
/// the step's factor (`domain::adapt::CORNER_POWER`), reaches the target, and needs
/// fewer nodes than the uniform loop's second step, which has 16 times the first's (60
/// 602 nodes, estimate 5.04e-3, not reached; its tip 1.4 % off). The target is met in
/// truth at the tip: the tip deflection of the step written is within 1e-2 max |u| of
/// finite elements (-4.975e-4 m, benches/fem_reference.py). Measured: with the
/// higher-degree reference as the estimate a third step, tip 0.16 % off; since the
/// defect estimate with the higher-degree rows at the corners (2026-11-28) the second
/// step, 17 537 nodes, estimate 2.47e-3, tip 0.54 % off (4.7e-3 of max |u|, so an
/// effectivity of 0.53, 1.06 counted double). With the corners refined by the plain
/// factor the loop stopped at 42 039 nodes with the tip 1.3 % off.
#[test]
fn the_bracket_reaches_its_target_by_refining_its_corners() {
    let p = common::scene("bracket", &[]);
    let o = pursue(&p, &target(1e-2, TargetNorm::EInfU, Refinement::Local), &Silent, |_| {}).unwrap();
    let steps: Vec<(usize, f64)> = o.history.iter().map(|s| (s.nodes, s.estimate)).collect();
    assert!(matches!(o.stop, Stop::Reached) && o.best + 1 == steps.len(), "{:?}, {steps:?}", o.stop);
    assert!(steps[o.best].1 <= 5e-3, "{steps:?}");
    assert!(steps[o.best].0 < 16 * steps[0].0, "{steps:?}");
    let tip = o.solution.probes.iter().find(|p| p.name == "tip_deflection").expect("the bracket's probe").value;
    let largest = o.solution.displacement.iter().map(|u| u[0].hypot(u[1])).fold(0.0, f64::max);
    assert!((tip - -4.975e-4).abs() <= 1e-2 * largest, "tip {tip:e}, max |u| {largest:e}, {steps:?}");
}

/// The hp choices on the shipped Lame ring (degree 4, 3 388 nodes): the loop raises
/// the degree to 6, starts from about 1 000 nodes, refines uniformly by the predicted
/// factor, and stops near the target: reached in at most three solves, the true error
/// at most 2 E (the estimate's measured effectivities, module docs) and not more than
/// 10x below E (the bound on overshooting). Measured: two solves, 1 000 then
/// about 7 000 nodes (BENCHMARKS.md "Time to accuracy").
#[test]
fn lame_hp_raises_the_degree_and_stops_near_the_target() {
    let p = common::scene("lame", &[]);
    let e = 1e-6;
    let o = pursue(&p, &hp_target(e, TargetNorm::EInfU), &Silent, |_| {}).unwrap();
    let steps: Vec<(usize, f64, Option<f64>)> = o.history.iter().map(|s| (s.nodes, s.estimate, s.error)).collect();
    assert!(matches!(o.stop, Stop::Reached) && o.history.len() <= 3, "{:?}, {steps:?}", o.stop);
    assert_eq!(o.refinement, Refinement::Uniform);
    assert!(o.notes.iter().any(|n| n.contains("raises the degree from 4 to 6")), "{:?}", o.notes);
    assert!(o.history[0].nodes < 1500, "the first step is the probe: {steps:?}");
    let error = o.history[o.best].error.expect("exact solution");
    assert!(error <= 2.0 * e && error >= e / 10.0, "true error {error:.2e} for a target of {e:e}: {steps:?}");
}

/// Which scenes the loop treats as smooth: those with an exact solution (Lame) and
/// those without singular corners; not the bracket (re-entrant corner, clamped base
/// meeting free edges), where it keeps the scene's degree and refines locally.
#[test]
fn smooth_scenes_are_told_from_singular_ones() {
    let smooth = |p: &mlsm::scene::problem::Problem| hp::is_smooth(p, p.expected_nodes());
    assert!(smooth(&common::scene("lame", &[])));
    assert!(!smooth(&common::scene("bracket", &[])));
    let lame = common::scene("lame", &[]);
    assert!(hp::raised_degree(&lame, 1e-2).is_none(), "a loose target keeps degree 4");
    let (raised, _) = hp::raised_degree(&lame, 1e-4).expect("raised");
    assert_eq!(raised.navier.approximation.support, 56);
    let bracket = common::scene("bracket", &[("nodes.spacing", f(4e-3))]);
    let o = pursue(&bracket, &Target { max_steps: 1, ..hp_target(1e-3, TargetNorm::EInfU) }, &Silent, |_| {}).unwrap();
    assert_eq!(o.refinement, Refinement::Local);
    assert!(!o.notes.iter().any(|n| n.contains("raises the degree")), "{:?}", o.notes);
}

/// The hp loop's probe (its first step, about 1 000 nodes) is accepted alone only when
/// its estimate is at most half the target (`PROBE_MARGIN`): its estimate can read the
/// true error low (effectivity 0.59 measured on Lame at degree 6), and a loose target
/// met by the probe alone ended at 1.7 E before. With the target set to 1.5 times the
/// probe's own estimate, the loop takes a second step aimed at E / 2, and the result's
/// true error is below E.
#[test]
fn the_probe_alone_is_accepted_only_with_a_margin() {
    let p = common::scene("lame", &[]);
    let first = pursue(&p, &Target { max_steps: 1, ..hp_target(1e-3, TargetNorm::EInfU) }, &Silent, |_| {}).unwrap();
    let v0 = first.history[0].estimate;
    assert!(first.history[0].nodes < 1500 && v0 < 1e-3 / 1.5, "the probe: {} nodes, estimate {v0:e}", first.history[0].nodes);
    let e = 1.5 * v0;
    let o = pursue(&p, &hp_target(e, TargetNorm::EInfU), &Silent, |_| {}).unwrap();
    let steps: Vec<(usize, f64, Option<f64>)> = o.history.iter().map(|s| (s.nodes, s.estimate, s.error)).collect();
    eprintln!("probe estimate {v0:.3e}, target {e:.3e}: {steps:?}");
    assert!(matches!(o.stop, Stop::Reached) && o.history.len() >= 2, "{:?}, {steps:?}", o.stop);
    let error = o.history[o.best].error.expect("exact solution");
    assert!(error <= e, "true error {error:.2e} for a target of {e:.2e}: {steps:?}");
}
