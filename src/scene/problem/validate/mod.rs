//! Scene text -> [`SceneSpec`] (syntax, types, unknown keys) -> [`Problem`]
//! (physics and consistency). Every error names the file, the field and the reason.
//! One file per scene table; option words are read through their enum's
//! [`Choice`] table.

mod approximation;
mod conditions;
mod domain;
mod dynamics;
mod exact;
mod expressions;
mod material;
mod peridynamics;
mod probes;
mod solver;

pub use crate::mlsm::default_support;
pub use approximation::{expected_nodes, DEFAULT_GHOST_NODES};
pub use peridynamics::{check_peridynamics, material_refusal as peridynamic_material_refusal, MAX_HORIZON_RATIO, POISSON_SNAP};

use super::preset::Preset;
use super::spec::{EstimateSpec, SceneSpec};
use super::{Model, ModelParams, Problem, ProblemError};
use crate::physics::case::{Case, OutputField, Outputs};
use crate::scene::choice::Choice;
use crate::domain::{Domain, FillKind};
use crate::scene::expression::Constants;
use crate::models::navier::estimate::DEFAULT_THRESHOLD;
use crate::models::navier::{EstimateParams, NavierParams};
use std::path::Path;

/// Largest node count a run may ask for (a sparse LU of 1e8 unknowns does not fit in memory).
pub const MAX_NODES: f64 = 5e7;

// The solver's 32-bit indices (`linalg::triplets`, `linalg::Csr`) hold every system
// the node limit admits: three unknowns per node (the u-p form), with ten times room
// for a node count above its estimate.
const _: () = assert!(MAX_NODES * 3.0 * 10.0 <= u32::MAX as f64);

/// What a spacing too coarse for the stencils is refused with (in `nodes.spacing`, of
/// kind [`crate::scene::problem::ProblemErrorKind::TooFewNodes`]), by the validation and
/// [`crate::scene::problem::Problem::with_fill`].
pub const TOO_FEW_NODES: &str = "too few for supports";

/// The refusal of a spacing that gives about `expected` nodes for supports of
/// `support` nodes (fewer than two supports' worth).
pub fn too_few_nodes(spacing: f64, expected: f64, support: usize) -> Option<String> {
    (expected < 2.0 * support as f64)
        .then(|| {
            format!(
                "spacing {spacing} gives about {expected:.0} nodes, {TOO_FEW_NODES} of {support} nodes (at least two supports' worth, {}, \
                 are needed); use a smaller spacing",
                2 * support
            )
        })
}

/// Nodes per unit area of a fill at spacing `h`, relative to `1/h^2`: used to turn
/// `nodes.count` into a spacing and to predict node counts (the scattered fill packs
/// about 0.9 nodes per h^2: 0.79-0.84 of the 1.1 assumed before on the 7 shipped
/// scattered scenes and their presets, 1e3 to 1.5e5 nodes;
/// docs/notebook/2026-11-29-memory-estimate.md).
pub(crate) fn packing(kind: FillKind) -> f64 {
    match kind {
        FillKind::Grid => 1.0,
        FillKind::Scattered => 0.9,
    }
}

/// TOML syntax, types and unknown keys; the message carries line, column and key path.
pub fn parse(text: &str, path: &Path) -> Result<SceneSpec, ProblemError> {
    let err = |field: String, reason: String| ProblemError { file: path.to_path_buf(), field, reason, kind: crate::scene::problem::ProblemErrorKind::Invalid };
    let de = toml::Deserializer::parse(text).map_err(|e| err("(syntax)".into(), located(text, &e)))?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = e.path().to_string();
        let inner = e.into_inner();
        err(if field == "." { "(top level)".into() } else { field }, located(text, &inner))
    })
}

