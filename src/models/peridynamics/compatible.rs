//! Asymptotically compatible bond weights: per node, the smallest relative change of
//! the base coefficients `c0` that makes the discrete operator reproduce the moments
//! of the continuum operator of a calibrated kernel,
//!
//! ```text
//! minimise sum_j (c_j - c0_j)^2 / c0_j   subject to   sum_j c_j p_k(xi_j / delta) = mu_k,
//!     mu_k = int_{H_i} lambda(|xi|) p_k(xi / delta) dA,
//! ```
//!
//! over monomials `p_k`; `H_i` is the node's horizon disc intersected with the body
//! (solid plus Dirichlet collar). Only degrees >= 3 enter: `u_j - u_i` of a constant
//! vanishes and `xi ⊗ xi` adds two degrees, so matching the moments of degrees 3..k+2
//! makes `L_h p = L p` for every polynomial `p` of degree k.
//!
//! * Complete families (`H_i` the whole disc): degrees 3, 4 and 5 (15 conditions) with
//!   the closed form `mu = M / delta^4 (3, 0, 1, 0, 3)` for the fourth degree and 0 for the
//!   odd ones. Then `L_h u = N u` (Navier) for every cubic field, and
//!   `L_h u - N u = O(delta^2)` for smooth `u` at a fixed ratio `m = delta/h`.
//! * Truncated families near free edges: degrees 3 and 4 (9 conditions) with `mu_k`
//!   integrated over the truncated disc ([`truncated_moments`]). Then `L_h` reproduces the
//!   continuum operator, surface effect included, for quadratic fields; without this the
//!   one-point rule's O(1) moment error near the edge acts like a spurious edge load whose
//!   effect does not shrink with delta (pd_tension.toml stalls: docs/methods/peridynamics.md).
//!
//! Solution (Lagrange multipliers): `c = c0 + S A^T y`, `(A S A^T) y = mu - A c0`,
//! `S = diag(c0)`, `A_kj = p_k(xi_j / delta)`: the same small weighted least-squares
//! machinery as the MLSM shapes. Scaling by delta keeps `A` of order one. The small
//! system is solved by Cholesky; a singular one (too few or degenerate bonds) returns
//! `None` and the caller keeps the base weights.

use super::Micromodulus;
use crate::domain::Point;
use gauss_quad::GaussLegendre;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;
use std::num::NonZeroUsize;

/// Exponents `(a, b)` of the constrained monomials `z1^a z2^b`, degrees 3 to 5.
pub const MOMENTS: [(i32, i32); 15] =
    [(3, 0), (2, 1), (1, 2), (0, 3), (4, 0), (3, 1), (2, 2), (1, 3), (0, 4), (5, 0), (4, 1), (3, 2), (2, 3), (1, 4), (0, 5)];

/// The moments constrained on truncated families (degrees 3 and 4).
pub const TRUNCATED_MOMENTS: &[(i32, i32)] = MOMENTS.split_at(9).0;

/// Continuum value of `sum_j c_j z1^a z2^b` over a complete family, for a kernel with
/// fourth moment `moment`.
pub fn target_moment((a, b): (i32, i32), moment: f64, delta: f64) -> f64 {
    let m = moment / delta.powi(4);
    match (a, b) {
        (4, 0) | (0, 4) => 3.0 * m,
        (2, 2) => m,
        _ => 0.0,
    }
}

