//! Default stencil sizes: how many nearest nodes a support takes when the scene does
//! not say (`approximation.support`).

use crate::domain::FillKind;

/// Default support size for a basis of `m` functions.
///
/// Scattered fills: `2 m` (12 for degree-2 monomials), a least-squares fit
/// over-determined by a factor 2. Grid fills: the smallest complete ring of lattice
/// neighbours (9, 13, 21, 25, 29, 37, 45, 49, ...) with at least `1.4 m` nodes, because
/// the `n` nearest of a lattice node are ambiguous when the n-th distance is shared
/// by several nodes; an arbitrary pick makes stencils asymmetric and costs order
/// (docs/notebook/round1-one-local-least-squares-solve.md, "From the code comments").
pub fn default_support(m: usize, fill: FillKind) -> usize {
    match fill {
        FillKind::Scattered => 2 * m,
        FillKind::Grid => lattice_ring(1.4 * m as f64),
    }
}

/// Default stencil of an RBF-FD basis with `m` polynomial terms: `2 m` nodes (Flyer,
/// Fornberg, Bayona and Barnett), on grids the smallest complete lattice ring of at
/// least `2 m`.
pub fn default_rbf_fd_support(m: usize, fill: FillKind) -> usize {
    match fill {
        FillKind::Scattered => 2 * m,
        FillKind::Grid => lattice_ring(2.0 * m as f64),
    }
}

/// The node count of the smallest disc of lattice points holding at least `count`.
fn lattice_ring(count: f64) -> usize {
    // Count lattice points within radius^2 = r2 for increasing r2.
    let mut r2 = 1;
    loop {
        let k = (r2 as f64).sqrt() as i64;
        let inside = (-k..=k).flat_map(|i| (-k..=k).map(move |j| i * i + j * j)).filter(|&d| d <= r2).count();
        if inside as f64 >= count {
            return inside;
        }
        r2 += 1;
    }
}

/// The `n` nodes nearest to the origin of a unit lattice jittered by up to `jitter / 2`
/// in each coordinate (a scattered fill's local regularity), the origin first: a
/// reproducible scattered stencil (`seed` picks the jitter) for the weights' tests
/// and `benches/stencil_weights.rs`.
pub fn jittered_lattice(n: usize, jitter: f64, seed: u64) -> Vec<[f64; 2]> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let reach = (n as f64).sqrt().ceil() as i32 + 1;
    let mut around: Vec<[f64; 2]> = (-reach..=reach)
        .flat_map(|i| (-reach..=reach).map(move |j| (i, j)))
        .filter(|&ij| ij != (0, 0))
        .map(|(i, j)| [i as f64 + jitter * (rng.random::<f64>() - 0.5), j as f64 + jitter * (rng.random::<f64>() - 0.5)])
        .collect();
    around.sort_by(|a, b| a[0].hypot(a[1]).total_cmp(&b[0].hypot(b[1])));
    std::iter::once([0.0, 0.0]).chain(around.into_iter().take(n.saturating_sub(1))).collect()
}
