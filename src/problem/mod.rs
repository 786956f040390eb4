//! The validated problem: built once from a scene file by [`Problem::from_file`].
//! After this point no code handles raw strings or unchecked numbers.

pub mod spec;
pub mod validate;

use crate::domain::{Domain, FillParams};
use crate::elasticity::material::Material;
use crate::linalg::SolverParams;
use crate::mlsm::Approximation;
use crate::peridynamics::PdParams;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// A scene file that cannot be used, with the file, the field and the reason.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{}: {field}: {reason}", file.display())]
pub struct ProblemError {
    /// The scene file.
    pub file: PathBuf,
    /// Dotted path of the offending field (`approximation.support`, `boundary[2].part`, ...).
    pub field: String,
    /// What is wrong and what to change.
    pub reason: String,
}

/// How a displacement component is constrained on a boundary part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ComponentCondition {
    /// Prescribed displacement component.
    Displacement,
    /// Prescribed traction component `(sigma n)_c`.
    Traction,
}

/// Where a boundary or body-force value comes from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Value {
    /// A constant vector.
    Constant([f64; 2]),
    /// The scene's exact solution (displacement, traction `sigma n`, or body force).
    Exact,
}

/// The condition imposed on one boundary part.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BoundaryCondition {
    /// Condition on the x and y components.
    pub components: [ComponentCondition; 2],
    /// Prescribed displacement or traction.
    pub value: Value,
}

/// A closed-form solution named in the scene (built by [`crate::exact::from_kind`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ExactKind {
    /// Timoshenko cantilever, variant A (verification.md 1).
    Cantilever { load: f64, length: f64, depth: f64 },
    /// Kirsch plate with a hole (verification.md 2).
    Kirsch { tension: f64, radius: f64 },
    /// Lame thick cylinder under internal pressure (verification.md 3).
    Lame { pressure: f64, inner: f64, outer: f64 },
    /// `u = (sin(pi x) cos(pi y), x^2 y^3)` with its body force (verification.md 6).
    Manufactured,
    /// Uniform uniaxial stress `sigma_xx = tension` (a linear field, zero at the origin).
    Tension { tension: f64 },
    /// A polynomial field of degree <= 3 with its body force (patch tests).
    Polynomial { ux: [f64; 10], uy: [f64; 10] },
}

/// The model `mlsm run` solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Model {
    /// The Navier equation by MLSM.
    Navier,
    /// Linear bond-based peridynamics.
    Peridynamics,
}

/// Output fields a run writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Outputs {
    /// Displacement vector.
    pub displacement: bool,
    /// Strain components.
    pub strain: bool,
    /// Stress components.
    pub stress: bool,
    /// Von Mises stress.
    pub von_mises: bool,
    /// Error fields and norms against the exact solution.
    pub error: bool,
}

impl Outputs {
    /// Whether post-processing needs the displacement gradient (first-derivative shapes everywhere).
    pub fn needs_gradient(&self) -> bool {
        self.strain || self.stress || self.von_mises || self.error
    }
}

/// A validated scene.
#[derive(Debug, Clone)]
pub struct Problem {
    /// Scene name (output folder).
    pub name: String,
    /// The scene file it came from.
    pub source: PathBuf,
    /// The solid.
    pub domain: Domain,
    /// Node generation (spacing resolved).
    pub fill: FillParams,
    /// Local approximation.
    pub approximation: Approximation,
    /// Material.
    pub material: Material,
    /// Body force.
    pub body_force: Value,
    /// Condition of each boundary part, indexed like `domain.parts`.
    pub conditions: Vec<BoundaryCondition>,
    /// Linear solver.
    pub solver: SolverParams,
    /// Requested fields.
    pub outputs: Outputs,
    /// Closed-form solution, if any.
    pub exact: Option<ExactKind>,
    /// Model of `mlsm run`.
    pub model: Model,
    /// Peridynamic discretisation, when the scene has a `[peridynamics]` table.
    pub peridynamics: Option<PdParams>,
    /// Time-dependent run settings, when the scene has a `[dynamics]` table.
    pub dynamics: Option<DynamicsParams>,
}

