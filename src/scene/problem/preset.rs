//! Presets (`preset = "fast" | "balanced" | "accurate"` in a scene, `mlsm run
//! --preset`): rules that choose the approximation and the node spacing from the
//! geometry. The spacing is a fraction of the domain's smallest feature `L` (the
//! shortest rectangle side, disc radius or polygon edge); a graded spacing
//! (`[nodes.refine]`) is scaled with it. The rules were read off the fronts that
//! `mlsm tradeoff` measured on the shipped scenes (docs/guide/tradeoff.md, and
//! docs/notebook/round2-fronts-and-presets.md). A `balanced` or `accurate` run first
//! tries `fast` (`app::preset_trial`).

use super::spec::SceneSpec;
use crate::scene::choice::{choice, Choice};
use crate::domain::{Domain, Primitive};

choice! {
    /// A named trade of speed for accuracy (`preset`).
    pub enum Preset("preset", default None, note "none: the scene's own [nodes] spacing and [approximation]", serde "lowercase") {
        Fast = "fast" => "RBF-FD PHS r^3 + degree 4, default stencil, spacing L / 6 (L: the smallest feature of the domain) or small enough for 300 nodes; e_inf(sigma) 1e-4 to 3e-2 on the shipped scenes",
        Balanced = "balanced" => "RBF-FD PHS r^3 + degree 6, default stencil, spacing L / 16 or small enough for 1500 nodes; e_inf(sigma) 1e-7 to 3e-4; \"fast\" is tried first and written instead when its estimate is below 1e-7 (a solution the basis reproduces)",
        Accurate = "accurate" => "RBF-FD PHS r^3 + degree 6, default stencil, spacing L / 32 or small enough for 6000 nodes; e_inf(sigma) 1e-9 to 1e-5; \"fast\" is tried first and written instead when its estimate is below 1e-9",
    }
}

/// What a preset sets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rule {
    /// `approximation.basis`.
    pub basis: &'static str,
    /// `approximation.degree`.
    pub degree: u32,
    /// The far-field spacing is `L / divisions`...
    pub divisions: f64,
    /// ...or smaller, so that the domain of area `A` holds at least this many nodes
    /// (`h <= sqrt(A / min_nodes)`): a thin or small feature alone would leave a large
    /// plate with too few nodes for the stencils.
    pub min_nodes: f64,
}

impl Preset {
    /// The rule of this preset.
    pub fn rule(self) -> Rule {
        match self {
            Preset::Fast => Rule { basis: "phs", degree: 4, divisions: 6.0, min_nodes: 300.0 },
            Preset::Balanced => Rule { basis: "phs", degree: 6, divisions: 16.0, min_nodes: 1500.0 },
            Preset::Accurate => Rule { basis: "phs", degree: 6, divisions: 32.0, min_nodes: 6000.0 },
        }
    }
}

impl Preset {
    /// The band `(floor, ceiling)` of e_inf(sigma) this preset landed in on the shipped
    /// scenes with non-polynomial exact solutions (docs/guide/tradeoff.md, "Presets").
    pub fn band(self) -> (f64, f64) {
        match self {
            Preset::Fast => (1e-4, 3e-2),
            Preset::Balanced => (1e-7, 3e-4),
            Preset::Accurate => (1e-9, 1e-5),
        }
    }

    /// The cheaper preset whose run, with its error estimate, is tried first
    /// (`app::preset_trial`): when its estimate is already below this preset's floor,
    /// the basis reproduces the solution and more nodes would add only round-off.
    pub fn trial(self) -> Option<Preset> {
        match self {
            Preset::Fast => None,
            Preset::Balanced | Preset::Accurate => Some(Preset::Fast),
        }
    }
}

/// The smallest feature `L` of `domain`: the shortest side of a rectangle, radius of
/// a disc or edge of a polygon among its regions.
pub fn feature_length(domain: &Domain) -> f64 {
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    domain
        .regions
        .iter()
        .map(|r| match &r.primitive {
            Primitive::Rectangle { min, max } => (max[0] - min[0]).min(max[1] - min[1]),
            Primitive::Disc { radius, .. } => *radius,
            Primitive::Polygon { vertices } => {
                (0..vertices.len()).map(|k| dist(vertices[k], vertices[(k + 1) % vertices.len()])).fold(f64::INFINITY, f64::min)
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// Rewrite `spec` as `preset` says (module docs) and return the note that tells the
/// user what it set and what it replaced. `scattered_packing` converts a node count
/// of the scene into its spacing (for scaling a graded spacing).
pub(super) fn apply(preset: Preset, spec: &mut SceneSpec, domain: &Domain, area: f64, scattered_packing: f64) -> String {
    let rule = preset.rule();
    let length = feature_length(domain);
    let by_count = (area / rule.min_nodes).sqrt();
    let spacing = significant((length / rule.divisions).min(by_count), 4);
    let why = if by_count < length / rule.divisions {
        format!(
            "sqrt(A / {}) with A = {} the area (L / {} with L = {length} the smallest feature would give fewer nodes)",
            rule.min_nodes,
            significant(area, 4),
            rule.divisions
        )
    } else {
        format!("L / {} with L = {length} the smallest feature of the domain", rule.divisions)
    };
    let old = spec.nodes.spacing.or_else(|| spec.nodes.count.map(|n| (area * scattered_packing / n as f64).sqrt()));
    let mut replaced = Vec::new();
    if let Some(h) = spec.nodes.spacing {
        replaced.push(format!("nodes.spacing = {h}"));
    }
    if let Some(n) = spec.nodes.count {
        replaced.push(format!("nodes.count = {n}"));
    }
    spec.nodes.spacing = Some(spacing);
    spec.nodes.count = None;
    if let (Some(r), Some(old)) = (spec.nodes.refine.as_mut(), old) {
        let factor = spacing / old;
        r.spacing = r.spacing.map(|s| s * factor);
        r.growth = r.growth.map(|g| g * factor);
        replaced.push(format!("[nodes.refine] scaled by {factor:.3}"));
    }
    let a = &mut spec.approximation;
    for (name, set) in [("basis", a.basis.is_some()), ("degree", a.degree.is_some()), ("support", a.support.is_some())] {
        if set {
            replaced.push(format!("approximation.{name}"));
        }
    }
    a.basis = Some(rule.basis.into());
    a.degree = Some(rule.degree);
    (a.support, a.weight, a.sigma, a.shape, a.exponent) = (None, None, None, None, None);
    let replaced = if replaced.is_empty() { String::new() } else { format!("; replaces {}", replaced.join(", ")) };
    format!(
        "preset \"{}\": basis \"{}\", degree {}, default stencil, spacing {spacing} = {why}{replaced}",
        preset.name(),
        rule.basis,
        rule.degree,
    )
}

/// `x` rounded to `digits` significant decimal digits.
pub fn significant(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    // Dividing by an exact power of ten gives the shortest decimal representation.
    if scale >= 1.0 {
        (x * scale).round() / scale
    } else {
        (x / (1.0 / scale).round()).round() * (1.0 / scale).round()
    }
}
