//! # mlsm-elasticity
//!
//! 2D linear elasticity (plane stress / plane strain Navier equation) solved in strong
//! form by meshless shape functions (MLSM), verified against closed-form solutions and
//! cross-checked against linear peridynamics on the same plate.
//!
//! The folders read as the pipeline of a run:
//! - [`scene`]: the scene file, from text to a validated [`scene::problem::Problem`];
//! - [`physics`]: the solid, its material, conditions, stress and exact solutions;
//! - [`domain`]: geometry, nodes and their neighbours;
//! - [`mlsm`]: the local approximation (meshless shape functions);
//! - [`models`]: the Navier and peridynamic models, time integration, the dispatch;
//! - [`linalg`]: one solve contract, Krylov methods and preconditioners;
//! - [`parallel`]: MPI ranks and PETSc, the only place that knows about ranks;
//! - [`stages`]: what every run shares: named stages, timing, progress, run errors;
//! - [`quality`]: error norms, warnings, the nonlocal-to-local comparison;
//! - [`tradeoff`]: the speed-accuracy sweep, presets and `--target-error` policy;
//! - [`output`]: files (VTK, CSV, JSON), written whole or not at all;
//! - [`app`]: the commands and the command line (the only printing).
//!
//! Inside the folders, each concern sits on a floor and imports only concerns on the
//! floors below its own (`tests/architecture.rs` reads the floors from the lines
//! below; a folder of concerns lists its parts as `folder::part`):
//!
// Floor 1: scene::choice scene::expression output parallel::petsc
// Floor 2: domain linalg physics::elasticity
// Floor 3: mlsm physics::exact parallel::partition parallel::distributed parallel::launch
// Floor 4: stages quality::post parallel::share
// Floor 5: models::dynamics
// Floor 6: physics::case
// Floor 7: models::navier models::peridynamics
// Floor 8: scene::problem
// Floor 9: models::resources
// Floor 10: quality::warnings
// Floor 11: models::dispatch
// Floor 12: quality::compare tradeoff
// Floor 13: app

pub mod app;
pub mod domain;
pub mod linalg;
pub mod mlsm;
pub mod models;
pub mod output;
pub mod parallel;
pub mod physics;
pub mod quality;
pub mod scene;
pub mod stages;
pub mod tradeoff;
