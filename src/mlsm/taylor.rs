//! Local polynomial fits of nodal values and their Taylor parts: what the `defect`
//! error estimate (`models::navier::defect`) measures a stencil's
//! truncation error with.
//!
//! A fit of total degree `q` at a centre `c`, in local coordinates `z = (x - c) / h`
//! (`h` the distance to the farthest fitted point), minimises
//! `sum_j w_j |P(z_j) - u_j|^2` with the Gaussian weight `w_j = exp(-|z_j|^2)`
//! (Householder QR of the weighted monomial matrix). Re-expanded about another point
//! `x_i`, `P = T_p + H_p`: `T_p` the terms of degree `<= p` in `(x - x_i) / h`, `H_p`
//! the rest. A stencil exact for polynomials of degree `<= p` and an operator of order
//! `<= 2 < p + 1` give `(L H_p)(x_i) = 0`, so the stencil's truncation error on `P` at
//! `x_i` is `sum_j a_j H_p(x_j)`: no exact operator is needed, only the weights.

use super::basis::polynomial_size;
use super::wls::{householder_qr, pivot_ratio, reflect};

/// The exponents `(a, b)` of the monomials `z1^a z2^b` of total degree `<= q`,
/// degree by degree.
pub fn exponents(q: u32) -> Vec<(u32, u32)> {
    (0..=q).flat_map(|t| (0..=t).map(move |a| (a, t - a))).collect()
}

/// A polynomial of total degree `q` with `K` components, in the local coordinates of
/// its centre.
#[derive(Debug, Clone)]
pub struct LocalPolynomial<const K: usize> {
    /// The centre `c`.
    pub centre: [f64; 2],
    /// The length `h` of the local coordinates `z = (x - c) / h`.
    pub scale: f64,
    /// Total degree `q`.
    pub degree: u32,
    /// Coefficients of the monomials of [`exponents`]`(q)`, per component.
    pub coefficients: Vec<[f64; K]>,
}

/// Why a fit could not be made.
#[derive(Debug, Clone, PartialEq)]
pub enum FitError {
    /// Fewer points than monomials, or points that do not determine them.
    Underdetermined { points: usize, monomials: usize },
}

/// The weighted least-squares fit of degree `q` of `values` at `points` about `centre`
/// (module docs); an error when the points do not determine the `(q+1)(q+2)/2`
/// coefficients (a diagonal of `R` below [`super::wls::RANK_TOLERANCE`] of its largest).
///
/// Solved by the normal equations where they are well conditioned (every fit of
/// degree `<= 5`, and the interior ones of degree 6, on grid and jittered clouds,
/// one-sided at edges and corners: `cond(V)` 5-2.5e3 column-scaled), at about half the
/// cost of the Householder QR that takes the others (150 x 15: 10 against 20 us).
pub fn fit<const K: usize>(centre: [f64; 2], points: &[[f64; 2]], values: &[[f64; K]], q: u32) -> Result<LocalPolynomial<K>, FitError> {
    let powers = exponents(q);
    let (n, m) = (points.len(), powers.len());
    let underdetermined = FitError::Underdetermined { points: n, monomials: m };
    if n < m || q > MAX_FIT_DEGREE {
        return Err(underdetermined);
    }
    let scale = points.iter().map(|p| (p[0] - centre[0]).hypot(p[1] - centre[1])).fold(0.0, f64::max);
    let scale = if scale > 0.0 { scale } else { 1.0 };
    // The weighted monomial matrix (column-major, n x m), then the K weighted value
    // columns.
    let mut a = vec![0.0; n * (m + K)];
    for (j, p) in points.iter().enumerate() {
        let z = [(p[0] - centre[0]) / scale, (p[1] - centre[1]) / scale];
        let w = (-(z[0] * z[0] + z[1] * z[1])).exp();
        let (z1, z2) = (powers_of(z[0], q), powers_of(z[1], q));
        for (k, &(e1, e2)) in powers.iter().enumerate() {
            a[k * n + j] = w * z1[e1 as usize] * z2[e2 as usize];
        }
        for c in 0..K {
            a[(m + c) * n + j] = w * values[j][c];
        }
    }
    if let Some(coefficients) = normal_equations::<K>(&a, n, m) {
        return Ok(LocalPolynomial { centre, scale, degree: q, coefficients });
    }
    let coefficients = householder(&mut a, n, m).ok_or(underdetermined)?;
    Ok(LocalPolynomial { centre, scale, degree: q, coefficients })
}

