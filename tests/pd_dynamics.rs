//! Peridynamic elastodynamics on the seed's steel plate (problems/steel_plate_dynamic.toml,
//! coarse: m = 3, 270 nodes): rigid motion, energy, the nonlinear bond-stretch law
//! against the linear one, and the time-step limit.

mod common;

use common::*;
use mlsm::models::dynamics::Integrator;
use mlsm::models::peridynamics::simulate;
use mlsm::scene::problem::{Model, Problem};
use mlsm::stages::{RunError, Silent};

/// Final time, displacement (flat) and energy history of a run.
type Run = (f64, Vec<f64>, Vec<mlsm::models::dynamics::driver::EnergyRow>);

/// Final time, displacement and energy history of a run of `p`.
fn run(p: &Problem) -> Result<Run, RunError> {
    let sim = simulate(&p.case, p.model.peridynamics().unwrap(), p.case.dynamics.as_ref().unwrap(), &Silent, |_| Ok(()))?;
    Ok((sim.energies.last().unwrap()[0], sim.u.iter().flatten().copied().collect(), sim.energies))
}

fn plate(edits: &[(&str, Option<toml::Value>)]) -> Problem {
    let mut all = vec![("peridynamics.m", f(3.0))];
    all.extend_from_slice(edits);
    scene("steel_plate_dynamic", &all)
}

/// A uniform velocity is a rigid motion: every scheme moves the plate as a whole
/// (u = v0 t to round-off) with no elastic energy.
#[test]
fn uniform_velocity_is_a_rigid_motion() {
    for integrator in ["emu", "verlet", "rk4"] {
        let v0 =
            toml::Value::try_from(std::collections::BTreeMap::from([("x", vec![3.0, 0.0, 0.0]), ("y", vec![-2.0, 0.0, 0.0])])).unwrap();
        let p = plate(&[("dynamics.integrator", s(integrator)), ("dynamics.initial_velocity", Some(v0))]);
        let (t, u, energies) = run(&p).unwrap();
        let worst = u.chunks_exact(2).map(|u| (u[0] - 3.0 * t).abs().max((u[1] + 2.0 * t).abs())).fold(0.0, f64::max);
        let elastic = energies.iter().map(|e| e[2]).fold(0.0, f64::max);
        eprintln!("{integrator}: max |u - v0 t| = {worst:.1e}, max E_el = {elastic:.1e}");
        assert!(worst < 1e-15 && elastic < 1e-20, "{integrator}: {worst} {elastic}");
    }
}

/// With Verlet the total energy of the free plate (no body force, no constraint:
/// E_kin + E_el is conserved by the continuum) oscillates within 5e-3 of its initial
/// value (measured 2.6e-3 at 0.8 of the stable step, about 2.5 periods of the axial
/// mode up to t_end = 1e-3 s, during which the kinetic energy turns almost entirely
/// into elastic energy and back) and does not drift: the largest deviation in the
/// second half of the run is at most 1.1 times that of the first half.
#[test]
fn verlet_conserves_the_plate_energy() {
    let (_, _, energies) = run(&plate(&[("dynamics.integrator", s("verlet"))])).unwrap();
    let total = |e: &mlsm::models::dynamics::driver::EnergyRow| e[1] + e[2] + e[3];
    let e0 = total(&energies[0]);
    let drift = energies.iter().map(|e| (total(e) - e0).abs() / e0).fold(0.0, f64::max);
    let peak_elastic = energies.iter().map(|e| e[2]).fold(0.0, f64::max) / e0;
    eprintln!("plate, Verlet: max |E - E0| / E0 = {drift:.2e}, peak E_el / E0 = {peak_elastic:.2e}, E_kin(0) = {:.6e}", energies[0][1]);
    assert!(drift < 5e-3, "{drift}");
    let half = energies.len() / 2;
    let dev = |r: &[mlsm::models::dynamics::driver::EnergyRow]| r.iter().map(|e| (total(e) - e0).abs() / e0).fold(0.0, f64::max);
    let (first, second) = (dev(&energies[..half]), dev(&energies[half..]));
    eprintln!("  first half {first:.2e}, second half {second:.2e}");
    assert!(second <= 1.1 * first, "energy drifts: {first} then {second}");
    assert!(peak_elastic > 1e-2, "{peak_elastic}");
    // E_kin(0) = rho/2 * 0.3 * int_0^1 (10 (x - 1/2))^2 dx = 1e4 J/m (midpoint sum: 1e4 (1 - 1/N^2) with N = 30 columns).
    assert!((energies[0][1] - 1e4 * (1.0 - 1.0 / 900.0)).abs() < 1e-8, "{}", energies[0][1]);
}

