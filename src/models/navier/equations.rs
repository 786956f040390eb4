//! The two boundary equations of a boundary node of the Navier model, resolved from
//! the conditions of the parts it touches.
//!
//! Per component `c`:
//! * if any touching part prescribes the displacement of `c`, the node gets the
//!   displacement equation `u_c = g_c` (Dirichlet wins at corners);
//! * otherwise it gets a traction equation. At a corner of parts `k` with normals
//!   `n_k` and prescribed tractions `t_k`, the equation is
//!   `(sigma(u) n)_c = sum_k t_{k,c} / |sum_k n_k|` with `n = sum_k n_k / |sum_k n_k|`:
//!   since `sigma n` is linear in `n`, this is exactly the sum of the parts'
//!   equations, so it holds for any stress field that satisfies both.

use crate::domain::BoundarySample;
use crate::physics::elasticity::conditions::{BoundaryCondition, ComponentCondition};
use crate::physics::exact::{self, ExactSolution};

/// One scalar boundary equation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ComponentEquation {
    /// `u_c = value`.
    Displacement { value: f64 },
    /// `(sigma(u) normal)_c = value`.
    Traction { normal: [f64; 2], value: f64 },
}

impl ComponentEquation {
    /// Whether this is a traction equation.
    pub fn is_traction(&self) -> bool {
        matches!(self, ComponentEquation::Traction { .. })
    }
}

/// Equations for components x and y of a boundary node.
pub fn resolve(sample: &BoundarySample, conditions: &[BoundaryCondition], exact: Option<&dyn ExactSolution>) -> [ComponentEquation; 2] {
    let p = sample.position;
    let eq = |c: usize| {
        for &(part, _) in &sample.touches {
            let bc = &conditions[part];
            if bc.components[c] == ComponentCondition::Displacement {
                let g = exact::value(&bc.value, p, exact, |e| e.displacement(p));
                return ComponentEquation::Displacement { value: g[c] };
            }
        }
        let mut n = [0.0; 2];
        let mut t = 0.0;
        for &(part, normal) in &sample.touches {
            let bc = &conditions[part];
            n[0] += normal[0];
            n[1] += normal[1];
            t += exact::value(&bc.value, p, exact, |e| e.traction(p, normal))[c];
        }
        let len = n[0].hypot(n[1]);
        if len < 1e-8 {
            // Opposite normals (a zero-thickness slit): use the first part alone.
            let (part, normal) = sample.touches[0];
            let t = exact::value(&conditions[part].value, p, exact, |e| e.traction(p, normal))[c];
            return ComponentEquation::Traction { normal, value: t };
        }
        ComponentEquation::Traction { normal: [n[0] / len, n[1] / len], value: t / len }
    };
    [eq(0), eq(1)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::conditions::Value;
    use crate::physics::elasticity::material::{Material, PlaneModel, YoungPoisson};
    use crate::physics::exact::Polynomial;

    fn condition(components: [ComponentCondition; 2], value: [f64; 2]) -> BoundaryCondition {
        BoundaryCondition { components, value: Value::Constant(value) }
    }

    fn corner(touches: Vec<(usize, [f64; 2])>) -> BoundarySample {
        let lengths = vec![0.05; touches.len()];
        BoundarySample { position: [1.0, 1.0], touches, lengths }
    }

    #[test]
    fn prescribed_displacement_wins_per_component_at_corners() {
        use ComponentCondition::{Displacement as D, Traction as T};
        // Part 0: symmetry (u prescribed, v traction-free); part 1: traction (3, 4).
        let conditions = [condition([D, T], [0.5, 0.0]), condition([T, T], [3.0, 4.0])];
        let eq = resolve(&corner(vec![(0, [-1.0, 0.0]), (1, [0.0, 1.0])]), &conditions, None);
        assert_eq!(eq[0], ComponentEquation::Displacement { value: 0.5 });
        // v: both parts are traction parts: bisector normal, summed tractions / |n0 + n1|.
        let s = 2f64.sqrt();
        match eq[1] {
            ComponentEquation::Traction { normal, value } => {
                assert!((normal[0] + 1.0 / s).abs() < 1e-15 && (normal[1] - 1.0 / s).abs() < 1e-15);
                assert!((value - (0.0 + 4.0) / s).abs() < 1e-15);
            }
            other => panic!("expected a traction equation, got {other:?}"),
        }
    }

    /// The combined corner equation holds for every stress that satisfies both parts'
    /// equations: `sigma = [[1, 0], [0, 2]]` gives `sigma n_k = t_k` on the two sides.
    #[test]
    fn corner_traction_is_the_sum_of_the_parts_equations() {
        let conditions =
            [condition([ComponentCondition::Traction; 2], [1.0, 0.0]), condition([ComponentCondition::Traction; 2], [0.0, 2.0])];
        let eq = resolve(&corner(vec![(0, [1.0, 0.0]), (1, [0.0, 1.0])]), &conditions, None);
        let sigma = [[1.0, 0.0], [0.0, 2.0]];
        for (c, e) in eq.iter().enumerate() {
            let ComponentEquation::Traction { normal, value } = *e else { panic!("traction expected") };
            let sn = sigma[c][0] * normal[0] + sigma[c][1] * normal[1];
            assert!((sn - value).abs() < 1e-15, "component {c}: {sn} vs {value}");
        }
    }

    #[test]
    fn exact_values_come_from_the_exact_solution_and_slits_use_the_first_part() {
        let material = Material { elastic: YoungPoisson { young: 10.0, poisson: 0.25 }, plane: PlaneModel::Strain };
        let exact = Polynomial::quadratic([0.0, 1.0, 2.0, 0.5, 0.0, 0.0], [1.0, 0.0, -1.0, 0.0, 0.25, 0.0], material).unwrap();
        let disp = [BoundaryCondition { components: [ComponentCondition::Displacement; 2], value: Value::Exact }];
        let sample = BoundarySample { position: [0.3, -0.2], touches: vec![(0, [0.0, -1.0])], lengths: vec![0.1] };
        let eq = resolve(&sample, &disp, Some(&exact));
        let u = exact.displacement(sample.position);
        assert_eq!(eq, [ComponentEquation::Displacement { value: u[0] }, ComponentEquation::Displacement { value: u[1] }]);
        // A zero-thickness slit: opposite normals of two traction parts.
        let trac = [0, 1].map(|_| BoundaryCondition { components: [ComponentCondition::Traction; 2], value: Value::Exact });
        let slit = BoundarySample { position: [0.3, -0.2], touches: vec![(0, [0.0, 1.0]), (1, [0.0, -1.0])], lengths: vec![0.1, 0.1] };
        let eq = resolve(&slit, &trac, Some(&exact));
        let t = exact.traction(slit.position, [0.0, 1.0]);
        assert_eq!(eq[1], ComponentEquation::Traction { normal: [0.0, 1.0], value: t[1] });
    }
}
