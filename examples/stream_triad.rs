//! Memory bandwidth of this machine, for comparison with the PD force loop
//! (BENCHMARKS.md): the STREAM triad `a = b + s c` over three arrays of 5e7 doubles
//! with rayon, best of 5; counted bytes = 3 x 8 x n (write-allocate traffic not counted).
//! cargo run --release --example stream_triad

use rayon::prelude::*;

fn main() {
    let n = 50_000_000;
    let (b, c) = (vec![1.0f64; n], vec![2.0f64; n]);
    let mut a = vec![0.0f64; n];
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t = std::time::Instant::now();
        a.par_iter_mut().zip(&b).zip(&c).for_each(|((a, b), c)| *a = b + 3.0 * c);
        best = best.min(t.elapsed().as_secs_f64());
    }
    println!("triad: {:.1} GB/s with {} threads (a[0] = {})", 24.0 * n as f64 / best / 1e9, rayon::current_num_threads(), a[0]);
}
