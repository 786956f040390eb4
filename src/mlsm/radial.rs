//! The radial functions of RBF-FD stencils, `r = |z - z_j|` in local coordinates:
//! * polyharmonic spline `r^beta`, `beta` odd `>= 3` (no shape parameter; all its
//!   derivatives up to second order vanish at `r = 0`);
//! * Gaussian `exp(-(r/c)^2)`, multiquadric `sqrt(r^2 + c^2)`, inverse multiquadric
//!   `1/sqrt(r^2 + c^2)`, with `c` in local units (the scene gives it in units of the
//!   local spacing).

use super::ops::Op;
use serde::Serialize;

/// The radial function of an RBF-FD stencil.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Radial {
    /// Polyharmonic spline `r^order`, `order` odd and at least 3.
    Phs {
        /// The exponent (3, 5, 7, ...).
        order: u32,
    },
    /// `exp(-(r/c)^2)`, `c = shape` x local spacing.
    Gaussian {
        /// Shape parameter in units of the local spacing.
        shape: f64,
    },
    /// `sqrt(r^2 + c^2)`.
    Mq {
        /// Shape parameter in units of the local spacing.
        shape: f64,
    },
    /// `1 / sqrt(r^2 + c^2)`.
    Imq {
        /// Shape parameter in units of the local spacing.
        shape: f64,
    },
}

impl Radial {
    /// Shape parameter in units of the local spacing (`None` for PHS).
    pub fn shape(&self) -> Option<f64> {
        match *self {
            Radial::Phs { .. } => None,
            Radial::Gaussian { shape } | Radial::Mq { shape } | Radial::Imq { shape } => Some(shape),
        }
    }

    /// `(phi, dphi/dr / r, (d2phi/dr2 - dphi/dr / r) / r^2)` at distance `r`, with `c` the
    /// shape parameter in local units: then `d phi / dz_a = f1 d_a` and
    /// `d2 phi / dz_a dz_b = f2 d_a d_b + f1 delta_ab` for `d = z - z_j`.
    pub(super) fn profile(&self, r: f64, c: f64) -> (f64, f64, f64) {
        match *self {
            Radial::Phs { order } => {
                let b = order as f64;
                if r == 0.0 {
                    // Every derivative up to second order vanishes at the centre for b >= 3.
                    return (0.0, 0.0, 0.0);
                }
                // Integer powers by multiplication (`powf` was most of the cost of a
                // stencil: docs/notebook/round2-shapes-per-node-by-basis.md).
                let k = order as i32;
                let rk2 = r.powi(k - 2);
                (rk2 * r * r, b * rk2, b * (b - 2.0) * rk2 / (r * r))
            }
            Radial::Gaussian { .. } => {
                let f = (-(r * r) / (c * c)).exp();
                (f, -2.0 * f / (c * c), 4.0 * f / (c * c * c * c))
            }
            Radial::Mq { .. } => {
                let t = (r * r + c * c).sqrt();
                (t, 1.0 / t, -1.0 / (t * t * t))
            }
            Radial::Imq { .. } => {
                let t = (r * r + c * c).sqrt();
                (1.0 / t, -1.0 / (t * t * t), 3.0 / (t * t * t * t * t))
            }
        }
    }

    /// `phi(|z_i - zj|)` for every `z_i` of `z`, into `out` (one column of the
    /// stencil's matrix; local coordinates within the unit disc, so `sqrt` needs no
    /// guard against overflow). The kind is matched once for the column, so the loop
    /// over the points is straight-line arithmetic (`r^3 = r^2 sqrt(r^2)` for the
    /// usual PHS).
    pub(super) fn column(&self, z: &[[f64; 2]], zj: [f64; 2], c: f64, out: &mut [f64]) {
        let r2 = |zi: &[f64; 2]| {
            let (dx, dy) = (zi[0] - zj[0], zi[1] - zj[1]);
            dx * dx + dy * dy
        };
        match *self {
            Radial::Phs { order: 3 } => z.iter().zip(out).for_each(|(zi, o)| {
                let s = r2(zi);
                *o = s * s.sqrt();
            }),
            Radial::Phs { order } => {
                let half = (order / 2) as i32;
                z.iter().zip(out).for_each(|(zi, o)| {
                    let s = r2(zi);
                    *o = s.powi(half) * s.sqrt();
                })
            }
            _ => z.iter().zip(out).for_each(|(zi, o)| *o = self.profile(r2(zi).sqrt(), c).0),
        }
    }

    /// The radial function about `zj` and its derivatives at `z = 0`, from which
    /// [`AtCentre::apply`] takes `L phi(|z - zj|)` at `z = 0` for each operator.
    pub(super) fn at_centre(&self, zj: [f64; 2], c: f64) -> AtCentre {
        let d = [-zj[0], -zj[1]];
        // Local coordinates (within the unit disc): no overflow for `sqrt` to guard against.
        let (f, f1, f2) = self.profile((d[0] * d[0] + d[1] * d[1]).sqrt(), c);
        AtCentre { d, f, f1, f2 }
    }
}

/// A radial function about a stencil node `zj`, at the centre `z = 0`: `d = -zj` and
/// the profile `(phi, phi'/r, (phi'' - phi'/r)/r^2)` there ([`Radial::profile`]).
pub(super) struct AtCentre {
    d: [f64; 2],
    f: f64,
    f1: f64,
    f2: f64,
}

impl AtCentre {
    /// `L phi` at the centre: `d phi / dz_a = f1 d_a`, `d2 phi / dz_a dz_b = f2 d_a d_b + f1 delta_ab`.
    pub(super) fn apply(&self, op: Op) -> f64 {
        let AtCentre { d, f, f1, f2 } = *self;
        match op {
            Op::Value => f,
            Op::Dx => f1 * d[0],
            Op::Dy => f1 * d[1],
            Op::Dxx => f2 * d[0] * d[0] + f1,
            Op::Dxy => f2 * d[0] * d[1],
            Op::Dyy => f2 * d[1] * d[1] + f1,
        }
    }
}
