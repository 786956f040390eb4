//! The dilatation term of the linear peridynamic solid (Silling et al. 2007,
//! linearised; written as Mengesha and Du's peridynamic Navier operator): any
//! Poisson ratio on top of the bond-based operator `L_b` of [`super::operator`].
//!
//! ```text
//! theta(x) = (D u)(x) = (2 / A(x)) int_{H_x} xi . (u(x + xi) - u(x)) / |xi|^2 dA,     A(x) = |H_x|,
//! (L u)(x) = (L_b u)(x) - beta (D^* theta)(x),     beta = lambda - mu   (in-plane Lame constants),
//! ```
//!
//! `H_x` the horizon disc clipped to the body and `L_b` calibrated to `M = 2 mu`
//! ([`super::kernel`]). In the interior `int 2 / (pi delta^2) xi ⊗ xi / |xi|^2 dA = I`, so
//! `D u -> div u`, and `-D^* theta = int 2 / (pi delta^2) xi / |xi|^2 (theta(x + xi) + theta(x)) dA
//! -> grad theta`. Both are exact on polynomials: `D` on cubic `u` up to a constant (its
//! fourth moments), which `-D^*` does not see, and `-D^*` on quadratics; so
//! `L u = mu lap u + 2 mu grad div u + (lambda - mu) grad div u`, the Navier operator for
//! any `nu`, exactly for cubic fields. The term is the variation of the energy
//! `(beta / 2) int theta^2 dA`: the stiffness stays symmetric, and `beta < 0` (`nu < 1/4`
//! in plane strain, `nu < 1/3` in plane stress) lowers the bond-based one.
//!
//! Discretisation, on the bond-based rule's nodes: `theta_i = sum_j w_ij xi_ij . (u_j - u_i)`
//! at the free nodes and at every collar node a free node reads (the collar is `2 delta`
//! wide, [`super::PdParams::collar_width`], so that those have complete families), and
//! `-D_h^*` is `D_h`'s adjoint in the volume-weighted inner product:
//!
//! ```text
//! (L_dil u)_k = beta sum_j xi_kj (w_kj theta_k + (V_j / V_k) w_jk theta_j),     K_dil = beta D_h^T diag(V) D_h.
//! ```
//!
//! Weights: base `w_ij = 2 / (A_i |xi_ij|^2) V_j f_ij` (`f_ij` of the rule,
//! [`super::weights::area_fraction`]). With the compatible rule (`ac`) a complete family's
//! weights are the smallest relative change of the base ones
//! ([`super::compatible::compatible_weights`]) that matches the continuum moments of
//! degrees 1-4 (14 conditions: those of `D_h` are degrees 2-4, those of `-D_h^*` 1-3),
//! a truncated family's the moments of degrees 1-3 over its truncated disc with its own
//! area `A_i` ([`super::compatible::ray_moments`]). With the other rules, and where a fit
//! is singular, the base weights are scaled so that `sum_j w_ij |xi_ij|^2 = 2` (the
//! node's own weighted volume, as LPS codes normalise): `theta` is exact for an
//! isotropic expansion at every node. A family cut by the sight of fictitious nodes
//! ([`super::extension::in_sight`]) matches the whole disc's moments of degrees 1-3.

use super::assembly::{chunks, RowBuilder};
use super::compatible::{compatible_weights, ray_moments};
use super::extension::in_sight;
use super::family::Families;
use super::nodes::{Body, PdNodes};
use super::weights::{area_fraction, full_families, search_radius};
use super::{PdParams, Quadrature};
use crate::domain::Point;
use crate::physics::elasticity::material::Material;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Exponents `(a, b)` of the moments `sum_j w_j z1^a z2^b` (`z = xi / delta`) a complete
/// family's weights match: degrees 1 to 4.
pub const MOMENTS: [(i32, i32); 14] =
    [(1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3), (4, 0), (3, 1), (2, 2), (1, 3), (0, 4)];

