//! External loads of the peridynamic model as a body force density `b_i` at the free
//! nodes (N/m^3, per unit thickness):
//!
//! ```text
//! b_i = f(x_i) + sum_{parts k with |x_i - Gamma_k| < h} t_k(p_ik) / h
//! ```
//!
//! `f` is the scene's body force; `t_k` the traction of boundary part `k` evaluated at
//! `p_ik`, the point of `Gamma_k` nearest to the node (constant, or `sigma(u_exact) n`
//! of the exact solution). The traction is spread over the first cell layer (thickness
//! `h`): on a straight edge the layer holds exactly `|Gamma| h` of node volume for every
//! rule, so the layer's total force equals `int t ds`. The seven-point triangle rule
//! shares the points of the cell edges; those at distance exactly `h` get half of their
//! volume from the layer cells (the rule's shares are symmetric across a cell edge), so
//! they carry `t / (2 h)`. Corner nodes within `h` of two loaded parts receive both.
//! Zero tractions (free edges) add nothing.

use super::nodes::PdNodes;
use crate::domain::{boundary::discretise_boundary, Domain, Point};
use crate::elasticity::conditions::{BoundaryCondition, ComponentCondition, Value};
use crate::exact::{self, ExactSolution};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Relative distance within which a node counts as lying on the layer's inner line.
const ON_LINE: f64 = 1e-9;

/// Search reach relative to `h`: the nearest boundary sample of a node on the inner
/// line can be `h/32` along the edge from its foot point.
const REACH: f64 = 1.001;

/// Fraction of a node's volume inside the first cell layer: 1 inside (distance `d`
/// to the nearest sample of the edge below `h`), 1/2 on the layer's inner line (shared
/// points, whose distance `d_normal` along the edge normal is `h`), 0 beyond.
fn layer_share(d: f64, d_normal: f64, h: f64) -> f64 {
    if d < h * (1.0 - ON_LINE) {
        1.0
    } else if (d_normal - h).abs() <= ON_LINE * h && d <= REACH * h {
        0.5
    } else {
        0.0
    }
}

/// Body force density of every free node, and the number of nodes in a loaded layer.
pub fn body_forces(
    domain: &Domain,
    conditions: &[BoundaryCondition],
    body_force: &Value,
    exact: Option<&dyn ExactSolution>,
    nodes: &PdNodes,
) -> (Vec<[f64; 2]>, usize) {
    let h = nodes.spacing;
    let loaded: Vec<bool> = conditions.iter().map(|bc| bc.is_all(ComponentCondition::Traction) && !bc.value.is_zero()).collect();
    // Samples every h/16 locate the nearest point of a part to within h/32.
    let samples = if loaded.iter().any(|&l| l) { discretise_boundary(domain, h / 16.0) } else { Vec::new() };
    let points: Vec<Point> = samples.iter().map(|s| s.position).collect();
    let reach = REACH * h;
    let tree = (!points.is_empty()).then(|| ImmutableKdTree::<f64, 2>::new_from_slice(&points).expect("finite samples"));
    let forces: Vec<([f64; 2], bool)> = (0..nodes.free)
        .into_par_iter()
        .map(|i| {
            let x = nodes.positions[i];
            let mut b = exact::value(body_force, x, exact, |e| e.body_force(x));
            let mut in_layer = false;
            if let Some(tree) = &tree {
                // Nearest sample of each loaded part within h.
                let mut nearest: Vec<(usize, f64, Point, Point)> = Vec::new();
                for found in tree.query(&x).within::<SquaredEuclidean<f64>>(reach * reach).execute() {
                    let s = &samples[found.item as usize];
                    for &(part, normal) in &s.touches {
                        if !loaded[part] {
                            continue;
                        }
                        match nearest.iter_mut().find(|e| e.0 == part) {
                            Some(e) if e.1 <= found.distance => {}
                            Some(e) => *e = (part, found.distance, s.position, normal),
                            None => nearest.push((part, found.distance, s.position, normal)),
                        }
                    }
                }
                for (part, d2, p, normal) in nearest {
                    let d_normal = ((x[0] - p[0]) * normal[0] + (x[1] - p[1]) * normal[1]).abs();
                    let share = layer_share(d2.sqrt(), d_normal, h);
                    if share == 0.0 {
                        continue;
                    }
                    let t = exact::value(&conditions[part].value, p, exact, |e| e.traction(p, normal));
                    b[0] += share * t[0] / h;
                    b[1] += share * t[1] / h;
                    in_layer = true;
                }
            }
            (b, in_layer)
        })
        .collect();
    let layer = forces.iter().filter(|f| f.1).count();
    (forces.into_iter().map(|f| f.0).collect(), layer)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::peridynamics::test_case::{params, plate, plate_nodes};
    use crate::peridynamics::Quadrature;

    /// The traction layer carries exactly the edge load `t |Gamma|` for every rule (the
    /// first cell layer holds `|Gamma| h` of node volume on a straight edge); nodes
    /// farther than `h` from the loaded edge get the body force alone.
    #[test]
    fn traction_layer_carries_the_edge_load() {
        let (t, f) = ([2.0, -1.0], [0.5, 0.25]);
        let (domain, conditions) = plate(t);
        for rule in [Quadrature::FullArea, Quadrature::Gauss2x2, Quadrature::TriangleP2, Quadrature::TriangleP3] {
            let p = params(0.06, rule);
            let nodes = plate_nodes(&domain, &conditions, &p);
            let (b, layer) = body_forces(&domain, &conditions, &Value::Constant(f), None, &nodes);
            assert!(layer > 0);
            let h = nodes.spacing;
            let mut load = [0.0, 0.0];
            for (i, bi) in b.iter().enumerate() {
                let v = nodes.volumes[i];
                load[0] += v * (bi[0] - f[0]);
                load[1] += v * (bi[1] - f[1]);
                if nodes.positions[i][0] < 1.0 - h - 1e-12 {
                    assert_eq!(*bi, f, "{rule:?}: node {i} at {:?} is not in the layer", nodes.positions[i]);
                }
            }
            // The edge has length 0.5; the volumes are sums of h^2 shares (round-off 1e-14).
            for c in 0..2 {
                assert!((load[c] - 0.5 * t[c]).abs() < 1e-12, "{rule:?}: layer load {load:?}, edge load {:?}", [0.5 * t[0], 0.5 * t[1]]);
            }
        }
    }
}
