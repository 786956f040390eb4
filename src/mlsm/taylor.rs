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
use nalgebra::{DMatrix, DVector};

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
/// coefficients (a diagonal of `R` below `1e-10` of its largest).
pub fn fit<const K: usize>(centre: [f64; 2], points: &[[f64; 2]], values: &[[f64; K]], q: u32) -> Result<LocalPolynomial<K>, FitError> {
    let powers = exponents(q);
    let (n, m) = (points.len(), powers.len());
    let underdetermined = FitError::Underdetermined { points: n, monomials: m };
    if n < m || q > MAX_FIT_DEGREE {
        return Err(underdetermined);
    }
    let scale = points.iter().map(|p| (p[0] - centre[0]).hypot(p[1] - centre[1])).fold(0.0, f64::max);
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let mut v = DMatrix::<f64>::zeros(n, m);
    let mut rhs = DMatrix::<f64>::zeros(n, K);
    for (j, p) in points.iter().enumerate() {
        let z = [(p[0] - centre[0]) / scale, (p[1] - centre[1]) / scale];
        let w = (-(z[0] * z[0] + z[1] * z[1])).exp();
        let (z1, z2) = (powers_of(z[0], q), powers_of(z[1], q));
        for (k, &(a, b)) in powers.iter().enumerate() {
            v[(j, k)] = w * z1[a as usize] * z2[b as usize];
        }
        for c in 0..K {
            rhs[(j, c)] = w * values[j][c];
        }
    }
    let qr = v.qr();
    let r = qr.r();
    let largest = (0..m).map(|k| r[(k, k)].abs()).fold(0.0, f64::max);
    if (0..m).any(|k| !(r[(k, k)].abs() > 1e-10 * largest)) {
        return Err(underdetermined);
    }
    let mut qt_rhs = rhs;
    qr.q_tr_mul(&mut qt_rhs);
    let mut coefficients = vec![[0.0; K]; m];
    for c in 0..K {
        let column: DVector<f64> = qt_rhs.rows(0, m).column(c).into_owned();
        let solved = r.solve_upper_triangular(&column).ok_or(underdetermined.clone())?;
        for k in 0..m {
            coefficients[k][c] = solved[k];
        }
    }
    Ok(LocalPolynomial { centre, scale, degree: q, coefficients })
}

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

/// `C(n, k)`.
fn binomial(n: u32, k: u32) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * f64::from(n - i) / f64::from(i + 1))
}

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
                        let f = binomial(big_a, a) * binomial(big_b, b) * d1[(big_a - a) as usize] * d2[(big_b - b) as usize];
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

/// Points a fit of degree `q` takes: 10 times its monomials. The fitted values carry
/// the run's own error, and only wide least-squares fits average its rough part out
/// of the high-degree coefficients: with 2.5 times the monomials the estimate of the
/// tensor cantilever overshoots 1.5-4x, with 10 times it is within 0.84-1.20 of the
/// true error on every measured scene (docs/notebook/2026-11-28-cheap-estimate.md).
pub fn fit_points(q: u32) -> usize {
    10 * polynomial_size(q)
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

    /// Too few points, or points on a line, are refused, not fitted.
    #[test]
    fn underdetermined_fits_are_refused() {
        let line: Vec<[f64; 2]> = (0..20).map(|k| [k as f64, 0.0]).collect();
        let values = vec![[0.0; 1]; 20];
        assert!(fit([0.0, 0.0], &line, &values, 2).is_err());
        assert!(fit([0.0, 0.0], &line[..4], &values[..4], 2).is_err());
    }
}