/// Moments `int_{H} lambda(|xi|) (xi1/delta)^a (xi2/delta)^b dA` over the horizon disc
/// of `x` clipped to the points where `contains` holds ([`ray_moments`]); the radial
/// integral is exact for the plain kernel (`c R^(n-1) / ((n-1) delta^n)`) and
/// 16 x 12-point Gauss-Legendre otherwise (relative error below 1e-10 on the whole disc).
pub fn truncated_moments(x: Point, contains: &dyn Fn(Point) -> bool, kernel: &Micromodulus, moments: &[(i32, i32)]) -> Vec<f64> {
    let delta = kernel.horizon;
    let radial_rule = GaussLegendre::new(NonZeroUsize::new(12).unwrap());
    let radial = |reach: f64, n: i32| match kernel.kernel {
        super::Kernel::Plain => kernel.constant * reach.powi(n - 1) / ((n - 1) as f64 * delta.powi(n)),
        super::Kernel::Regularised { .. } => {
            let f = |r: f64| kernel.value(r) * (r / delta).powi(n) * r;
            (0..16).map(|q| radial_rule.integrate(reach * q as f64 / 16.0, reach * (q + 1) as f64 / 16.0, f)).sum()
        }
    };
    ray_moments(x, contains, delta, &radial, moments)
}

/// `int_0^2pi cos^a sin^b radial(R(theta), a + b) dtheta` for every `(a, b)` of
/// `moments`, `R(theta)` the distance from `x` along the ray at angle `theta` to the
/// first point where `contains` fails, capped at `delta`: 128 Gauss-Legendre panels of
/// 4 points in the angle; along each ray the first exit is bracketed in steps of
/// `delta/16` and bisected to `1e-12 delta`. With `radial(R, n) = int_0^R k(r) (r/delta)^n r dr`
/// this is the moment `int_H k(|xi|) (xi1/delta)^a (xi2/delta)^b dA` of a radial kernel `k`.
pub fn ray_moments(x: Point, contains: &dyn Fn(Point) -> bool, delta: f64, radial: &dyn Fn(f64, i32) -> f64, moments: &[(i32, i32)]) -> Vec<f64> {
    let angle_rule = GaussLegendre::new(NonZeroUsize::new(4).unwrap());
    let panels = 128;
    let mut out = vec![0.0; moments.len()];
    for k in 0..panels {
        let (t0, t1) = (2.0 * PI * k as f64 / panels as f64, 2.0 * PI * (k + 1) as f64 / panels as f64);
        for &(t, w) in angle_rule.as_node_weight_pairs() {
            let theta = 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * t;
            let wt = 0.5 * (t1 - t0) * w;
            let dir = [theta.cos(), theta.sin()];
            let at = |r: f64| contains([x[0] + r * dir[0], x[1] + r * dir[1]]);
            let reach = first_exit(&at, delta);
            // The radial integral depends on the degree n = a + b only: once per degree.
            let mut radial_of = [f64::NAN; 8];
            for (slot, &(a, b)) in out.iter_mut().zip(moments) {
                let n = (a + b) as usize;
                if radial_of[n].is_nan() {
                    radial_of[n] = radial(reach, a + b);
                }
                *slot += wt * dir[0].powi(a) * dir[1].powi(b) * radial_of[n];
            }
        }
    }
    out
}

