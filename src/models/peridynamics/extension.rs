//! Fictitious nodes beyond traction and free edges: their displacements extended from
//! the solid so that the local traction condition holds, which makes every family
//! complete and the run converge to the Navier solution at second order in delta.
//!
//! For a fictitious node `g` with foot `x_b` (the nearest boundary point, outward
//! normal `n` of each traction part there) the extension is the cubic vector field
//!
//! ```text
//! p = argmin sum_i w_i |p(x_i) - u_i|^2   subject to   sigma(p)(x_b) n_k = t_k(x_b)  for every part k at x_b,
//!                                         (per component p_c(x_b) = u_c on a mixed part's displacement component)
//! u_g = p(x_g),
//! ```
//!
//! over the [`FIT_NODES`] free nodes nearest to `x_b`, `w_i = exp(-(2 d_i / d_K)^2)`
//! (`d_K` the distance of the farthest), monomials in `(x - x_b) / d_K`, and
//! `sigma(p) = lambda div p I + mu (grad p + grad p^T)` with the in-plane Lame constants.
//! The constrained least-squares problem is solved by its KKT system once per node
//! (SVD: at a corner between traction parts one of the four conditions is redundant), giving `u_g = sum_i E_gi u_i + sum_k F_gk t_k`: linear in the free
//! displacements and the tractions. The stiffness then has the columns of the
//! fictitious nodes condensed onto those of the fit ([`super::assembly`]), and the
//! tractions enter through `F` (no layer body force, [`super::loads`]).
//!
//! A cubic `u` that meets the traction condition is reproduced exactly, so with the
//! compatible weights (exact on cubics) a cubic solution with traction edges is
//! computed to round-off. The extension is not the variation of an energy: the
//! stiffness is not symmetric (GMRES, LU), and explicit dynamics keeps the nonlocal
//! surface (`boundary = "surface"`).
//!
//! Related: fictitious nodes with Taylor-extended displacements (Scabbia, Zaccariotto
//! and Galvanetto 2022), volume constraints from local boundary data (D'Elia, Tian and
//! Yu 2019: order 2 needs a smooth extension, Foss, Radu and Yu 2021).

use super::nodes::{Body, PdNodes};
use crate::domain::Point;
use crate::physics::elasticity::conditions::{BoundaryCondition, ComponentCondition};
use crate::physics::elasticity::material::Material;
use crate::physics::exact::{self, ExactSolution};
use crate::stages::RunError;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::DMatrix;
use rayon::prelude::*;
use std::num::NonZeroUsize;

/// Free nodes in each fit: three times the ten cubic monomials of a component.
pub const FIT_NODES: usize = 30;

/// Monomials of degree <= 3 in `z`: `1, z1, z2, z1^2, z1 z2, z2^2, z1^3, z1^2 z2, z1 z2^2, z2^3`.
fn cubic(z: Point) -> [f64; 10] {
    let (a, b) = (z[0], z[1]);
    [1.0, a, b, a * a, a * b, b * b, a * a * a, a * a * b, a * b * b, b * b * b]
}

/// The extension of every fictitious node (module docs).
#[derive(Debug, Clone)]
pub struct Extension {
    /// Per fictitious node: range into `terms`.
    offsets: Vec<usize>,
    /// `(free node i, E_gi as [xx, xy, yx, yy])`.
    terms: Vec<(u32, [f64; 4])>,
    /// Per fictitious node: `(part k, normal n_k, F_gk as [xx, xy, yx, yy])`, `F_gk`
    /// applied to the part's value (per component a displacement or a traction).
    tractions: Vec<Vec<(usize, Point, [f64; 4])>>,
    /// Its foot point (where the tractions are read).
    feet: Vec<Point>,
}

/// Smallest cosine between two normals taken as the same side of the solid (45 degrees).
pub const SAME_SIDE: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Whether a bond between nodes `i` and `j` reads a fictitious node the way its
/// extension assumes: through the side of the solid its foot is on. A bond from a free
/// node leaves the solid at an exit point `e`; it reads fictitious node `g` (foot `f`)
/// unless the two sides face each other across a concave (re-entrant) turn of the
/// boundary: normals more than 45 degrees apart with `(e - f) . n_f > 0` and
/// `(f - e) . n_e > 0` (at a convex corner both are negative). Two fictitious nodes are
/// tested the same way with their feet. Across a re-entrant corner (or a hole narrower
/// than the band) the wedge's fictitious nodes are extended from one arm, and bonds
/// from the other arm would tie the arms through them like material; those bonds are
/// not made (the families there are cut and fitted as such, [`super::weights`]).
pub fn in_sight(body: &Body, nodes: &PdNodes, i: usize, j: usize) -> bool {
    let (fi, fj) = (i >= nodes.fictitious, j >= nodes.fictitious);
    let side = |g: usize| {
        let foot = &nodes.feet[g - nodes.fictitious];
        (foot.point, foot.parts.iter().map(|p| p.1).collect::<Vec<Point>>())
    };
    let tol = 1e-9 * nodes.spacing;
    // Whether the sides (point a, normals na) and (point b, normals nb) face each other.
    let facing = |(a, na): (Point, Vec<Point>), (b, nb): (Point, Vec<Point>)| {
        let dot = |u: Point, v: Point| u[0] * v[0] + u[1] * v[1];
        let same = na.iter().any(|n| nb.iter().any(|m| dot(*n, *m) >= SAME_SIDE));
        let d = [a[0] - b[0], a[1] - b[1]];
        !same && nb.iter().any(|m| dot(d, *m) > tol) && na.iter().any(|n| -dot(d, *n) > tol)
    };
    match (fi, fj) {
        (false, false) => true,
        (true, true) => !facing(side(i), side(j)),
        (true, false) | (false, true) => {
            let (a, g) = if fi { (j, i) } else { (i, j) };
            if a >= nodes.free {
                return true;
            }
            body.exit(nodes.positions[a], nodes.positions[g], nodes.spacing).is_none_or(|exit| !facing(exit, side(g)))
        }
    }
}