/// The nonlinear bond-stretch law agrees with the linear one for small motions (the
/// seed found them nearly identical on this plate) and the difference is a geometric
/// nonlinearity: relative difference of the final displacement 2.7e-4 at the seed's
/// v0 (10 m/s at the ends) and ten times smaller at v0 / 10 (ratio measured 0.100).
#[test]
fn bond_stretch_matches_linear_for_small_motions() {
    let difference = |scale: f64| {
        let v0 = toml::Value::try_from(std::collections::BTreeMap::from([
            ("x", vec![-5.0 * scale, 10.0 * scale, 0.0]),
            ("y", vec![0.0, 0.0, 0.0]),
        ]))
        .unwrap();
        let base = [("dynamics.initial_velocity", Some(v0.clone()))];
        let (_, lin, _) = run(&plate(&base)).unwrap();
        let (_, nl, _) = run(&plate(&[("dynamics.initial_velocity", Some(v0)), ("peridynamics.force", s("bond-stretch"))])).unwrap();
        let umax = lin.iter().map(|v| v.abs()).fold(0.0, f64::max);
        lin.iter().zip(&nl).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / umax
    };
    let (d1, d10) = (difference(1.0), difference(0.1));
    eprintln!("bond-stretch vs linear: {d1:.2e} at v0, {d10:.2e} at v0/10, ratio {:.3}", d10 / d1);
    assert!(d1 < 1e-3, "{d1}");
    assert!((d10 / d1 - 0.1).abs() < 0.02, "{}", d10 / d1);
}

/// A fixed step above the stability limit is refused before any step is taken; the
/// same run at 0.9 of the limit finishes.
#[test]
fn unstable_time_step_is_refused() {
    let err = run(&plate(&[("dynamics.integrator", s("verlet")), ("dynamics.time_step", f(1e-4))])).unwrap_err();
    let RunError::UnstableTimeStep { given, limit, .. } = err else { panic!("expected UnstableTimeStep, got {err}") };
    assert_eq!(given, 1e-4);
    let ok = run(&plate(&[("dynamics.integrator", s("verlet")), ("dynamics.time_step", f(0.9 * limit))]));
    assert!(ok.is_ok());
    assert_eq!(Integrator::Rk4.stability_factor(), 2f64.sqrt());
}

/// MLSM explicit elastodynamics of the same plate (tensor-quadratic basis, 13-node
/// supports, no ghost nodes, h = 0.02): a uniform velocity moves it rigidly (to
/// 1e-12), and with Verlet and with RK4 the total energy stays within 5e-3 of its
/// initial value over t_end (largest deviation measured: Verlet 2.1e-3, RK4 3.3e-3 at
/// h = 0.02; at t_end -5.7e-4 and -7.2e-4 at h = 0.01; an unstable run reaches 1e15).
/// With ghost nodes the condensed operator has growing modes: Verlet diverges at
/// h = 0.02, 0.01 and 0.005 (docs/limits.md); that is asserted too.
#[test]
fn mlsm_elastodynamics_is_stable_and_conserves_energy() {
    let navier = |p: &Problem| mlsm::models::navier::simulate(&p.case, &p.navier, p.case.dynamics.as_ref().unwrap(), &Silent, |_| Ok(()));
    let total = |e: &mlsm::models::dynamics::driver::EnergyRow| e[1] + e[2] + e[3];
    for integrator in ["verlet", "rk4"] {
        let p = scene("steel_plate_dynamic", &[("nodes.spacing", f(0.02)), ("dynamics.integrator", s(integrator))]);
        let sim = navier(&p).unwrap();
        let e0 = total(&sim.energies[0]);
        let drift = sim.energies.iter().map(|e| (total(e) - e0).abs() / e0).fold(0.0, f64::max);
        eprintln!("MLSM plate, {integrator}: {} steps, max |E - E0| / E0 = {drift:.2e}", sim.report.steps);
        assert!(drift < 5e-3, "{integrator}: {drift}");
    }
    let ghosts = scene(
        "steel_plate_dynamic",
        &[("nodes.spacing", f(0.02)), ("dynamics.integrator", s("verlet")), ("approximation.ghost_nodes", b(true))],
    );
    match navier(&ghosts) {
        Err(RunError::Diverged { .. }) => {}
        Ok(sim) => {
            let e0 = total(&sim.energies[0]);
            let grown = total(sim.energies.last().unwrap()) / e0;
            assert!(grown > 1e3, "with ghost nodes the run was expected to grow, energy ratio {grown}");
        }
        Err(_) => panic!("unexpected failure"),
    }
    let v0 = toml::Value::try_from(std::collections::BTreeMap::from([("x", vec![3.0, 0.0, 0.0]), ("y", vec![-2.0, 0.0, 0.0])])).unwrap();
    let p = scene("steel_plate_dynamic", &[("nodes.spacing", f(0.02)), ("dynamics.initial_velocity", Some(v0))]);
    let sim = navier(&p).unwrap();
    let t = sim.energies.last().unwrap()[0];
    let worst = sim.u.iter().map(|u| (u[0] - 3.0 * t).abs().max((u[1] + 2.0 * t).abs())).fold(0.0, f64::max);
    eprintln!("MLSM rigid motion: max |u - v0 t| = {worst:.1e}");
    assert!(worst < 1e-12, "{worst}");
}

