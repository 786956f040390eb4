//! Bond coefficients `c_ij` of `(L_h u)_i = sum_j c_ij (xi_ij ⊗ xi_ij)(u_j - u_i)`:
//!
//! ```text
//! c_ij = lambda(|xi_ij|) * V_j * f_ij * g_ij
//! ```
//!
//! with `V_j` the node's quadrature weight (cell area share), `f_ij` the partial-area
//! fraction `|cell_j ∩ B(x_i, delta)| / |cell_j|` (partial-area rule; 1 otherwise) and
//! `g_ij = 2 / (r_i + r_j)` the volume surface correction, `r_i = V_i^fam / V^fam_full`
//! the node's family volume relative to that of the same rule point in an unbounded
//! lattice (1 for constrained nodes; `g = 1` without correction). Using the lattice's own
//! full-family volume rather than `pi delta^2` keeps `g = 1` exactly in the interior.
//! With the asymptotically compatible rule every row is then corrected by
//! [`super::compatible::compatible_weights`] (complete families: moments of degrees 3-5
//! in closed form; truncated ones: degrees 3-4 integrated over the truncated disc; those
//! cut by the sight of fictitious nodes, [`super::extension::in_sight`]: degrees 3-4 of the
//! whole disc, a consistent one-sided row).
//!
//! Every rule but the compatible one gives `V_i c_ij = V_j c_ji`: the stiffness is symmetric.

use super::compatible::{compatible_weights, target_moment, truncated_moments, MOMENTS, TRUNCATED_MOMENTS};
use super::family::Families;
use super::nodes::{Body, PdNodes};
use super::{Micromodulus, PdParams, Quadrature, SurfaceCorrection};
use crate::domain::Point;
use rayon::prelude::*;

/// Radius of the family search of a rule (padded by `1e-9` relative so that lattice
/// points at exactly the horizon belong to the family).
pub fn search_radius(params: &PdParams) -> f64 {
    let reach = match params.quadrature {
        Quadrature::PartialArea => params.horizon + params.spacing() / 2f64.sqrt(),
        _ => params.horizon,
    };
    reach * (1.0 + 1e-9)
}

/// Area of the disc of radius `r` at the origin inside `[x0, x1] x [y0, y1]`, exactly
/// (inclusion-exclusion of quadrant areas; circular segments by their primitive).
pub fn disc_rectangle_area(r: f64, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    // Area of the disc inside [0, x] x [0, y] for x, y >= 0.
    let quadrant = |x: f64, y: f64| -> f64 {
        let (x, y) = (x.min(r), y.min(r));
        if x * x + y * y <= r * r {
            return x * y;
        }
        let prim = |t: f64| 0.5 * (t * (r * r - t * t).max(0.0).sqrt() + r * r * (t / r).clamp(-1.0, 1.0).asin());
        let a = (r * r - y * y).max(0.0).sqrt();
        a * y + prim(x) - prim(a)
    };
    let signed = |x: f64, y: f64| x.signum() * y.signum() * quadrant(x.abs(), y.abs());
    signed(x1, y1) - signed(x0, y1) - signed(x1, y0) + signed(x0, y0)
}

/// `f_ij`: share of the cell of side `h` centred at offset `xi` inside the horizon disc.
pub fn partial_area_fraction(xi: Point, h: f64, delta: f64) -> f64 {
    let a = disc_rectangle_area(delta, xi[0] - h / 2.0, xi[0] + h / 2.0, xi[1] - h / 2.0, xi[1] + h / 2.0);
    (a / (h * h)).clamp(0.0, 1.0)
}

/// `f_ij` of the rule (1 but for the partial-area rule, [`partial_area_fraction`]).
pub fn area_fraction(params: &PdParams, xi: Point) -> f64 {
    match params.quadrature {
        Quadrature::PartialArea => partial_area_fraction(xi, params.spacing(), params.horizon),
        _ => 1.0,
    }
}

/// Family volume and bond count of each rule point in an unbounded lattice.
pub fn full_families(params: &PdParams) -> Vec<(f64, usize)> {
    let h = params.spacing();
    let pts = params.quadrature.unit_cell();
    let radius = search_radius(params);
    let k = (radius / h).ceil() as i64 + 2;
    pts.iter()
        .enumerate()
        .map(|(own, (q, _))| {
            let (mut volume, mut count) = (0.0, 0);
            for a in -k..=k {
                for b in -k..=k {
                    for (l, (p, w)) in pts.iter().enumerate() {
                        if a == 0 && b == 0 && l == own {
                            continue;
                        }
                        let xi = [(a as f64 + p[0] - q[0]) * h, (b as f64 + p[1] - q[1]) * h];
                        if xi[0].hypot(xi[1]) <= radius {
                            volume += w * h * h * area_fraction(params, xi);
                            count += 1;
                        }
                    }
                }
            }
            (volume, count)
        })
        .collect()
}

