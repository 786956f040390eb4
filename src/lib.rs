//! # mlsm-elasticity
//!
//! 2D linear elasticity (plane stress / plane strain Navier equation) solved in strong
//! form by meshless shape functions (MLSM), verified against closed-form solutions and
//! cross-checked against linear bond-based peridynamics on the same plate.
//!
//! The modules from the bottom up, one floor at a time: a module uses only modules on
//! the floors below its own (`tests/architecture.rs` checks it).
//! 1. [`choice`]: scene names, defaults and help of every option enum; [`output`]:
//!    files; [`cli`]: the command line; [`expression`]: formulas of the scene file;
//!    [`petsc`]: PETSc and MPI behind the feature `petsc`;
//! 2. [`domain`]: geometry and nodes; [`linalg`]: sparse solvers; [`elasticity`]:
//!    material, boundary conditions, unknown layout, stress;
//! 3. [`mlsm`]: weighted least-squares shape functions; [`exact`]: closed-form and
//!    manufactured solutions;
//! 4. [`pipeline`]: stage names, timing, progress, run errors; [`post`]: error norms;
//! 5. [`dynamics`]: explicit time integrators and the shared time loop;
//! 6. [`case`]: the physical problem of a scene, independent of any discretisation;
//! 7. the models: [`navier`] (MLSM collocation, static and elastodynamic) and
//!    [`peridynamics`] (linear bond-based, static and dynamic);
//! 8. [`problem`]: scene file (TOML) -> validated [`problem::Problem`];
//! 9. [`resources`]: the memory a run will need, checked before it starts;
//! 10. [`warnings`]: the checks that turn a doubtful result into a warning;
//! 11. [`model`]: the one dispatch static/dynamic × Navier/peridynamics;
//! 12. [`compare`]: the nonlocal-to-local comparison; [`tradeoff`]: the design and
//!     the Pareto front of a speed-accuracy sweep;
//! 13. [`app`]: the commands (the only printing).

// Floor 1
pub mod choice;
pub mod cli;
pub mod expression;
pub mod output;
pub mod petsc;

// Floor 2
pub mod domain;
pub mod elasticity;
pub mod linalg;

// Floor 3
pub mod exact;
pub mod mlsm;

// Floor 4
pub mod pipeline;
pub mod post;

// Floor 5
pub mod dynamics;

// Floor 6
pub mod case;

// Floor 7
pub mod navier;
pub mod peridynamics;

// Floor 8
pub mod problem;

// Floor 9
pub mod resources;

// Floor 10
pub mod warnings;

// Floor 11
pub mod model;

// Floor 12
pub mod compare;
pub mod tradeoff;

// Floor 13
pub mod app;
