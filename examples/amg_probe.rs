//! Probe the multigrid preconditioner on an exported system (`mlsm run --export-system DIR`):
//! `cargo run --release --example amg_probe DIR [THETA]`. Equilibrates the rows as
//! `linalg::solve` does, then prints the hierarchy, the residual of ten V-cycles used as
//! a stationary iteration, and the GMRES(30) iterations to 1e-10.
use mlsm::linalg::amg::{product, Amg, AmgParams, NodeLayout};
use mlsm::linalg::{assemble, gmres, scaling, Triplets};
use nalgebra_sparse::io::load_coo_from_matrix_market_file;

fn main() {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).expect("usage: amg_probe DIR [THETA]"));
    let theta: f64 = std::env::args().nth(2).map_or(0.0, |s| s.parse().expect("THETA is a number"));
    let coo = load_coo_from_matrix_market_file::<f64, _>(dir.join("matrix.mtx")).expect("matrix.mtx");
    let rhs = load_coo_from_matrix_market_file::<f64, _>(dir.join("rhs.mtx")).expect("rhs.mtx");
    let n = coo.nrows();
    let mut t = Triplets::new(n);
    for (i, j, v) in coo.triplet_iter() {
        t.push(i, j, *v);
    }
    let mut b = vec![0.0; n];
    for (i, _, v) in rhs.triplet_iter() {
        b[i] += v;
    }
    let (a, d) = scaling::equilibrate_rows(&assemble(&t).unwrap()).unwrap();
    let b = scaling::scale_rhs(&b, &d);
    let text = std::fs::read_to_string(dir.join("unknowns.csv")).expect("unknowns.csv");
    let mut positions = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f[2] == "0" {
            positions.push([f[3].parse::<f64>().unwrap(), f[4].parse::<f64>().unwrap()]);
        }
    }
    let layout = NodeLayout { per_node: n / positions.len(), positions: &positions };
    let t0 = std::time::Instant::now();
    let amg = Amg::build(&a, Some(layout), AmgParams { strength: theta, ..AmgParams::default() }).unwrap();
    println!("setup {:.2} s, levels {:?}, operator complexity {:.2}", t0.elapsed().as_secs_f64(), amg.sizes(), amg.operator_complexity());
    let rows = amg.fine_operator().expect("more than one level");
    let (mut x, mut r) = (vec![0.0; n], b.clone());
    let bn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
    for cycle in 0..10 {
        let mut z = r.clone();
        amg.solve_in_place(&mut z);
        x.iter_mut().zip(&z).for_each(|(x, z)| *x += z);
        product(rows, &x, &mut r);
        r.iter_mut().zip(&b).for_each(|(r, b)| *r = b - *r);
        println!("cycle {cycle}: residual {:.3e}", r.iter().map(|v| v * v).sum::<f64>().sqrt() / bn);
    }
    let restart = mlsm::linalg::GMRES_RESTART;
    let t0 = std::time::Instant::now();
    let out = gmres::solve_gmres(rows, &b, |v| amg.solve_in_place(v), 1e-10, 500, restart);
    println!("history {:?}", out.history);
    println!(
        "gmres: {:?} {} iterations, residual {:.2e}, {:.2} s",
        out.status,
        out.iterations,
        out.relative_residual,
        t0.elapsed().as_secs_f64()
    );
}
