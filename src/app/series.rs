//! The files of a time-dependent run: snapshots (`snapshots/step_<k>.vtu` with
//! displacement, velocity and, as the scene's outputs ask, stress and von Mises; the
//! damage where bonds break), `series.pvd`, `energies.csv` (with the released energy and
//! the broken bonds where they break) and the final
//! `solution.vtu`, written into the run's staged directory (`output::StagedDir`),
//! which replaces the earlier results only when the run finishes: a run that fails or
//! is interrupted leaves no partial series and the earlier results intact.

use super::fields::{estimate_fields, scalar, stress_fields, vector};
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
    /// The stress and damage arrays of the last snapshot (the final state's, for
    /// `solution.vtu`).
    last_fields: Vec<PointField>,
    /// Whether bonds break (`energies.csv` says what they released).
    fracture: bool,
}

impl<'a> Series<'a> {
    /// A writer into `dir` (the staged directory) of a run in which bonds break or not
    /// (`fracture`); nothing is created yet.
    pub(super) fn new(dir: &Path, case: &'a Case, fracture: bool) -> Self {
        Series { dir: dir.to_path_buf(), case, triangles: None, entries: Vec::new(), last_fields: Vec::new(), fracture }
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
        self.last_fields = stress_fields(self.case, None, s.stress);
        if let Some(d) = s.damage {
            self.last_fields.push(scalar("damage", d.iter().copied()));
        }
        self.write(&folder.join(&file), s.positions, (s.u, s.v), self.last_fields.clone())?;
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
        let path = self.dir.join("energies.csv");
        if self.fracture {
            let rows: Vec<Vec<f64>> = energies.iter().map(|e| vec![e[0], e[1], e[2], e[3], e[4], e[5], e[1] + e[2] + e[3] + e[4]]).collect();
            output::write_csv(&path, &["t", "kinetic", "elastic", "external", "released", "broken_bonds", "total"], &rows)?;
        } else {
            let rows: Vec<Vec<f64>> = energies.iter().map(|e| vec![e[0], e[1], e[2], e[3], e[1] + e[2] + e[3]]).collect();
            output::write_csv(&path, &["t", "kinetic", "elastic", "external", "total"], &rows)?;
        }
        let mut more = std::mem::take(&mut self.last_fields);
        more.extend(estimate_fields(estimate));
        Ok(self.write(&self.dir.join("solution.vtu"), points, (u, v), more)?)
    }
}
