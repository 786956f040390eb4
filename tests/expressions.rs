//! Formulas in scene files: every site where an expression can stand (boundary
//! values, body force, initial state, `[exact] kind = "expression"`), the scenes that
//! use them, and the errors a wrong formula gives.
mod common;

use common::{f, s, scene, solve};
use mlsm::models::navier::Solution;
use mlsm::scene::problem::Problem;

/// The trapezoidal law of dam engineering: on the horizontal section at height `y0`
/// (width `b`, from the vertical upstream face x = 0), `sigma_yy = -N/b + k (x - b/2)`
/// with `N` the weight above the section and `k b^3/12` the moment of the weight and
/// of the water about the section's centre (dam of `tests/../problems/gravity_dam.toml`
/// with crest width `crest`).
fn trapezoidal_law(crest: f64, y0: f64, x: f64) -> f64 {
    let (h, base, g, rho_w, rho_c) = (100.0, 80.0, 9.81, 1000.0, 2400.0);
    let b = base + (crest - base) * y0 / h;
    let depth = h - y0;
    // The part above the section: a rectangle of width `crest` and a triangle of width `b - crest`.
    let (rect, tri) = (crest * depth, 0.5 * (b - crest) * depth);
    let area = rect + tri;
    let centroid = (rect * crest / 2.0 + tri * (crest + (b - crest) / 3.0)) / area;
    let weight = rho_c * g * area;
    let water = 0.5 * rho_w * g * depth * depth;
    let xc = b / 2.0;
    let moment = -weight * (centroid - xc) - water * depth / 3.0;
    -weight / b + 12.0 * moment / b.powi(3) * (x - xc)
}

/// Largest `|sigma_yy - law|` over the nodes within 2 m of height `y0`, relative to the
/// law's peak there.
fn deviation_from_law(sol: &Solution, crest: f64, y0: f64) -> f64 {
    let sigma = &sol.stress.as_ref().unwrap().sigma;
    let (mut worst, mut peak, mut count) = (0.0f64, 0.0f64, 0);
    for (q, s) in sol.nodes.positions.iter().zip(sigma) {
        if (q[1] - y0).abs() < 2.0 {
            let law = trapezoidal_law(crest, q[1], q[0]);
            worst = worst.max((s[1] - law).abs());
            peak = peak.max(law.abs());
            count += 1;
        }
    }
    assert!(count > 30, "{count} nodes near y = {y0}");
    worst / peak
}

/// The shipped gravity dam (loads written as formulas) against the trapezoidal law at
/// mid-height, half a base width above the clamped foundation. The law neglects the
/// crest and the taper of the sections, so it is itself only approximate for a
/// trapezoid: measured deviation 8.3 % of the section's peak at h = 1 m and 8.1 % at
/// h = 0.5 m (so it is the law's error, not the discretisation's); bound 10 %.
///
/// With the crest removed the dam is a wedge, for which the law is the exact
/// elasticity solution (Levy 1898) away from the foundation: measured 0.05 % at
/// y = 85 m (0.7 % at 70 m, 2.9 % at 50 m: the clamp's disturbance decays upwards);
/// bound 0.5 %.
#[test]
fn gravity_dam_follows_the_trapezoidal_law_away_from_the_foundation() {
    let dam = solve(&scene("gravity_dam", &[]));
    let trapezoid = deviation_from_law(&dam, 5.0, 50.0);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/gravity_dam.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let wedge_text = text
        .replace("[[0.0, 0.0], [80.0, 0.0], [5.0, 100.0], [0.0, 100.0]]", "[[0.0, 0.0], [80.0, 0.0], [0.0, 100.0]]")
        .replace("[\"foundation\", \"downstream\", \"crest\", \"upstream\"]", "[\"foundation\", \"downstream\", \"upstream\"]")
        .replace("[[boundary]]\npart = \"crest\"\nkind = \"traction\"\nvalue = [0.0, 0.0]\n", "");
    let wedge = solve(&Problem::from_str(&wedge_text, &path).unwrap());
    let levy = deviation_from_law(&wedge, 0.0, 85.0);
    eprintln!("gravity dam: trapezoid at y = 50: {trapezoid:.4}; wedge at y = 85: {levy:.5}");
    assert!(trapezoid < 0.10, "trapezoid: deviation {trapezoid:.3} of the peak");
    assert!(levy < 0.005, "wedge: deviation {levy:.4} of the peak");
}

/// The published MLSM setting of the cantilever (a discretisation error of ~1e-4, so
/// the comparison below is not hidden behind round-off).
fn published() -> Vec<(&'static str, Option<toml::Value>)> {
    vec![
        ("approximation.basis", s("tensor")),
        ("approximation.degree", common::i(2)),
        ("approximation.weight", s("gaussian")),
        ("approximation.sigma", f(1.0)),
        ("approximation.support", common::i(13)),
        ("approximation.exponent", None),
    ]
}