/// Distance along a ray to the first point where `inside` fails, capped at `delta`.
fn first_exit(inside: &dyn Fn(f64) -> bool, delta: f64) -> f64 {
    let step = delta / 16.0;
    let mut r = 0.0;
    while r < delta {
        let next = (r + step).min(delta);
        if !inside(next) {
            let (mut lo, mut hi) = (r, next);
            while hi - lo > 1e-12 * delta {
                let mid = 0.5 * (lo + hi);
                if inside(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return lo;
        }
        r = next;
    }
    delta
}

/// Smallest squared pivot of the unit-diagonal Gram matrix of a compatible fit that
/// determines its correction (the reciprocal of a condition number of about 1e12).
const GRAM_PIVOT_LIMIT: f64 = 1e-12;

/// Corrected coefficients for the bonds `xi` with base coefficients `base` so that the
/// `moments` take the values `targets`, or `None` when the conditions cannot be met
/// (to `1e-9` of `scale`, the size of the largest moment) or do not determine the
/// correction (the Gram matrix's pivots, [`GRAM_PIVOT_LIMIT`]).
pub fn compatible_weights(xi: &[Point], base: &[f64], delta: f64, moments: &[(i32, i32)], targets: &[f64], scale: f64) -> Option<Vec<f64>> {
    let n = xi.len();
    let k = moments.len();
    if n < k || base.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
        return None;
    }
    let a = DMatrix::from_fn(k, n, |r, j| {
        let (p, q) = moments[r];
        (xi[j][0] / delta).powi(p) * (xi[j][1] / delta).powi(q)
    });
    let c0 = DVector::from_column_slice(base);
    let target = DVector::from_column_slice(targets);
    let residual = &target - &a * &c0;
    let a_s = DMatrix::from_fn(k, n, |r, j| a[(r, j)] * base[j]);
    let gram = &a_s * a.transpose();
    // Jacobi-scaled to a unit diagonal, the Gram matrix's pivots measure how well the
    // bonds separate the moment conditions whatever the units of the micromodulus;
    // below GRAM_PIVOT_LIMIT the correction is not determined (10 bonds for 9
    // conditions can leave it numerically singular), and whether Cholesky happened
    // to pass its rounding would decide the fit (it flipped with E from 1e-50 to 1e-230).
    let d: Vec<f64> = gram.diagonal().iter().map(|g| if *g > 0.0 { 1.0 / g.sqrt() } else { 0.0 }).collect();
    if d.iter().any(|v| *v == 0.0 || !v.is_finite()) {
        return None;
    }
    let unit = DMatrix::from_fn(k, k, |r, s| gram[(r, s)] * d[r] * d[s]);
    let chol = unit.cholesky()?;
    if chol.l_dirty().diagonal().iter().take(k).any(|l| l * l < GRAM_PIVOT_LIMIT) {
        return None;
    }
    let scaled_residual = DVector::from_fn(k, |r, _| residual[r] * d[r]);
    let z = chol.solve(&scaled_residual);
    let y = DVector::from_fn(k, |r, _| z[r] * d[r]);
    let c = c0 + a_s.transpose() * y;
    let err = (&a * &c - &target).amax();
    (err <= 1e-9 * scale && c.iter().all(|v| v.is_finite())).then(|| c.as_slice().to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::peridynamics::Kernel;

    /// Over a whole disc the ray quadrature reproduces the closed-form moments.
    #[test]
    fn truncated_moments_of_a_whole_disc() {
        for kernel in [Kernel::Plain, Kernel::Regularised { alpha: -3.0 }, Kernel::Regularised { alpha: 1.0 }] {
            let mm = Micromodulus::calibrated(kernel, 0.3, 2.0);
            let got = truncated_moments([0.0, 0.0], &|_| true, &mm, &MOMENTS);
            for (k, &(a, b)) in MOMENTS.iter().enumerate() {
                let want = target_moment((a, b), 2.0, 0.3);
                assert!((got[k] - want).abs() <= 1e-10 * 3.0 * 2.0 / 0.3f64.powi(4), "{kernel:?} {a},{b}: {} vs {want}", got[k]);
            }
        }
    }

    /// A half disc (straight edge through the centre) keeps half of every even moment
    /// and gives the odd ones a known sign.
    #[test]
    fn truncated_moments_of_a_half_disc() {
        let mm = Micromodulus::calibrated(Kernel::Plain, 1.0, 1.0);
        let got = truncated_moments([0.0, 0.0], &|p| p[1] <= 0.0, &mm, TRUNCATED_MOMENTS);
        let full: Vec<f64> = TRUNCATED_MOMENTS.iter().map(|&m| target_moment(m, 1.0, 1.0)).collect();
        for k in 4..9 {
            assert!((got[k] - full[k] / 2.0).abs() < 1e-8, "even moment {k}: {} vs {}", got[k], full[k] / 2.0);
        }
        // z2^3 over the lower half is negative, z1^3 vanishes by symmetry.
        assert!(got[3] < 0.0 && got[0].abs() < 1e-8);
    }
}