/// Serde's type names in a parse message and the words a scene's author reads.
const TYPE_WORDS: [(&str, &str); 16] = [
    ("u8", "a whole number (0, 1, 2, ...)"),
    ("u16", "a whole number (0, 1, 2, ...)"),
    ("u32", "a whole number (0, 1, 2, ...)"),
    ("u64", "a whole number (0, 1, 2, ...)"),
    ("usize", "a whole number (0, 1, 2, ...)"),
    ("i8", "a whole number"),
    ("i16", "a whole number"),
    ("i32", "a whole number"),
    ("i64", "a whole number"),
    ("isize", "a whole number"),
    ("f32", "a number"),
    ("f64", "a number"),
    ("bool", "true or false"),
    ("a boolean", "true or false"),
    ("a sequence", "a list in brackets, [...]"),
    ("a map", "a table"),
];

/// `msg` with the Rust type names after `expected` (`expected u32`, `expected f64`)
/// replaced by words ([`TYPE_WORDS`]), and serde's `floating point` by `number`.
fn plain_types(msg: &str) -> String {
    let mut out = msg.replace("invalid type: floating point", "invalid type: decimal number");
    for (rust, words) in TYPE_WORDS {
        let from = format!("expected {rust}");
        let mut done = String::new();
        let mut rest = out.as_str();
        while let Some(k) = rest.find(&from) {
            let end = k + from.len();
            // Only the whole name: `expected u32`, not `expected u32x`.
            let whole = !rest[end..].starts_with(|c: char| c.is_alphanumeric() || c == '_');
            done.push_str(&rest[..k]);
            done.push_str(if whole { "expected " } else { &from });
            if whole {
                done.push_str(words);
            }
            rest = &rest[end..];
        }
        done.push_str(rest);
        out = done;
    }
    out
}

fn located(text: &str, e: &toml::de::Error) -> String {
    let msg = plain_types(e.message().trim());
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("line {line}, column {col}: {msg}")
        }
        None => msg,
    }
}

/// The scene file being validated (for error messages) and its constants.
struct Ctx<'a> {
    path: &'a Path,
    constants: Constants,
    /// Whether the scene has `[dynamics]` (its loads may use the time `t`).
    dynamic: bool,
}

impl Ctx<'_> {
    fn error(&self, field: impl Into<String>, reason: impl Into<String>) -> ProblemError {
        ProblemError { file: self.path.to_path_buf(), field: field.into(), reason: reason.into(), kind: crate::scene::problem::ProblemErrorKind::Invalid }
    }

    fn err<T>(&self, field: impl Into<String>, reason: impl Into<String>) -> Result<T, ProblemError> {
        Err(self.error(field, reason))
    }

    fn positive(&self, field: &str, v: f64) -> Result<f64, ProblemError> {
        if v.is_finite() && v > 0.0 {
            self.finite(field, &[v])?;
            Ok(v)
        } else {
            self.err(field, format!("must be a positive finite number, got {v}"))
        }
    }

    /// Every number finite and none subnormal (`0 < |x| < 2.2e-308`, where a double
    /// keeps fewer than 15 significant digits and products underflow to zero).
    fn finite(&self, field: &str, v: &[f64]) -> Result<(), ProblemError> {
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return self.err(field, format!("must be finite, got {x}"));
        }
        match v.iter().find(|x| x.is_subnormal()) {
            Some(x) => self.err(
                field,
                format!(
                    "{x:e} is below the smallest normal double ({:e}): it keeps fewer than 15 digits and its \
                     products underflow; rescale the units (e.g. loads in kN or MPa)",
                    f64::MIN_POSITIVE
                ),
            ),
            None => Ok(()),
        }
    }

    fn need<T>(&self, field: &str, v: Option<T>, what: &str) -> Result<T, ProblemError> {
        match v {
            Some(x) => Ok(x),
            None => self.err(field, format!("missing: {what}")),
        }
    }

    /// The option `word` names at `field`; its default when absent.
    fn choose<C: Choice>(&self, field: &str, word: Option<&str>) -> Result<C, ProblemError> {
        match (word, C::DEFAULT) {
            (Some(w), _) => C::parse(w).map_err(|reason| self.error(field, reason)),
            (None, Some(d)) => Ok(d),
            (None, None) => self.err(field, format!("missing: one of {}", C::expected())),
        }
    }
}

