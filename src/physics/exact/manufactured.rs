//! Manufactured solution `u = (sin(pi x) cos(pi y), x^2 y^3)`.
//!
//! Source: verification.md, section 6. The body force is
//! `f = -((lambda + mu) grad div u + mu lap u)` with the in-plane `lambda`, so the field
//! solves the Navier equation exactly for either planar model. Derivatives by hand:
//!
//! ```text
//! u_x  =  pi cos(pi x) cos(pi y)        v_x  = 2 x y^3
//! u_y  = -pi sin(pi x) sin(pi y)        v_y  = 3 x^2 y^2
//! u_xx = -pi^2 sin(pi x) cos(pi y)      v_xx = 2 y^3
//! u_xy = -pi^2 cos(pi x) sin(pi y)      v_xy = 6 x y^2
//! u_yy = -pi^2 sin(pi x) cos(pi y)      v_yy = 6 x^2 y
//! ```
//!
//! Natural domain: the unit square (any bounded region works; `v` grows like `r^5`).

use serde::Serialize;
use std::f64::consts::PI;

use super::{navier_body_force, Check, ExactSolution, ParameterError};
use crate::physics::elasticity::material::Material;

/// `u = (sin(pi x) cos(pi y), x^2 y^3)` with its Navier body force.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Manufactured {
    /// Material entering the body force and the stresses.
    pub material: Material,
}

impl Manufactured {
    /// Checked constructor.
    pub fn new(material: Material) -> Result<Self, ParameterError> {
        Check("manufactured").compressible_material(&material)?;
        Ok(Manufactured { material })
    }

    /// Hessians `([[u_xx, u_xy], [u_xy, u_yy]], [[v_xx, v_xy], [v_xy, v_yy]])`.
    pub fn hessians(&self, [x, y]: [f64; 2]) -> ([[f64; 2]; 2], [[f64; 2]; 2]) {
        let (sx, cx, sy, cy) = ((PI * x).sin(), (PI * x).cos(), (PI * y).sin(), (PI * y).cos());
        let pi2 = PI * PI;
        let hu = [[-pi2 * sx * cy, -pi2 * cx * sy], [-pi2 * cx * sy, -pi2 * sx * cy]];
        let hv = [[2.0 * y.powi(3), 6.0 * x * y * y], [6.0 * x * y * y, 6.0 * x * x * y]];
        (hu, hv)
    }
}

impl ExactSolution for Manufactured {
    fn name(&self) -> &'static str {
        "manufactured"
    }

    fn material(&self) -> Material {
        self.material
    }

    fn displacement(&self, [x, y]: [f64; 2]) -> [f64; 2] {
        [(PI * x).sin() * (PI * y).cos(), x * x * y.powi(3)]
    }

    fn gradient(&self, [x, y]: [f64; 2]) -> [[f64; 2]; 2] {
        let (sx, cx, sy, cy) = ((PI * x).sin(), (PI * x).cos(), (PI * y).sin(), (PI * y).cos());
        [[PI * cx * cy, -PI * sx * sy], [2.0 * x * y.powi(3), 3.0 * x * x * y * y]]
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

    #[test]
    fn body_force_written_out() {
        // An independent transcription of f = -((lambda + mu) grad div u + mu lap u) at one
        // point, to catch an index slip in navier_body_force.
        let material = Material { elastic: YoungPoisson { young: 3.0, poisson: 0.25 }, plane: PlaneModel::Strain };
        let m = Manufactured::new(material).unwrap();
        let (lambda, mu) = (1.2, 1.2); // E nu/((1+nu)(1-2nu)) = 0.75/0.625, E/(2(1+nu)) = 1.2
        let (x, y) = (0.3, 0.7);
        let (sx, cx, sy, cy) = ((PI * x).sin(), (PI * x).cos(), (PI * y).sin(), (PI * y).cos());
        let pi2 = PI * PI;
        let fx = -((lambda + mu) * (-pi2 * sx * cy + 6.0 * x * y * y) + mu * (-2.0 * pi2 * sx * cy));
        let fy = -((lambda + mu) * (-pi2 * cx * sy + 6.0 * x * x * y) + mu * (2.0 * y.powi(3) + 6.0 * x * x * y));
        let f = m.body_force([x, y]);
        // Same arithmetic in a different order: round-off on O(10) numbers.
        assert!((f[0] - fx).abs() <= 1e-13 && (f[1] - fy).abs() <= 1e-13, "{f:?} vs [{fx}, {fy}]");
    }
}
