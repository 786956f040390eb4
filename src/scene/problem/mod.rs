//! The validated problem: built once from a scene file by [`Problem::from_file`].
//! After this point no code handles raw strings or unchecked numbers.

pub mod preset;
pub mod reference;
pub mod spec;
pub mod validate;

use crate::physics::case::Case;
use crate::scene::choice::choice;
use crate::domain::FillParams;
use crate::models::navier::NavierParams;
use crate::models::peridynamics::PdParams;
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
    /// What kind of refusal it is, for a caller that acts on it.
    pub kind: ProblemErrorKind,
}

/// What kind of refusal a [`ProblemError`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProblemErrorKind {
    /// Any invalid value, key or file.
    Invalid,
    /// A spacing too coarse for the stencils (fewer nodes than two supports' worth,
    /// [`validate::too_few_nodes`]): a sweep passes over such a level.
    TooFewNodes,
}

choice! {
    /// The model `mlsm run` solves.
    pub enum Model("model", default Some(Model::Navier), serde "lowercase") {
        /// The Navier equation by MLSM.
        Navier = "navier" => "the Navier equation by MLSM collocation",
        /// Linear bond-based peridynamics.
        Peridynamics = "peridynamics" => "linear bond-based peridynamics (needs [peridynamics])",
    }
}

/// Why `method` cannot estimate a run of `model` (static, or `dynamic`), or `None`:
/// `higher-degree` and `defect` estimate static Navier runs, `richardson` and `refined` dynamic Navier runs,
/// `local-model` peridynamic runs.
pub fn estimate_mismatch(model: Model, dynamic: bool, method: crate::models::navier::EstimateMethod) -> Option<&'static str> {
    use crate::models::navier::EstimateMethod as M;
    let fits = match (model, dynamic) {
        (Model::Peridynamics, _) => method.peridynamics_estimates(),
        (Model::Navier, false) => method.static_navier_estimates(),
        (Model::Navier, true) => method.dynamic_navier_estimates(),
    };
    if fits || method == M::None {
        return None;
    }
    Some(match (model, dynamic) {
        (Model::Peridynamics, _) => "a peridynamic run is estimated against the Navier model: \"local-model\" (or \"auto\", \"none\")",
        (Model::Navier, false) => "a static Navier run takes \"higher-degree\" or \"defect\" (or \"auto\", \"none\")",
        (Model::Navier, true) => {
            "a dynamic Navier run takes \"richardson\" or \"refined\" (or \"auto\", \"none\"); higher-degree PHS stencils have growing modes in explicit dynamics"
        }
    })
}

/// A validated scene: the physical case, the discretisation of each model, and the
/// model `mlsm run` solves.
#[derive(Debug, Clone)]
pub struct Problem {
    /// Scene name (output folder).
    pub name: String,
    /// The scene file it came from.
    pub source: PathBuf,
    /// The solid, its loads, its reference solution and the requested fields.
    pub case: Case,
    /// The Navier model's discretisation (nodes, approximation, solver).
    pub navier: NavierParams,
    /// The model `mlsm run` solves, holding the peridynamic discretisation when the
    /// scene has a `[peridynamics]` table.
    pub model: ModelParams,
    /// The preset that set the nodes and the approximation, if any.
    pub preset: Option<preset::Preset>,
    /// What validation changed in the scene's values, to print (e.g. a Poisson ratio
    /// snapped to the value peridynamics represents).
    pub notes: Vec<String>,
}

/// The polynomial degree of the local model's reference for a peridynamic estimate
/// (`local-model`): a scene whose Navier basis has a lower degree is solved with PHS
/// r^3 and monomials of this degree instead.
pub const LOCAL_REFERENCE_DEGREE: u32 = 4;

/// The model a problem runs, with the parameters only that model has: a peridynamic
/// run cannot be made without its `[peridynamics]` table. The Navier parameters are
/// [`Problem::navier`] in both: every problem has them (a peridynamic run's
/// `local-model` estimate solves the Navier model too).
#[derive(Debug, Clone)]
pub enum ModelParams {
    /// The Navier model; the scene's `[peridynamics]` table, if it has one, is kept
    /// for `mlsm compare` and `--model peridynamics`.
    Navier {
        /// The scene's peridynamic discretisation, if any.
        peridynamics: Option<PdParams>,
    },
    /// Linear peridynamics with this discretisation.
    Peridynamics(PdParams),
}

impl ModelParams {
    /// Which model this is.
    pub fn kind(&self) -> Model {
        match self {
            ModelParams::Navier { .. } => Model::Navier,
            ModelParams::Peridynamics(_) => Model::Peridynamics,
        }
    }