/// One fictitious node's extension: `E_gi` per free node, `F_gk` per part.
type Fit = (Vec<(u32, [f64; 4])>, Vec<(usize, Point, [f64; 4])>);

/// The normals of `parts` that differ (two parts meeting at a corner), with their parts.
fn distinct(parts: &[(usize, Point)]) -> Vec<(usize, Point)> {
    let mut out: Vec<(usize, Point)> = Vec::new();
    for &(part, n) in parts {
        if out.iter().all(|(_, m)| n[0] * m[0] + n[1] * m[1] < 0.999) {
            out.push((part, n));
        }
    }
    out
}

impl Extension {
    /// The extension of the fictitious nodes of `nodes` for `material` and the parts'
    /// `conditions`, or the first fictitious node whose fit is singular (too few or
    /// degenerate free nodes).
    pub fn new(nodes: &PdNodes, material: &Material, conditions: &[BoundaryCondition]) -> Result<Extension, usize> {
        let free = &nodes.positions[..nodes.free];
        let tree = ImmutableKdTree::<f64, 2>::new_from_slice(free).expect("finite node positions");
        let lame = material.lame();
        let (lambda, mu) = (lame.lambda / lame.mu, 1.0);
        let k = FIT_NODES.min(nodes.free);
        let fits: Vec<Option<Fit>> = (0..nodes.fictitious_count())
            .into_par_iter()
            .map(|g| {
                let foot = &nodes.feet[g];
                let xb = foot.point;
                let near = tree.query(&xb).nearest_n::<SquaredEuclidean<f64>>(NonZeroUsize::new(k)?).execute();
                let scale = near.iter().map(|n| n.distance).fold(0.0, f64::max).sqrt();
                if scale <= 0.0 {
                    return None;
                }
                let z = |p: Point| [(p[0] - xb[0]) / scale, (p[1] - xb[1]) / scale];
                let parts = distinct(&foot.parts);
                let (nu, nc) = (20, 2 * parts.len());
                // KKT: [H C^T; C 0] [a; y] = [R u; v~], H = blockdiag(Phi^T W Phi) (x then y
                // coefficients), R = blockdiag(Phi^T W); a condition's value v~ is t scale / mu
                // for a traction component and u for a displacement component.
                let mut kkt = DMatrix::<f64>::zeros(nu + nc, nu + nc);
                let mut rhs = DMatrix::<f64>::zeros(nu + nc, 2 * near.len() + nc);
                for (col, n) in near.iter().enumerate() {
                    let phi = cubic(z(free[n.item as usize]));
                    let w = f64::exp(-4.0 * n.distance / (scale * scale));
                    for c in 0..2 {
                        for a in 0..10 {
                            rhs[(10 * c + a, 2 * col + c)] = w * phi[a];
                            for b in 0..10 {
                                kkt[(10 * c + a, 10 * c + b)] += w * phi[a] * phi[b];
                            }
                        }
                    }
                }
                let fit = kkt.view((0, 0), (nu, nu)).clone_owned().symmetric_eigenvalues();
                if fit.min() <= 1e-12 * fit.max() {
                    return None;
                }
                for (r, &(part, n)) in parts.iter().enumerate() {
                    // sigma(p) n / mu at x_b from the linear coefficients (z1: index 1, z2:
                    // index 2), times `scale` (d/dx = (1/scale) d/dz1); p_c(x_b) is the
                    // constant coefficient (index 0).
                    let (xx, xy, yx, yy) = (1, 2, 11, 12); // dpx/dz1, dpx/dz2, dpy/dz1, dpy/dz2
                    let traction = [
                        vec![(xx, (lambda + 2.0 * mu) * n[0]), (yy, lambda * n[0]), (xy, mu * n[1]), (yx, mu * n[1])],
                        vec![(xy, mu * n[0]), (yx, mu * n[0]), (xx, lambda * n[1]), (yy, (lambda + 2.0 * mu) * n[1])],
                    ];
                    for (c, row) in traction.into_iter().enumerate() {
                        let row = match conditions[part].components[c] {
                            ComponentCondition::Traction => row,
                            ComponentCondition::Displacement => vec![(10 * c, 1.0)],
                        };
                        for (a, v) in row {
                            kkt[(nu + 2 * r + c, a)] += v;
                            kkt[(a, nu + 2 * r + c)] += v;
                        }
                        rhs[(nu + 2 * r + c, 2 * near.len() + 2 * r + c)] = 1.0;
                    }
                }
                // At a corner two parts' conditions can coincide (both tractions hold
                // sigma_xy): the pseudo-inverse (SVD) takes the consistent solution.
                let svd = kkt.svd(true, true);
                let eps = 1e-13 * svd.singular_values.max();
                let sol = svd.solve(&rhs, eps).ok()?;
                let phi_g = cubic(z(nodes.positions[nodes.fictitious + g]));
                // Component c of u_g: phi_g . (coefficients of component c) for each right-hand side.
                let value = |c: usize, col: usize| (0..10).map(|a| phi_g[a] * sol[(10 * c + a, col)]).sum::<f64>();
                let block =
                    |cx: usize, cy: usize, sx: f64, sy: f64| [value(0, cx) * sx, value(0, cy) * sy, value(1, cx) * sx, value(1, cy) * sy];
                let terms: Vec<(u32, [f64; 4])> =
                    near.iter().enumerate().map(|(i, n)| (n.item, block(2 * i, 2 * i + 1, 1.0, 1.0))).collect();
                let t0 = 2 * near.len();
                let values = parts
                    .iter()
                    .enumerate()
                    .map(|(r, &(part, n))| {
                        let per = |c: usize| match conditions[part].components[c] {
                            ComponentCondition::Traction => scale / lame.mu,
                            ComponentCondition::Displacement => 1.0,
                        };
                        (part, n, block(t0 + 2 * r, t0 + 2 * r + 1, per(0), per(1)))
                    })
                    .collect();
                let finite = terms.iter().all(|(_, b)| b.iter().all(|v| v.is_finite()));
                finite.then_some((terms, values))
            })
            .collect();
        let mut ext =
            Extension { offsets: vec![0], terms: Vec::new(), tractions: Vec::new(), feet: nodes.feet.iter().map(|f| f.point).collect() };
        for (g, fit) in fits.into_iter().enumerate() {
            let (terms, tractions) = fit.ok_or(nodes.fictitious + g)?;
            ext.terms.extend(terms);
            ext.offsets.push(ext.terms.len());
            ext.tractions.push(tractions);
        }
        Ok(ext)
    }

