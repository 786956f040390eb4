//! Polynomial displacement fields of total degree at most 3, for patch tests.
//!
//! Source: verification.md, sections 1 (caveat) and 6. Each component is
//! `sum_k c_k x^i_k y^j_k` over the ten monomials [`Polynomial::MONOMIALS`]
//! `1, x, y, x^2, x y, y^2, x^3, x^2 y, x y^2, y^3`. Derivatives are exact:
//! `d^a/dx^a d^b/dy^b x^i y^j = i!/(i-a)! j!/(j-b)! x^(i-a) y^(j-b)`, and the body force is
//! `f = -((lambda + mu) grad div u + mu lap u)`, linear in `x, y`. A scheme that reproduces
//! total-degree-3 polynomials must recover these fields to round-off; a quadratic field
//! has a constant body force, a linear one none.

use serde::Serialize;

use super::named::{Parameter, ParameterKind};
use super::{navier_body_force, Check, ExactSolution, ParameterError};
use crate::physics::elasticity::material::Material;

/// `u = sum_k ux[k] m_k(x, y)`, `v = sum_k uy[k] m_k(x, y)` over [`Polynomial::MONOMIALS`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Polynomial {
    /// Coefficients of the x displacement.
    pub ux: [f64; 10],
    /// Coefficients of the y displacement.
    pub uy: [f64; 10],
    /// Material entering the body force and the stresses.
    pub material: Material,
}

impl Polynomial {
    /// Parameters of `[exact] kind = "polynomial"`.
    pub const PARAMETERS: &'static [Parameter] = &[
        Parameter {
            name: "ux",
            kind: ParameterKind::Coefficients(10),
            help: "u over the monomials 1, x, y, x^2, x y, y^2, x^3, x^2 y, x y^2, y^3",
        },
        Parameter { name: "uy", kind: ParameterKind::Coefficients(10), help: "v over the same monomials as ux" },
    ];

    /// Parameters of `[exact] kind = "tension"`.
    pub const TENSION_PARAMETERS: &'static [Parameter] =
        &[Parameter { name: "tension", kind: ParameterKind::Number, help: "uniaxial stress sigma_xx (Pa)" }];

    /// Exponents `(i, j)` of the monomials `x^i y^j`, in coefficient order.
    pub const MONOMIALS: [(u32, u32); 10] = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3)];

    /// Checked constructor for a general cubic field.
    pub fn new(ux: [f64; 10], uy: [f64; 10], material: Material) -> Result<Self, ParameterError> {
        let check = Check("polynomial");
        for c in ux.iter().chain(&uy) {
            check.finite("coefficient", *c)?;
        }
        check.compressible_material(&material)?;
        Ok(Polynomial { ux, uy, material })
    }

    /// Uniform uniaxial stress `sigma_xx = tension`, `sigma_yy = sigma_xy = 0`:
    /// `u = (e_xx x, e_yy y)` with (in-plane Lame parameters)
    /// `e_xx = T (lambda + 2 mu) / (4 mu (lambda + mu))` and `e_yy = -lambda e_xx / (lambda + 2 mu)`.
    pub fn uniaxial_tension(tension: f64, material: Material) -> Result<Self, ParameterError> {
        Check("tension").finite("tension", tension)?;
        let l = material.lame();
        // In this order no product of two moduli is formed: E = 1e250 would overflow it.
        let exx = tension / (4.0 * l.mu) * ((l.lambda + 2.0 * l.mu) / (l.lambda + l.mu));
        let eyy = -l.lambda * exx / (l.lambda + 2.0 * l.mu);
        Polynomial::quadratic([0.0, exx, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, eyy, 0.0, 0.0, 0.0], material)
    }

    /// A quadratic field: coefficients of `1, x, y, x^2, x y, y^2`.
    pub fn quadratic(ux: [f64; 6], uy: [f64; 6], material: Material) -> Result<Self, ParameterError> {
        let pad = |c: [f64; 6]| {
            let mut full = [0.0; 10];
            full[..6].copy_from_slice(&c);
            full
        };
        Polynomial::new(pad(ux), pad(uy), material)
    }

    /// Highest total degree with a non-zero coefficient (0 for the zero field).
    pub fn degree(&self) -> u32 {
        Self::MONOMIALS
            .iter()
            .zip(self.ux.iter().zip(&self.uy))
            .filter(|(_, (a, b))| **a != 0.0 || **b != 0.0)
            .map(|((i, j), _)| i + j)
            .max()
            .unwrap_or(0)
    }

    /// `d^a/dx^a d^b/dy^b` of the component with coefficients `c`, at `(x, y)`.
    fn derivative(c: &[f64; 10], a: u32, b: u32, [x, y]: [f64; 2]) -> f64 {
        let falling = |n: u32, k: u32| (0..k).map(|m| f64::from(n - m)).product::<f64>();
        Self::MONOMIALS
            .iter()
            .zip(c)
            .filter(|((i, j), _)| *i >= a && *j >= b)
            .map(|((i, j), ck)| ck * falling(*i, a) * falling(*j, b) * x.powi((i - a) as i32) * y.powi((j - b) as i32))
            .sum()
    }

    /// Hessians `([[u_xx, u_xy], [u_xy, u_yy]], [[v_xx, v_xy], [v_xy, v_yy]])`.
    pub fn hessians(&self, p: [f64; 2]) -> ([[f64; 2]; 2], [[f64; 2]; 2]) {
        let h = |c: &[f64; 10]| {
            let (xx, xy, yy) = (Self::derivative(c, 2, 0, p), Self::derivative(c, 1, 1, p), Self::derivative(c, 0, 2, p));
            [[xx, xy], [xy, yy]]
        };
        (h(&self.ux), h(&self.uy))
    }
}

