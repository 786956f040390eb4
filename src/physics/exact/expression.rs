//! A manufactured solution written as two formulas (`[exact] kind = "expression"`,
//! `ux`, `uy`): its gradient and Hessians are derived symbolically once
//! (`Expression::derivative`), so the body force
//! `f = -((lambda + mu) grad div u + mu lap u)`, the stresses and the tractions of any
//! smooth field come without hand algebra.

use super::named::{Parameter, ParameterKind};
use super::{navier_body_force, Check, ExactSolution, ParameterError};
use crate::physics::elasticity::material::Material;
use crate::scene::expression::{Expression, ExpressionError};

/// Stack of the thread that differentiates (only the pages used are allocated).
const DERIVATION_STACK: usize = 256 << 20;

/// `u = ux(x, y)`, `v = uy(x, y)` with their symbolic derivatives.
#[derive(Debug, Clone)]
pub struct ExpressionSolution {
    /// `[ux, uy]` as written.
    pub displacement: [Expression; 2],
    /// `[[u_x, u_y], [v_x, v_y]]`.
    gradient: [[Expression; 2]; 2],
    /// `[u_xx, u_xy, u_yy]` and `[v_xx, v_xy, v_yy]`.
    hessians: [[Expression; 3]; 2],
    /// Material entering the body force and the stresses.
    pub material: Material,
}

impl ExpressionSolution {
    /// Parameters of `[exact] kind = "expression"`.
    pub const PARAMETERS: &'static [Parameter] = &[
        Parameter { name: "ux", kind: ParameterKind::Expression, help: "x displacement as a formula in x, y (m)" },
        Parameter { name: "uy", kind: ParameterKind::Expression, help: "y displacement as a formula in x, y (m)" },
    ];

    /// Differentiate `ux`, `uy` twice; refused for functions without derivatives.
    /// exmex differentiates recursively on its expression tree, and a long formula (a
    /// ten-term cubic) overflows a 2 MiB thread stack, so the work runs on a thread of
    /// its own with [`DERIVATION_STACK`] bytes of stack.
    pub fn derive(ux: Expression, uy: Expression, material: Material) -> Result<Self, ExpressionError> {
        std::thread::scope(|scope| {
            std::thread::Builder::new()
                .stack_size(DERIVATION_STACK)
                .spawn_scoped(scope, || Self::derive_here(ux, uy, material))
                .expect("a thread for the symbolic derivatives")
                .join()
                .expect("symbolic differentiation does not panic")
        })
    }

    fn derive_here(ux: Expression, uy: Expression, material: Material) -> Result<Self, ExpressionError> {
        let first = |e: &Expression| -> Result<[Expression; 2], ExpressionError> { Ok([e.derivative(0)?, e.derivative(1)?]) };
        let (gu, gv) = (first(&ux)?, first(&uy)?);
        let second = |g: &[Expression; 2]| -> Result<[Expression; 3], ExpressionError> {
            Ok([g[0].derivative(0)?, g[0].derivative(1)?, g[1].derivative(1)?])
        };
        let hessians = [second(&gu)?, second(&gv)?];
        Ok(ExpressionSolution { displacement: [ux, uy], gradient: [gu, gv], hessians, material })
    }

    /// The solution of `[exact]` with validated parameters (their derivatives were
    /// checked by [`ExpressionSolution::derive`] during validation).
    pub fn from_parameters(p: &super::Parameters, material: Material) -> Result<Self, ParameterError> {
        Check("expression").compressible_material(&material)?;
        let (ux, uy) = (p.expression("ux").clone(), p.expression("uy").clone());
        Ok(Self::derive(ux, uy, material).expect("validated: the expressions are differentiable"))
    }
}

impl ExpressionSolution {
    /// The first formula (displacement or a derivative) that is not finite at `p`:
    /// its field (`exact.ux`, `exact.uy`), text and value.
    pub fn non_finite_at(&self, p: [f64; 2]) -> Option<(String, &str, f64)> {
        (0..2).find_map(|c| {
            let derived = self.gradient[c].iter().chain(&self.hessians[c]);
            std::iter::once(&self.displacement[c]).chain(derived).find_map(|e| {
                let v = e.eval(p);
                (!v.is_finite()).then(|| (format!("exact.{}", ["ux", "uy"][c]), e.text(), v))
            })
        })
    }
}

