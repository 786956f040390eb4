//! One weighted least-squares solve: the shape functions of a set of operators at
//! one node (seed 002, eq. 10).
//!
//! With `B_jk = b_k(z_j)` (support in local coordinates `z = (x - p)/s`),
//! `W = diag(sqrt(w_j))` and `l = (L b)(p)`, the shape function is
//! `phi_L = (L b)(p)^T (W B)^+ W`, so that `(L u)(p) ~= phi_L . u[support]`.
//! It is evaluated through a thin QR factorisation `W B = Q R` (never through the
//! normal equations, which square the condition number):
//! `phi_L = W Q R^-T l`. Derivatives in local coordinates are converted back by
//! `d^k/dx^k = s^-k d^k/dz^k`. A rank-deficient `W B` (collinear support,
//! duplicated nodes) is reported, not turned into NaNs.

use super::basis::{Basis, LocalBasis, Weight};
use super::frame::{LocalFrame, RankDeficient};
use super::ops::Op;

/// Relative size of the smallest QR pivot below which `W B` counts as rank deficient.
pub const RANK_TOLERANCE: f64 = 1e-10;

/// Smallest `|R_kk| / max |R_kk|` over the diagonal `diag` of an upper triangular `R`
/// (0 for a zero matrix).
pub(super) fn pivot_ratio(diag: impl Iterator<Item = f64> + Clone) -> f64 {
    let diag_max = diag.clone().map(f64::abs).fold(0.0, f64::max);
    let diag_min = diag.map(f64::abs).fold(f64::INFINITY, f64::min);
    if diag_max > 0.0 {
        diag_min / diag_max
    } else {
        0.0
    }
}

/// Smallest relative QR pivot `|R_kk| / max |R_kk|` of the column-major `n x m`
/// matrix `b` (`n >= m`; overwritten by its factorisation): its numerical rank test.
/// By [`householder_qr`] (faer's blocked QR was no faster at these sizes, nalgebra's
/// slower: docs/notebook/2026-11-27-shapes-rank-test-sqrt.md); the reflectors' diagonal
/// and scales in buffers the caller keeps (`diag`, `beta`).
pub fn rank_ratio_in(b: &mut [f64], n: usize, m: usize, (diag, beta): (&mut Vec<f64>, &mut Vec<f64>)) -> f64 {
    diag.clear();
    diag.resize(m, 0.0);
    beta.clear();
    beta.resize(m, 0.0);
    householder_qr(b, n, m, diag, beta);
    pivot_ratio(diag.iter().copied())
}

/// Weighted least-squares shape functions of `ops` at `centre` for the support
/// `points` (the centre first; `stencil = (centre, points)`), written to
/// `out[k * n .. (k + 1) * n]` for the k-th operator; `basis` is a monomial or tensor
/// basis (every basis goes through [`super::fit::shape_functions`], which sends
/// RBF-FD to [`super::rbffd`]).
pub fn shape_functions(
    basis: &Basis,
    weight: &Weight,
    (centre, points): ([f64; 2], &[[f64; 2]]),
    ops: &[Op],
    out: &mut [f64],
) -> Result<(), RankDeficient> {
    SCRATCH.with(|scratch| {
        let mut scratch = scratch.borrow_mut();
        let Scratch { frame, local, work } = &mut *scratch;
        if local.as_ref().is_none_or(|(b, _)| b != basis) {
            *local = Some((*basis, LocalBasis::new(basis)));
        }
        let local = &local.as_ref().expect("set above").1;
        frame.fill(centre, points);
        fit(local, weight, frame, ops, work, out)
    })
}