/// An affine vector field `u_c(x, y) = c[0] + c[1] x + c[2] y` per component.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Affine {
    /// Coefficients of the x component.
    pub x: [f64; 3],
    /// Coefficients of the y component.
    pub y: [f64; 3],
}

impl Affine {
    /// The zero field.
    pub const ZERO: Affine = Affine { x: [0.0; 3], y: [0.0; 3] };

    /// Value at `p`.
    pub fn at(&self, p: [f64; 2]) -> [f64; 2] {
        [self.x[0] + self.x[1] * p[0] + self.x[2] * p[1], self.y[0] + self.y[1] * p[0] + self.y[2] * p[1]]
    }
}

/// The `[dynamics]` table, validated.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DynamicsParams {
    /// Mass density rho (kg/m^3).
    pub density: f64,
    /// Final time (s).
    pub end_time: f64,
    /// Time integrator.
    pub integrator: crate::dynamics::Integrator,
    /// Fixed time step, if the scene gives one.
    pub time_step: Option<f64>,
    /// Fraction of the stable step used otherwise.
    pub safety: f64,
    /// Initial displacement.
    pub initial_displacement: Affine,
    /// Initial velocity.
    pub initial_velocity: Affine,
    /// Snapshots in the .pvd series.
    pub snapshots: usize,
    /// A snapshot every k steps, when given (instead of `snapshots`).
    pub snapshot_every: Option<usize>,
}

impl Problem {
    /// Read, parse and validate a scene file.
    pub fn from_file(path: &Path) -> Result<Problem, ProblemError> {
        let text = std::fs::read_to_string(path).map_err(|e| ProblemError {
            file: path.to_path_buf(),
            field: "(file)".into(),
            reason: format!("cannot read the scene file: {e}"),
        })?;
        Problem::from_str(&text, path)
    }

    /// Parse and validate scene text; `path` is used in messages and for the default name.
    pub fn from_str(text: &str, path: &Path) -> Result<Problem, ProblemError> {
        let spec = validate::parse(text, path)?;
        validate::validate(spec, path)
    }

    /// The same problem at another node spacing (used by convergence studies and
    /// `--spacing`); refused when the spacing is not positive or would give more than
    /// [`validate::MAX_NODES`] or fewer than two supports' worth of nodes.
    pub fn with_spacing(&self, spacing: f64) -> Result<Problem, ProblemError> {
        let expected = self.domain.area_estimate(400) / spacing.powi(2) * validate::packing(self.fill.kind);
        let reason = if !(spacing.is_finite() && spacing > 0.0) {
            Some(format!("spacing must be a positive number, got {spacing}"))
        } else if expected > validate::MAX_NODES {
            Some(format!("spacing {spacing} gives about {expected:.1e} nodes (over {:e})", validate::MAX_NODES))
        } else if expected < 2.0 * self.approximation.support as f64 {
            Some(format!("spacing {spacing} gives about {expected:.0} nodes, too few for supports of {}", self.approximation.support))
        } else {
            None
        };
        match reason {
            Some(reason) => Err(ProblemError { file: self.source.clone(), field: "nodes.spacing".into(), reason }),
            None => {
                let mut p = self.clone();
                p.fill.spacing = spacing;
                Ok(p)
            }
        }
    }

    /// The same problem with other peridynamic parameters (used by `compare` and
    /// `--horizon`), checked like the scene's own table.
    pub fn with_peridynamics(&self, params: PdParams) -> Result<Problem, ProblemError> {
        validate::check_peridynamics(&params, &self.domain).map_err(|(field, reason)| ProblemError {
            file: self.source.clone(),
            field: format!("peridynamics.{field}"),
            reason,
        })?;
        let mut p = self.clone();
        p.peridynamics = Some(params);
        Ok(p)
    }
}