/// The least-squares solution of `V c = Y` from `a = [V | Y]` (column-major, `n` rows,
/// `m + K` columns, overwritten) by the shape functions' Householder kernel
/// ([`super::wls`]); `None` when a diagonal of `R` is below [`super::wls::RANK_TOLERANCE`] of its largest.
fn householder<const K: usize>(a: &mut [f64], n: usize, m: usize) -> Option<Vec<[f64; K]>> {
    let (v, y) = a.split_at_mut(m * n);
    let (mut diag, mut beta) = (vec![0.0; m], vec![0.0; m]);
    householder_qr(v, n, m, &mut diag, &mut beta);
    let ratio = pivot_ratio(diag.iter().copied());
    if ratio.is_nan() || ratio <= super::wls::RANK_TOLERANCE {
        return None;
    }
    // Q^T y, then R c = (Q^T y)[..m] by back substitution.
    let mut coefficients = vec![[0.0; K]; m];
    for (c, column) in y.chunks_exact_mut(n).enumerate() {
        for j in 0..m {
            reflect(&v[j * n + j..(j + 1) * n], beta[j], &mut column[j..]);
        }
        for k in (0..m).rev() {
            let above: f64 = (k + 1..m).map(|t| v[t * n + k] * coefficients[t][c]).sum();
            coefficients[k][c] = (column[k] - above) / diag[k];
        }
    }
    Some(coefficients)
}

/// The least-squares solution of `V c = Y` from `a = [V | Y]` (column-major, `n` rows,
/// `m + K` columns) by the normal equations, `V^T V c = V^T Y`, formed in one product
/// `V^T [V | Y]` (faer's small-matrix kernels), Jacobi-scaled and Cholesky-factored,
/// with one step of iterative refinement on the residual `Y - V c` (without it the
/// corner fits of degree 4 were off by 5e-11 of the largest coefficient); `None` when a
/// scaled pivot falls below [`NORMAL_PIVOT`] (the QR then decides).
fn normal_equations<const K: usize>(a: &[f64], n: usize, m: usize) -> Option<Vec<[f64; K]>> {
    use faer::{linalg::matmul::matmul, Accum, MatMut, MatRef, Par};
    let all = MatRef::from_column_major_slice(a, n, m + K);
    let v = all.subcols(0, m);
    let mut gram = vec![0.0; m * (m + K)];
    matmul(MatMut::from_column_major_slice_mut(&mut gram, m, m + K), Accum::Replace, v.transpose(), all, 1.0, Par::Seq);
    // Jacobi scaling d_k = 1 / sqrt(G_kk), then G = R^T R in place (upper triangle,
    // column-major: G[(i, j)] at i + j m).
    let d: Vec<f64> = (0..m).map(|k| 1.0 / gram[k + k * m].sqrt()).collect();
    if d.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let g = |i: usize, j: usize| i + j * m;
    for j in 0..m {
        for i in 0..=j {
            gram[g(i, j)] *= d[i] * d[j];
        }
    }
    for k in 0..m {
        let pivot = gram[g(k, k)] - (0..k).map(|i| gram[g(i, k)] * gram[g(i, k)]).sum::<f64>();
        if !(pivot > NORMAL_PIVOT) {
            return None;
        }
        let r = pivot.sqrt();
        gram[g(k, k)] = r;
        for j in k + 1..m {
            gram[g(k, j)] = (gram[g(k, j)] - (0..k).map(|i| gram[g(i, k)] * gram[g(i, j)]).sum::<f64>()) / r;
        }
    }
    // c = D R^-1 R^-T D b for a right-hand side b = V^T y.
    let solve = |b: &mut [f64]| {
        for k in 0..m {
            b[k] = (b[k] * d[k] - (0..k).map(|i| gram[g(i, k)] * b[i]).sum::<f64>()) / gram[g(k, k)];
        }
        for k in (0..m).rev() {
            b[k] = (b[k] - (k + 1..m).map(|j| gram[g(k, j)] * b[j]).sum::<f64>()) / gram[g(k, k)];
        }
        b.iter_mut().zip(&d).for_each(|(x, dk)| *x *= dk);
    };
    let mut c = vec![0.0; m * K];
    for (column, b) in c.chunks_exact_mut(m).zip(gram[m * m..].chunks_exact(m)) {
        column.copy_from_slice(b);
        solve(column);
    }
    let mut coefficients = vec![[0.0; K]; m];
    // One refinement step: c += (V^T V)^-1 V^T (Y - V c).
    let mut residual = a[m * n..].to_vec();
    let cm = MatRef::from_column_major_slice(&c, m, K);
    matmul(MatMut::from_column_major_slice_mut(&mut residual, n, K), Accum::Add, v, cm, -1.0, Par::Seq);
    let mut step = vec![0.0; m * K];
    let rm = MatRef::from_column_major_slice(&residual, n, K);
    matmul(MatMut::from_column_major_slice_mut(&mut step, m, K), Accum::Replace, v.transpose(), rm, 1.0, Par::Seq);
    for (col, (ck, sk)) in c.chunks_exact(m).zip(step.chunks_exact_mut(m)).enumerate() {
        solve(sk);
        for k in 0..m {
            coefficients[k][col] = ck[k] + sk[k];
        }
    }
    Some(coefficients)
}

