//! The point-data arrays of `solution.vtu` (only the fields the scene asks for) and
//! the writing of a point set with its Delaunay cells.

use super::AppError;
use crate::physics::case::Case;
use crate::domain::{cells::cells_inside, Domain};
use crate::physics::elasticity::material::PlaneModel;
use crate::physics::elasticity::stress::{strain, Gradient, StressField};
use crate::models::navier::equations::ComponentEquation;
use crate::models::navier::{Estimate, Solution};
use crate::output::{self, FieldValues, PointField};
use crate::models::peridynamics::PdSolution;
use crate::quality::post::ExactFields;
use std::borrow::Cow;
use std::path::Path;

/// A vector array (3 components, z = 0, as ParaView expects).
pub(super) fn vector(name: &str, v: impl Iterator<Item = [f64; 2]>) -> PointField {
    PointField { name: name.into(), components: 3, values: FieldValues::F64(v.flat_map(|a| [a[0], a[1], 0.0]).collect()) }
}

/// A scalar array.
pub(super) fn scalar(name: &str, v: impl Iterator<Item = f64>) -> PointField {
    PointField { name: name.into(), components: 1, values: FieldValues::F64(v.collect()) }
}

/// An integer array.
pub(super) fn integer(name: &str, v: impl Iterator<Item = i32>) -> PointField {
    PointField { name: name.into(), components: 1, values: FieldValues::I32(v.collect()) }
}

/// Write `points` with `fields` to a .vtu, with Delaunay triangles inside the solid for
/// viewing (triangulated while the fields are encoded).
pub(super) fn write_points_vtu(path: &Path, points: &[[f64; 2]], domain: &Domain, fields: Vec<PointField>) -> Result<(), AppError> {
    Ok(output::write_vtu_with(path, points, || Cow::Owned(cells_inside(domain, points)), fields)?)
}

/// Strain, stress and von Mises arrays, as far as the scene asks for them.
pub(super) fn stress_fields(case: &Case, gradient: Option<&[Gradient]>, stress: Option<&StressField>) -> Vec<PointField> {
    let mut f = Vec::new();
    if let (Some(g), true) = (gradient, case.outputs.strain) {
        let e: Vec<[f64; 3]> = g.iter().map(|g| strain(*g)).collect();
        for (k, name) in ["eps_xx", "eps_yy", "eps_xy"].iter().enumerate() {
            f.push(scalar(name, e.iter().map(|e| e[k])));
        }
    }
    if let Some(s) = stress {
        if case.outputs.stress {
            for (k, name) in ["sigma_xx", "sigma_yy", "sigma_xy"].iter().enumerate() {
                f.push(scalar(name, s.sigma.iter().map(|s| s[k])));
            }
            if case.material.plane == PlaneModel::Strain {
                f.push(scalar("sigma_zz", s.sigma_zz.iter().copied()));
            }
        }
        if case.outputs.von_mises {
            f.push(scalar("von_mises", s.von_mises.iter().copied()));
        }
    }
    f
}

/// Exact displacement and the error fields, when the scene asks for errors.
fn error_fields(case: &Case, displacement: &[[f64; 2]], stress: &Option<StressField>, exact: &Option<ExactFields>) -> Vec<PointField> {
    let mut f = Vec::new();
    if let (true, Some(ex)) = (case.outputs.error, exact) {
        f.push(vector("exact_displacement", ex.displacement.iter().copied()));
        f.push(vector("error_displacement", displacement.iter().zip(&ex.displacement).map(|(a, b)| [a[0] - b[0], a[1] - b[1]])));
        if let (Some(s), Some(se)) = (stress, &ex.stress) {
            let d: Vec<f64> = s.sigma.iter().zip(se).flat_map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]]).collect();
            f.push(PointField { name: "error_stress".into(), components: 3, values: FieldValues::F64(d) });
        }
    }
    f
}

/// Node kind for the viewer: 0 interior, 1 displacement, 2 traction, 3 mixed.
fn node_kind(eq: &[ComponentEquation; 2]) -> i32 {
    match eq.map(|e| matches!(e, ComponentEquation::Displacement { .. })) {
        [true, true] => 1,
        [false, false] => 2,
        _ => 3,
    }
}

/// Point-data arrays of a static Navier solution.
pub(super) fn navier_fields(case: &Case, sol: &Solution) -> Vec<PointField> {
    let n = sol.nodes.len();
    let nb = sol.nodes.boundary.len();
    let mut f = vec![vector("displacement", sol.displacement.iter().copied())];
    f.extend(stress_fields(case, sol.gradient.as_deref(), sol.stress.as_ref()));
    if let Some(p) = &sol.pressure {
        f.push(scalar("pressure", p.iter().copied()));
    }
    f.push(integer("node_kind", (0..n).map(|i| if i < nb { node_kind(&sol.boundary_equations[i]) } else { 0 })));
    f.push(integer("boundary_part", (0..n).map(|i| if i < nb { sol.nodes.boundary[i].touches[0].0 as i32 } else { -1 })));
    f.push(vector("normal", (0..n).map(|i| if i < nb { sol.nodes.normal(i) } else { [0.0, 0.0] })));
    f.extend(error_fields(case, &sol.displacement, &sol.stress, &sol.exact));
    f.extend(estimate_fields(&sol.estimate));
    f
}

/// The per-node indicators of an estimate: `estimated_error` (displacement) and
/// `estimated_error_stress`.
pub(super) fn estimate_fields(estimate: &Estimate) -> Vec<PointField> {
    let mut f = Vec::new();
    if let Some(e) = estimate.done() {
        f.push(scalar("estimated_error", e.per_node_u.iter().copied()));
        if let Some(s) = &e.per_node_sigma {
            f.push(scalar("estimated_error_stress", s.iter().copied()));
        }
    }
    f
}

/// Point-data arrays of a static peridynamic solution (free nodes only).
pub(super) fn pd_fields(case: &Case, sol: &PdSolution, estimate: &Estimate) -> Vec<PointField> {
    let n = sol.nodes.free;
    let mut f = vec![vector("displacement", sol.displacement[..n].iter().copied())];
    f.extend(stress_fields(case, sol.gradient.as_deref(), sol.stress.as_ref()));
    f.push(vector("body_force", sol.body_force.iter().copied()));
    f.push(integer("interior", sol.interior.iter().map(|&b| b as i32)));
    f.push(scalar("volume", sol.nodes.volumes[..n].iter().copied()));
    f.extend(error_fields(case, &sol.displacement, &None, &sol.exact));
    f.extend(estimate_fields(estimate));
    f
}
