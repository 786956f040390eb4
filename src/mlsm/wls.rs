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
use super::ops::Op;
use nalgebra::DMatrix;

/// Why a local fit failed.
#[derive(Debug, Clone, PartialEq)]
pub struct RankDeficient {
    /// Smallest `|R_kk| / max |R_kk|` found.
    pub ratio: f64,
    /// Basis size `m`.
    pub basis_size: usize,
}

/// Relative size of the smallest QR pivot below which `W B` counts as rank deficient.
pub const RANK_TOLERANCE: f64 = 1e-10;

/// Smallest `|R_kk| / max |R_kk|` of an upper triangular `r` (0 for a zero matrix).
fn diagonal_ratio(r: &DMatrix<f64>) -> f64 {
    let m = r.ncols().min(r.nrows());
    let diag_max = (0..m).map(|k| r[(k, k)].abs()).fold(0.0, f64::max);
    let diag_min = (0..m).map(|k| r[(k, k)].abs()).fold(f64::INFINITY, f64::min);
    if diag_max > 0.0 {
        diag_min / diag_max
    } else {
        0.0
    }
}

/// Smallest relative QR pivot `|R_kk| / max |R_kk|` of `b`: its numerical rank test.
pub fn rank_ratio(b: &DMatrix<f64>) -> f64 {
    diagonal_ratio(&b.clone().qr().r())
}

/// Shape functions of `ops` at `centre` for the support `points` (the centre first),
/// written to `out[k * n .. (k + 1) * n]` for the k-th operator: weighted least
/// squares for the monomial bases, [`super::rbffd`] for RBF-FD.
pub fn shape_functions(
    basis: &Basis,
    weight: &Weight,
    centre: [f64; 2],
    points: &[[f64; 2]],
    ops: &[Op],
    out: &mut [f64],
) -> Result<(), RankDeficient> {
    if let Basis::RbfFd { radial, degree } = basis {
        return super::rbffd::shape_functions(radial, *degree, centre, points, ops, out);
    }
    let n = points.len();
    let LocalFrame { dist, radius: s, nearest: h_p, z } = LocalFrame::new(centre, points);
    let sw: Vec<f64> = dist.iter().map(|&r| weight.sqrt_weight(r, h_p)).collect();
    let local = LocalBasis::new(basis);
    let m = local.len();

    let mut row = vec![0.0; m];
    let mut wb = DMatrix::<f64>::zeros(n, m);
    for j in 0..n {
        local.values(z[j], &mut row);
        for k in 0..m {
            wb[(j, k)] = sw[j] * row[k];
        }
    }
    let qr = wb.qr();
    let r = qr.r();
    let ratio = diagonal_ratio(&r);
    if ratio.is_nan() || ratio <= RANK_TOLERANCE {
        return Err(RankDeficient { ratio, basis_size: m });
    }
    // All operators at once: Y = R^-T L (m x k), then phi = W Q Y (n x k).
    let k = ops.len();
    let mut l = nalgebra::DMatrix::<f64>::zeros(m, k);
    for (c, &op) in ops.iter().enumerate() {
        local.operator_at_centre(op, &mut row);
        let scale = s.powi(-op.order());
        for a in 0..m {
            l[(a, c)] = row[a] * scale;
        }
    }
    let y = r.tr_solve_upper_triangular(&l).expect("nonzero pivots checked above");
    let phi = qr.q() * y;
    for c in 0..k {
        for j in 0..n {
            out[c * n + j] = sw[j] * phi[(j, c)];
        }
    }
    Ok(())
}

/// A stencil in local coordinates: `z_j = (x_j - centre) / radius`, `radius` the
/// largest distance from the centre, `nearest` the smallest non-zero one (the local
/// spacing that scales weights and shape parameters). Shared by least squares and
/// RBF-FD, so both are invariant to translation and to the unit of length.
pub(super) struct LocalFrame {
    /// `|x_j - centre|`.
    pub dist: Vec<f64>,
    /// `max_j |x_j - centre|`.
    pub radius: f64,
    /// `min_j |x_j - centre|` over the points other than the centre.
    pub nearest: f64,
    /// Scaled local coordinates.
    pub z: Vec<[f64; 2]>,
}

impl LocalFrame {
    /// The frame of `points` around `centre`.
    pub fn new(centre: [f64; 2], points: &[[f64; 2]]) -> LocalFrame {
        let rel: Vec<[f64; 2]> = points.iter().map(|x| [x[0] - centre[0], x[1] - centre[1]]).collect();
        let dist: Vec<f64> = rel.iter().map(|d| d[0].hypot(d[1])).collect();
        let radius = dist.iter().cloned().fold(0.0, f64::max);
        let nearest = dist.iter().cloned().filter(|&d| d > 0.0).fold(f64::INFINITY, f64::min);
        let z = rel.iter().map(|d| [d[0] / radius, d[1] / radius]).collect();
        LocalFrame { dist, radius, nearest, z }
    }
}