/// Largest difference of two displacement fields on the same nodes, relative to the
/// largest displacement.
fn field_difference(a: &Solution, b: &Solution) -> f64 {
    assert_eq!(a.nodes.positions, b.nodes.positions);
    let peak = b.displacement.iter().flat_map(|u| u.iter()).fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a.displacement.iter().zip(&b.displacement).flat_map(|(u, v)| [u[0] - v[0], u[1] - v[1]]);
    diff.fold(0.0f64, |m, d| m.max(d.abs())) / peak
}

/// Formula loads (parabolic shear, Timoshenko's clamp displacement) give the solution
/// of the `"exact"` loads: the two evaluate the same formulas in a different order,
/// so only round-off differs (measured 2e-12 of the peak displacement; bound 1e-9,
/// far below the discretisation error 1e-4 of this setting).
#[test]
fn formula_loads_reproduce_the_exact_loads_of_the_cantilever() {
    let exact = solve(&scene("cantilever", &published()));
    let formula = solve(&scene("cantilever_traction", &published()));
    let d = field_difference(&formula, &exact);
    let (ea, eb) = (exact.errors.unwrap().e_inf_u, formula.errors.unwrap().e_inf_u);
    eprintln!("cantilever: fields differ by {d:.2e}; e_inf(u) {ea:.6e} vs {eb:.6e}");
    assert!(ea > 1e-6, "the setting must have a visible discretisation error: {ea:e}");
    assert!(d < 1e-9, "{d:e}");
}

/// `[exact] kind = "expression"` with the shipped manufactured field derives the same
/// body force, boundary values and errors as `kind = "manufactured"` (round-off only:
/// measured 1e-13 of the peak displacement; bound 1e-9).
#[test]
fn expression_exact_solution_reproduces_the_manufactured_one() {
    let named = solve(&scene("manufactured_traction", &[]));
    let edits = [("exact.kind", s("expression")), ("exact.ux", s("sin(pi*x)*cos(pi*y)")), ("exact.uy", s("x^2*y^3"))];
    let derived = solve(&scene("manufactured_traction", &edits));
    let d = field_difference(&derived, &named);
    eprintln!("manufactured: fields differ by {d:.2e}");
    assert!(d < 1e-9, "{d:e}");
    let (a, b) = (named.errors.unwrap(), derived.errors.unwrap());
    assert!((a.e_inf_sigma.unwrap() - b.e_inf_sigma.unwrap()).abs() <= 1e-6 * a.e_inf_sigma.unwrap());
}

/// A polynomial written as a formula runs like `kind = "polynomial"` (patch test: both
/// reproduce the cubic to round-off on degree-3 stencils).
#[test]
fn polynomial_formula_reproduces_the_polynomial_solution() {
    let ux = [1e-3, 2e-3, -1e-3, 3e-3, 1e-3, -2e-3, 1e-3, 2e-3, -3e-3, 1e-3];
    let uy = [0.0, -1e-3, 2e-3, 1e-3, -1e-3, 2e-3, -2e-3, 1e-3, 1e-3, -1e-3];
    let array = |c: [f64; 10]| Some(toml::Value::Array(c.iter().map(|&v| toml::Value::Float(v)).collect()));
    let text = |c: [f64; 10]| {
        let monomials = ["1", "x", "y", "x^2", "x*y", "y^2", "x^3", "x^2*y", "x*y^2", "y^3"];
        c.iter().zip(monomials).map(|(c, m)| format!("({c:e})*{m}")).collect::<Vec<_>>().join(" + ")
    };
    let base = [("approximation.degree", common::i(3)), ("approximation.support", common::i(16))];
    let mut poly: Vec<(&str, Option<toml::Value>)> = base.to_vec();
    poly.extend([("exact.kind", s("polynomial")), ("exact.ux", array(ux)), ("exact.uy", array(uy))]);
    let mut formula: Vec<(&str, Option<toml::Value>)> = base.to_vec();
    formula.extend([("exact.kind", s("expression")), ("exact.ux", s(&text(ux))), ("exact.uy", s(&text(uy)))]);
    let (a, b) = (solve(&scene("manufactured_traction", &poly)), solve(&scene("manufactured_traction", &formula)));
    let d = field_difference(&b, &a);
    let (ea, eb) = (a.errors.unwrap().e_inf_u, b.errors.unwrap().e_inf_u);
    eprintln!("polynomial: fields differ by {d:.2e}; e_inf(u) {ea:.2e} vs {eb:.2e}");
    assert!(d < 1e-9 && ea < 1e-8 && eb < 1e-8, "{d:e} {ea:e} {eb:e}");
}

