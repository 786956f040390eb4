//! `mlsm check`: validate a scene and print what it describes, in the numbers and
//! units a reader writes (`spacing 1 m`, not `1.0000e0`).

use super::number::plain;
use super::AppError;
use crate::scene::choice::Choice;
use crate::scene::problem::Problem;
use std::path::Path;

/// Validate `scene`; unless `quiet`, print its parts and settings.
pub(super) fn run(scene: &Path, quiet: bool) -> Result<(), AppError> {
    let p = Problem::from_file(scene)?;
    if quiet {
        return Ok(());
    }
    println!("{}: valid", scene.display());
    for line in describe(&p) {
        println!("  {line}");
    }
    Ok(())
}

/// `n` and `word`, plural unless `n` is 1: `1 node`, `37 nodes`.
fn count(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

/// The lines `check` prints about a valid scene.
fn describe(p: &Problem) -> Vec<String> {
    let mut lines = vec![
        format!("model: {} (what `mlsm run` solves; --model overrides)", p.model.kind().name()),
        format!("boundary parts: {}", p.case.domain.parts.join(", ")),
    ];
    lines.extend(p.notes.iter().map(|n| format!("note: {n}")));
    let m = &p.case.material;
    lines.push(format!("material: E = {} Pa, nu = {}, plane {}", plain(m.elastic.young), plain(m.elastic.poisson), m.plane.name()));
    let n = &p.navier;
    let graded = if n.fill.refine.is_some() { ", graded finer towards [nodes.refine]" } else { "" };
    lines.push(format!(
        "nodes (Navier model): spacing {} m ({} fill{graded}), supports of {}, {}",
        plain(n.fill.spacing),
        n.fill.kind.name(),
        count(n.approximation.support, "node"),
        n.approximation.basis.describe()
    ));
    if let Some(d) = &p.case.dynamics {
        let scheme = d.integrator.name();
        let step = match d.time_step {
            Some(dt) => format!("{} s", plain(dt)),
            None => format!("{} of the {scheme} stability limit", plain(d.safety)),
        };
        lines.push(format!("dynamics: density {} kg/m^3, end time {} s, {scheme}, time step {step}", plain(d.density), plain(d.end_time)));
    }
    if let Some(pd) = p.model.peridynamics() {
        lines.push(format!(
            "peridynamics: horizon {} m, m = {} (node spacing h = {} m), {} per cell, quadrature {}, kernel {}",
            plain(pd.horizon),
            plain(pd.ratio),
            plain(pd.spacing()),
            count(pd.nodes_per_cell(), "node"),
            pd.quadrature.name(),
            pd.kernel.label()
        ));
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str) -> Problem {
        Problem::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("problems").join(name)).unwrap()
    }

    /// Numbers read as written, with their units (issue 50: `1.0000e0 (Grid fill)`).
    #[test]
    fn check_prints_plain_numbers_with_units() {
        let lines = describe(&shipped("cantilever.toml")).join("\n");
        assert!(lines.contains("spacing 1 m (grid fill), supports of 37 nodes"), "{lines}");
        assert!(lines.contains("material: E = 7.21e10 Pa, nu = 0.33, plane stress"), "{lines}");
        assert!(lines.contains("model: navier"), "{lines}");
        assert!(!lines.contains("e0") && !lines.contains("Grid"), "{lines}");
        let lines = describe(&shipped("plate_pulse.toml")).join("\n");
        assert!(lines.contains("model: peridynamics"), "{lines}");
        assert!(lines.contains("dynamics: density 8000 kg/m^3, end time 1e-4 s, rk4, time step 0.8 of the rk4 stability limit"), "{lines}");
        assert!(lines.contains("horizon 0.1 m, m = 6 (node spacing h = 0.01667 m), 1 node per cell"), "{lines}");
    }
}