    /// `E_gi` of fictitious node `g` (counted from the first fictitious node).
    pub fn terms(&self, g: usize) -> &[(u32, [f64; 4])] {
        &self.terms[self.offsets[g]..self.offsets[g + 1]]
    }

    /// `sum_k F_gk v_k` of fictitious node `g` for the values `v_k` of `conditions` at
    /// its foot (per component the displacement or the traction the part prescribes).
    pub fn traction_part(&self, g: usize, conditions: &[BoundaryCondition], exact: Option<&dyn ExactSolution>) -> [f64; 2] {
        let x = self.feet[g];
        self.tractions[g].iter().fold([0.0, 0.0], |s, &(part, n, f)| {
            let bc = &conditions[part];
            let t = exact::value(&bc.value, x, exact, |e| {
                let (u, t) = (e.displacement(x), e.traction(x, n));
                let pick = |c: usize| if bc.components[c] == ComponentCondition::Displacement { u[c] } else { t[c] };
                [pick(0), pick(1)]
            });
            [s[0] + f[0] * t[0] + f[1] * t[1], s[1] + f[2] * t[0] + f[3] * t[1]]
        })
    }

    /// The traction parts `sum_k F_gk t_k` of every fictitious node, or the first one
    /// where a traction is not finite.
    pub fn traction_parts(
        &self,
        nodes: &PdNodes,
        conditions: &[BoundaryCondition],
        exact: Option<&dyn ExactSolution>,
    ) -> Result<Vec<[f64; 2]>, RunError> {
        let parts: Vec<[f64; 2]> = (0..self.feet.len()).into_par_iter().map(|g| self.traction_part(g, conditions, exact)).collect();
        match parts.iter().position(|v| !v[0].is_finite() || !v[1].is_finite()) {
            Some(g) => Err(RunError::not_finite_at(nodes.fictitious + g, nodes.positions[nodes.fictitious + g])),
            None => Ok(parts),
        }
    }

    /// `u_g = sum_i E_gi u_i + traction part` of every fictitious node, `u` of the free nodes.
    pub fn values(&self, u: &[[f64; 2]], traction_parts: &[[f64; 2]]) -> Vec<[f64; 2]> {
        (0..self.feet.len())
            .into_par_iter()
            .map(|g| {
                self.terms(g).iter().fold(traction_parts[g], |s, &(i, e)| {
                    let ui = u[i as usize];
                    [s[0] + e[0] * ui[0] + e[1] * ui[1], s[1] + e[2] * ui[0] + e[3] * ui[1]]
                })
            })
            .collect()
    }
}