impl ExactSolution for Polynomial {
    fn name(&self) -> &'static str {
        "polynomial"
    }

    fn material(&self) -> Material {
        self.material
    }

    fn displacement(&self, p: [f64; 2]) -> [f64; 2] {
        [Self::derivative(&self.ux, 0, 0, p), Self::derivative(&self.uy, 0, 0, p)]
    }

    fn gradient(&self, p: [f64; 2]) -> [[f64; 2]; 2] {
        let d = |c: &[f64; 10]| [Self::derivative(c, 1, 0, p), Self::derivative(c, 0, 1, p)];
        [d(&self.ux), d(&self.uy)]
    }

    fn body_force(&self, p: [f64; 2]) -> [f64; 2] {
        let (hu, hv) = self.hessians(p);
        navier_body_force(self.material.lame(), hu, hv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::material::{PlaneModel, YoungPoisson};

    fn material() -> Material {
        Material { elastic: YoungPoisson { young: 3.0, poisson: 0.25 }, plane: PlaneModel::Strain }
    }

    #[test]
    fn monomial_derivatives_by_hand() {
        // u = 2 x^2 y - y^3 + 4 x: u_x = 4 x y + 4, u_y = 2 x^2 - 3 y^2,
        // u_xx = 4 y, u_xy = 4 x, u_yy = -6 y. Integer arithmetic: exact.
        let mut ux = [0.0; 10];
        (ux[7], ux[9], ux[1]) = (2.0, -1.0, 4.0);
        let poly = Polynomial::new(ux, [0.0; 10], material()).unwrap();
        let p = [3.0, -2.0];
        assert_eq!(poly.displacement(p)[0], 2.0 * 9.0 * -2.0 + 8.0 + 12.0);
        assert_eq!(poly.gradient(p)[0], [4.0 * 3.0 * -2.0 + 4.0, 2.0 * 9.0 - 12.0]);
        assert_eq!(poly.hessians(p).0, [[-8.0, 12.0], [12.0, 12.0]]);
        assert_eq!(poly.degree(), 3);
    }

    #[test]
    fn degrees_and_body_force_of_low_order_fields() {
        let lin = Polynomial::quadratic([1.0, 2.0, 3.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.5, 0.0, 0.0, 0.0], material()).unwrap();
        assert_eq!(lin.degree(), 1);
        assert_eq!(lin.body_force([0.7, -0.2]), [0.0, 0.0]);
        // u = x^2: grad div u = (2, 0), lap u = (2, 0), so f = -(lambda + 2 mu)(2, 0);
        // lambda = mu = 1.2 for E = 3, nu = 1/4 in plane strain.
        let quad = Polynomial::quadratic([0.0, 0.0, 0.0, 1.0, 0.0, 0.0], [0.0; 6], material()).unwrap();
        assert_eq!(quad.degree(), 2);
        let f = quad.body_force([5.0, 9.0]);
        assert!((f[0] + 2.0 * 3.6).abs() <= 1e-14 && f[1] == 0.0, "{f:?}");
    }
}