/// The moments a truncated family's weights match (degrees 1 to 3).
pub const TRUNCATED_MOMENTS: &[(i32, i32)] = MOMENTS.split_at(9).0;

/// `beta = lambda - mu` of the in-plane Lame constants: the dilatation term's factor.
pub fn coefficient(material: &Material) -> f64 {
    let l = material.lame();
    l.lambda - l.mu
}

/// Continuum value of `sum_j w_j z1^a z2^b` over a whole disc, kernel
/// `2 / (pi delta^2 |xi|^2)`: `1 / delta^2` for `z1^2`, `z2^2`; `3 / (8 delta^2)` for `z1^4`,
/// `z2^4`; `1 / (8 delta^2)` for `z1^2 z2^2`; 0 otherwise.
pub fn target_moment((a, b): (i32, i32), delta: f64) -> f64 {
    let d2 = delta * delta;
    match (a, b) {
        (2, 0) | (0, 2) => 1.0 / d2,
        (4, 0) | (0, 4) => 3.0 / (8.0 * d2),
        (2, 2) => 1.0 / (8.0 * d2),
        _ => 0.0,
    }
}

/// The dilatation's families and weights over the nodes that carry a `theta`.
#[derive(Debug, Clone)]
pub struct Dilatation {
    /// Families of every node (free and collar), the same radius as the bonds'.
    pub families: Families,
    /// `w_ij` per bond of `families` (zero for nodes no free node reads).
    weights: Vec<f64>,
    /// Per bond `i -> j`: `w_ji`, the weight of the reverse bond in `j`'s row.
    reverse: Vec<f64>,
    /// `sum_j w_ij xi_ij` of every node (`theta_i`'s coefficient of `u_i`, negated).
    sums: Vec<[f64; 2]>,
    /// `beta = lambda - mu`.
    pub coefficient: f64,
    /// Nodes whose weights were fitted to the continuum moments (`ac`).
    pub fitted_rows: usize,
    /// Nodes where that fit was singular (normalised base weights kept).
    pub fit_failures: usize,
}

fn offset(x: &[Point], i: usize, j: usize) -> Point {
    [x[j][0] - x[i][0], x[j][1] - x[i][1]]
}

/// `w` scaled so that `sum_j w_j |xi_j|^2 = 2` (unchanged when that sum is zero).
fn normalised(mut w: Vec<f64>, xi: &[Point]) -> Vec<f64> {
    let m: f64 = w.iter().zip(xi).map(|(w, d)| w * (d[0] * d[0] + d[1] * d[1])).sum();
    if m > 0.0 {
        w.iter_mut().for_each(|v| *v *= 2.0 / m);
    }
    w
}

