//! The analogue of table 6.1.1 of seed 000: the steel plate set in motion
//! (problems/steel_plate_dynamic.toml, delta = 0.1 or --horizon), refined in h at the fixed horizon,
//! for several quadrature rules and kernels. Error = max |u_h - u_ref| (and the same
//! for v) at t_end over the free nodes at distance >= delta from the boundary, with the
//! reference (midpoint rule, m = --reference) interpolated at the coarse nodes by
//! degree-2 MLS; order = least-squares slope of log e against log h, and the smallest
//! order between consecutive levels (the worst step).
//!
//! cargo bench --bench plate_table -- [--horizon 0.1] [--reference 24]
//!     [--ratios 3,4,6,8] [--rules full-area,gauss2x2,triangle-p2] [--kernels plain,-2,0,1]
//!     [--perturbation P]   (the runs on a perturbed lattice, the seed's "random" rows;
//!     the reference stays the midpoint rule's lattice)

use mlsm::mlsm::interpolate::mls_values;
use mlsm::models::peridynamics::simulate;
use mlsm::models::peridynamics::solve::interior_flags;
use mlsm::models::peridynamics::{Kernel, PdParams, Quadrature};
use mlsm::quality::post::observed_order;
use mlsm::scene::choice::Choice;
use mlsm::scene::problem::Problem;
use mlsm::stages::Silent;
use std::path::Path;

struct Run {
    positions: Vec<[f64; 2]>,
    u: Vec<[f64; 2]>,
    v: Vec<[f64; 2]>,
    interior: Vec<bool>,
    seconds: f64,
}

fn run(p: &Problem, params: &PdParams) -> Run {
    let t0 = std::time::Instant::now();
    let dynamics = p.case.dynamics.as_ref().expect("a [dynamics] table");
    let sim = simulate(&p.case, params, dynamics, &Silent, |_| Ok(())).map_err(|_| "integration failed").unwrap();
    let positions = sim.discretisation.nodes.positions[..sim.discretisation.nodes.free].to_vec();
    let interior = interior_flags(&p.case.domain, &positions, params.horizon);
    Run { positions, u: sim.u, v: sim.v, interior, seconds: t0.elapsed().as_secs_f64() }
}

fn max_error(run: &Run, field: &[[f64; 2]], reference: &Run, reference_field: &[[f64; 2]]) -> f64 {
    let targets: Vec<[f64; 2]> = run.positions.iter().zip(&run.interior).filter(|(_, &i)| i).map(|(p, _)| *p).collect();
    let values: Vec<[f64; 2]> = field.iter().zip(&run.interior).filter(|(_, &i)| i).map(|(v, _)| *v).collect();
    let r = mls_values(&reference.positions, reference_field, &targets).unwrap();
    values.iter().zip(&r).map(|(a, b)| (a[0] - b[0]).abs().max((a[1] - b[1]).abs())).fold(0.0, f64::max)
}

fn list(args: &[String], flag: &str, default: &str) -> Vec<String> {
    let v = args.iter().position(|a| a == flag).map(|k| args[k + 1].clone()).unwrap_or_else(|| default.to_string());
    v.split(',').map(|s| s.to_string()).collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let reference_m: f64 = list(&args, "--reference", "24")[0].parse().unwrap();
    let ratios: Vec<f64> = list(&args, "--ratios", "3,4,6,8").iter().map(|s| s.parse().unwrap()).collect();
    let rules = list(&args, "--rules", "full-area,gauss2x2,triangle-p2");
    let kernels = list(&args, "--kernels", "plain,-2,0,1");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/steel_plate_dynamic.toml");
    let p = Problem::from_file(&path).unwrap();
    let mut base = *p.model.peridynamics().expect("a [peridynamics] table");
    base.horizon = list(&args, "--horizon", "0.1")[0].parse().unwrap();
    let perturbation: f64 = list(&args, "--perturbation", "0")[0].parse().unwrap();
    println!("| rule | kernel | h | nodes | e_inf(u) | e_inf(v) | seconds |");
    println!("|---|---|---|---|---|---|---|");
    let mut summary = Vec::new();
    for k in &kernels {
        let kernel = if k == "plain" { Kernel::Plain } else { Kernel::Regularised { alpha: k.parse().unwrap() } };
        let reference = run(&p, &PdParams { ratio: reference_m, kernel, quadrature: Quadrature::FullArea, ..base });
        eprintln!("kernel {k}: reference m = {reference_m}: {} nodes, {:.1} s", reference.positions.len(), reference.seconds);
        for rule in &rules {
            let quadrature = Quadrature::parse(rule).expect("known rule");
            let (mut hs, mut eu, mut ev) = (Vec::new(), Vec::new(), Vec::new());
            for &m in &ratios {
                let params = PdParams { ratio: m, kernel, quadrature, perturbation, ..base };
                let r = run(&p, &params);
                let (e_u, e_v) = (max_error(&r, &r.u, &reference, &reference.u), max_error(&r, &r.v, &reference, &reference.v));
                println!("| {rule} | {k} | {:.4e} | {} | {e_u:.3e} | {e_v:.3e} | {:.1} |", params.spacing(), r.positions.len(), r.seconds);
                hs.push(params.spacing());
                eu.push(e_u);
                ev.push(e_v);
            }
            let worst = |e: &[f64]| (1..e.len()).map(|i| (e[i - 1] / e[i]).ln() / (hs[i - 1] / hs[i]).ln()).fold(f64::INFINITY, f64::min);
            summary.push((
                rule.clone(),
                k.clone(),
                observed_order(&hs, &eu).unwrap(),
                observed_order(&hs, &ev).unwrap(),
                worst(&eu),
                worst(&ev),
            ));
        }
    }
    println!();
    println!("| rule | kernel | order u (worst step) | order v (worst step) |");
    println!("|---|---|---|---|");
    for (rule, k, ou, ov, wu, wv) in summary {
        println!("| {rule} | {k} | {ou:.2} ({wu:.2}) | {ov:.2} ({wv:.2}) |");
    }
}