/// Smallest scaled Cholesky pivot the normal equations are taken with: `cond(V^T V)`
/// below about `1e8`, where one refinement step leaves errors of `~(1e8 eps)^2` of the
/// largest coefficient.
const NORMAL_PIVOT: f64 = 1e-8;

/// Highest degree of a fit: the degree 8 of the highest basis plus 2.
pub const MAX_FIT_DEGREE: u32 = 10;

/// `[z^0, z^1, ..., z^q, 0, ...]` (`q <=` [`MAX_FIT_DEGREE`]).
fn powers_of(z: f64, q: u32) -> [f64; MAX_FIT_DEGREE as usize + 1] {
    let mut p = [0.0; MAX_FIT_DEGREE as usize + 1];
    p[0] = 1.0;
    for k in 1..=q.min(MAX_FIT_DEGREE) as usize {
        p[k] = p[k - 1] * z;
    }
    p
}

/// `C(n, k)` for `k <= n <=` [`MAX_FIT_DEGREE`] (Pascal's triangle, built at compile time).
const BINOMIAL: [[f64; MAX_FIT_DEGREE as usize + 1]; MAX_FIT_DEGREE as usize + 1] = {
    let mut c = [[0.0; MAX_FIT_DEGREE as usize + 1]; MAX_FIT_DEGREE as usize + 1];
    let mut n = 0;
    while n <= MAX_FIT_DEGREE as usize {
        c[n][0] = 1.0;
        let mut k = 1;
        while k <= n {
            c[n][k] = c[n - 1][k - 1] + c[n - 1][k];
            k += 1;
        }
        n += 1;
    }
    c
};

/// The part of degree above `p` of a polynomial re-expanded about a point
/// ([`LocalPolynomial::high_part_about`]).
#[derive(Debug, Clone)]
pub struct HighPart<const K: usize> {
    origin: [f64; 2],
    scale: f64,
    /// `(a, b, coefficients)` of the monomials `((x - origin) / scale)^(a, b)`, `a + b > p`.
    terms: Vec<(u32, u32, [f64; K])>,
}

impl<const K: usize> LocalPolynomial<K> {
    /// `H_p` about `origin`: the terms of degree above `p` of this polynomial written
    /// in `(x - origin) / h` (binomial re-expansion of each monomial).
    pub fn high_part_about(&self, origin: [f64; 2], p: u32) -> HighPart<K> {
        let d = [(origin[0] - self.centre[0]) / self.scale, (origin[1] - self.centre[1]) / self.scale];
        let powers = exponents(self.degree);
        let (d1, d2) = (powers_of(d[0], self.degree), powers_of(d[1], self.degree));
        let terms = powers
            .iter()
            .filter(|&&(a, b)| a + b > p)
            .map(|&(a, b)| {
                // The coefficient of z'^(a, b) collects every monomial (A, B) >= (a, b):
                // (z' + d)^(A, B) contributes C(A, a) C(B, b) d1^(A - a) d2^(B - b).
                let mut c = [0.0; K];
                for (k, &(big_a, big_b)) in powers.iter().enumerate() {
                    if big_a >= a && big_b >= b {
                        let f = BINOMIAL[big_a as usize][a as usize] * BINOMIAL[big_b as usize][b as usize] * d1[(big_a - a) as usize] * d2[(big_b - b) as usize];
                        for (ci, v) in c.iter_mut().zip(&self.coefficients[k]) {
                            *ci += f * v;
                        }
                    }
                }
                (a, b, c)
            })
            .collect();
        HighPart { origin, scale: self.scale, terms }
    }

