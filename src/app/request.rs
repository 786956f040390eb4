//! What `mlsm run` was asked for: the command line's scene and overrides, read once
//! by [`super`] and handed to the run, the preset trial and the rank start-up.

use crate::scene::problem::Model;
use crate::tradeoff::target::Target;
use std::path::PathBuf;

/// What `run` was asked for, after the command line was read.
pub(super) struct RunRequest {
    /// The scene file.
    pub scene: PathBuf,
    /// `--out`: the output folder.
    pub out: Option<PathBuf>,
    /// `--spacing`: the node spacing (m).
    pub spacing: Option<f64>,
    /// `--model`.
    pub model: Option<Model>,
    /// `--horizon`: the peridynamic horizon (m).
    pub horizon: Option<f64>,
    /// `--strict`: exit 4 on warnings.
    pub strict: bool,
    /// `--preset`.
    pub preset: Option<String>,
    /// `--allow-long`.
    pub allow_long: bool,
    /// `--export-system`: the folder of the exported system.
    pub export_system: Option<PathBuf>,
    /// `--target-error` and its options.
    pub target: Option<Target>,
    /// PETSc's options (after `--`).
    pub petsc_options: Vec<String>,
}
