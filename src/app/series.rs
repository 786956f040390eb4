//! The files of a time-dependent run: snapshots (`snapshots/step_<k>.vtu` with
//! displacement and velocity), `series.pvd`, `energies.csv` and the final
//! `solution.vtu`. Nothing is created before the first snapshot, which comes after
//! every check of the run.
//!
//! Snapshots are staged in `.snapshots.partial/` and replace `snapshots/` only when
//! the run finishes, so a run that fails or is interrupted leaves no partial series and
//! the series of an earlier run intact: the writer removes its staging folder when it
//! is dropped unfinished (and a stale one, left by a killed process, at its first
//! snapshot).

use super::fields::vector;
use super::{create_dir, AppError};
use crate::domain::{cells::cells_inside, Domain};
use crate::dynamics::driver::{EnergyRow, Snapshot};
use crate::output::{self, OutputError};
use std::path::{Path, PathBuf};

/// Folder of the finished series, inside the run's folder.
const SNAPSHOTS: &str = "snapshots";
/// Folder the snapshots are written to until the run finishes.
const STAGING: &str = ".snapshots.partial";

/// Snapshot writer of one run (the Delaunay cells are built at the first snapshot).
pub(super) struct Series<'a> {
    dir: PathBuf,
    domain: &'a Domain,
    triangles: Option<Vec<[usize; 3]>>,
    entries: Vec<(f64, String)>,
    /// Whether this writer created the staging folder.
    staged: bool,
    finished: bool,
}

impl<'a> Series<'a> {
    /// A writer into `dir`; nothing is created yet.
    pub(super) fn new(dir: &Path, domain: &'a Domain) -> Self {
        Series { dir: dir.to_path_buf(), domain, triangles: None, entries: Vec::new(), staged: false, finished: false }
    }

    fn write(&mut self, path: &Path, points: &[[f64; 2]], u: &[[f64; 2]], v: &[[f64; 2]]) -> Result<(), OutputError> {
        let domain = self.domain;
        let tris = self.triangles.get_or_insert_with(|| cells_inside(domain, points));
        let fields = vec![vector("displacement", u.iter().copied()), vector("velocity", v.iter().copied())];
        output::write_vtu(path, points, tris, &fields)
    }

    /// `step_<k>.vtu` in the staging folder; listed in `series.pvd` as
    /// `snapshots/step_<k>.vtu`.
    pub(super) fn snapshot(&mut self, s: Snapshot) -> Result<(), OutputError> {
        let staging = self.dir.join(STAGING);
        if !self.staged {
            if staging.exists() {
                std::fs::remove_dir_all(&staging).map_err(|e| OutputError::io(&staging, e))?;
            }
            std::fs::create_dir_all(&staging).map_err(|e| OutputError::io(&staging, e))?;
            self.staged = true;
        }
        let file = format!("step_{:06}.vtu", s.step);
        self.write(&staging.join(&file), s.positions, s.u, s.v)?;
        self.entries.push((s.t, format!("{SNAPSHOTS}/{file}")));
        Ok(())
    }

    /// The staged series becomes `snapshots/` (replacing an earlier one), then
    /// `series.pvd`, `energies.csv` and the final `solution.vtu`.
    pub(super) fn finish(&mut self, energies: &[EnergyRow], points: &[[f64; 2]], u: &[[f64; 2]], v: &[[f64; 2]]) -> Result<(), AppError> {
        create_dir(&self.dir)?;
        let (staging, snapshots) = (self.dir.join(STAGING), self.dir.join(SNAPSHOTS));
        if staging.exists() {
            if snapshots.exists() {
                std::fs::remove_dir_all(&snapshots).map_err(|e| OutputError::io(&snapshots, e))?;
            }
            std::fs::rename(&staging, &snapshots).map_err(|e| OutputError::io(&snapshots, e))?;
        }
        self.finished = true;
        output::write_pvd(&self.dir.join("series.pvd"), &self.entries)?;
        let rows: Vec<Vec<f64>> = energies.iter().map(|e| vec![e[0], e[1], e[2], e[3], e[1] + e[2] + e[3]]).collect();
        output::write_csv(&self.dir.join("energies.csv"), &["t", "kinetic", "elastic", "external", "total"], &rows)?;
        Ok(self.write(&self.dir.join("solution.vtu"), points, u, v)?)
    }
}

impl Drop for Series<'_> {
    /// An unfinished run (failed or interrupted) leaves no partial series.
    fn drop(&mut self) {
        if self.staged && !self.finished {
            let _ = std::fs::remove_dir_all(self.dir.join(STAGING));
        }
    }
}