    /// `P(x)`.
    pub fn value(&self, x: [f64; 2]) -> [f64; K] {
        let terms = exponents(self.degree).into_iter().zip(&self.coefficients).map(|((a, b), c)| (a, b, c));
        sum_of_terms(terms, [(x[0] - self.centre[0]) / self.scale, (x[1] - self.centre[1]) / self.scale], self.degree)
    }
}

impl<const K: usize> HighPart<K> {
    /// `H_p(x)`.
    pub fn value(&self, x: [f64; 2]) -> [f64; K] {
        let degree = self.terms.iter().map(|&(a, b, _)| a + b).max().unwrap_or(0);
        let terms = self.terms.iter().map(|(a, b, c)| (*a, *b, c));
        sum_of_terms(terms, [(x[0] - self.origin[0]) / self.scale, (x[1] - self.origin[1]) / self.scale], degree)
    }
}

/// `sum_k c_k z1^a_k z2^b_k` over `terms` `(a_k, b_k, c_k)` of degree `<= q`.
fn sum_of_terms<'a, const K: usize>(terms: impl Iterator<Item = (u32, u32, &'a [f64; K])>, z: [f64; 2], q: u32) -> [f64; K] {
    let (z1, z2) = (powers_of(z[0], q), powers_of(z[1], q));
    let mut out = [0.0; K];
    for (a, b, c) in terms {
        let m = z1[a as usize] * z2[b as usize];
        for (o, v) in out.iter_mut().zip(c) {
            *o += m * v;
        }
    }
    out
}