impl Dilatation {
    /// Families and weights (module docs) of the nodes of `nodes` over `body` for `params`,
    /// the factor of `material`.
    pub fn new(body: &Body, nodes: &PdNodes, params: &PdParams, material: &Material) -> Dilatation {
        let n = nodes.len();
        let x = &nodes.positions;
        let families = Families::within(x, n, search_radius(params));
        let families = if nodes.fictitious_count() > 0 { families.retain(|i, j| in_sight(body, nodes, i, j)).0 } else { families };
        // A node carries a theta when a free node reads it: itself free or in a free family.
        let mut needed = vec![false; n];
        for i in 0..nodes.free {
            needed[i] = true;
            for &j in families.of(i) {
                needed[j as usize] = true;
            }
        }
        let delta = params.horizon;
        let full = full_families(params);
        let complete_targets: Vec<f64> = MOMENTS.iter().map(|&m| target_moment(m, delta)).collect();
        let with_area: Vec<(i32, i32)> = std::iter::once((0, 0)).chain(TRUNCATED_MOMENTS.iter().copied()).collect();
        let scale = 1.0 / (delta * delta);
        // Per node: weights, and whether a fit was tried and succeeded.
        let rows: Vec<(Vec<f64>, Option<bool>)> = (0..n)
            .into_par_iter()
            .map(|i| {
                let family = families.of(i);
                if !needed[i] {
                    return (vec![0.0; family.len()], None);
                }
                let xi: Vec<Point> = family.iter().map(|&j| offset(x, i, j as usize)).collect();
                let base = |c: f64| -> Vec<f64> {
                    xi.iter()
                        .zip(family)
                        .map(|(d, &j)| c / (d[0] * d[0] + d[1] * d[1]) * nodes.volumes[j as usize] * area_fraction(params, *d))
                        .collect()
                };
                if params.quadrature != Quadrature::Compatible {
                    return (normalised(base(1.0), &xi), None);
                }
                let complete = full.get(nodes.rule_point[i] as usize).is_some_and(|f| family.len() == f.1);
                let fitted = if families.is_cut(i) {
                    // Cut by the sight of fictitious nodes: a consistent one-sided row
                    // (the whole disc's moments of degrees 1-3).
                    compatible_weights(&xi, &base(2.0 / (PI * delta * delta)), delta, TRUNCATED_MOMENTS, &complete_targets[..9], scale)
                } else if complete {
                    compatible_weights(&xi, &base(2.0 / (PI * delta * delta)), delta, &MOMENTS, &complete_targets, scale)
                } else {
                    // int_0^R r^-2 (r/delta)^n r dr = (R/delta)^n / n; the (0, 0) entry is the area.
                    let radial = |reach: f64, k: i32| if k == 0 { 0.5 * reach * reach } else { (reach / delta).powi(k) / k as f64 };
                    let m = ray_moments(x[i], &|p| body.contains(p), delta, &radial, &with_area);
                    let area = m[0];
                    let targets: Vec<f64> = m[1..].iter().map(|v| 2.0 * v / area).collect();
                    (area > 0.0).then(|| compatible_weights(&xi, &base(2.0 / area), delta, TRUNCATED_MOMENTS, &targets, scale)).flatten()
                };
                match fitted {
                    Some(w) => (w, Some(true)),
                    None => (normalised(base(1.0), &xi), Some(false)),
                }
            })
            .collect();
        let counted = |want: bool| rows.iter().take(nodes.free).filter(|r| r.1 == Some(want)).count();
        let (fitted_rows, fit_failures) = (counted(true), counted(false));
        let weights: Vec<f64> = rows.into_iter().flat_map(|r| r.0).collect();
        let reverse: Vec<f64> = (0..n)
            .into_par_iter()
            .flat_map_iter(|i| {
                let (families, weights) = (&families, &weights);
                families.of(i).iter().map(move |&j| {
                    let j = j as usize;
                    families.of(j).binary_search(&(i as u32)).map_or(0.0, |p| weights[families.range(j).start + p])
                })
            })
            .collect();
        let sums: Vec<[f64; 2]> = (0..n)
            .into_par_iter()
            .map(|i| {
                families.range(i).zip(families.of(i)).fold([0.0, 0.0], |s, (b, &j)| {
                    let d = offset(x, i, j as usize);
                    [s[0] + weights[b] * d[0], s[1] + weights[b] * d[1]]
                })
            })
            .collect();
        Dilatation { families, weights, reverse, sums, coefficient: coefficient(material), fitted_rows, fit_failures }
    }

    /// `theta_i = sum_j w_ij xi_ij . (u_j - u_i)` at every node, `u` the displacement of
    /// every node (collar included).
    pub fn theta(&self, nodes: &PdNodes, u: &[[f64; 2]]) -> Vec<f64> {
        let x = &nodes.positions;
        (0..nodes.len())
            .into_par_iter()
            .map(|i| {
                let f = &self.families;
                f.range(i).zip(f.of(i)).fold(0.0, |t, (b, &j)| {
                    let (j, d) = (j as usize, offset(x, i, j as usize));
                    t + self.weights[b] * (d[0] * (u[j][0] - u[i][0]) + d[1] * (u[j][1] - u[i][1]))
                })
            })
            .collect()
    }

