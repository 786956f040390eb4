//! The shape functions of one stencil, whatever the basis: the one place that
//! dispatches a [`Basis`] to its local solve (least squares or RBF-FD).

use super::basis::{Basis, Weight};
use super::frame::RankDeficient;
use super::ops::Op;
use super::{rbffd, wls};

/// Shape functions of `ops` at `centre` for the support `points` (the centre first),
/// written to `out[k * n .. (k + 1) * n]` for the k-th operator, so that
/// `(L u)(centre) ~= out[k] . u[support]`: weighted least squares ([`wls`]) for the
/// monomial and tensor bases, RBF-FD ([`rbffd`]) for the radial ones.
pub fn shape_functions(
    basis: &Basis,
    weight: &Weight,
    centre: [f64; 2],
    points: &[[f64; 2]],
    ops: &[Op],
    out: &mut [f64],
) -> Result<(), RankDeficient> {
    match basis {
        Basis::Monomials { .. } | Basis::Tensor { .. } => wls::shape_functions(basis, weight, (centre, points), ops, out),
        Basis::RbfFd { radial, degree } => rbffd::shape_functions(radial, *degree, centre, points, ops, out),
    }
}