/// Points a fit of degree `q` takes: 10 times its monomials up to degree 4, 5 times
/// for degrees 5 and 6, 2.5 times above. The fitted values carry the run's own error,
/// and only wide least-squares fits average its rough part out of the high-degree
/// coefficients: with 2.5 times the monomials the estimate of the tensor cantilever
/// (degree 2, fits of degree 4) overshoots 1.5-4x, with 10 times it is within
/// 0.84-1.20 of the true error on every measured scene
/// (docs/notebook/2026-11-28-cheap-estimate.md). But the fits of a high-degree run
/// are of a high degree themselves, and 10 times their monomials (450 points at
/// degree 8) span a good part of a coarse plate, more than a polynomial follows:
/// PHS degree 6 on Kirsch at 2 495 nodes read e_inf(u) 15.5x too high, on Lame at
/// 1 742 nodes 0.29x; with 2.5 times, 2.06x and 1.00x, and from about 5 000 nodes on
/// 0.93-1.33 on both in u and sigma (degree 4 with 5 times: 0.77-1.98 from 872 nodes;
/// docs/notebook/2026-11-29-time-to-accuracy.md).
pub fn fit_points(q: u32) -> usize {
    let m = polynomial_size(q);
    match q {
        ..=4 => 10 * m,
        5 | 6 => 5 * m,
        _ => 5 * m / 2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic is fitted exactly by degree 4 (to round-off), and its part above degree
    /// 1 about another point, plus the first-degree Taylor terms there, gives back the
    /// cubic: `P(x) = P(o) + grad P(o) . (x - o) + H_1(x)`.
    #[test]
    fn fit_and_high_part_reproduce_a_cubic() {
        let f = |x: [f64; 2]| [1.0 + 2.0 * x[0] - x[1] + x[0] * x[0] * x[1] - 3.0 * x[1].powi(3), x[0].powi(3)];
        let points: Vec<[f64; 2]> = (0..40).map(|k| [0.3 * ((k * 7 % 13) as f64 / 13.0), 0.3 * ((k * 5 % 11) as f64 / 11.0)]).collect();
        let values: Vec<[f64; 2]> = points.iter().map(|&p| f(p)).collect();
        let poly = fit([0.15, 0.15], &points, &values, 4).unwrap();
        let x = [0.21, 0.07];
        for c in 0..2 {
            assert!((poly.value(x)[c] - f(x)[c]).abs() < 1e-12, "fitted value");
        }
        let o = [0.1, 0.2];
        let h = poly.high_part_about(o, 1);
        let eps = 1e-6;
        let grad = |c: usize| {
            [
                (f([o[0] + eps, o[1]])[c] - f([o[0] - eps, o[1]])[c]) / (2.0 * eps),
                (f([o[0], o[1] + eps])[c] - f([o[0], o[1] - eps])[c]) / (2.0 * eps),
            ]
        };
        for c in 0..2 {
            let g = grad(c);
            let taylor = f(o)[c] + g[0] * (x[0] - o[0]) + g[1] * (x[1] - o[1]);
            assert!((taylor + h.value(x)[c] - f(x)[c]).abs() < 1e-8, "component {c}");
        }
    }

    /// The normal equations and the QR give the same coefficients on an interior and a
    /// one-sided (corner) cloud of 150 jittered grid points with rough values at degree
    /// 4, and [`fit`] takes the normal equations there. Both solve one least-squares
    /// problem with a scaled condition number below 5e2, the normal equations refined
    /// once, so they agree to about `cond * eps` of the largest coefficient; 1e-11
    /// leaves a factor 100.
    #[test]
    fn normal_equations_agree_with_the_qr() {
        let cloud: Vec<[f64; 2]> = (0..900)
            .map(|k| {
                let (i, j) = ((k % 30) as f64, (k / 30) as f64);
                [0.01 * (i + 0.3 * (k as f64 * 1.7).sin()), 0.01 * (j + 0.3 * (k as f64 * 2.3).cos())]
            })
            .collect();
        let f = |x: [f64; 2]| [3.0 + (4.0 * x[0]).sin() * x[1].exp() + 1e-7 * (x[0] * 1e3).cos(), 1.0 / (1.0 + x[0] + x[1])];
        for centre in [[0.15, 0.15], [0.0, 0.0]] {
            let distance = |p: &[f64; 2]| (p[0] - centre[0]).hypot(p[1] - centre[1]);
            let mut near = cloud.clone();
            near.sort_by(|a, b| distance(a).total_cmp(&distance(b)));
            near.truncate(150);
            let (n, m) = (near.len(), polynomial_size(4));
            let mut a = vec![0.0; n * (m + 2)];
            for (j, p) in near.iter().enumerate() {
                let z = [(p[0] - centre[0]) / 0.2, (p[1] - centre[1]) / 0.2];
                for (k, &(e1, e2)) in exponents(4).iter().enumerate() {
                    a[k * n + j] = z[0].powi(e1 as i32) * z[1].powi(e2 as i32);
                }
                let y = f(*p);
                (a[m * n + j], a[(m + 1) * n + j]) = (y[0], y[1]);
            }
            let normal = normal_equations::<2>(&a, n, m).expect("well conditioned");
            let qr = householder::<2>(&mut a.clone(), n, m).expect("full rank");
            let largest = qr.iter().flatten().fold(0.0f64, |l, x| l.max(x.abs()));
            for (x, y) in normal.iter().flatten().zip(qr.iter().flatten()) {
                assert!((x - y).abs() < 1e-11 * largest, "centre {centre:?}: {x} against {y}");
            }
            let values: Vec<[f64; 2]> = near.iter().map(|&p| f(p)).collect();
            let scale = near.iter().map(distance).fold(0.0, f64::max);
            let weighted = |k: usize, j: usize| {
                let z = [(near[j][0] - centre[0]) / scale, (near[j][1] - centre[1]) / scale];
                let (e1, e2) = exponents(4)[k];
                (-(z[0] * z[0] + z[1] * z[1])).exp() * z[0].powi(e1 as i32) * z[1].powi(e2 as i32)
            };
            let mut b: Vec<f64> = (0..m * n).map(|i| weighted(i / n, i % n)).collect();
            b.extend((0..2).flat_map(|c| (0..n).map(move |j| (c, j))).map(|(c, j)| {
                let z = [(near[j][0] - centre[0]) / scale, (near[j][1] - centre[1]) / scale];
                (-(z[0] * z[0] + z[1] * z[1])).exp() * values[j][c]
            }));
            let expected = normal_equations::<2>(&b, n, m).unwrap();
            let fitted = fit(centre, &near, &values, 4).unwrap();
            for (x, y) in fitted.coefficients.iter().flatten().zip(expected.iter().flatten()) {
                assert!((x - y).abs() <= 1e-13 * largest, "fit takes the normal equations: {x} against {y}");
            }
        }
    }

    /// Too few points, or points on a line, are refused, not fitted.
    #[test]
    fn underdetermined_fits_are_refused() {
        let line: Vec<[f64; 2]> = (0..20).map(|k| [k as f64, 0.0]).collect();
        let values = vec![[0.0; 1]; 20];
        assert!(fit([0.0, 0.0], &line, &values, 2).is_err());
        assert!(fit([0.0, 0.0], &line[..4], &values[..4], 2).is_err());
    }
}
