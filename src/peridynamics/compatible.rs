//! Asymptotically compatible bond weights: per node, the smallest relative change of
//! the base coefficients `c0` that makes the discrete operator reproduce the
//! continuum moments of a calibrated kernel,
//!
//! ```text
//! minimise sum_j (c_j - c0_j)^2 / c0_j   subject to   sum_j c_j p_k(xi_j / delta) = mu_k,
//! ```
//!
//! over the monomials `p_k` of degrees 3, 4 and 5 (15 conditions):
//! `mu = M / delta^4 * (3, 0, 1, 0, 3)` for `(z1^4, z1^3 z2, z1^2 z2^2, z1 z2^3, z2^4)` and
//! 0 for every odd monomial. Then `L_h p = L p` for every cubic `p` (the even moments of
//! degree <= 2 do not enter: `u_j - u_i` of a constant vanishes and `xi ⊗ xi` adds two
//! degrees), so `L_h u = N u` (the Navier operator) for all cubic fields, and
//! `L_h u - N u = O(delta^2)` for smooth `u` at a fixed ratio `m = delta/h`.
//!
//! Solution (Lagrange multipliers): `c = c0 + S A^T y`, `(A S A^T) y = mu - A c0`,
//! `S = diag(c0)`, `A_kj = p_k(xi_j / delta)`: the same small weighted least-squares
//! machinery as the MLSM shapes. Scaling by delta keeps `A` of order one. The 15 x 15
//! system is solved by Cholesky; a singular one (too few or degenerate bonds) returns
//! `None` and the caller keeps the base weights.

use crate::domain::Point;
use nalgebra::{DMatrix, DVector};

/// Exponents `(a, b)` of the constrained monomials `z1^a z2^b`, degrees 3 to 5.
pub const MOMENTS: [(i32, i32); 15] =
    [(3, 0), (2, 1), (1, 2), (0, 3), (4, 0), (3, 1), (2, 2), (1, 3), (0, 4), (5, 0), (4, 1), (3, 2), (2, 3), (1, 4), (0, 5)];

/// Continuum value of `sum_j c_j z1^a z2^b` for a kernel with fourth moment `moment`.
pub fn target_moment((a, b): (i32, i32), moment: f64, delta: f64) -> f64 {
    let m = moment / delta.powi(4);
    match (a, b) {
        (4, 0) | (0, 4) => 3.0 * m,
        (2, 2) => m,
        _ => 0.0,
    }
}

/// Corrected coefficients for the bonds `xi` with base coefficients `base`, or `None`
/// when the moment conditions cannot be met.
pub fn compatible_weights(xi: &[Point], base: &[f64], delta: f64, moment: f64) -> Option<Vec<f64>> {
    let n = xi.len();
    let k = MOMENTS.len();
    if n < k || base.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
        return None;
    }
    let a = DMatrix::from_fn(k, n, |r, j| {
        let (p, q) = MOMENTS[r];
        (xi[j][0] / delta).powi(p) * (xi[j][1] / delta).powi(q)
    });
    let c0 = DVector::from_column_slice(base);
    let target = DVector::from_fn(k, |r, _| target_moment(MOMENTS[r], moment, delta));
    let residual = &target - &a * &c0;
    let a_s = DMatrix::from_fn(k, n, |r, j| a[(r, j)] * base[j]);
    let gram = &a_s * a.transpose();
    let y = gram.cholesky()?.solve(&residual);
    let c = c0 + a_s.transpose() * y;
    // Accept only if the conditions hold to round-off (relative to the largest moment).
    let err = (&a * &c - &target).amax();
    let scale = 3.0 * moment / delta.powi(4);
    (err <= 1e-9 * scale && c.iter().all(|v| v.is_finite())).then(|| c.as_slice().to_vec())
}
