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
use crate::elasticity::conditions::{BoundaryCondition, ComponentCondition};
use crate::exact::{self, ExactSolution};

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
                let g = exact::value(bc.value, exact, |e| e.displacement(p));
                return ComponentEquation::Displacement { value: g[c] };
            }
        }
        let mut n = [0.0; 2];
        let mut t = 0.0;
        for &(part, normal) in &sample.touches {
            let bc = &conditions[part];
            n[0] += normal[0];
            n[1] += normal[1];
            t += exact::value(bc.value, exact, |e| e.traction(p, normal))[c];
        }
        let len = n[0].hypot(n[1]);
        if len < 1e-8 {
            // Opposite normals (a zero-thickness slit): use the first part alone.
            let (part, normal) = sample.touches[0];
            let t = exact::value(conditions[part].value, exact, |e| e.traction(p, normal))[c];
            return ComponentEquation::Traction { normal, value: t };
        }
        ComponentEquation::Traction { normal: [n[0] / len, n[1] / len], value: t / len }
    };
    [eq(0), eq(1)]
}