/// Semantic validation: physics, geometry, consistency of names and options.
pub fn validate(mut spec: SceneSpec, path: &Path, preset: Option<Preset>) -> Result<Problem, ProblemError> {
    let c = Ctx { path, constants: Constants::default(), dynamic: spec.dynamics.is_some() };
    let c = Ctx { constants: expressions::constants(&c, spec.constants.as_ref())?, ..c };
    let name = scene_name(&c, spec.name.as_deref(), path)?;
    let domain = domain::domain(&c, &spec.domain)?;
    let area = domain.area_estimate(400);
    let dynamic = spec.dynamics.is_some();
    let preset = match preset {
        Some(p) => Some(p),
        None => spec.preset.as_deref().map(|w| c.choose::<Preset>("preset", Some(w))).transpose()?,
    };
    let mut notes = Vec::new();
    if let Some(p) = preset {
        if dynamic {
            return c.err("preset", "presets were measured on static solves; with [dynamics] set [nodes] and [approximation] yourself");
        }
        notes.push(super::preset::apply(p, &mut spec, &domain, area, packing(FillKind::Scattered)));
    }
    let fill = approximation::nodes(&c, &spec.nodes, &domain, area)?;
    let approximation = approximation::approximation(&c, &spec.approximation, fill.kind, dynamic)?;
    approximation::check_node_count(&c, &domain, &fill, &approximation, area)?;
    let mut material = material::material(&c, &spec.material)?;
    if spec.peridynamics.as_ref().is_some_and(|p| !peridynamics::names_lps(p)) {
        notes.extend(peridynamics::snap_poisson(&mut material));
    }
    let formulation = approximation::formulation(&c, &spec.approximation, &material, dynamic)?;
    let pressure_stabilisation = approximation::pressure_stabilisation(&c, &spec.approximation)?;
    let exact = spec.exact.as_ref().map(|e| exact::exact(&c, e, material)).transpose()?;
    let body_force = exact::body_force(&c, spec.body_force.as_ref(), exact.as_ref())?;
    let dynamics = spec.dynamics.as_ref().map(|d| dynamics::dynamics(&c, d)).transpose()?;
    let present = parts_present(&domain, fill.spacing);
    let conditions = conditions::conditions(&c, &spec.boundary, &domain, &present, exact.is_some(), dynamic)?;
    let solver = solver::solver(&c, &spec.solver)?;
    let multigrid = solver::multigrid(&c, &spec.solver, &solver)?;
    let mut outputs = outputs(&c, spec.output.fields.as_deref(), exact.is_some())?;
    let peridynamics = match &spec.peridynamics {
        Some(pd) => Some(peridynamics::peridynamics(&c, pd, &domain, &material, &spec.boundary, dynamic)?),
        None => None,
    };
    let model: Model = c.choose("model", spec.model.as_deref())?;
    if model == Model::Peridynamics && preset.is_some() {
        return c
            .err("preset", "presets choose the MLSM nodes and approximation; the peridynamic model is set by [peridynamics] (horizon, m)");
    }
    let Some(model) = (ModelParams::Navier { peridynamics }).running(model) else {
        return c.err("model", "model = \"peridynamics\" needs a [peridynamics] table (horizon, quadrature, ...)");
    };
    if let Some(why) = (model.kind() == Model::Peridynamics).then(|| peridynamics::material_refusal(&material)).flatten() {
        return c.err("material.nu", why);
    }
    if dynamic && !spec.probe.is_empty() {
        return c.err("probe", "probes read static solutions (run, convergence); a [dynamics] run writes its fields over time instead");
    }
    let probes = probes::probes(&c, &spec.probe, &domain, &mut outputs)?;
    let estimate = estimate(&c, &spec.estimate)?;
    if let Some(why) = crate::scene::problem::estimate_mismatch(model.kind(), dynamics.is_some(), estimate.method) {
        return c.err("estimate.method", why);
    }
    Ok(Problem {
        name,
        source: path.to_path_buf(),
        case: Case { domain, material, body_force, conditions, exact, outputs, dynamics, probes },
        navier: NavierParams { fill, approximation, formulation, pressure_stabilisation, solver, multigrid, estimate, keep_system: false },
        model,
        preset,
        notes,
    })
}

