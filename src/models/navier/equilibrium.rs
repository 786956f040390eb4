//! Global equilibrium of a static solution: the reactions on the prescribed
//! displacement components must balance the applied tractions and the body force,
//!
//! ```text
//! R + T + B = 0,   R = Σ_{displacement components} ∮ (sigma_h n)_c ds,
//!                  T = Σ_{traction components} ∮ t_c ds,   B = ∫ b dA.
//! ```
//!
//! Strong-form collocation does not build this balance in (a Galerkin method does), so
//! its defect measures the error of the computed stress along the supports, in the
//! units of the loads. Boundary integrals use the trapezoid weights of the boundary
//! samples (`BoundarySample::lengths`); the body force of a constant `b` is `b A` with
//! the area `A = ½ ∮ (x - x₀)·n ds` from the same weights, and an exact body force
//! integrates as `-∮ sigma_exact n ds` (divergence theorem), so the check compares
//! like with like at the same quadrature. A body force given by an expression is
//! integrated by the centroid rule on the Delaunay cells of the nodes.
//!
//! The relative imbalance divides `|R + T + B|` by the force that flows through the
//! boundary, `Σ |contribution of one node and part|` (plus `|B|`): the size of the
//! terms that should cancel.

use crate::physics::case::Case;
use crate::domain::cells::cells_inside;
use crate::domain::{NodeSet, Point};
use crate::physics::elasticity::conditions::{ComponentCondition, Value};
use crate::physics::elasticity::stress::StressField;
use crate::physics::exact::{self, ExactSolution};
use serde::Serialize;

/// The force balance of a static solution (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Equilibrium {
    /// Applied tractions `T`, integrated over the traction components.
    pub applied: [f64; 2],
    /// Body force `B` over the solid.
    pub body: [f64; 2],
    /// Reactions `R` of the computed stress on the displacement components.
    pub reactions: [f64; 2],
    /// `R + T + B`.
    pub imbalance: [f64; 2],
    /// `|R + T + B| / (Σ |node contributions| + |B|)`.
    pub relative: f64,
}

/// `sigma n` for the in-plane stress `[sxx, syy, sxy]`.
fn traction(s: [f64; 3], n: Point) -> [f64; 2] {
    [s[0] * n[0] + s[2] * n[1], s[2] * n[0] + s[1] * n[1]]
}

/// `∫ f dA` by the centroid rule on the Delaunay cells of the nodes inside the solid
/// (second order; the slivers between a curved boundary and its chords are left out).
fn centroid_integral(case: &Case, points: &[Point], f: impl Fn(Point) -> [f64; 2]) -> [f64; 2] {
    let mut total = [0.0; 2];
    for t in cells_inside(&case.domain, points) {
        let (p, q, r) = (points[t[0]], points[t[1]], points[t[2]]);
        let area = 0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1])).abs();
        let v = f([(p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0]);
        total[0] += area * v[0];
        total[1] += area * v[1];
    }
    total
}

