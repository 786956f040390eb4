//! The files of a time-dependent run: snapshots (`snapshots/step_<k>.vtu` with
//! displacement and velocity), `series.pvd`, `energies.csv` and the final
//! `solution.vtu`. Nothing is created before the first snapshot, which comes after
//! every check of the run.

use super::fields::vector;
use super::{create_dir, AppError};
use crate::domain::{cells::cells_inside, Domain};
use crate::dynamics::driver::{EnergyRow, Snapshot};
use crate::output::{self, OutputError};
use std::path::{Path, PathBuf};

/// Snapshot writer of one run (the Delaunay cells are built at the first snapshot).
pub(super) struct Series<'a> {
    dir: PathBuf,
    domain: &'a Domain,
    triangles: Option<Vec<[usize; 3]>>,
    entries: Vec<(f64, String)>,
}

impl<'a> Series<'a> {
    /// A writer into `dir`; nothing is created yet.
    pub(super) fn new(dir: &Path, domain: &'a Domain) -> Self {
        Series { dir: dir.to_path_buf(), domain, triangles: None, entries: Vec::new() }
    }

    fn write(&mut self, name: &str, points: &[[f64; 2]], u: &[[f64; 2]], v: &[[f64; 2]]) -> Result<(), OutputError> {
        if self.triangles.is_none() {
            let dir = self.dir.join("snapshots");
            std::fs::create_dir_all(&dir).map_err(|e| OutputError::Io { path: dir, source: e })?;
        }
        let domain = self.domain;
        let tris = self.triangles.get_or_insert_with(|| cells_inside(domain, points));
        let fields = vec![vector("displacement", u.iter().copied()), vector("velocity", v.iter().copied())];
        output::write_vtu(&self.dir.join(name), points, tris, &fields)
    }

    /// `snapshots/step_<k>.vtu`, listed in `series.pvd`.
    pub(super) fn snapshot(&mut self, s: Snapshot) -> Result<(), OutputError> {
        let name = format!("snapshots/step_{:06}.vtu", s.step);
        self.write(&name, s.positions, s.u, s.v)?;
        self.entries.push((s.t, name));
        Ok(())
    }

    /// `series.pvd`, `energies.csv` and the final `solution.vtu`.
    pub(super) fn finish(&mut self, energies: &[EnergyRow], points: &[[f64; 2]], u: &[[f64; 2]], v: &[[f64; 2]]) -> Result<(), AppError> {
        create_dir(&self.dir)?;
        output::write_pvd(&self.dir.join("series.pvd"), &self.entries)?;
        let rows: Vec<Vec<f64>> = energies.iter().map(|e| vec![e[0], e[1], e[2], e[3], e[1] + e[2] + e[3]]).collect();
        output::write_csv(&self.dir.join("energies.csv"), &["t", "kinetic", "elastic", "external", "total"], &rows)?;
        Ok(self.write("solution.vtu", points, u, v)?)
    }
}