/// `[estimate]`: the estimator and the warning threshold.
fn estimate(c: &Ctx, s: &EstimateSpec) -> Result<EstimateParams, ProblemError> {
    let method = c.choose("estimate.method", s.method.as_deref())?;
    let threshold = c.positive("estimate.threshold", s.threshold.unwrap_or(DEFAULT_THRESHOLD))?;
    Ok(EstimateParams { method, threshold })
}

/// The scene's name (default: the file stem), which names its output folder.
fn scene_name(c: &Ctx, name: Option<&str>, path: &Path) -> Result<String, ProblemError> {
    match name {
        Some(n) if n.is_empty() || n.contains(['/', '\\']) || n == "." || n == ".." => {
            c.err("name", format!("\"{n}\" cannot name an output folder (no slashes, not empty)"))
        }
        Some(n) => Ok(n.to_string()),
        None => Ok(path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into())),
    }
}

/// Which boundary parts hold boundary nodes at `spacing` (a part cut away by a
/// subtraction holds none).
fn parts_present(domain: &Domain, spacing: f64) -> Vec<bool> {
    let mut present = vec![false; domain.parts.len()];
    for b in crate::domain::boundary::discretise_boundary(domain, spacing) {
        for (part, _) in b.touches {
            present[part] = true;
        }
    }
    present
}

/// `[output] fields`: the requested fields (default: displacement, stress, von
/// Mises, and errors when the scene has an exact solution).
fn outputs(c: &Ctx, fields: Option<&[String]>, has_exact: bool) -> Result<Outputs, ProblemError> {
    let mut o = Outputs::default();
    match fields {
        None => {
            for f in [OutputField::Displacement, OutputField::Stress, OutputField::VonMises] {
                o.request(f);
            }
            o.error = has_exact;
        }
        Some(fields) => {
            for (k, f) in fields.iter().enumerate() {
                o.request(c.choose(&format!("output.fields[{k}]"), Some(f))?);
            }
        }
    }
    if o.error && !has_exact {
        return c.err("output.fields", "\"error\" needs an [exact] solution to compare with");
    }
    // The displacement is the solution itself: always written.
    o.displacement = true;
    Ok(o)
}

#[cfg(test)]
mod tests {
    use super::plain_types;

    /// Parse messages name no Rust type (issue 50: `expected u32`, `expected f64`).
    #[test]
    fn parse_messages_say_what_a_value_must_be_in_words() {
        let cases = [
            (
                "invalid type: floating point `1.5`, expected usize",
                "invalid type: decimal number `1.5`, expected a whole number (0, 1, 2, ...)",
            ),
            ("invalid type: string \"a\", expected f64", "invalid type: string \"a\", expected a number"),
            ("invalid type: integer `1`, expected a boolean", "invalid type: integer `1`, expected true or false"),
            ("invalid type: integer `3`, expected a sequence", "invalid type: integer `3`, expected a list in brackets, [...]"),
            ("invalid value: integer `-3`, expected u32", "invalid value: integer `-3`, expected a whole number (0, 1, 2, ...)"),
            ("expected u32x or f64", "expected u32x or f64"),
        ];
        for (serde, words) in cases {
            assert_eq!(plain_types(serde), words);
        }
    }
}