    /// The peridynamic discretisation, whichever model runs (the scene's table).
    pub fn peridynamics(&self) -> Option<&PdParams> {
        match self {
            ModelParams::Navier { peridynamics } => peridynamics.as_ref(),
            ModelParams::Peridynamics(pd) => Some(pd),
        }
    }

    /// Whether the scene's solid is cracked or its bonds break (`[peridynamics.fracture]`):
    /// a model without cracks cannot stand in for it, nor estimate its error.
    pub fn has_fracture(&self) -> bool {
        self.peridynamics().is_some_and(|pd| pd.fracture.is_some())
    }

    /// [`ModelParams::peridynamics`], to change.
    pub fn peridynamics_mut(&mut self) -> Option<&mut PdParams> {
        match self {
            ModelParams::Navier { peridynamics } => peridynamics.as_mut(),
            ModelParams::Peridynamics(pd) => Some(pd),
        }
    }

    /// The same parameters running `model`; `None` for peridynamics without a table.
    pub fn running(&self, model: Model) -> Option<ModelParams> {
        let peridynamics = self.peridynamics().copied();
        match model {
            Model::Navier => Some(ModelParams::Navier { peridynamics }),
            Model::Peridynamics => peridynamics.map(ModelParams::Peridynamics),
        }
    }
}

/// The most a dynamic `local-model` reference's spacing exceeds the scene's
/// ([`Problem::local_reference`]): without an own estimate to check it by, its error, of
/// order 2 in `h`, grows at most four times over the reference at the scene's spacing.
pub const DYNAMIC_REFERENCE_COARSENING: f64 = 2.0;

impl Problem {
    /// The Navier problem the `local-model` estimate of this (peridynamic) problem
    /// starts from: the scene's nodes, no finer than the peridynamic spacing; a static
    /// one with the scene's basis, or PHS r^3 with monomials of
    /// degree [`LOCAL_REFERENCE_DEGREE`] when the scene's degree is lower (so that the
    /// reference is far more accurate than the nonlocal solution it judges), and its own
    /// error estimate (`auto`: the defect estimate, 0.3 of the cost the higher-degree
    /// one had on the shipped pd_* scenes); a dynamic one with the scene's basis (PHS
    /// stencils grow in explicit dynamics) and no estimate of its own (a second
    /// integration costs more than it tells).
    pub fn local_reference(&self) -> Problem {
        use crate::mlsm::{default_rbf_fd_support, Approximation, Basis, Radial, Weight};
        use crate::models::navier::EstimateMethod;
        let mut navier = Problem { model: self.model.running(Model::Navier).expect("the Navier model always runs"), ..self.clone() };
        navier.navier.keep_system = false;
        let dynamic = navier.case.dynamics.is_some();
        navier.navier.estimate.method = if dynamic { EstimateMethod::None } else { EstimateMethod::Auto };
        let approximation = &mut navier.navier.approximation;
        // Explicit dynamics keeps the scene's basis: PHS stencils have growing modes there.
        if !dynamic && approximation.basis.polynomial_degree() < LOCAL_REFERENCE_DEGREE {
            let basis = Basis::RbfFd { radial: Radial::Phs { order: 3 }, degree: LOCAL_REFERENCE_DEGREE };
            let support = default_rbf_fd_support(basis.size(), navier.navier.fill.kind);
            *approximation = Approximation { basis, weight: Weight::None, support, ghost_nodes: approximation.ghost_nodes };
        }
        // The reference starts at the peridynamic spacing `delta / m` where that is
        // coarser than the scene's `[nodes]`, and is refined from there as far as its
        // margin asks (`quality::compare::estimate::local_model`): the degree-4 reference
        // at the peridynamic spacing is already far more accurate than the model
        // difference it measures (order 2-4 in `h` against order 2 in `delta = m h`). On
        // pd_manufactured (225 peridynamic nodes) the scene's 1 681 nodes made a reference
        // 1e4 times more accurate than the difference (own estimate 2.3e-6 against
        // 1.8e-2) for 12 times the run's time; at 256 nodes its own estimate is 1.1e-4
        // and the difference reads the same to three digits. A dynamic reference too,
        // with no own estimate to refine by (as at the scene's spacing), so no coarser
        // than [`DYNAMIC_REFERENCE_COARSENING`] times the scene's spacing: its integration
        // costs as the cube of `1 / h` (nodes times steps), and on the shipped dynamic
        // scenes (1.67 times) its own error stays some 40 times below the difference it
        // measures (docs/notebook/2026-11-30-pd-reference-at-its-spacing.md).
        let scene = navier.navier.fill.spacing;
        let start = self.model.peridynamics().map_or(0.0, |pd| {
            if dynamic {
                pd.spacing().min(DYNAMIC_REFERENCE_COARSENING * scene)
            } else {
                pd.spacing()
            }
        });
        if start > scene {
            if let Ok(coarser) = navier.with_spacing(start) {
                return coarser;
            }
        }
        navier
    }

