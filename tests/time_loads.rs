//! Loads that depend on time (`t` in the boundary values and body force of a scene
//! with `[dynamics]`), on a manufactured space-time solution both models reproduce
//! up to the time integration:
//!
//! ```text
//! u(x, y, t) = a sin(w t) (x, -nu y)        (uniaxial stress sigma_xx = E a sin(w t))
//! f = rho u_tt = -rho w^2 a sin(w t) (x, -nu y)
//! ```
//!
//! A linear field has `L u = 0`, and both discretisations reproduce linear fields
//! (degree-2 MLSM shapes exactly; PD bond forces of an affine field cancel in every
//! symmetric family, which the Dirichlet collar completes), so the semi-discrete
//! systems reduce to `u'' = f / rho` and the error left is the time integration's.

use mlsm::stages::{RunError, Silent};
use mlsm::scene::problem::Problem;
use std::path::Path;

const A: f64 = 1e-3;
const W: f64 = 3.0;

/// The exact displacement at `p`, time `t` (module docs), for Poisson ratio `nu`.
fn exact(p: [f64; 2], t: f64, nu: f64) -> [f64; 2] {
    let s = A * (W * t).sin();
    [s * p[0], -nu * s * p[1]]
}

/// The scene: unit square, plane stress, rho = 1, E = 1; displacement formulas on
/// left and bottom, and on right and top either the displacement (`traction = false`)
/// or the traction `sigma n` (right: `(E a sin(w t), 0)`, top: free).
/// With `pd`, the peridynamic model (horizon 0.3, m = 3); time step `dt`.
fn scene(nu: f64, traction: bool, integrator: &str, pd: bool, dt: f64) -> Problem {
    let displacement = |part: &str| {
        format!("[[boundary]]\npart = \"{part}\"\nkind = \"displacement\"\nvalue = [\"a * sin(w*t) * x\", \"-nu * a * sin(w*t) * y\"]\n")
    };
    let (right, top) = if traction {
        (
            "[[boundary]]\npart = \"right\"\nkind = \"traction\"\nvalue = [\"a * sin(w*t)\", 0]\n".to_string(),
            "[[boundary]]\npart = \"top\"\nkind = \"traction\"\nvalue = [0, 0]\n".to_string(),
        )
    } else {
        (displacement("right"), displacement("top"))
    };
    let model = if pd {
        "model = \"peridynamics\"\n[peridynamics]\nhorizon = 0.3\nm = 3\nkernel = \"plain\"\nquadrature = \"full-area\"\n"
    } else {
        ""
    };
    let text = format!(
        r#"
name = "time_loads"
body_force = ["-(w^2) * a * sin(w*t) * x", "w^2 * nu * a * sin(w*t) * y"]
{model}
[constants]
a = {A:e}
w = {W:e}
nu = {nu:e}

[[domain.region]]
shape = "rectangle"
min = [0.0, 0.0]
max = [1.0, 1.0]

[nodes]
spacing = 0.1
fill = "grid"

[approximation]
basis = "tensor"
support = 13

[material]
E = 1.0
nu = {nu:e}
plane = "stress"

[dynamics]
density = 1.0
end_time = 1.0
integrator = "{integrator}"
initial_velocity = ["w * a * x", "-w * nu * a * y"]
time_step = {dt:e}

{}
{}
{right}
{top}
"#,
        displacement("left"),
        displacement("bottom"),
    );
    Problem::from_str(&text, Path::new("time_loads.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// Largest error of `u` against the exact field at time `t`, relative to `a`.
fn error(positions: &[[f64; 2]], u: &[[f64; 2]], t: f64, nu: f64) -> f64 {
    positions.iter().zip(u).map(|(&p, u)| (0..2).map(|c| (u[c] - exact(p, t, nu)[c]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max) / A
}

/// The time steps of the order measurements: w dt = 0.075 and 0.0375.
const STEPS: [f64; 2] = [1.0 / 40.0, 1.0 / 80.0];

/// Observed order between the two steps of [`STEPS`].
fn order(errors: [f64; 2]) -> f64 {
    (errors[0] / errors[1]).ln() / (STEPS[0] / STEPS[1]).ln()
}

/// MLSM elastodynamics with a time-dependent body force, displacement on two sides
/// and a time-dependent traction on the right: at t = 1 (0.48 of a period of the
/// load) the error is the time integration's alone, so it falls with the scheme's
/// order when the step halves: RK4 4, Verlet 2 (each within 0.3: the two steps are in
/// the asymptotic range, w dt <= 0.075). A spatial error, or a load read at the wrong
/// time (t = 0, or the start of an RK4 stage), would not halve away: an RK4 stage at
/// the wrong time is an O(dt) error per step. The velocities of the boundary nodes
/// come from d/dt of the formulas (module docs of navier::dynamics) and fall the same
/// way.
#[test]
fn mlsm_follows_time_dependent_tractions_displacements_and_body_force() {
    let nu = 0.25;
    for (integrator, expected) in [("rk4", 4.0), ("verlet", 2.0)] {
        let (mut eu, mut ev) = ([0.0; 2], [0.0; 2]);
        for (k, dt) in STEPS.into_iter().enumerate() {
            let p = scene(nu, true, integrator, false, dt);
            let sim = mlsm::models::navier::simulate(&p.case, &p.navier, p.case.dynamics.as_ref().unwrap(), &Silent, |_| Ok(())).unwrap();
            let t = sim.energies.last().unwrap()[0];
            assert!((t - 1.0).abs() < 1e-12, "{t}");
            eu[k] = error(&sim.positions, &sim.u, t, nu);
            let c = W * A * (W * t).cos();
            ev[k] = sim
                .positions
                .iter()
                .zip(&sim.v)
                .map(|(&p, v)| (v[0] - c * p[0]).abs().max((v[1] + nu * c * p[1]).abs()))
                .fold(0.0, f64::max)
                / (W * A);
        }
        let (ou, ov) = (order(eu), order(ev));
        eprintln!("MLSM {integrator}: max |u - u_exact| / a = {:.2e}, {:.2e} (order {ou:.2}), max |v - v_exact| / (w a) = {:.2e}, {:.2e} (order {ov:.2})", eu[0], eu[1], ev[0], ev[1]);
        assert!((ou - expected).abs() < 0.3 && (ov - expected).abs() < 0.3, "{integrator}: orders {ou} {ov}");
    }
}

/// A time-dependent load changes the result: the same scene with `t` frozen at 0 in
/// every load (constant loads, here zero body force and boundary values) stays at
/// the initial motion, far from the exact field (guards against `t` silently read as 0).
#[test]
fn frozen_time_differs() {
    let nu = 0.25;
    let p = scene(nu, true, "rk4", false, STEPS[0]);
    let mut frozen = p.clone();
    frozen.case.body_force = frozen.case.body_force.at_time(0.0);
    for c in &mut frozen.case.conditions {
        c.value = c.value.at_time(0.0);
    }
    let sim = mlsm::models::navier::simulate(&frozen.case, &frozen.navier, frozen.case.dynamics.as_ref().unwrap(), &Silent, |_| Ok(())).unwrap();
    let e = error(&sim.positions, &sim.u, 1.0, nu);
    eprintln!("MLSM with loads frozen at t = 0: max |u - u_exact| / a = {e:.2e}");
    assert!(e > 0.1, "{e}");
}

/// Peridynamics with the displacement formulas on every side (so on the whole
/// Dirichlet collar, evaluated at every force evaluation) and the time-dependent
/// body force: the bond forces of the affine field cancel, and the error is RK4's,
/// falling with order 4 (within 0.3) when the step halves. nu = 1/3, the value
/// bond-based PD represents in plane stress.
#[test]
fn peridynamics_follows_a_moving_collar_and_body_force() {
    let nu = 1.0 / 3.0;
    let mut e = [0.0; 2];
    for (k, dt) in STEPS.into_iter().enumerate() {
        let p = scene(nu, false, "rk4", true, dt);
        let sim =
            mlsm::models::peridynamics::simulate(&p.case, p.model.peridynamics().unwrap(), p.case.dynamics.as_ref().unwrap(), &Silent, |_| Ok(()))
                .unwrap();
        let nodes = &sim.discretisation.nodes;
        let t = sim.energies.last().unwrap()[0];
        assert!((t - 1.0).abs() < 1e-12, "{t}");
        e[k] = error(&nodes.positions[..nodes.free], &sim.u, t, nu);
    }
    eprintln!("PD rk4: max |u - u_exact| / a = {:.2e}, {:.2e} (order {:.2})", e[0], e[1], order(e));
    assert!((order(e) - 4.0).abs() < 0.3, "{e:?}");
}

/// A load formula that stops being finite during the run (`1 / (t - 0.5)` at t = 0.5
/// of a step) is reported with its field, formula and time, not as a divergence.
#[test]
fn a_load_that_blows_up_in_time_names_its_formula() {
    let mut text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/steel_plate_dynamic.toml")).unwrap();
    text = text.replace(
        "[[boundary]]\npart = \"right\"\nkind = \"traction\"\nvalue = [0.0, 0.0]",
        "[[boundary]]\npart = \"right\"\nkind = \"traction\"\nvalue = [\"1e6 * sqrt(1e-4 - t)\", 0]",
    );
    assert!(text.contains("sqrt(1e-4 - t)"));
    for model in ["navier", "peridynamics"] {
        let mut q = Problem::from_str(&text, Path::new("blowup.toml")).unwrap();
        q.model.peridynamics_mut().unwrap().horizon = 0.3;
        let dynamics = q.case.dynamics.as_ref().unwrap();
        let err = match model {
            "navier" => mlsm::models::navier::simulate(&q.case, &q.navier, dynamics, &Silent, |_| Ok(())).err(),
            _ => mlsm::models::peridynamics::simulate(&q.case, q.model.peridynamics().unwrap(), dynamics, &Silent, |_| Ok(())).err(),
        };
        let err = err.unwrap_or_else(|| panic!("{model}: the run should fail"));
        let message = err.to_string();
        eprintln!("{model}: {message}");
        assert!(matches!(err, RunError::BadFormula { .. }), "{model}: {message}");
        assert!(
            message.contains("boundary[1].value[0]") && message.contains("sqrt(1e-4 - t)") && message.contains(") at t = 1.0"),
            "{model}: {message}"
        );
    }
}

/// `t` is refused where it has no meaning: in a static scene, and in the initial
/// state of a dynamic one; the message names the field.
#[test]
fn time_is_refused_outside_dynamic_loads() {
    let base = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/steel_plate_dynamic.toml")).unwrap();
    let initial = base.replace("initial_velocity = { x = [-5.0, 10.0, 0.0], y = [0.0, 0.0, 0.0] }", "initial_velocity = [\"t\", 0]");
    let e = Problem::from_str(&initial, Path::new("s.toml")).unwrap_err().to_string();
    assert!(e.contains("dynamics.initial_velocity[0]") && e.contains("[dynamics]"), "{e}");
    let dam = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/gravity_dam.toml")).unwrap();
    let static_t = dam.replace("body_force = [0.0, \"-rho_c * g\"]", "body_force = [\"t\", \"-rho_c * g\"]");
    assert_ne!(static_t, dam);
    let e = Problem::from_str(&static_t, Path::new("s.toml")).unwrap_err().to_string();
    assert!(e.contains("body_force[0]") && e.contains("the time t exists only"), "{e}");
}

/// problems/plate_pulse.toml: the pulse `p0 sin(pi t / T)^2` on the right edge has
/// not reached the clamp at t_end = T (the wave travels about 0.53 m of the 1 m), so
/// the plate's total x-momentum equals the load's impulse `H p0 T / 2` = 1500 N s/m,
/// and its y-momentum is zero. PD: `sum rho V_i v_i` over the free nodes; the
/// traction layer carries exactly the edge load at every instant, so only RK4's
/// error over 14 steps and round-off are left: measured 1.2e-9 (x) and 4e-17 (y) of
/// the impulse, tolerances 1e-6 and 1e-10. MLSM: the lumped Delaunay areas weigh the
/// nodal velocities only approximately: measured 4.7e-4 (x) and 4.1e-6 (y),
/// tolerances 5e-3 and 1e-4.
#[test]
fn the_shipped_pulse_gives_the_plate_the_impulse_of_its_load() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/plate_pulse.toml");
    let p = Problem::from_str(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    let (rho, impulse) = (8000.0, 0.3 * 100e6 * 1e-4 / 2.0);
    let dynamics = p.case.dynamics.as_ref().unwrap();
    let pd = mlsm::models::peridynamics::simulate(&p.case, p.model.peridynamics().unwrap(), dynamics, &Silent, |_| Ok(())).unwrap();
    let volumes = &pd.discretisation.nodes.volumes;
    let pd_momentum = (0..2).map(|c| pd.v.iter().zip(volumes).map(|(v, w)| rho * w * v[c]).sum::<f64>()).collect::<Vec<_>>();
    let navier = mlsm::models::navier::simulate(&p.case, &p.navier, dynamics, &Silent, |_| Ok(())).unwrap();
    let areas = mlsm::domain::cells::nodal_areas(&navier.positions, &mlsm::domain::cells::cells_inside(&p.case.domain, &navier.positions));
    let mlsm_momentum = (0..2).map(|c| navier.v.iter().zip(&areas).map(|(v, a)| rho * a * v[c]).sum::<f64>()).collect::<Vec<_>>();
    let rel = |m: &[f64]| ((m[0] - impulse).abs() / impulse, m[1].abs() / impulse);
    let (pd_x, pd_y) = rel(&pd_momentum);
    let (ml_x, ml_y) = rel(&mlsm_momentum);
    eprintln!("impulse {impulse}: PD momentum {pd_momentum:?} (x off by {pd_x:.1e}), MLSM {mlsm_momentum:?} (x off by {ml_x:.1e})");
    assert!(pd_x < 1e-6 && pd_y < 1e-10, "PD {pd_x} {pd_y}");
    assert!(ml_x < 5e-3 && ml_y < 1e-4, "MLSM {ml_x} {ml_y}");
}

/// plate_pulse with a pulse ten times shorter (`T = 1e-5`: time scale `T / pi` =
/// 3.2e-6 s) at the step the scene's stability rule picks for RK4 (7.1e-6 s, 0.45 steps
/// per time scale, RK4's error per radian 0.21) is warned (`load-time-resolution`), and
/// the warning is right: the final displacement is off the one at a 114x finer step
/// by 9.5e-3 of max |u| (measured; bound 3e-3), about the threshold; at 2e-6 s (1.6
/// steps per time scale, error per radian 1.3e-3) it is not warned and is off by
/// 2.0e-5 (bound 1e-4). (PD: the cheaper model on this scene; the check looks only at
/// the loads.)
#[test]
fn a_load_faster_than_the_step_resolves_is_warned() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/plate_pulse.toml");
    let text = std::fs::read_to_string(&path).unwrap().replace("T = 1e-4", "T = 1e-5");
    let run = |time_step: Option<f64>| {
        let text = match time_step {
            Some(dt) => text.replace("integrator = \"rk4\"", &format!("integrator = \"rk4\"\ntime_step = {dt:e}")),
            None => text.clone(),
        };
        let p = Problem::from_str(&text, &path).unwrap();
        let dynamics = p.case.dynamics.as_ref().unwrap();
        let pd = mlsm::models::peridynamics::simulate(&p.case, p.model.peridynamics().unwrap(), dynamics, &Silent, |_| Ok(())).unwrap();
        let dt = pd.report.time_step;
        let pd_spacing = p.model.peridynamics().map(|pd| pd.horizon / pd.ratio).unwrap();
        let warning = mlsm::quality::warnings::load_time_resolution(&p.case, pd_spacing, dt, dynamics.end_time, dynamics.integrator, 1e-2);
        (pd.u, dt, warning)
    };
    let (reference, _, _) = run(Some(6.25e-8));
    let scale = reference.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let off =
        |u: &[[f64; 2]]| u.iter().zip(&reference).flat_map(|(a, b)| [a[0] - b[0], a[1] - b[1]]).fold(0.0f64, |m, x| m.max(x.abs())) / scale;
    let (coarse, dt, warned) = run(None);
    let warned = warned.expect("the stability step does not resolve the short pulse");
    assert!(warned.message.contains("boundary[1].value") && warned.message.contains("dynamics.time_step"), "{}", warned.message);
    let (fine, dt_fine, quiet) = run(Some(2e-6));
    let (coarse_off, fine_off) = (off(&coarse), off(&fine));
    eprintln!("dt {dt:.2e}: off by {coarse_off:.1e} (warned); dt {dt_fine:.2e}: off by {fine_off:.1e}");
    assert!(quiet.is_none(), "{:?}", quiet.map(|w| w.message));
    assert!(coarse_off > 3e-3 && fine_off < 1e-4, "{coarse_off:e} {fine_off:e}");
}

/// A narrow spot of pressure (width w = 5e-4 m) swaying on the right edge of plate_pulse
/// between two points of the bounding-box lattice (y = 0 and 0.075): centred at
/// `y = 0.04 + 0.01 sin(omega t)`, at least 50 w from the lattice, where its value
/// underflows to zero, so that the lattice alone saw no load in t at all. Read at the
/// boundary samples of the run's spacing (1.7e-2 m, which the spot sweeps across), a
/// fast sway (omega = 6.3e4 /s: a sample is crossed in about w / (0.86 v) = 9e-7 s, an
/// eighth of the 7.1e-6 s step) is warned; a slow one (omega = 100 /s, 2.6 steps per
/// time scale at the nearest sample) is not.
#[test]
fn a_narrow_moving_load_is_read_where_it_acts() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/plate_pulse.toml");
    let check = |omega: f64, spacing: Option<f64>| {
        let load = format!("value = [\"p0 * exp(-(((y - 0.04 - 0.01 * sin({omega:e} * t)) / 5e-4)^2))\", 0.0]");
        let text = std::fs::read_to_string(&path).unwrap().replace("value = [\"p0 * sin(pi * t / T)^2\", 0.0]", &load);
        assert!(text.contains(&load), "the edit must hit the right edge's load");
        let p = Problem::from_str(&text, &path).unwrap();
        let d = p.case.dynamics.as_ref().unwrap();
        let pd = p.model.peridynamics().copied().unwrap();
        let h = spacing.unwrap_or(pd.horizon / pd.ratio);
        mlsm::quality::warnings::load_time_resolution(&p.case, h, 7.1e-6, d.end_time, d.integrator, 1e-2)
    };
    let fast = check(6.3e4, None).expect("a spot crossing a sample in 9e-7 s is not resolved by 7.1e-6 s steps");
    assert!(fast.message.contains("boundary[1].value"), "{}", fast.message);
    assert!(check(100.0, None).is_none(), "a slow sway is resolved");
    // Read only at the corners and the lattice (a spacing of the plate's length), the
    // spot underflows everywhere and is missed: what the lattice alone did.
    assert!(check(6.3e4, Some(1.0)).is_none(), "the corners and the lattice do not see the spot");
}
