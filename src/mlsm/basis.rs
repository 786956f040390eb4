//! Approximation bases and weights of the weighted least-squares fit, evaluated in
//! local coordinates `z = (x - p) / s` (`p` the centre node, `s` the support radius).
//!
//! * monomials of total degree `k`: `z1^a z2^b`, `a + b <= k` (`m = (k+1)(k+2)/2`);
//! * tensor-product monomials of degree `k`: `a, b <= k` (`m = (k+1)^2`);
//! * radial basis functions centred at the support nodes (`m = n`):
//!   Gaussian `exp(-(r/c)^2)`, multiquadric `sqrt(r^2 + c^2)`, inverse multiquadric
//!   `1/sqrt(r^2 + c^2)` (seeds-digest, 002, sec. 3), with the shape parameter `c`
//!   given in units of the local node spacing.
//!
//! Weight (seed 002, eq. 10 uses `W = diag(sqrt(w))`): none (`w = 1`) or Gaussian
//! `w(r) = exp(-(r / (sigma h_p))^2)` with `sigma` in units of the local spacing `h_p`
//! (distance from the centre to its nearest neighbour).

use super::ops::Op;
use crate::choice::choice;
use serde::Serialize;

/// Radial function of an RBF basis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RbfKind {
    /// `exp(-(r/c)^2)`.
    Gaussian,
    /// `sqrt(r^2 + c^2)`.
    Mq,
    /// `1 / sqrt(r^2 + c^2)`.
    Imq,
}

/// Basis of the local fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Basis {
    /// Monomials of total degree `<= degree`.
    Monomials { degree: u32 },
    /// Monomials `x^a y^b` with `a, b <= degree`.
    Tensor { degree: u32 },
    /// RBFs centred at the support nodes; `shape` in units of the local spacing.
    Rbf { rbf: RbfKind, shape: f64 },
}

choice! {
    /// The name of a basis in a scene (`approximation.basis`); its degree or shape
    /// parameter are their own fields.
    pub enum BasisKind("approximation.basis", default Some(BasisKind::Monomials)) {
        Monomials = "monomials" => "monomials x^a y^b of total degree a + b <= `degree` (2..6, default 2)",
        Tensor = "tensor" => "tensor-product monomials x^a y^b, a, b <= `degree`",
        Gaussian = "gaussian" => "Gaussian RBF exp(-(r/c)^2) at the support nodes, c = `shape` x local spacing",
        Mq = "mq" => "multiquadric RBF sqrt(r^2 + c^2), c = `shape` x local spacing",
        Imq = "imq" => "inverse multiquadric RBF 1/sqrt(r^2 + c^2), c = `shape` x local spacing",
    }
}

impl BasisKind {
    /// The radial function of an RBF basis (`None` for the polynomial bases).
    pub fn rbf(self) -> Option<RbfKind> {
        match self {
            BasisKind::Monomials | BasisKind::Tensor => None,
            BasisKind::Gaussian => Some(RbfKind::Gaussian),
            BasisKind::Mq => Some(RbfKind::Mq),
            BasisKind::Imq => Some(RbfKind::Imq),
        }
    }
}