/// Both models hand every snapshot the stress of its state: zero at the start (the
/// plate starts undeformed, only moving), finite and nonzero once the pulse has
/// travelled, one value per snapshot node; von Mises is never below the largest
/// in-plane shear `|sigma_xy|` (it is at least sqrt(3) |sigma_xy| in plane stress).
#[test]
fn snapshots_carry_the_stress_of_their_state() {
    let p = scene("steel_plate_dynamic", &[("dynamics.end_time", f(2e-5))]);
    for model in [Model::Navier, Model::Peridynamics] {
        let q = Problem { model: p.model.running(model).unwrap(), ..p.clone() };
        let mut seen: Vec<(usize, f64)> = Vec::new();
        let collect = |s: mlsm::models::dynamics::driver::Snapshot| {
            let stress = s.stress.unwrap_or_else(|| panic!("{model:?}: snapshot {} without stress", s.step));
            assert_eq!(stress.von_mises.len(), s.positions.len(), "{model:?}");
            for (vm, sig) in stress.von_mises.iter().zip(&stress.sigma) {
                assert!(vm.is_finite() && *vm >= sig[2].abs() * (1.0 - 1e-12), "{model:?}: von Mises {vm} against {sig:?}");
            }
            seen.push((s.step, stress.von_mises.iter().fold(0.0f64, |m, v| m.max(*v))));
            Ok(())
        };
        let d = q.case.dynamics.as_ref().unwrap();
        match model {
            Model::Navier => mlsm::models::navier::simulate(&q.case, &q.navier, d, &Silent, collect).map(|_| ()),
            Model::Peridynamics => simulate(&q.case, q.model.peridynamics().unwrap(), d, &Silent, collect).map(|_| ()),
        }
        .unwrap_or_else(|e| panic!("{model:?}: {e}"));
        assert!(seen.len() >= 2, "{model:?}: {seen:?}");
        assert_eq!(seen[0], (0, 0.0), "{model:?}: the undeformed start has no stress");
        assert!(seen.last().unwrap().1 > 0.0, "{model:?}: no stress after the pulse started: {seen:?}");
    }
}

/// Under Verlet the force loop sums the elastic energy of the evaluation that ends each
/// step, so the history has a row at every step (the energy-drift check reads them all);
/// under `emu`, whose evaluation is at the start of the step, the energies cost a pass
/// over the bonds and the rows stay at every fourth step. Both histories start at the
/// same energy, and Verlet's rows move the total by no more than its own bound above.
#[test]
fn verlet_records_every_step() {
    for (integrator, every) in [("verlet", 1), ("emu", 4)] {
        let p = plate(&[("dynamics.integrator", s(integrator)), ("dynamics.end_time", f(2e-4))]);
        let sim = simulate(&p.case, p.model.peridynamics().unwrap(), p.case.dynamics.as_ref().unwrap(), &Silent, |_| Ok(())).unwrap();
        let steps = sim.report.steps;
        let rows: Vec<f64> = sim.energies.iter().map(|e| e[0]).collect();
        let dt = sim.report.time_step;
        eprintln!("{integrator}: {steps} steps, {} rows", rows.len());
        assert_eq!(rows.len(), steps / every + 1 + usize::from(steps % every != 0), "{integrator}: rows");
        assert!(
            rows.windows(2).take(steps / every).all(|w| ((w[1] - w[0]) / dt - every as f64).abs() < 1e-6),
            "{integrator}: a row every {every} steps"
        );
        let e0 = sim.energies[0][1] + sim.energies[0][2];
        let drift = sim.energies.iter().map(|e| (e[1] + e[2] + e[3] - e0).abs() / e0).fold(0.0, f64::max);
        assert!(integrator != "verlet" || (drift > 0.0 && drift < 5e-3), "{integrator}: {drift}");
    }
}
