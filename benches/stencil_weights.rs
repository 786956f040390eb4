//! Stencil weights per node, one core: the shape functions of the five operators
//! of a Navier row (`d/dx`, `d/dy`, `d2/dx2`, `d2/dxdy`, `d2/dy2`) on scattered stencils
//! of the default size for each basis (`2 m` nearest of a jittered lattice, the
//! centre first), timed over `REPS` passes of 400 stencils after one warm-up pass, the fastest of five
//! such timings.
//!
//! `cargo bench --bench stencil_weights` prints microseconds per stencil for least
//! squares (degree 2) and PHS r^3 RBF-FD of degree 2, 4, 6 and 8, and a checksum of
//! the weights, so that two builds can be compared back to back (issue 53, item 2;
//! BENCHMARKS.md "Shape functions per node").

use mlsm::mlsm::basis::{polynomial_size, Basis, Weight};
use mlsm::mlsm::fit::shape_functions;
use mlsm::mlsm::ops::Op;
use mlsm::mlsm::radial::Radial;
use mlsm::mlsm::stencil::jittered_lattice;
use std::time::Instant;

const REPS: usize = 10;
const STENCILS: usize = 400;

fn main() {
    let ops = [Op::Dx, Op::Dy, Op::Dxx, Op::Dxy, Op::Dyy];
    let phs = |degree| Basis::RbfFd { radial: Radial::Phs { order: 3 }, degree };
    let cases = [
        ("least squares, degree 2, gaussian", Basis::Monomials { degree: 2 }, Weight::Gaussian { sigma: 1.0 }, 12),
        ("PHS r^3 + degree 2", phs(2), Weight::None, 2 * polynomial_size(2)),
        ("PHS r^3 + degree 4", phs(4), Weight::None, 2 * polynomial_size(4)),
        ("PHS r^3 + degree 6", phs(6), Weight::None, 2 * polynomial_size(6)),
        ("PHS r^3 + degree 8", phs(8), Weight::None, 2 * polynomial_size(8)),
    ];
    println!("| basis | stencil | us per stencil (one core) | checksum |");
    println!("|---|---|---|---|");
    for (label, basis, weight, n) in cases {
        let stencils: Vec<Vec<[f64; 2]>> = (0..STENCILS as u64).map(|k| jittered_lattice(n, 0.6, k)).collect();
        let mut out = vec![0.0; n * ops.len()];
        let pass = |out: &mut [f64]| {
            let mut checksum = 0.0;
            for s in &stencils {
                shape_functions(&basis, &weight, s[0], s, &ops, out).expect("a jittered lattice stencil is not degenerate");
                checksum += out.iter().map(|w| w.abs()).sum::<f64>();
            }
            checksum
        };
        let checksum = pass(&mut out);
        // The fastest of five timings of `REPS` passes: this 2-vCPU machine's neighbours
        // add 10-20 % of noise to single timings, never take any away.
        let us = (0..5)
            .map(|_| {
                let t = Instant::now();
                for _ in 0..REPS {
                    pass(&mut out);
                }
                t.elapsed().as_secs_f64() / (REPS * STENCILS) as f64 * 1e6
            })
            .fold(f64::INFINITY, f64::min);
        println!("| {label} | {n} | {us:.2} | {checksum:.12e} |");
    }
}
