//! The files of a time-dependent run: snapshots (`snapshots/step_<k>.vtu` with
//! displacement, velocity and, as the scene's outputs ask, stress and von Mises),
//! `series.pvd`, `energies.csv` and the final
//! `solution.vtu`, written into the run's staged directory (`output::StagedDir`),
//! which replaces the earlier results only when the run finishes: a run that fails or
//! is interrupted leaves no partial series and the earlier results intact.

use super::fields::{estimate_fields, stress_fields, vector};
use super::AppError;
use crate::domain::cells::cells_inside;
use crate::physics::case::Case;
use crate::models::dynamics::driver::{EnergyRow, Snapshot};
use crate::models::navier::Estimate;
use crate::output::{self, OutputError, PointField};
use std::path::{Path, PathBuf};

/// Folder of the snapshots, inside the run's folder.
const SNAPSHOTS: &str = "snapshots";

/// Snapshot writer of one run (the Delaunay cells are built at the first snapshot).
pub(super) struct Series<'a> {
    dir: PathBuf,
    case: &'a Case,
    triangles: Option<Vec<[usize; 3]>>,
    entries: Vec<(f64, String)>,
    /// The stress arrays of the last snapshot (the final state's, for `solution.vtu`).
    last_stress: Vec<PointField>,
}

impl<'a> Series<'a> {
    /// A writer into `dir` (the staged directory); nothing is created yet.
    pub(super) fn new(dir: &Path, case: &'a Case) -> Self {
        Series { dir: dir.to_path_buf(), case, triangles: None, entries: Vec::new(), last_stress: Vec::new() }
    }

    fn write(
        &mut self,
        path: &Path,
        points: &[[f64; 2]],
        (u, v): (&[[f64; 2]], &[[f64; 2]]),
        more: Vec<PointField>,
    ) -> Result<(), OutputError> {
        let domain = &self.case.domain;
        let tris = self.triangles.get_or_insert_with(|| cells_inside(domain, points));
        let mut fields = vec![vector("displacement", u.iter().copied()), vector("velocity", v.iter().copied())];
        fields.extend(more);
        output::write_vtu(path, points, tris, fields)
    }

    /// `snapshots/step_<k>.vtu`, listed in `series.pvd`.
    pub(super) fn snapshot(&mut self, s: Snapshot) -> Result<(), OutputError> {
        let folder = self.dir.join(SNAPSHOTS);
        if self.entries.is_empty() {
            std::fs::create_dir(&folder).map_err(|e| OutputError::io(&folder, e))?;
        }
        let file = format!("step_{:06}.vtu", s.step);
        self.last_stress = stress_fields(self.case, None, s.stress);
        self.write(&folder.join(&file), s.positions, (s.u, s.v), self.last_stress.clone())?;
        self.entries.push((s.t, format!("{SNAPSHOTS}/{file}")));
        Ok(())
    }

    /// `series.pvd`, `energies.csv` and the final `solution.vtu` (with the estimate's
    /// per-node indicator `estimated_error`, its largest over the history, when made).
    pub(super) fn finish(
        &mut self,
        energies: &[EnergyRow],
        points: &[[f64; 2]],
        (u, v): (&[[f64; 2]], &[[f64; 2]]),
        estimate: &Estimate,
    ) -> Result<(), AppError> {
        output::write_pvd(&self.dir.join("series.pvd"), &self.entries)?;
        let rows: Vec<Vec<f64>> = energies.iter().map(|e| vec![e[0], e[1], e[2], e[3], e[1] + e[2] + e[3]]).collect();
        output::write_csv(&self.dir.join("energies.csv"), &["t", "kinetic", "elastic", "external", "total"], &rows)?;
        let mut more = std::mem::take(&mut self.last_stress);
        more.extend(estimate_fields(estimate));
        Ok(self.write(&self.dir.join("solution.vtu"), points, (u, v), more)?)
    }
}
