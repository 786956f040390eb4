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
//! Zero tractions (free edges) add nothing. With fictitious nodes beyond the traction
//! parts ([`super::extension`]) there is no layer: the tractions enter through the
//! extension.

use super::nodes::PdNodes;
use crate::domain::{boundary::discretise_boundary, Domain, Point};
use crate::physics::elasticity::conditions::{BoundaryCondition, ComponentCondition, Value};
use crate::physics::exact::{self, ExactSolution};
use crate::stages::RunError;
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

/// One traction share of a free node: the part, the point of the part nearest to the
/// node (where the traction is read), its outward normal and the node's layer share.
#[derive(Debug, Clone, Copy)]
struct Share {
    node: usize,
    part: usize,
    point: Point,
    normal: Point,
    share: f64,
}

/// Where the loads act on the free nodes: the body force at every node and the
/// traction shares of the nodes in a loaded layer (module docs). Built once; the load
/// values are read by [`LoadLayer::forces`] at any time.
pub struct LoadLayer {
    shares: Vec<Share>,
    spacing: f64,
    layer_nodes: usize,
}

impl LoadLayer {
    /// The traction shares of `nodes` for the traction parts of `conditions` that are
    /// not zero (a part whose value depends on time counts as loaded).
    pub fn new(domain: &Domain, conditions: &[BoundaryCondition], nodes: &PdNodes) -> LoadLayer {
        let h = nodes.spacing;
        if nodes.fictitious_count() > 0 {
            // The tractions enter through the fictitious nodes' extension instead.
            return LoadLayer { shares: Vec::new(), spacing: h, layer_nodes: 0 };
        }
        let loaded: Vec<bool> = conditions.iter().map(|bc| bc.is_all(ComponentCondition::Traction) && !bc.value.is_zero()).collect();
        // Samples every h/16 locate the nearest point of a part to within h/32.
        let samples = if loaded.iter().any(|&l| l) { discretise_boundary(domain, h / 16.0) } else { Vec::new() };
        let points: Vec<Point> = samples.iter().map(|s| s.position).collect();
        let reach = REACH * h;
        let Some(tree) = (!points.is_empty()).then(|| ImmutableKdTree::<f64, 2>::new_from_slice(&points).expect("finite samples")) else {
            return LoadLayer { shares: Vec::new(), spacing: h, layer_nodes: 0 };
        };
        let per_node: Vec<Vec<Share>> = (0..nodes.free)
            .into_par_iter()
            .map(|node| {
                let x = nodes.positions[node];
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
                nearest
                    .into_iter()
                    .filter_map(|(part, d2, point, normal)| {
                        let d_normal = ((x[0] - point[0]) * normal[0] + (x[1] - point[1]) * normal[1]).abs();
                        let share = layer_share(d2.sqrt(), d_normal, h);
                        (share > 0.0).then_some(Share { node, part, point, normal, share })
                    })
                    .collect()
            })
            .collect();
        let layer_nodes = per_node.iter().filter(|s| !s.is_empty()).count();
        LoadLayer { shares: per_node.into_iter().flatten().collect(), spacing: h, layer_nodes }
    }

    /// Number of free nodes in a loaded layer.
    pub fn layer_nodes(&self) -> usize {
        self.layer_nodes
    }

    /// Body force density `b_i` of every free node (module docs) for the loads
    /// `body_force` and `conditions` (of one instant: `case::Case::loads_at`), or
    /// [`RunError::NotFinite`] at the first free node whose load is not finite (an
    /// overflow, or an exact solution's singular point).
    pub fn forces(
        &self,
        body_force: &Value,
        conditions: &[BoundaryCondition],
        exact: Option<&dyn ExactSolution>,
        nodes: &PdNodes,
    ) -> Result<Vec<[f64; 2]>, RunError> {
        let free = &nodes.positions[..nodes.free];
        let mut b: Vec<[f64; 2]> = free.par_iter().map(|&x| exact::value(body_force, x, exact, |e| e.body_force(x))).collect();
        for s in &self.shares {
            let t = exact::value(&conditions[s.part].value, s.point, exact, |e| e.traction(s.point, s.normal));
            b[s.node][0] += s.share * t[0] / self.spacing;
            b[s.node][1] += s.share * t[1] / self.spacing;
        }
        match b.par_iter().position_first(|v| !v[0].is_finite() || !v[1].is_finite()) {
            Some(i) => Err(RunError::not_finite_at(i, free[i])),
            None => Ok(b),
        }
    }
}

/// Body force density of every free node ([`LoadLayer::forces`]), and the number of
/// nodes in a loaded layer.
pub fn body_forces(
    domain: &Domain,
    conditions: &[BoundaryCondition],
    body_force: &Value,
    exact: Option<&dyn ExactSolution>,
    nodes: &PdNodes,
) -> Result<(Vec<[f64; 2]>, usize), RunError> {
    let layer = LoadLayer::new(domain, conditions, nodes);
    let b = layer.forces(body_force, conditions, exact, nodes)?;
    Ok((b, layer.layer_nodes()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::peridynamics::test_case::{params, plate, plate_nodes};
    use crate::models::peridynamics::Quadrature;

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
            let (b, layer) = body_forces(&domain, &conditions, &Value::Constant(f), None, &nodes).unwrap();
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

    /// A traction in `t` is read at the time of the loads handed to
    /// [`LoadLayer::forces`]: the layer built once carries `|Gamma| t(t)` at every time
    /// (round-off as above), and a part whose formula is zero at t = 0 still counts as
    /// loaded.
    #[test]
    fn traction_layer_follows_a_load_in_time() {
        use crate::scene::expression::{Constants, Expression, Scope, VectorExpression};
        let (domain, mut conditions) = plate([0.0, 0.0]);
        let parse = |text: &str| Expression::parse(text, Scope::SpaceTime, &Constants::default()).unwrap();
        let formula = VectorExpression { x: parse("3 * sin(2 * t)"), y: parse("-t"), origin: "boundary[1].value".into() };
        conditions[1].value = Value::Expression(std::sync::Arc::new(formula));
        let nodes = plate_nodes(&domain, &conditions, &params(0.06, Quadrature::Gauss2x2));
        let layer = LoadLayer::new(&domain, &conditions, &nodes);
        assert!(layer.layer_nodes() > 0);
        let zero = Value::Constant([0.0, 0.0]);
        for time in [0.0, 0.3, 1.7] {
            let at: Vec<BoundaryCondition> =
                conditions.iter().map(|c| BoundaryCondition { value: c.value.at_time(time), ..c.clone() }).collect();
            let b = layer.forces(&zero, &at, None, &nodes).unwrap();
            let load: Vec<f64> = (0..2).map(|c| b.iter().zip(&nodes.volumes).map(|(b, v)| v * b[c]).sum()).collect();
            let want = [0.5 * 3.0 * (2.0 * time).sin(), -0.5 * time];
            for c in 0..2 {
                assert!((load[c] - want[c]).abs() < 1e-12, "t = {time}: layer load {load:?}, edge load {want:?}");
            }
        }
    }
}
