//! Micro-benchmark of one local WLS solve (`cargo run --release --example shapes_bench`).
use mlsm::mlsm::basis::{Basis, Weight};
use mlsm::mlsm::wls::shape_functions;
use mlsm::mlsm::Op;
use std::time::Instant;

fn main() {
    for (basis, n, ops) in [
        (Basis::Monomials { degree: 2 }, 9usize, vec![Op::Dx, Op::Dy, Op::Dxx, Op::Dxy, Op::Dyy]),
        (Basis::Monomials { degree: 2 }, 12, vec![Op::Dx, Op::Dy, Op::Dxx, Op::Dxy, Op::Dyy]),
        (Basis::Tensor { degree: 2 }, 13, vec![Op::Dx, Op::Dy, Op::Dxx, Op::Dxy, Op::Dyy]),
    ] {
        let pts: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                if k == 0 {
                    [0.0, 0.0]
                } else {
                    let t = k as f64 * 2.4;
                    let r = 1.0 + 0.1 * (k as f64).sqrt();
                    [r * t.cos(), r * t.sin()]
                }
            })
            .collect();
        let mut out = vec![0.0; ops.len() * n];
        let reps = 200_000;
        let t0 = Instant::now();
        for _ in 0..reps {
            shape_functions(&basis, &Weight::Gaussian { sigma: 1.0 }, pts[0], &pts, &ops, &mut out).unwrap();
            std::hint::black_box(&out);
        }
        println!("{basis:?} n = {n}: {:.2} us per node (one core)", t0.elapsed().as_secs_f64() / reps as f64 * 1e6);
    }
}