    /// Read, parse and validate a scene file.
    pub fn from_file(path: &Path) -> Result<Problem, ProblemError> {
        Problem::from_file_with_preset(path, None)
    }

    /// Parse and validate scene text; `path` is used in messages and for the default name.
    pub fn from_str(text: &str, path: &Path) -> Result<Problem, ProblemError> {
        Problem::from_str_with_preset(text, path, None)
    }

    /// [`Problem::from_file`] with `preset` in place of the scene's own `preset`.
    pub fn from_file_with_preset(path: &Path, preset: Option<preset::Preset>) -> Result<Problem, ProblemError> {
        let text = std::fs::read_to_string(path).map_err(|e| ProblemError {
            file: path.to_path_buf(),
            field: "(file)".into(),
            reason: format!("cannot read the scene file: {e}"),
            kind: crate::scene::problem::ProblemErrorKind::Invalid,
        })?;
        Problem::from_str_with_preset(&text, path, preset)
    }

    /// [`Problem::from_str`] with `preset` in place of the scene's own `preset`.
    pub fn from_str_with_preset(text: &str, path: &Path, preset: Option<preset::Preset>) -> Result<Problem, ProblemError> {
        let spec = validate::parse(text, path)?;
        validate::validate(spec, path, preset)
    }

    /// Nodes the Navier fill is expected to make ([`validate::expected_nodes`]).
    pub fn expected_nodes(&self) -> f64 {
        validate::expected_nodes(&self.case.domain, &self.navier.fill, self.case.domain.area_estimate(400))
    }

    /// The same problem at another node spacing (used by convergence studies and
    /// `--spacing`); refused when the spacing is not positive or would give more than
    /// [`validate::MAX_NODES`] or fewer than two supports' worth of nodes.
    pub fn with_spacing(&self, spacing: f64) -> Result<Problem, ProblemError> {
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(self.spacing_error(format!("spacing must be a positive number, got {spacing}")));
        }
        // A graded spacing h(x) is scaled as a whole: every h(x) by the same factor.
        self.with_fill(self.navier.fill.scaled(spacing / self.navier.fill.spacing))
    }

    /// The same problem with the nodes of `fill` (an adapted spacing, a scaled one),
    /// refused like [`Problem::with_spacing`] when the node count is out of range.
    pub fn with_fill(&self, fill: FillParams) -> Result<Problem, ProblemError> {
        let expected = validate::expected_nodes(&self.case.domain, &fill, self.case.domain.area_estimate(400));
        let spacing = fill.spacing;
        if expected > validate::MAX_NODES {
            return Err(self.spacing_error(format!("spacing {spacing} gives about {expected:.1e} nodes (over {:e})", validate::MAX_NODES)));
        }
        if let Some(reason) = validate::too_few_nodes(spacing, expected, self.navier.approximation.support) {
            return Err(ProblemError { kind: ProblemErrorKind::TooFewNodes, ..self.spacing_error(reason) });
        }
        let mut p = self.clone();
        p.navier.fill = fill;
        Ok(p)
    }

    fn spacing_error(&self, reason: String) -> ProblemError {
        ProblemError { file: self.source.clone(), field: "nodes.spacing".into(), reason, kind: ProblemErrorKind::Invalid }
    }

    /// The same problem with other peridynamic parameters (used by `compare` and
    /// `--horizon`), checked like the scene's own table.
    pub fn with_peridynamics(&self, params: PdParams) -> Result<Problem, ProblemError> {
        if let Some(reason) = validate::peridynamic_material_refusal(&self.case.material) {
            return Err(ProblemError { file: self.source.clone(), field: "material.nu".into(), reason, kind: ProblemErrorKind::Invalid });
        }
        validate::check_peridynamics(&params, &self.case.domain).map_err(|(field, reason)| ProblemError {
            file: self.source.clone(),
            field: format!("peridynamics.{field}"),
            reason,
            kind: crate::scene::problem::ProblemErrorKind::Invalid,
        })?;
        let mut p = self.clone();
        p.model = match p.model {
            ModelParams::Navier { .. } => ModelParams::Navier { peridynamics: Some(params) },
            ModelParams::Peridynamics(_) => ModelParams::Peridynamics(params),
        };
        Ok(p)
    }
}
