//! # mlsm-elasticity
//!
//! 2D linear elasticity (plane stress / plane strain Navier equation) solved in strong
//! form by meshless shape functions (MLSM), verified against closed-form solutions and
//! cross-checked against linear bond-based peridynamics on the same plate.
//!
//! The modules from the bottom up (each uses only those listed before it):
//! 1. [`choice`]: scene names, defaults and help of every option enum;
//!    [`output`], [`linalg`], [`domain`]: files, sparse solvers, geometry and nodes;
//! 2. [`mlsm`]: weighted least-squares shape functions for the operators each node needs;
//! 3. [`pipeline`]: stage names, timing, progress, run errors;
//! 4. [`elasticity`]: material, boundary conditions, unknown layout, stress;
//! 5. [`exact`]: closed-form and manufactured solutions; [`post`]: error norms, orders;
//! 6. [`dynamics`]: explicit time integrators and the shared time loop;
//! 7. [`case`]: the physical problem of a scene, independent of any discretisation;
//! 8. the models: [`navier`] (MLSM collocation, static and elastodynamic) and
//!    [`peridynamics`] (linear bond-based, static and dynamic);
//! 9. [`problem`]: scene file (TOML) -> validated [`problem::Problem`];
//! 10. [`model`]: the one dispatch static/dynamic × Navier/peridynamics;
//! 11. [`compare`]: the nonlocal-to-local comparison;
//! 12. [`app`] and [`cli`]: the command line (the only printing).

pub mod case;
pub mod choice;
pub mod compare;
pub mod domain;
pub mod dynamics;
pub mod elasticity;
pub mod exact;
pub mod linalg;
pub mod mlsm;
pub mod model;
pub mod navier;
pub mod output;
pub mod peridynamics;
pub mod pipeline;
pub mod post;
pub mod problem;

pub mod app;
pub mod cli;
