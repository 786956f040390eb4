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
//! rule, so the layer's total force equals `int t ds`. Corner nodes within `h` of two
//! loaded parts receive both. Zero tractions (free edges) add nothing.

use super::nodes::PdNodes;
use crate::domain::{boundary::discretise_boundary, Domain, Point};
use crate::elasticity::conditions::{BoundaryCondition, ComponentCondition, Value};
use crate::exact::{self, ExactSolution};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

/// Body force density of every free node, and the number of nodes in a loaded layer.
pub fn body_forces(
    domain: &Domain,
    conditions: &[BoundaryCondition],
    body_force: Value,
    exact: Option<&dyn ExactSolution>,
    nodes: &PdNodes,
) -> (Vec<[f64; 2]>, usize) {
    let h = nodes.spacing;
    let loaded: Vec<bool> =
        conditions.iter().map(|bc| bc.is_all(ComponentCondition::Traction) && bc.value != Value::Constant([0.0, 0.0])).collect();
    // Samples every h/16 locate the nearest point of a part to within h/32.
    let samples = if loaded.iter().any(|&l| l) { discretise_boundary(domain, h / 16.0) } else { Vec::new() };
    let points: Vec<Point> = samples.iter().map(|s| s.position).collect();
    let tree = (!points.is_empty()).then(|| ImmutableKdTree::<f64, 2>::new_from_slice(&points).expect("finite samples"));
    let forces: Vec<([f64; 2], bool)> = (0..nodes.free)
        .into_par_iter()
        .map(|i| {
            let x = nodes.positions[i];
            let mut b = exact::value(body_force, exact, |e| e.body_force(x));
            let mut in_layer = false;
            if let Some(tree) = &tree {
                // Nearest sample of each loaded part within h.
                let mut nearest: Vec<(usize, f64, Point, Point)> = Vec::new();
                for found in tree.query(&x).within::<SquaredEuclidean<f64>>(h * h).execute() {
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
                    if d2 >= h * h {
                        continue;
                    }
                    let t = exact::value(conditions[part].value, exact, |e| e.traction(p, normal));
                    b[0] += t[0] / h;
                    b[1] += t[1] / h;
                    in_layer = true;
                }
            }
            (b, in_layer)
        })
        .collect();
    let layer = forces.iter().filter(|f| f.1).count();
    (forces.into_iter().map(|f| f.0).collect(), layer)
}
