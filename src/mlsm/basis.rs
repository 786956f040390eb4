//! Approximation bases and weights of the local fits, evaluated in local coordinates
//! `z = (x - p) / s` (`p` the centre node, `s` the support radius).
//!
//! Weighted least squares ([`super::wls`]):
//! * monomials of total degree `k`: `z1^a z2^b`, `a + b <= k` (`m = (k+1)(k+2)/2`);
//! * tensor-product monomials of degree `k`: `a, b <= k` (`m = (k+1)^2`);
//!
//! with the weight (seed 002, eq. 10 uses `W = diag(sqrt(w))`) none (`w = 1`) or
//! Gaussian `w(r) = exp(-(r / (sigma h_p))^2)`, `sigma` in units of the local spacing
//! `h_p` (distance from the centre to its nearest neighbour).
//!
//! RBF-FD ([`super::rbffd`]): a radial function centred at every stencil node
//! (polyharmonic spline, or Gaussian, multiquadric, inverse multiquadric with a
//! shape parameter in units of the local spacing) augmented with the monomials of
//! total degree `p`. Plain RBF collocation without the monomials (`m = n`) is not
//! offered: it does not reproduce constants, and gave e_inf(u) 0.55 to 2.9 on the
//! shipped scenes.

use super::ops::Op;
use super::radial::Radial;
use crate::scene::choice::choice;
use serde::Serialize;

/// Basis of the local fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Basis {
    /// Monomials of total degree `<= degree` (weighted least squares).
    Monomials { degree: u32 },
    /// Monomials `x^a y^b` with `a, b <= degree` (weighted least squares).
    Tensor { degree: u32 },
    /// RBF-FD: `radial` at every stencil node plus the monomials of total degree `<= degree`.
    #[serde(rename = "rbf-fd")]
    RbfFd { radial: Radial, degree: u32 },
}

choice! {
    /// The name of a basis in a scene (`approximation.basis`); its degree, PHS order or
    /// shape parameter are their own fields.
    pub enum BasisKind("approximation.basis", default Some(BasisKind::Monomials)) {
        Monomials = "monomials" => "weighted least squares on monomials x^a y^b of total degree a + b <= `degree`",
        Tensor = "tensor" => "weighted least squares on tensor-product monomials x^a y^b, a, b <= `degree`",
        Phs = "phs" => "RBF-FD: polyharmonic spline r^`exponent` (odd, at least 3, default 3) plus monomials of total degree `degree`",
        Gaussian = "gaussian" => "RBF-FD: Gaussian exp(-(r/c)^2), c = `shape` x local spacing, plus monomials of total degree `degree`",
        Mq = "mq" => "RBF-FD: multiquadric sqrt(r^2 + c^2), c = `shape` x local spacing, plus monomials of total degree `degree`",
        Imq = "imq" => "RBF-FD: inverse multiquadric 1/sqrt(r^2 + c^2), c = `shape` x local spacing, plus monomials of total degree `degree`",
    }
}

impl BasisKind {
    /// Whether the basis is RBF-FD (an interpolation on its stencil, no weight).
    pub fn is_rbf_fd(self) -> bool {
        !matches!(self, BasisKind::Monomials | BasisKind::Tensor)
    }

    /// Whether the basis takes a shape parameter.
    pub fn has_shape(self) -> bool {
        matches!(self, BasisKind::Gaussian | BasisKind::Mq | BasisKind::Imq)
    }
}

choice! {
    /// The name of a weight in a scene (`approximation.weight`).
    pub enum WeightKind("approximation.weight", default Some(WeightKind::Gaussian), note "\"gaussian\" for least-squares bases; none for RBF-FD") {
        Gaussian = "gaussian" => "w(r) = exp(-(r / (sigma h))^2), `sigma` in units of the local spacing h (default 1)",
        None = "none" => "w = 1 (unweighted least squares)",
    }
}

/// Weight of the local fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Weight {
    /// `w = 1`.
    None,
    /// `w(r) = exp(-(r / (sigma h_p))^2)`.
    Gaussian { sigma: f64 },
}

impl Weight {
    /// `sqrt(w)` at distance `r` from a centre whose local spacing is `h_p`.
    pub fn sqrt_weight(&self, r: f64, h_p: f64) -> f64 {
        match self {
            Weight::None => 1.0,
            Weight::Gaussian { sigma } => (-0.5 * (r / (sigma * h_p)).powi(2)).exp(),
        }
    }
}