/// Bond coefficients and what the weighting did.
#[derive(Debug, Clone)]
pub struct BondWeights {
    /// `c_ij` per bond, in family order.
    pub coefficients: Vec<f64>,
    /// Free nodes whose family is complete (as many bonds as in an unbounded lattice).
    pub complete_families: usize,
    /// Rows given asymptotically compatible weights.
    pub compatible_rows: usize,
    /// Complete rows where the moment problem was singular (base weights kept).
    pub compatible_failures: usize,
}

/// The halo a rank of a distributed run needs around its own rows, in layers of
/// bonds ([`Families::around`]): `(rows, families)`. The compatible rule's
/// symmetrisation reads the rows of the own nodes' neighbours (one layer of rows),
/// and the volume correction of every row computed reads its neighbours' family
/// volumes (one more layer of families).
pub fn halo_layers(params: &PdParams) -> (u8, u8) {
    let rows = u8::from(params.quadrature == Quadrature::Compatible);
    (rows, rows + u8::from(params.correction == SurfaceCorrection::Volume))
}

/// Coefficients of every bond (module docs); `moment` is the calibrated `M`.
/// `layer` (from [`Families::around`]) restricts the work to the rows a rank needs:
/// those of layers up to [`halo_layers`]'s `rows` are computed (the coefficients of
/// the others are left 0), and the counts are of layer 0, its own rows; `None`:
/// every row, all counted.
pub fn bond_coefficients(
    body: &Body,
    nodes: &PdNodes,
    families: &Families,
    kernel: &Micromodulus,
    params: &PdParams,
    moment: f64,
    layer: Option<&[u8]>,
) -> BondWeights {
    let row_layers = halo_layers(params).0;
    let computed = |i: usize| layer.is_none_or(|l| l[i] <= row_layers);
    let counted = |i: usize| layer.is_none_or(|l| l[i] == 0);
    let delta = params.horizon;
    let complete_targets: Vec<f64> = MOMENTS.iter().map(|&m| target_moment(m, moment, delta)).collect();
    let scale = 3.0 * moment / delta.powi(4);
    let x = &nodes.positions;
    let offset = |i: usize, j: u32| -> Point {
        let (a, b) = (x[i], x[j as usize]);
        [b[0] - a[0], b[1] - a[1]]
    };
    let full = full_families(params);
    let base_row = |i: usize| -> Vec<f64> {
        families
            .of(i)
            .iter()
            .map(|&j| kernel.value(norm(offset(i, j))) * nodes.volumes[j as usize] * area_fraction(params, offset(i, j)))
            .collect()
    };
    let ratio = relative_family_volumes(nodes, families, params, &full);
    let r_of = |j: usize| if j < nodes.free { ratio[j] } else { 1.0 };
    let rows: Vec<(Vec<f64>, bool, Option<bool>)> = (0..nodes.free)
        .into_par_iter()
        .map(|i| {
            if !computed(i) {
                return (vec![0.0; families.of(i).len()], false, None);
            }
            let mut c = base_row(i);
            if params.correction == SurfaceCorrection::Volume {
                for (cj, &j) in c.iter_mut().zip(families.of(i)) {
                    *cj *= 2.0 / (r_of(i) + r_of(j as usize));
                }
            }
            // A node of a Delaunay set has no lattice count: complete when its disc lies in the solid.
            let complete = match full.get(nodes.rule_point[i] as usize) {
                Some(f) => families.of(i).len() == f.1,
                None => body.domain().signed_distance(x[i]) <= -delta,
            };
            let mut compatible = None;
            if params.quadrature == Quadrature::Compatible {
                let xi: Vec<Point> = families.of(i).iter().map(|&j| offset(i, j)).collect();
                let fitted = if families.is_cut(i) {
                    // Cut by the sight of fictitious nodes: a consistent one-sided row (the
                    // whole disc's moments of degrees 3-4: the Navier operator on quadratics).
                    compatible_weights(&xi, &c, delta, TRUNCATED_MOMENTS, &complete_targets[..9], scale)
                } else if complete {
                    compatible_weights(&xi, &c, delta, &MOMENTS, &complete_targets, scale)
                } else {
                    let targets = truncated_moments(nodes.positions[i], &|p| body.contains(p), kernel, TRUNCATED_MOMENTS);
                    compatible_weights(&xi, &c, delta, TRUNCATED_MOMENTS, &targets, scale)
                };
                match fitted {
                    Some(w) => {
                        c = w;
                        compatible = Some(true);
                    }
                    None => compatible = Some(false),
                }
            }
            (c, complete, compatible)
        })
        .collect();
    let complete: Vec<bool> = rows.iter().map(|r| r.1).collect();
    let count = |pick: fn(bool, Option<bool>) -> bool| rows.iter().enumerate().filter(|(i, r)| counted(*i) && pick(r.1, r.2)).count();
    let complete_families = count(|complete, _| complete);
    let compatible_rows = count(|_, compatible| compatible == Some(true));
    let compatible_failures = count(|_, compatible| compatible == Some(false));
    let mut coefficients: Vec<f64> = rows.into_iter().flat_map(|r| r.0).collect();
    if params.quadrature == Quadrature::Compatible {
        coefficients = symmetrised(nodes, families, &coefficients, &complete, counted);
    }
    BondWeights { coefficients, complete_families, compatible_rows, compatible_failures }
}