choice! {
    /// The name of a weight in a scene (`approximation.weight`).
    pub enum WeightKind("approximation.weight", default Some(WeightKind::Gaussian)) {
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

/// Exponents `(a, b)` of a monomial basis.
pub fn monomial_exponents(basis: &Basis) -> Vec<(u32, u32)> {
    match *basis {
        Basis::Monomials { degree } => (0..=degree).flat_map(|t| (0..=t).map(move |b| (t - b, b))).collect(),
        Basis::Tensor { degree } => (0..=degree).flat_map(|a| (0..=degree).map(move |b| (a, b))).collect(),
        Basis::Rbf { .. } => Vec::new(),
    }
}

impl Basis {
    /// Number of basis functions `m` for a support of `n` nodes.
    pub fn size(&self, n: usize) -> usize {
        match self {
            Basis::Rbf { .. } => n,
            _ => monomial_exponents(self).len(),
        }
    }

    /// Highest total degree of polynomial the basis reproduces exactly (RBF: none, `None`).
    pub fn polynomial_degree(&self) -> Option<u32> {
        match *self {
            Basis::Monomials { degree } | Basis::Tensor { degree } => Some(degree),
            Basis::Rbf { .. } => None,
        }
    }

    /// Human-readable name for the summary.
    pub fn describe(&self) -> String {
        match self {
            Basis::Monomials { degree } => format!("monomials of total degree {degree}"),
            Basis::Tensor { degree } => format!("tensor-product monomials of degree {degree}"),
            Basis::Rbf { rbf, shape } => format!("{rbf:?} RBF, shape {shape} x spacing"),
        }
    }
}

/// Radial profile as a function of `q = r^2`: `(phi, dphi/dq, d2phi/dq2)`.
fn radial(kind: RbfKind, q: f64, c: f64) -> (f64, f64, f64) {
    let c2 = c * c;
    match kind {
        RbfKind::Gaussian => {
            let f = (-q / c2).exp();
            (f, -f / c2, f / (c2 * c2))
        }
        RbfKind::Mq => {
            let t = (q + c2).sqrt();
            (t, 0.5 / t, -0.25 / (t * t * t))
        }
        RbfKind::Imq => {
            let t = (q + c2).sqrt();
            (1.0 / t, -0.5 / (t * t * t), 0.75 / (t * t * t * t * t))
        }
    }
}

/// Local evaluation context of a basis at one centre.
pub struct LocalBasis<'a> {
    basis: Basis,
    exponents: Vec<(u32, u32)>,
    /// RBF centres (the support in local coordinates) and shape in local units.
    centres: &'a [[f64; 2]],
    shape_local: f64,
}

impl<'a> LocalBasis<'a> {
    /// Prepare `basis` for a support whose local coordinates are `centres`;
    /// `spacing_local = h_p / s`.
    pub fn new(basis: &Basis, centres: &'a [[f64; 2]], spacing_local: f64) -> Self {
        let shape_local = match basis {
            Basis::Rbf { shape, .. } => shape * spacing_local,
            _ => 0.0,
        };
        LocalBasis { basis: *basis, exponents: monomial_exponents(basis), centres, shape_local }
    }

    /// Number of functions `m`.
    pub fn len(&self) -> usize {
        match self.basis {
            Basis::Rbf { .. } => self.centres.len(),
            _ => self.exponents.len(),
        }
    }

    /// Whether the basis is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `b_k(z)` for all `k`.
    pub fn values(&self, z: [f64; 2], out: &mut [f64]) {
        match self.basis {
            Basis::Rbf { rbf, .. } => {
                for (o, c) in out.iter_mut().zip(self.centres) {
                    let q = (z[0] - c[0]).powi(2) + (z[1] - c[1]).powi(2);
                    *o = radial(rbf, q, self.shape_local).0;
                }
            }
            _ => {
                for (o, &(a, b)) in out.iter_mut().zip(&self.exponents) {
                    *o = z[0].powi(a as i32) * z[1].powi(b as i32);
                }
            }
        }
    }

    /// `(L b_k)(0)` in local coordinates for operator `op`.
    pub fn operator_at_centre(&self, op: Op, out: &mut [f64]) {
        let (da, db) = op.multi_index();
        match self.basis {
            Basis::Rbf { rbf, .. } => {
                for (o, c) in out.iter_mut().zip(self.centres) {
                    let d = [-c[0], -c[1]];
                    let (f, f1, f2) = radial(rbf, d[0] * d[0] + d[1] * d[1], self.shape_local);
                    *o = match op {
                        Op::Value => f,
                        Op::Dx => 2.0 * f1 * d[0],
                        Op::Dy => 2.0 * f1 * d[1],
                        Op::Dxx => 4.0 * f2 * d[0] * d[0] + 2.0 * f1,
                        Op::Dxy => 4.0 * f2 * d[0] * d[1],
                        Op::Dyy => 4.0 * f2 * d[1] * d[1] + 2.0 * f1,
                    };
                }
            }
            _ => {
                // d^(da+db) z1^a z2^b at z = 0 is a! b! when (a, b) = (da, db), else 0.
                let fact = |k: u32| (1..=k).product::<u32>() as f64;
                for (o, &(a, b)) in out.iter_mut().zip(&self.exponents) {
                    *o = if (a, b) == (da, db) { fact(a) * fact(b) } else { 0.0 };
                }
            }
        }
    }
}