impl ExactSolution for ExpressionSolution {
    fn name(&self) -> &'static str {
        "expression"
    }

    fn material(&self) -> Material {
        self.material
    }

    fn displacement(&self, p: [f64; 2]) -> [f64; 2] {
        self.displacement.each_ref().map(|e| e.eval(p))
    }

    fn gradient(&self, p: [f64; 2]) -> [[f64; 2]; 2] {
        self.gradient.each_ref().map(|g| g.each_ref().map(|e| e.eval(p)))
    }

    fn body_force(&self, p: [f64; 2]) -> [f64; 2] {
        let h = |k: usize| {
            let [xx, xy, yy] = self.hessians[k].each_ref().map(|e| e.eval(p));
            [[xx, xy], [xy, yy]]
        };
        navier_body_force(self.material.lame(), h(0), h(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::material::{PlaneModel, YoungPoisson};
    use crate::physics::exact::{Manufactured, Polynomial};
    use crate::scene::expression::{Constants, Scope};

    fn solution(ux: &str, uy: &str, material: Material) -> ExpressionSolution {
        let parse = |t: &str| Expression::parse(t, Scope::Space, &Constants::default()).unwrap();
        ExpressionSolution::derive(parse(ux), parse(uy), material).unwrap()
    }

    fn material(plane: PlaneModel) -> Material {
        Material { elastic: YoungPoisson { young: 2.0e11, poisson: 0.3 }, plane }
    }

    /// The derived body force of the shipped manufactured field equals the hand-written
    /// one to 1e-12 relative (both are exact formulas; only round-off differs).
    #[test]
    fn derived_body_force_matches_the_hand_written_manufactured_one() {
        for plane in [PlaneModel::Stress, PlaneModel::Strain] {
            let m = material(plane);
            let derived = solution("sin(pi*x)*cos(pi*y)", "x^2*y^3", m);
            let hand = Manufactured::new(m).unwrap();
            let scale = (0..=10)
                .flat_map(|i| (0..=10).map(move |j| [i as f64 / 10.0, j as f64 / 10.0]))
                .map(|p| hand.body_force(p).iter().fold(0.0f64, |a, v| a.max(v.abs())))
                .fold(0.0, f64::max);
            for i in 0..=10 {
                for j in 0..=10 {
                    let p = [i as f64 / 10.0, j as f64 / 10.0];
                    let (a, b) = (derived.body_force(p), hand.body_force(p));
                    for c in 0..2 {
                        assert!((a[c] - b[c]).abs() <= 1e-12 * scale, "{plane:?} at {p:?}: {a:?} vs {b:?}");
                    }
                    let (sa, sb) = (derived.stress(p), hand.stress(p));
                    for c in 0..3 {
                        assert!((sa[c] - sb[c]).abs() <= 1e-12 * sb.iter().fold(1.0f64, |m, v| m.max(v.abs())));
                    }
                }
            }
        }
    }

    /// A cubic written as an expression gives the same displacement, gradient, stress
    /// and body force as `kind = "polynomial"` with the same coefficients.
    #[test]
    fn polynomial_expression_reproduces_the_polynomial_solution() {
        let m = material(PlaneModel::Strain);
        let ux = [1e-3, 2e-3, -1e-3, 3e-3, 1e-3, -2e-3, 1e-3, 2e-3, -3e-3, 1e-3];
        let uy = [0.0, -1e-3, 2e-3, 1e-3, -1e-3, 2e-3, -2e-3, 1e-3, 1e-3, -1e-3];
        let poly = Polynomial::new(ux, uy, m).unwrap();
        let text = |c: [f64; 10]| {
            let monomials = ["1", "x", "y", "x^2", "x*y", "y^2", "x^3", "x^2*y", "x*y^2", "y^3"];
            c.iter().zip(monomials).map(|(c, m)| format!("({c:e})*{m}")).collect::<Vec<_>>().join(" + ")
        };
        let e = solution(&text(ux), &text(uy), m);
        for p in [[0.3, -0.7], [1.5, 2.0], [-2.0, 0.1]] {
            let close = |a: &[f64], b: &[f64], what: &str| {
                let scale = b.iter().fold(1e-300f64, |m, v| m.max(v.abs()));
                for (x, y) in a.iter().zip(b) {
                    assert!((x - y).abs() <= 1e-13 * scale, "{what} at {p:?}: {a:?} vs {b:?}");
                }
            };
            close(&e.displacement(p), &poly.displacement(p), "displacement");
            close(&e.gradient(p).concat(), &poly.gradient(p).concat(), "gradient");
            close(&e.stress(p), &poly.stress(p), "stress");
            close(&e.body_force(p), &poly.body_force(p), "body force");
        }
    }
}
