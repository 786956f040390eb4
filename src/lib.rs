//! # mlsm-elasticity
//!
//! 2D linear elasticity (plane stress / plane strain Navier equation) solved in strong
//! form by meshless shape functions (MLSM), verified against closed-form solutions.
//!
//! The pipeline of one run, module by module:
//! 1. [`problem`]: scene file (TOML) -> validated [`problem::Problem`];
//! 2. [`domain`]: CSG geometry with named boundary parts -> nodes, normals, supports;
//! 3. [`mlsm`]: weighted least-squares shape functions for the operators each node needs;
//! 4. [`elasticity`]: material, unknown layout, boundary equations, Navier / traction /
//!    displacement rows, stresses;
//! 5. [`linalg`]: sparse assembly, sparse LU or preconditioned BiCGSTAB;
//! 6. [`post`]: error norms and observed orders; [`exact`]: closed-form solutions;
//! 7. [`output`]: `solution.vtu`, `summary.json`, CSV tables (atomic writes);
//! 8. [`peridynamics`]: the linear bond-based model on the same plate (nodes as
//!    quadrature points, families, calibrated kernels, static solve);
//! 9. [`dynamics`]: explicit time integrators (EMU, Stormer-Verlet, RK4);
//! 10. [`compare`]: the nonlocal-to-local comparison (PD at a sequence of horizons
//!     against the Navier solution).
//!
//! [`run`] strings the stages together; [`app`] and [`cli`] are the command line.

pub mod compare;
pub mod domain;
pub mod dynamics;
pub mod elasticity;
pub mod exact;
pub mod linalg;
pub mod mlsm;
pub mod output;
pub mod peridynamics;
pub mod post;
pub mod problem;
pub mod run;

pub mod app;
pub mod cli;