/// The buffers of one thread's fits, kept between nodes: each fit allocated five of
/// them (the frame's three, the basis's exponents, the work buffer), which with the
/// node's operator list slowed the shapes stage
/// (docs/notebook/2026-11-27-issue-12-scaling-remeasured.md, "The least-squares fit
/// without allocations").
#[derive(Default)]
struct Scratch {
    frame: LocalFrame,
    local: Option<(Basis, LocalBasis)>,
    work: Vec<f64>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

/// [`shape_functions`] of a monomial basis on the stencil `frame`, `work` its buffer.
fn fit(
    local: &LocalBasis,
    weight: &Weight,
    frame: &LocalFrame,
    ops: &[Op],
    work: &mut Vec<f64>,
    out: &mut [f64],
) -> Result<(), RankDeficient> {
    let LocalFrame { dist, radius: s, nearest: h_p, z, .. } = frame;
    let (s, h_p) = (*s, *h_p);
    let n = z.len();
    let m = local.len();
    if n < m {
        return Err(RankDeficient { ratio: 0.0, basis_size: m });
    }
    // One buffer: W B (n x m, column-major, then the Householder vectors and R), R's
    // diagonal, the reflections' factors, a row of the basis, W's diagonal, a column.
    work.clear();
    work.resize(n * m + 3 * m + 2 * n, 0.0);
    let (wb, rest) = work.split_at_mut(n * m);
    let (diag, rest) = rest.split_at_mut(m);
    let (beta, rest) = rest.split_at_mut(m);
    let (row, rest) = rest.split_at_mut(m);
    let (sw, x) = rest.split_at_mut(n);
    for j in 0..n {
        sw[j] = weight.sqrt_weight(dist[j], h_p);
        local.values(z[j], row);
        for k in 0..m {
            wb[k * n + j] = sw[j] * row[k];
        }
    }
    householder_qr(wb, n, m, diag, beta);
    let ratio = pivot_ratio(diag.iter().copied());
    if ratio.is_nan() || ratio <= RANK_TOLERANCE {
        return Err(RankDeficient { ratio, basis_size: m });
    }
    // Each operator: y = R^-T l (forward substitution), then phi = W Q [y; 0], Q applied
    // as its reflections, last first.
    for (c, &op) in ops.iter().enumerate() {
        local.operator_at_centre(op, row);
        let scale = s.powi(-op.order());
        x.fill(0.0);
        for i in 0..m {
            let mut v = row[i] * scale;
            for t in 0..i {
                v -= wb[i * n + t] * x[t];
            }
            x[i] = v / diag[i];
        }
        for j in (0..m).rev() {
            reflect(&wb[j * n + j..(j + 1) * n], beta[j], &mut x[j..]);
        }
        for j in 0..n {
            out[c * n + j] = sw[j] * x[j];
        }
    }
    Ok(())
}

/// Householder QR of the column-major `n x m` matrix `a` (`n >= m`) in place, `A = Q R`
/// with `Q = H_0 ... H_(m-1)`, `H_j = I - beta_j v_j v_j^T` acting on rows `j..n`
/// (Golub & Van Loan, Matrix Computations, alg. 5.2.1): on return column `j` holds
/// `R`'s entries above the diagonal in rows `0..j` and `v_j` in rows `j..n`, `diag[j]`
/// is `R_jj` and `beta[j]` is `beta_j` (0 for a zero column, `H_j = I`). Written here
/// because nalgebra's QR forms `Q` (`QR::q`) to apply it, which cost as much as the
/// factorisation on these `13 x 9` systems; its reflections are private.
pub(super) fn householder_qr(a: &mut [f64], n: usize, m: usize, diag: &mut [f64], beta: &mut [f64]) {
    for j in 0..m {
        let (done, rest) = a.split_at_mut((j + 1) * n);
        let v = &mut done[j * n + j..];
        let norm = dot(v, v).sqrt();
        if norm == 0.0 {
            (diag[j], beta[j]) = (0.0, 0.0);
            continue;
        }
        // v = x - alpha e_1 with alpha = -sign(x_0) |x|, so that no cancellation occurs.
        let alpha = if v[0] >= 0.0 { -norm } else { norm };
        beta[j] = 1.0 / (norm * (norm + v[0].abs()));
        v[0] -= alpha;
        diag[j] = alpha;
        for c in 0..m - j - 1 {
            reflect(v, beta[j], &mut rest[c * n + j..(c + 1) * n]);
        }
    }
}

/// `x <- (I - beta v v^T) x`.
pub(super) fn reflect(v: &[f64], beta: f64, x: &mut [f64]) {
    let s = beta * dot(v, x);
    for (xi, vi) in x.iter_mut().zip(v) {
        *xi -= s * vi;
    }
}

/// `a . b` with four partial sums, so that the additions need not wait for each other
/// (a single running sum is a chain of dependent additions the compiler may not
/// reorder: the rank test of degree-8 stencils was 11 % of a run with it).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut sums = [0.0f64; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = a4.remainder().iter().zip(b4.remainder()).map(|(x, y)| x * y).sum();
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            sums[k] += x[k] * y[k];
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3]) + tail
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// The Householder kernel gives `phi = W (W B)^+T l`, checked against nalgebra's
    /// SVD pseudo-inverse on jittered-lattice supports of 13, 20 and 30 nodes for the monomial
    /// and tensor bases and every operator. Both are backward stable, so they agree to
    /// a few hundred ulps of the largest weight times the condition number of `W B`
    /// (1e2-1e4 here): 1e-10 relative.
    #[test]
    fn householder_weights_equal_the_pseudo_inverse() {
        let mut seed = 12345u64;
        let mut uniform = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let ops = Op::ALL;
        for (basis, n) in [
            (Basis::Monomials { degree: 2 }, 13),
            (Basis::Tensor { degree: 2 }, 13),
            (Basis::Monomials { degree: 4 }, 30),
            (Basis::Monomials { degree: 3 }, 20),
        ] {
            for weight in [Weight::Gaussian { sigma: 1.0 }, Weight::None] {
                let centre = [3.0 + uniform(), -2.0 + uniform()];
                // The n lattice points nearest the centre, spacing 0.01, each moved by up
                // to 0.3 spacings: a scattered support like a relaxed fill's.
                let mut lattice: Vec<(i32, i32)> = (-4..=4).flat_map(|i| (-4..=4).map(move |j| (i, j))).collect();
                lattice.sort_by_key(|&(i, j)| (i * i + j * j, i, j));
                let points: Vec<[f64; 2]> = lattice[..n]
                    .iter()
                    .enumerate()
                    .map(|(k, &(i, j))| {
                        let jitter = if k == 0 { [0.0, 0.0] } else { [0.6 * (uniform() - 0.5), 0.6 * (uniform() - 0.5)] };
                        [centre[0] + 0.01 * (i as f64 + jitter[0]), centre[1] + 0.01 * (j as f64 + jitter[1])]
                    })
                    .collect();
                let mut out = vec![0.0; ops.len() * n];
                shape_functions(&basis, &weight, (centre, &points), &ops, &mut out).unwrap();

                let LocalFrame { dist, radius: s, nearest: h_p, z } = LocalFrame::new(centre, &points);
                let local = LocalBasis::new(&basis);
                let m = local.len();
                let mut row = vec![0.0; m];
                let sw: Vec<f64> = dist.iter().map(|&r| weight.sqrt_weight(r, h_p)).collect();
                let wb = DMatrix::from_fn(n, m, |j, k| {
                    local.values(z[j], &mut row);
                    sw[j] * row[k]
                });
                let pinv = wb.pseudo_inverse(1e-300).unwrap();
                for (c, &op) in ops.iter().enumerate() {
                    local.operator_at_centre(op, &mut row);
                    let scale = s.powi(-op.order());
                    let got = &out[c * n..(c + 1) * n];
                    let want: Vec<f64> = (0..n).map(|j| sw[j] * (0..m).map(|a| pinv[(a, j)] * row[a] * scale).sum::<f64>()).collect();
                    let size = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                    for j in 0..n {
                        assert!(
                            (got[j] - want[j]).abs() <= 1e-10 * size,
                            "{basis:?} {weight:?} {op:?} node {j}: {} vs {}",
                            got[j],
                            want[j]
                        );
                    }
                }
            }
        }
    }
}
