//! What bond breaking costs an explicit step, measured in one process with the steps
//! alternated one by one, so that a machine whose speed drifts by 10-30 % from run to
//! run (ours does) slows both sides alike. The seed's steel plate set in motion
//! (problems/steel_plate_dynamic.toml, m = 6, Verlet at dt = 2e-7 s) at two horizons,
//! about 1e5 and 1e6 bonds per thread on 2 threads; each law with a critical stretch no
//! bond reaches (`s0 = 1`: the bookkeeping alone) and with `s0 = 2e-4` (the plate
//! shatters: a third of the bonds break).
//!
//! Each step of the run with `[peridynamics.fracture]` (the step and its breaking) is
//! timed, and beside it, on a copy of the same state, a step of the same law without
//! fracture and a step of the linear law without fracture; the three go in turn, the
//! first of them changed every step. Each side reads its own bond coefficients, as a
//! run does (two sides sharing one array kept it warm in the cache for each other: at
//! 1e6 bonds per thread that read 0.05-0.1 too high a ratio). Printed: each side's
//! seconds summed over the steps, of the first the breaking after the steps, and the
//! ratios "with breaking / the same law without" and "with breaking / the linear law
//! without".
//!
//! cargo bench --bench breaking_step -- [--rounds 3] [--only LAW] [--horizon DELTA]
//!     (rounds: the whole set again, the medians of the rounds' ratios printed last;
//!     LAW: linear or bond-stretch alone; DELTA: 0.075 or 0.0237 alone)

use mlsm::models::dynamics::SecondOrderSystem;
use mlsm::models::peridynamics::dynamics::PdDynamics;
use mlsm::models::peridynamics::operator::Bonds;
use mlsm::models::peridynamics::simulation::with_system;
use mlsm::models::peridynamics::BondForce;
use mlsm::scene::problem::Problem;
use mlsm::stages::{Silent, StageTimer};
use std::path::Path;
use std::time::Instant;

/// Seconds summed over the steps: with breaking, the same law without, the linear law
/// without, and of the first the breaking after the steps; the bonds broken and all bonds.
fn measure(delta: f64, end: f64, law: &str, s0: f64) -> ([f64; 4], usize, usize) {
    let path = Path::new("problems/steel_plate_dynamic.toml");
    let text = std::fs::read_to_string(path).expect("run from the repository's root");
    let text = text
        .replace("integrator = \"rk4\"", "integrator = \"verlet\"")
        .replace("snapshots = 20", "snapshots = 0\ntime_step = 2e-7")
        .replace("end_time = 1e-3", &format!("end_time = {end}"))
        .replace("horizon = 0.1", &format!("horizon = {delta}"))
        .replace("quadrature = \"full-area\"", &format!("quadrature = \"full-area\"\nforce = \"{law}\""));
    let text = format!("{text}\n[estimate]\nmethod = \"none\"\n[peridynamics.fracture]\ncritical_stretch = {s0}\n");
    let p = Problem::from_str(&text, path).unwrap_or_else(|e| panic!("{e}"));
    let params = p.model.peridynamics().expect("a peridynamic scene");
    let dynamics = p.case.dynamics.as_ref().expect("a [dynamics] table");
    let mut timer = StageTimer::new(&Silent);
    let ((seconds, broken, bonds), _) = with_system(&p.case, params, dynamics, &mut timer, |system, disc, mut state, grid, _| {
        let plain = PdDynamics { breaking: None, ..*system };
        // Each side reads its own coefficients, as a run does: two sides sharing one
        // array would keep it warm in the cache for each other.
        let own: Vec<f64> = system.bonds.coefficients.to_vec();
        let linear = PdDynamics { force: BondForce::Linear, bonds: Bonds { coefficients: &own, ..plain.bonds }, ..plain };
        let (mut seconds, mut settling) = ([0.0; 3], 0.0);
        for step in 0..grid.steps {
            let mut copies = [state.clone(), state.clone()];
            for k in 0..3 {
                let side = (k + step) % 3;
                let t0 = Instant::now();
                match side {
                    0 => {
                        dynamics.integrator.step(system, &mut state, grid.dt);
                        let t1 = Instant::now();
                        system.settle(&mut state);
                        settling += t1.elapsed().as_secs_f64();
                    }
                    1 => dynamics.integrator.step(&plain, &mut copies[0], grid.dt),
                    _ => dynamics.integrator.step(&linear, &mut copies[1], grid.dt),
                }
                seconds[side] += t0.elapsed().as_secs_f64();
            }
        }
        let broken = system.breaking.map_or(0, |b| b.released().0);
        Ok(([seconds[0], seconds[1], seconds[2], settling], broken, disc.families.bonds()))
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (seconds, broken, bonds)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rounds: usize =
        args.iter().position(|a| a == "--rounds").and_then(|k| args.get(k + 1)).map_or(1, |r| r.parse().expect("--rounds N"));
    let only = args.iter().position(|a| a == "--only").and_then(|k| args.get(k + 1)).cloned();
    let laws: Vec<&str> = ["linear", "bond-stretch"].into_iter().filter(|l| only.as_deref().is_none_or(|o| o == *l)).collect();
    let horizon: Option<f64> =
        args.iter().position(|a| a == "--horizon").and_then(|k| args.get(k + 1)).map(|d| d.parse().expect("--horizon DELTA"));
    let cases: Vec<(f64, f64)> = [(0.075, 2e-4), (0.0237, 4e-5)].into_iter().filter(|c| horizon.is_none_or(|d| d == c.0)).collect();
    let mut ratios: Vec<Vec<[f64; 2]>> = Vec::new();
    println!("| round | delta | bonds | law | s0 | with breaking s | of which breaking s | same law without s | linear without s | / same law | / linear | bonds broken |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for round in 1..=rounds {
        let mut k = 0;
        for &(delta, end) in &cases {
            for &law in &laws {
                for s0 in [1.0, 2e-4] {
                    let ([with, without, linear, settling], broken, bonds) = measure(delta, end, law, s0);
                    let r = [with / without, with / linear];
                    println!(
                        "| {round} | {delta} | {bonds} | {law} | {s0:e} | {with:.3} | {settling:.3} | {without:.3} | {linear:.3} | {:.2} | {:.2} | {broken} |",
                        r[0], r[1]
                    );
                    if ratios.len() <= k {
                        ratios.push(Vec::new());
                    }
                    ratios[k].push(r);
                    k += 1;
                }
            }
        }
    }
    if rounds > 1 {
        println!("\nMedians over {rounds} rounds (order as above): / same law, / linear");
        for r in &ratios {
            let median = |i: usize| {
                let mut v: Vec<f64> = r.iter().map(|x| x[i]).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            println!("{:.2} {:.2}", median(0), median(1));
        }
    }
}
