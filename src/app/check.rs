//! `mlsm check`: validate a scene and print what it describes.

use super::AppError;
use crate::choice::Choice;
use crate::problem::Problem;
use std::path::Path;

/// Validate `scene`; unless `quiet`, print its parts and settings.
pub(super) fn run(scene: &Path, quiet: bool) -> Result<(), AppError> {
    let p = Problem::from_file(scene)?;
    if quiet {
        return Ok(());
    }
    println!("{}: valid", scene.display());
    println!("  boundary parts: {}", p.case.domain.parts.join(", "));
    for n in &p.notes {
        println!("  note: {n}");
    }
    let n = &p.navier;
    println!(
        "  spacing {:.4e} ({:?} fill), support {}, {}",
        n.fill.spacing,
        n.fill.kind,
        n.approximation.support,
        n.approximation.basis.describe()
    );
    if let Some(d) = &p.case.dynamics {
        println!(
            "  dynamics: rho {:.4e}, t_end {:.4e} s, {}, step {}",
            d.density,
            d.end_time,
            d.integrator.name(),
            d.time_step.map_or(format!("{} of the stable step", d.safety), |dt| format!("{dt:.4e} s"))
        );
    }
    if let Some(pd) = &p.peridynamics {
        println!(
            "  peridynamics: horizon {:.4e}, m = {}, h = {:.4e}, {} nodes per cell, quadrature {}, kernel {}",
            pd.horizon,
            pd.ratio,
            pd.spacing(),
            pd.nodes_per_cell(),
            pd.quadrature.name(),
            pd.kernel.label()
        );
    }
    Ok(())
}