/// The balance of `stress` on `nodes` for `case` (module docs).
pub fn balance(case: &Case, nodes: &NodeSet, stress: &StressField, exact: Option<&dyn ExactSolution>) -> Equilibrium {
    let (lo, hi) = case.domain.bounding_box();
    let origin = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    let (mut applied, mut reactions, mut exact_flux) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    let (mut area, mut flow) = (0.0, 0.0);
    for (i, sample) in nodes.boundary.iter().enumerate() {
        let p = sample.position;
        for (&(part, n), &length) in sample.touches.iter().zip(&sample.lengths) {
            let condition = &case.conditions[part];
            let computed = traction(stress.sigma[i], n);
            let prescribed = exact::value(&condition.value, p, exact, |e| e.traction(p, n));
            let mut node = [0.0; 2];
            for c in 0..2 {
                node[c] = length
                    * match condition.components[c] {
                        ComponentCondition::Traction => prescribed[c],
                        ComponentCondition::Displacement => computed[c],
                    };
                match condition.components[c] {
                    ComponentCondition::Traction => applied[c] += node[c],
                    ComponentCondition::Displacement => reactions[c] += node[c],
                }
            }
            flow += node[0].hypot(node[1]);
            area += 0.5 * length * ((p[0] - origin[0]) * n[0] + (p[1] - origin[1]) * n[1]);
            if let Some(e) = exact {
                let t = e.traction(p, n);
                exact_flux[0] += length * t[0];
                exact_flux[1] += length * t[1];
            }
        }
    }
    let body = match &case.body_force {
        Value::Constant(b) => [b[0] * area, b[1] * area],
        Value::Exact => [-exact_flux[0], -exact_flux[1]],
        Value::Expression(f) => centroid_integral(case, &nodes.positions, |p| f.at(p)),
    };
    let imbalance = [reactions[0] + applied[0] + body[0], reactions[1] + applied[1] + body[1]];
    let scale = flow + body[0].hypot(body[1]);
    let relative = if scale > 0.0 { imbalance[0].hypot(imbalance[1]) / scale } else { 0.0 };
    Equilibrium { applied, body, reactions, imbalance, relative }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::case::OutputField;
    use crate::domain::{self, FillKind};
    use crate::models::navier::test_case::quadratic_plate;
    use crate::stages::Silent;

    /// The quadratic plate has a linear stress and a constant body force: the traction
    /// is linear along every straight edge, where the trapezoid rule is exact, and the
    /// area `½ ∮ (x - x₀)·n ds` of a rectangle is exact too; so with the exact stress,
    /// a constant body force and both the displacement and the traction edges in play,
    /// the balance holds to round-off (1e-12 of the force through the boundary).
    /// Shifting the stress of one displacement-edge node by 1 % of the largest stress
    /// must show (one node of the 10 on that edge carries ~1/10 of its force, so the
    /// imbalance is about 1e-3 of it).
    #[test]
    fn exact_stress_is_in_balance_and_a_wrong_reaction_is_not() {
        let (mut case, params) = quadratic_plate(FillKind::Scattered, 0.05);
        let exact = case.exact_solution().unwrap();
        let b = exact.body_force([0.3, 0.2]);
        assert!((exact.body_force([0.9, 0.1])[0] - b[0]).abs() < 1e-12, "constant body force");
        case.body_force = Value::Constant(b);
        let nodes = domain::generate(&case.domain, &params.fill);
        let sigma: Vec<[f64; 3]> = nodes.positions.iter().map(|&p| exact.stress(p)).collect();
        let stress = StressField { sigma_zz: vec![0.0; sigma.len()], von_mises: vec![0.0; sigma.len()], sigma };
        let q = balance(&case, &nodes, &stress, Some(exact.as_ref()));
        assert!(q.relative < 1e-12, "{q:?}");
        assert!(q.body[0].abs() > 0.1 && q.reactions[0].abs() > 0.1 && q.applied[0].abs() > 0.1, "{q:?}");

        let clamped = (0..nodes.boundary.len())
            .find(|&i| nodes.boundary[i].touches.len() == 1 && nodes.boundary[i].touches[0].0 == 3)
            .expect("a node on the displacement edge");
        let largest = stress.sigma.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut shifted = stress.clone();
        shifted.sigma[clamped][0] += 0.01 * largest;
        let q = balance(&case, &nodes, &shifted, Some(exact.as_ref()));
        assert!(q.relative > 1e-4, "{q:?}");
    }

    /// A full solve of the quadratic plate (degree 2 reproduces it to round-off) is in
    /// balance to 1e-10, the body force coming from the exact solution.
    #[test]
    fn solved_quadratic_plate_is_in_balance() {
        let (mut case, params) = quadratic_plate(FillKind::Scattered, 0.05);
        case.outputs.request(OutputField::Stress);
        let sol = crate::models::navier::solve(&case, &params, &Silent).unwrap();
        let q = sol.equilibrium.expect("stress requested");
        assert!(q.relative < 1e-10, "{q:?}");
    }
}
