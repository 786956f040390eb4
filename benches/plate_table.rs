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
//!     [--scene problems/pd_plate_hole.toml] [--points delaunay] [--cut-cells]
//!     (another scene; the runs on a Delaunay set; cut-cell weights on the lattice runs
//!     and the reference)
//!
//! Beside e_inf, the volume-weighted mean error over the same nodes (e_mean, an L1
//! error per unit area; [`interior_errors`]), with its own orders.

use mlsm::models::peridynamics::simulate;
use mlsm::models::peridynamics::solve::{interior_errors, interior_flags};
use mlsm::models::peridynamics::{Kernel, PdParams, PointSet, Quadrature};
use mlsm::quality::post::observed_order;
use mlsm::scene::choice::Choice;
use mlsm::scene::problem::Problem;
use mlsm::stages::Silent;
use std::path::Path;

struct Run {
    positions: Vec<[f64; 2]>,
    u: Vec<[f64; 2]>,
    v: Vec<[f64; 2]>,
    volumes: Vec<f64>,
    interior: Vec<bool>,
    seconds: f64,
}

fn run(p: &Problem, params: &PdParams) -> Run {
    let t0 = std::time::Instant::now();
    let dynamics = p.case.dynamics.as_ref().expect("a [dynamics] table");
    let sim = simulate(&p.case, params, dynamics, &Silent, |_| Ok(())).map_err(|_| "integration failed").unwrap();
    let positions = sim.discretisation.nodes.positions[..sim.discretisation.nodes.free].to_vec();
    let volumes = sim.discretisation.nodes.volumes[..sim.discretisation.nodes.free].to_vec();
    let interior = interior_flags(&p.case.domain, &positions, params.horizon);
    Run { positions, u: sim.u, v: sim.v, volumes, interior, seconds: t0.elapsed().as_secs_f64() }
}

/// `(e_inf, e_mean)` of `field` against the reference's.
fn errors(run: &Run, field: &[[f64; 2]], reference: &Run, reference_field: &[[f64; 2]]) -> (f64, f64) {
    interior_errors(&run.positions, field, &run.volumes, &run.interior, &reference.positions, reference_field).unwrap()
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
    let scene = list(&args, "--scene", "problems/steel_plate_dynamic.toml")[0].clone();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let p = Problem::from_file(&path).unwrap();
    let mut base = *p.model.peridynamics().expect("a [peridynamics] table");
    base.horizon = list(&args, "--horizon", "0.1")[0].parse().unwrap();
    let perturbation: f64 = list(&args, "--perturbation", "0")[0].parse().unwrap();
    let points = PointSet::parse(&list(&args, "--points", "lattice")[0]).expect("lattice or delaunay");
    let cut_cells = args.iter().any(|a| a == "--cut-cells");
    base.cut_cells = false;
    println!("| rule | kernel | h | nodes | e_inf(u) | e_inf(v) | e_mean(u) | e_mean(v) | seconds |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut summary = Vec::new();
    for k in &kernels {
        let kernel = if k == "plain" { Kernel::Plain } else { Kernel::Regularised { alpha: k.parse().unwrap() } };
        let lattice = PdParams { points: PointSet::Lattice, cut_cells, ..base };
        let reference = run(&p, &PdParams { ratio: reference_m, kernel, quadrature: Quadrature::FullArea, ..lattice });
        eprintln!("kernel {k}: reference m = {reference_m}: {} nodes, {:.1} s", reference.positions.len(), reference.seconds);
        for rule in &rules {
            let quadrature = Quadrature::parse(rule).expect("known rule");
            let (mut hs, mut eu, mut ev, mut mu, mut mv) = (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for &m in &ratios {
                let on = if points == PointSet::Delaunay { PdParams { points, ..base } } else { lattice };
                let params = PdParams { ratio: m, kernel, quadrature, perturbation, ..on };
                let r = run(&p, &params);
                let ((e_u, m_u), (e_v, m_v)) = (errors(&r, &r.u, &reference, &reference.u), errors(&r, &r.v, &reference, &reference.v));
                println!(
                    "| {rule} | {k} | {:.4e} | {} | {e_u:.3e} | {e_v:.3e} | {m_u:.3e} | {m_v:.3e} | {:.1} |",
                    params.spacing(),
                    r.positions.len(),
                    r.seconds
                );
                hs.push(params.spacing());
                eu.push(e_u);
                ev.push(e_v);
                mu.push(m_u);
                mv.push(m_v);
            }
            let worst = |e: &[f64]| (1..e.len()).map(|i| (e[i - 1] / e[i]).ln() / (hs[i - 1] / hs[i]).ln()).fold(f64::INFINITY, f64::min);
            summary.push((
                rule.clone(),
                k.clone(),
                observed_order(&hs, &eu).unwrap(),
                observed_order(&hs, &ev).unwrap(),
                worst(&eu),
                worst(&ev),
                observed_order(&hs, &mu).unwrap(),
                observed_order(&hs, &mv).unwrap(),
                worst(&mu),
                worst(&mv),
            ));
        }
    }
    println!();
    println!("| rule | kernel | order u (worst step) | order v (worst step) | mean-error order u (worst) | v (worst) |");
    println!("|---|---|---|---|---|---|");
    for (rule, k, ou, ov, wu, wv, mu, mv, wmu, wmv) in summary {
        println!("| {rule} | {k} | {ou:.2} ({wu:.2}) | {ov:.2} ({wv:.2}) | {mu:.2} ({wmu:.2}) | {mv:.2} ({wmv:.2}) |");
    }
}