/// The relative family volume `r_i` of every free node (its family's volume over a
/// complete family's at its quadrature point) for the volume correction; empty without
/// it (constrained nodes count as complete).
fn relative_family_volumes(nodes: &PdNodes, families: &Families, params: &PdParams, full: &[(f64, usize)]) -> Vec<f64> {
    match params.correction {
        SurfaceCorrection::None => return Vec::new(),
        SurfaceCorrection::Volume => {}
    }
    let x = &nodes.positions;
    (0..nodes.free)
        .into_par_iter()
        .map(|i| {
            let offset = |j: u32| [x[j as usize][0] - x[i][0], x[j as usize][1] - x[i][1]];
            let v: f64 = families.of(i).iter().map(|&j| nodes.volumes[j as usize] * area_fraction(params, offset(j))).sum();
            v / full[nodes.rule_point[i] as usize].0
        })
        .collect()
}

/// `c_ij <- (V_i c_ij + V_j c_ji) / (2 V_i)` for bonds between free nodes of which at
/// least one has a truncated family: internal forces then cancel pairwise (momentum is
/// conserved) near free edges. Without it the per-row weights leave a net force in the
/// edge strip that does not shrink with delta, and the tension plate's interior error
/// stalled; with it, first order (docs/methods/peridynamics.md). Bonds between
/// complete families are left alone: on a uniform lattice their weights are already
/// symmetric (translation invariance), and averaging the round-off of two moment
/// solves would cost the cubic exactness (docs/notebook/round1-peridynamics-static-m3.md,
/// "From the code comments"). Only the rows `wanted` picks are symmetrised (a rank's
/// own), the others are left as they are.
fn symmetrised(nodes: &PdNodes, families: &Families, c: &[f64], complete: &[bool], wanted: impl Fn(usize) -> bool + Sync) -> Vec<f64> {
    (0..nodes.free)
        .into_par_iter()
        .flat_map_iter(|i| {
            let wanted = wanted(i);
            families.range(i).zip(families.of(i)).map(move |(b, &j)| {
                let j = j as usize;
                if !wanted || j >= nodes.free || (complete[i] && complete[j]) {
                    return c[b];
                }
                let back = families.range(j).start + families.of(j).binary_search(&(i as u32)).expect("bonds are mutual");
                (nodes.volumes[i] * c[b] + nodes.volumes[j] * c[back]) / (2.0 * nodes.volumes[i])
            })
        })
        .collect()
}

fn norm(p: Point) -> f64 {
    p[0].hypot(p[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_rectangle_area_limits() {
        let pi = std::f64::consts::PI;
        // Whole disc, a quadrant, a half, a square inside.
        assert!((disc_rectangle_area(1.0, -2.0, 2.0, -2.0, 2.0) - pi).abs() < 1e-14);
        assert!((disc_rectangle_area(1.0, 0.0, 5.0, 0.0, 5.0) - pi / 4.0).abs() < 1e-14);
        assert!((disc_rectangle_area(2.0, -3.0, 0.0, -3.0, 3.0) - 2.0 * pi).abs() < 1e-13);
        assert!((disc_rectangle_area(1.0, -0.5, 0.5, -0.5, 0.5) - 1.0).abs() < 1e-15);
        assert_eq!(disc_rectangle_area(1.0, 2.0, 3.0, 0.0, 1.0), 0.0);
        // A strip x in [0.5, 1]: segment area r^2 acos(d) - d sqrt(r^2 - d^2) with d = 0.5.
        let seg = (0.5f64).acos() - 0.5 * (0.75f64).sqrt();
        assert!((disc_rectangle_area(1.0, 0.5, 2.0, -2.0, 2.0) - seg).abs() < 1e-14);
    }

    /// Partial areas of all cells of a lattice add up to the disc area.
    #[test]
    fn partial_areas_tile_the_disc() {
        let (h, delta) = (0.1, 0.3);
        let mut total = 0.0;
        for a in -5..=5 {
            for b in -5..=5 {
                total += partial_area_fraction([a as f64 * h, b as f64 * h], h, delta) * h * h;
            }
        }
        assert!((total - std::f64::consts::PI * delta * delta).abs() < 1e-14);
    }
}