/// A body force given as a formula equals the same constant given as numbers, and an
/// initial velocity given as formulas equals the affine table (same nodes, same
/// numbers, so the same result to round-off).
#[test]
fn body_force_and_initial_state_formulas_match_their_numeric_forms() {
    let numbers = Some(toml::Value::Array(vec![toml::Value::Float(2e6), toml::Value::Float(-1e6)]));
    let formulas = Some(toml::Value::Array(vec![toml::Value::String("2e6 + 0*x".into()), toml::Value::String("-1e6*(y - y + 1)".into())]));
    let (n, e) = (solve(&scene("steel_plate", &[("body_force", numbers)])), solve(&scene("steel_plate", &[("body_force", formulas)])));
    let d = field_difference(&e, &n);
    assert!(d <= 1e-12, "body force as formula: fields differ by {d:e}");
    let (a, b) = (
        scene("steel_plate_dynamic", &[("dynamics.end_time", f(1e-4))]),
        scene(
            "steel_plate_dynamic",
            &[
                ("dynamics.end_time", f(1e-4)),
                (
                    "dynamics.initial_velocity",
                    Some(toml::Value::Array(vec![toml::Value::String("-5 + 10*x".into()), toml::Value::Float(0.0)])),
                ),
            ],
        ),
    );
    assert_ne!(a.case.dynamics.as_ref().unwrap().initial_velocity, b.case.dynamics.as_ref().unwrap().initial_velocity);
    let run = |p: &Problem| {
        let mlsm::models::dispatch::Outcome::PdDynamic(sim) = mlsm::models::dispatch::solve(p, &mlsm::stages::Silent, |_| Ok(())).unwrap() else {
            panic!("a peridynamic dynamic run")
        };
        sim.v
    };
    let (va, vb) = (run(&a), run(&b));
    let worst = va.iter().zip(&vb).flat_map(|(p, q)| [p[0] - q[0], p[1] - q[1]]).fold(0.0f64, |m, d| m.max(d.abs()));
    assert!(worst <= 1e-12, "velocities differ by {worst:e}");
}

/// Run `mlsm run` on `text` (written to a temporary scene file); exit code and stderr.
fn run_scene(text: &str, name: &str) -> (i32, String) {
    let dir = tempfile::TempDir::new().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mlsm"))
        .args(["--quiet", "run"])
        .arg(&path)
        .arg("--out")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// problems/manufactured_dirichlet.toml with `from` replaced by `to` (each must occur).
fn edited(pairs: &[(&str, &str)]) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/manufactured_dirichlet.toml");
    // The same field as a formula: `kind = "manufactured"` insists on its own body force.
    let mut text = std::fs::read_to_string(path)
        .unwrap()
        .replace("spacing = 0.025", "spacing = 0.1")
        .replace("kind = \"manufactured\"", "kind = \"expression\"\nux = \"sin(pi*x)*cos(pi*y)\"\nuy = \"x^2*y^3\"");
    for (from, to) in pairs {
        assert!(text.contains(from), "{from}");
        text = text.replacen(from, to, 1);
    }
    text
}

/// Wrong formulas and over-long arrays: exit 2, a message with the file, the field
/// and the formula; for a value that is not finite at a node, also the node's position.
#[test]
fn wrong_formulas_and_arrays_are_refused_with_the_field() {
    let body = "body_force = \"exact\"";
    let cases: Vec<(String, Vec<&str>)> = vec![
        (edited(&[(body, "body_force = [\"z * x\", 0]\n[constants]\nP = 1")]), vec!["body_force[0]", "unknown name \"z\"", "P"]),
        (edited(&[(body, "body_force = [\"sin(x\", 0]")]), vec!["body_force[0]", "unbalanced parentheses"]),
        (edited(&[(body, "body_force = [0, \"-x^2\"]")]), vec!["body_force[1]", "sign before a power"]),
        (edited(&[(body, "body_force = [\"1/x\", 0]")]), vec!["scene.toml", "body_force[0]", "\"1/x\"", "inf", "(0.000000e0, "]),
        (edited(&[(body, "body_force = [0, \"sqrt(x - 0.5)\"]")]), vec!["body_force[1]", "NaN", "at ("]),
        (edited(&[(body, "body_force = [1, 2, 3]")]), vec!["body_force", "exactly 2 components [x, y], got 3"]),
        (edited(&[("min = [0.0, 0.0]", "min = [0.0, 0.0, 1.0]")]), vec!["domain.region[0].min", "exactly 2 numbers"]),
        (edited(&[("ux = \"sin(pi*x)*cos(pi*y)\"", "ux = \"abs(x)\"")]), vec!["exact.ux", "differentiated"]),
        (edited(&[(body, "body_force = \"exact\"\n[constants]\nE = 2")]), vec!["constants.E", "choose another name"]),
        (edited(&[(body, "body_force = \"exact\"\n[constants]\na = \"b + 1\"\nb = \"a\"")]), vec!["constants.a", "cycle of 2: a -> b -> a"]),
        (edited(&[(body, "body_force = \"exact\"\n[constants]\na = \"b + 1\"\nb = \"2e3 * zz\"")]), vec!["constants.b", "unknown name \"zz\""]),
    ];
    for (text, wanted) in cases {
        let (code, err) = run_scene(&text, "scene.toml");
        assert_eq!(code, 2, "{wanted:?}: {err}");
        for w in wanted {
            assert!(err.contains(w), "missing {w:?} in: {err}");
        }
    }
}