/// Exponents `(a, b)` of the monomials of a basis (for RBF-FD: of its polynomial part).
pub fn monomial_exponents(basis: &Basis) -> Vec<(u32, u32)> {
    match *basis {
        Basis::Monomials { degree } | Basis::RbfFd { degree, .. } => (0..=degree).flat_map(|t| (0..=t).map(move |b| (t - b, b))).collect(),
        Basis::Tensor { degree } => (0..=degree).flat_map(|a| (0..=degree).map(move |b| (a, b))).collect(),
    }
}

impl Basis {
    /// Number of polynomial terms `m` (a support needs at least this many nodes).
    pub fn size(&self) -> usize {
        match *self {
            Basis::RbfFd { degree, .. } => polynomial_size(degree),
            _ => monomial_exponents(self).len(),
        }
    }

    /// Highest total degree of polynomial the basis reproduces exactly.
    pub fn polynomial_degree(&self) -> u32 {
        match *self {
            Basis::Monomials { degree } | Basis::Tensor { degree } | Basis::RbfFd { degree, .. } => degree,
        }
    }

    /// Human-readable name for the summary.
    pub fn describe(&self) -> String {
        match self {
            Basis::Monomials { degree } => format!("monomials of total degree {degree}"),
            Basis::Tensor { degree } => format!("tensor-product monomials of degree {degree}"),
            Basis::RbfFd { radial: Radial::Phs { order }, degree } => format!("RBF-FD, PHS r^{order} + monomials of degree {degree}"),
            Basis::RbfFd { radial, degree } => {
                format!("RBF-FD, {radial:?} + monomials of degree {degree}")
            }
        }
    }
}

/// Number of monomials of total degree `<= degree` in 2D: `(p + 1)(p + 2) / 2`.
pub fn polynomial_size(degree: u32) -> usize {
    ((degree + 1) * (degree + 2) / 2) as usize
}

/// The monomials of a least-squares basis at one centre, in local coordinates.
pub struct LocalBasis {
    exponents: Vec<(u32, u32)>,
}

impl LocalBasis {
    /// The monomials of `basis`.
    pub fn new(basis: &Basis) -> Self {
        LocalBasis { exponents: monomial_exponents(basis) }
    }

    /// Number of functions `m`.
    pub fn len(&self) -> usize {
        self.exponents.len()
    }

    /// The exponents `(a, b)` of its monomials `z1^a z2^b`, in the order of [`LocalBasis::values`].
    pub fn exponents(&self) -> &[(u32, u32)] {
        &self.exponents
    }

    /// Whether the basis is empty.
    pub fn is_empty(&self) -> bool {
        self.exponents.is_empty()
    }

    /// `b_k(z)` for all `k`, from tables of the powers of `z1` and `z2` built by
    /// repeated multiplication (`powi` is a library call per factor, which slowed the
    /// shapes stage: docs/notebook/round2-target-error.md).
    pub fn values(&self, z: [f64; 2], out: &mut [f64]) {
        const POWERS: usize = 16;
        let top = self.exponents.iter().map(|&(a, b)| a.max(b) as usize).max().unwrap_or(0);
        if top >= POWERS {
            for (o, &(a, b)) in out.iter_mut().zip(&self.exponents) {
                *o = z[0].powi(a as i32) * z[1].powi(b as i32);
            }
            return;
        }
        let (mut px, mut py) = ([1.0f64; POWERS], [1.0f64; POWERS]);
        for k in 1..=top {
            px[k] = px[k - 1] * z[0];
            py[k] = py[k - 1] * z[1];
        }
        for (o, &(a, b)) in out.iter_mut().zip(&self.exponents) {
            *o = px[a as usize] * py[b as usize];
        }
    }

    /// `(L b_k)(0)` in local coordinates for operator `op`: `a! b!` for the monomial
    /// `z1^a z2^b` whose exponents are the derivative's, else 0.
    pub fn operator_at_centre(&self, op: Op, out: &mut [f64]) {
        let (da, db) = op.multi_index();
        let fact = |k: u32| (1..=k).product::<u32>() as f64;
        for (o, &(a, b)) in out.iter_mut().zip(&self.exponents) {
            *o = if (a, b) == (da, db) { fact(a) * fact(b) } else { 0.0 };
        }
    }
}