    /// `(L_dil u)_k = beta sum_j xi_kj (w_kj theta_k + (V_j / V_k) w_jk theta_j)` at free node
    /// `k`, `theta` from [`Dilatation::theta`].
    pub fn force_at(&self, nodes: &PdNodes, theta: &[f64], k: usize) -> [f64; 2] {
        let (x, v) = (&nodes.positions, &nodes.volumes);
        let f = &self.families;
        let mut out = [0.0, 0.0];
        for (b, &j) in f.range(k).zip(f.of(k)) {
            let j = j as usize;
            let d = offset(x, k, j);
            let s = self.weights[b] * theta[k] + v[j] / v[k] * self.reverse[b] * theta[j];
            out[0] += d[0] * s;
            out[1] += d[1] * s;
        }
        [self.coefficient * out[0], self.coefficient * out[1]]
    }

    /// `(beta / 2) sum_i V_i theta_i^2`, the dilatation's elastic energy.
    pub fn energy(&self, nodes: &PdNodes, theta: &[f64]) -> f64 {
        0.5 * self.coefficient * theta.iter().zip(&nodes.volumes).map(|(t, v)| v * t * t).sum::<f64>()
    }

    /// The 2x2 blocks `[xx, xy, yx, yy]` of free node `k`'s rows of
    /// `K_dil = beta D_h^T diag(V) D_h`, handed to `add` by column node (with repeats).
    pub fn row(&self, nodes: &PdNodes, k: usize, add: &mut dyn FnMut(usize, [f64; 4])) {
        let (x, v, f) = (&nodes.positions, &nodes.volumes, &self.families);
        let mut add = |l: usize, a: [f64; 2], d: [f64; 2]| add(l, [a[0] * d[0], a[0] * d[1], a[1] * d[0], a[1] * d[1]]);
        // Row k of K_dil = sum over the thetas that read u_k (k's own and its
        // neighbours') of beta V_s (coefficient of u_k in theta_s) ⊗ (row of theta_s).
        let beta = self.coefficient;
        let own = [-beta * v[k] * self.sums[k][0], -beta * v[k] * self.sums[k][1]];
        let sources = std::iter::once((k, own)).chain(f.range(k).zip(f.of(k)).map(|(b, &j)| {
            let j = j as usize;
            let d = offset(x, k, j);
            (j, [-beta * v[j] * self.reverse[b] * d[0], -beta * v[j] * self.reverse[b] * d[1]])
        }));
        for (s, a) in sources {
            for (c, &l) in f.range(s).zip(f.of(s)) {
                let d = offset(x, s, l as usize);
                add(l as usize, a, [self.weights[c] * d[0], self.weights[c] * d[1]]);
            }
            add(s, a, [-self.sums[s][0], -self.sums[s][1]]);
        }
    }

    /// Gershgorin bound `max_r sum_c |K_dil(r, c)| / V_k` of free node `k`'s two rows,
    /// per free node (for the stable time step).
    pub fn row_bounds(&self, nodes: &PdNodes) -> Vec<f64> {
        chunks(nodes.free)
            .into_par_iter()
            .flat_map_iter(|range| {
                let mut builder = RowBuilder::new(nodes, None);
                range
                    .map(|k| {
                        self.row(nodes, k, &mut |l, b| builder.add(l, b));
                        let rows = builder
                            .take()
                            .0
                            .iter()
                            .fold([0.0, 0.0], |s, (_, e)| [s[0] + e[0].abs() + e[1].abs(), s[1] + e[2].abs() + e[3].abs()]);
                        rows[0].max(rows[1]) / nodes.volumes[k]
                    })
                    .collect::<Vec<_>>()
            })
            .collect()
    }
}