/// A disc centre, a polygon vertex and an initial velocity with extra numbers are
/// errors, not silently truncated.
#[test]
fn extra_numbers_in_fixed_arrays_are_errors() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
    let read = |n: &str| std::fs::read_to_string(root.join(n)).unwrap();
    let cases = [
        (read("kirsch.toml").replacen("center = [0.0, 0.0]", "center = [0.0, 0.0, 7.0]", 1), "center"),
        (read("bracket.toml").replacen("[0.06, 0.0]", "[0.06, 0.0, 1.0]", 1), "vertices"),
        (read("steel_plate_dynamic.toml").replacen("x = [-5.0, 10.0, 0.0]", "x = [-5.0, 10.0, 0.0, 1.0]", 1), "initial_velocity"),
    ];
    for (text, field) in cases {
        assert!(text.contains(", 1.0]") || text.contains("7.0]"), "edit applied for {field}");
        let (code, err) = run_scene(&text, "scene.toml");
        assert_eq!(code, 2, "{field}: {err}");
        // Serde names the expected length, or (for the two forms of an initial state) both forms.
        let says = err.contains("exactly") || err.contains("expected") || err.contains("[c0, cx, cy]");
        assert!(err.contains(field) && says, "{field}: {err}");
    }
}

/// A fixed time step above the stability limit is an error of the scene file: the
/// message names the file and the field.
#[test]
fn unstable_time_step_names_the_file() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/steel_plate_dynamic.toml");
    let text = std::fs::read_to_string(path).unwrap().replace("end_time = 1e-3", "end_time = 1e-3\ntime_step = 5e-4");
    let (code, err) = run_scene(&text, "plate.toml");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("plate.toml") && err.contains("dynamics.time_step") && err.contains("stable step"), "{err}");
}

/// A negative number on the command line reaches our check (not clap's "unexpected
/// argument" tip), and the message names the option.
#[test]
fn negative_command_line_numbers_name_the_option() {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/cantilever.toml");
    for (option, value) in
        [("--spacing", "-1"), ("--horizon", "-0.1"), ("--spacing", "0"), ("--spacing", "-1e-3"), ("--target-error", "-1e-3")]
    {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_mlsm")).arg("run").arg(&scene).args([option, value]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{option} {value}: {err}");
        assert!(err.contains(option) && err.contains("must be a positive number"), "{option} {value}: {err}");
    }
}

/// Formulas are checked where each model uses them: a displacement formula also in
/// the peridynamic Dirichlet collar outside the solid (`sqrt(x)` on the left edge is
/// NaN at x < 0), and a load in `t` of a Navier dynamic run must have a derivative in
/// `t` (the velocity the boundary rows impose). Both exit 2 naming the field.
#[test]
fn collar_and_time_formulas_are_checked_where_used() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
    let pd = std::fs::read_to_string(root.join("pd_trig.toml")).unwrap().replacen("value = \"exact\"", "value = [\"sqrt(x)\", 0]", 1);
    let (code, err) = run_scene(&pd, "collar.toml");
    assert_eq!(code, 2, "{err}");
    for w in ["collar.toml", "boundary[0].value[0]", "Dirichlet collar outside the solid", "sqrt(x)", "NaN", "at (-"] {
        assert!(err.contains(w), "missing {w:?} in: {err}");
    }
    let plate = std::fs::read_to_string(root.join("steel_plate_dynamic.toml"))
        .unwrap()
        .replace("model = \"peridynamics\"", "model = \"navier\"")
        .replace("spacing = 0.01", "spacing = 0.05")
        .replacen("value = [0.0, 0.0]", "value = [\"abs(sin(1000 * t))\", 0]", 1);
    let (code, err) = run_scene(&plate, "kink.toml");
    assert_eq!(code, 2, "{err}");
    for w in ["kink.toml", "boundary[0].value", "cannot be differentiated", "d/dt"] {
        assert!(err.contains(w), "missing {w:?} in: {err}");
    }
}
