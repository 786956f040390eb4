//! `[material]`: one pair of elastic constants (E and nu, or lambda and mu) and the
//! planar model.

use super::Ctx;
use crate::physics::elasticity::material::{Material, PlaneModel, YoungPoisson};
use crate::scene::problem::spec::MaterialSpec;
use crate::scene::problem::ProblemError;

/// `[material]`.
pub(super) fn material(c: &Ctx, s: &MaterialSpec) -> Result<Material, ProblemError> {
    let plane = c.choose("material.plane", Some(&s.plane))?;
    let elastic = match (s.young, s.nu, s.lambda, s.mu) {
        (Some(e), Some(nu), None, None) => {
            c.positive("material.E", e)?;
            let incompressible = nu == 0.5 && plane == PlaneModel::Strain;
            if !(nu.is_finite() && nu > -1.0 && (nu < 0.5 || incompressible)) {
                let why = if nu == 0.5 { " (0.5, incompressible, is allowed in plane strain only)" } else { "" };
                return c.err("material.nu", format!("Poisson's ratio must lie in (-1, 0.5), got {nu}{why}"));
            }
            YoungPoisson { young: e, poisson: nu }
        }
        (None, None, Some(l), Some(m)) => {
            c.positive("material.mu", m)?;
            if !(l.is_finite() && l + 2.0 * m / 3.0 > 0.0) {
                return c.err("material.lambda", format!("the bulk modulus lambda + 2 mu / 3 must be positive, got lambda = {l}"));
            }
            YoungPoisson::from_lame_3d(l, m)
        }
        _ => return c.err("material", "give exactly one pair: E and nu, or lambda and mu"),
    };
    Ok(Material { elastic, plane })
}
