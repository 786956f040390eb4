//! Probes: named point values of a solution that a scene asks for (`[[probe]]`), e.g.
//! the tip deflection of a bracket or the hoop stress at a hole. A probe reads one
//! displacement or stress component at one point; the value is interpolated from the
//! nodal field by moving least squares (`mlsm::interpolate`, error `O(h^3)`, below
//! the discretisation error of the solution itself), and the exact value is given
//! beside it where the scene has a closed-form solution.

use crate::scene::choice::choice;
use crate::domain::Point;
use crate::physics::elasticity::stress::{von_mises, StressField};
use crate::physics::exact::ExactSolution;
use crate::mlsm::interpolate::mls_values;
use crate::mlsm::ShapeError;
use serde::Serialize;

choice! {
    /// The quantity a probe reads.
    pub enum ProbeQuantity("probe[k].quantity", default None, serde "snake_case") {
        /// Displacement, x component.
        Ux = "ux" => "displacement, x component",
        /// Displacement, y component.
        Uy = "uy" => "displacement, y component",
        /// Normal stress in x.
        SigmaXx = "sigma_xx" => "normal stress sigma_xx",
        /// Normal stress in y.
        SigmaYy = "sigma_yy" => "normal stress sigma_yy",
        /// Shear stress.
        SigmaXy = "sigma_xy" => "shear stress sigma_xy",
        /// Von Mises stress.
        VonMises = "von_mises" => "von Mises stress (with sigma_zz in plane strain)",
    }
}

impl ProbeQuantity {
    /// Whether the quantity is read from the stress field.
    pub fn is_stress(self) -> bool {
        !matches!(self, ProbeQuantity::Ux | ProbeQuantity::Uy)
    }

    /// The quantity of an exact solution at `p`.
    pub fn exact(self, exact: &dyn ExactSolution, p: Point) -> f64 {
        match self {
            ProbeQuantity::Ux => exact.displacement(p)[0],
            ProbeQuantity::Uy => exact.displacement(p)[1],
            ProbeQuantity::SigmaXx => exact.stress(p)[0],
            ProbeQuantity::SigmaYy => exact.stress(p)[1],
            ProbeQuantity::SigmaXy => exact.stress(p)[2],
            ProbeQuantity::VonMises => {
                let s = exact.stress(p);
                von_mises(s, exact.material().sigma_zz(s[0], s[1]))
            }
        }
    }
}

/// One `[[probe]]` of a scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Probe {
    /// Name (unique in the scene; a column name of `convergence.csv`).
    pub name: String,
    /// Where it reads, on or inside the solid.
    pub at: Point,
    /// What it reads.
    pub quantity: ProbeQuantity,
}

/// The value a solution gives a probe.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProbeValue {
    /// The probe's name.
    pub name: String,
    /// What it reads.
    pub quantity: ProbeQuantity,
    /// Where.
    pub at: Point,
    /// The solution's value there.
    pub value: f64,
    /// The exact value, where the scene has a closed-form solution.
    pub exact: Option<f64>,
}

/// The nodal fields a probe reads from.
pub struct NodalFields<'a> {
    /// Node positions.
    pub positions: &'a [Point],
    /// Displacement at the nodes.
    pub displacement: &'a [[f64; 2]],
    /// Stress at the nodes, when computed (every stress probe needs it).
    pub stress: Option<&'a StressField>,
}

/// The value of every probe, interpolated from `fields`; the exact value from `exact`.
/// A stress probe without a stress field reads NaN (the scene validation requests
/// the stress whenever a probe needs it).
pub fn probe_values(probes: &[Probe], fields: &NodalFields, exact: Option<&dyn ExactSolution>) -> Result<Vec<ProbeValue>, ShapeError> {
    if probes.is_empty() {
        return Ok(Vec::new());
    }
    let at: Vec<Point> = probes.iter().map(|p| p.at).collect();
    let u = mls_values(fields.positions, fields.displacement, &at)?;
    let stress = match fields.stress {
        Some(s) if probes.iter().any(|p| p.quantity.is_stress()) => {
            let packed: Vec<[f64; 4]> = s.sigma.iter().zip(&s.von_mises).map(|(s, v)| [s[0], s[1], s[2], *v]).collect();
            Some(mls_values(fields.positions, &packed, &at)?)
        }
        _ => None,
    };
    Ok(probes
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let stress_value = |c: usize| stress.as_ref().map_or(f64::NAN, |s| s[k][c]);
            let value = match p.quantity {
                ProbeQuantity::Ux => u[k][0],
                ProbeQuantity::Uy => u[k][1],
                ProbeQuantity::SigmaXx => stress_value(0),
                ProbeQuantity::SigmaYy => stress_value(1),
                ProbeQuantity::SigmaXy => stress_value(2),
                ProbeQuantity::VonMises => stress_value(3),
            };
            ProbeValue { name: p.name.clone(), quantity: p.quantity, at: p.at, value, exact: exact.map(|e| p.quantity.exact(e, p.at)) }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::material::{Material, PlaneModel, YoungPoisson};

    /// A quadratic field is read to round-off (degree-2 interpolation reproduces it),
    /// a stress probe without stresses reads NaN.
    #[test]
    fn probes_read_quadratic_fields_exactly() {
        let mut positions = Vec::new();
        for i in 0..8 {
            for j in 0..8 {
                positions.push([i as f64 * 0.1 + 0.013 * (j % 3) as f64, j as f64 * 0.1]);
            }
        }
        let field = |p: Point| [1.0 + p[0] * p[1], p[0] * p[0] - 2.0 * p[1]];
        let displacement: Vec<[f64; 2]> = positions.iter().map(|p| field(*p)).collect();
        let material = Material { elastic: YoungPoisson { young: 1.0, poisson: 0.25 }, plane: PlaneModel::Stress };
        let stress =
            StressField::from_gradients(&material, &positions.iter().map(|p| [[p[1], p[0]], [2.0 * p[0], -2.0]]).collect::<Vec<_>>());
        let probes = vec![
            Probe { name: "a".into(), at: [0.33, 0.41], quantity: ProbeQuantity::Uy },
            Probe { name: "b".into(), at: [0.33, 0.41], quantity: ProbeQuantity::SigmaXy },
        ];
        let fields = NodalFields { positions: &positions, displacement: &displacement, stress: Some(&stress) };
        let v = probe_values(&probes, &fields, None).unwrap();
        assert!((v[0].value - field([0.33, 0.41])[1]).abs() < 1e-12, "{}", v[0].value);
        // sigma_xy = mu (u_y + v_x) = 0.4 (x + 2 x) at E = 1, nu = 0.25: linear, reproduced.
        assert!((v[1].value - 0.4 * 3.0 * 0.33).abs() < 1e-12, "{}", v[1].value);
        let without = NodalFields { stress: None, ..fields };
        assert!(probe_values(&probes, &without, None).unwrap()[1].value.is_nan());
    }
}
