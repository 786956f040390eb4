//! `[nodes]` and `[approximation]`: node generation and the local approximation of
//! the Navier model (basis, weight, support size, ghost nodes).

use super::{packing, Ctx, MAX_NODES};
use crate::scene::choice::Choice;
use crate::domain::{Domain, FillKind, FillParams, Primitive, Refinement};
use crate::physics::elasticity::dofs::Unknowns;
use crate::physics::elasticity::material::Material;
use crate::mlsm::{default_rbf_fd_support, default_support, Approximation, Basis, BasisKind, Radial, Weight, WeightKind};
use crate::models::navier::formulation::{MAX_PRESSURE_STABILISATION, PRESSURE_STABILISATION};
use crate::models::navier::Formulation;
use crate::scene::problem::spec::{ApproximationSpec, NodesSpec, RefineSpec};
use crate::scene::problem::ProblemError;

/// Ghost nodes outside traction boundaries unless the scene says otherwise (static
/// scenes; time-dependent ones default to none).
pub const DEFAULT_GHOST_NODES: bool = true;

/// `[nodes]`: fill, spacing (or count), seed, relaxation sweeps.
pub(super) fn nodes(c: &Ctx, s: &NodesSpec, domain: &Domain, area: f64) -> Result<FillParams, ProblemError> {
    let single_rectangle = domain.regions.len() == 1 && matches!(domain.regions[0].primitive, Primitive::Rectangle { .. });
    let kind = match &s.fill {
        None if single_rectangle => FillKind::Grid,
        None => FillKind::Scattered,
        Some(w) => c.choose("nodes.fill", Some(w))?,
    };
    let spacing = match (s.spacing, s.count) {
        (Some(_), Some(_)) => return c.err("nodes", "give either spacing or count, not both"),
        (None, None) => return c.err("nodes", "missing: give spacing = <m> or count = <nodes>"),
        (Some(h), None) => c.positive("nodes.spacing", h)?,
        (None, Some(n)) => {
            if n < 4 {
                return c.err("nodes.count", format!("must be at least 4, got {n}"));
            }
            (area * packing(kind) / n as f64).sqrt()
        }
    };
    let size = domain.scale();
    if spacing > size / 2.0 {
        return c.err("nodes.spacing", format!("spacing {spacing} is more than {:.3e}, half the domain size ({size:.3e})", size / 2.0));
    }
    let relax = s.relax.unwrap_or(0);
    if relax > 1000 {
        return c.err("nodes.relax", format!("{relax} sweeps; the fill settles within tens (seed 002 uses about 10); at most 1000"));
    }
    let refine = s.refine.as_ref().map(|r| refinement(c, r, domain, kind, spacing)).transpose()?;
    Ok(FillParams { spacing, refine, adapted: None, kind, seed: s.seed.unwrap_or(0), relax_iterations: relax })
}

/// Largest growth rate of a refinement: the spacing of neighbouring nodes then
/// differs by less than a factor 1.5.
pub const MAX_GROWTH: f64 = 0.5;

/// `[nodes.refine]`: spacing at the targets, growth rate, targets.
fn refinement(c: &Ctx, r: &RefineSpec, domain: &Domain, kind: FillKind, far: f64) -> Result<Refinement, ProblemError> {
    if kind != FillKind::Scattered {
        return c.err("nodes.refine", "a graded spacing needs fill = \"scattered\" (a grid has one spacing)");
    }
    let spacing =
        c.positive("nodes.refine.spacing", c.need("nodes.refine.spacing", r.spacing, "the spacing at the refinement targets (m)")?)?;
    if spacing >= far {
        return c.err("nodes.refine.spacing", format!("{spacing} is not below nodes.spacing = {far}, the spacing far from the targets"));
    }
    let growth = c.need("nodes.refine.growth", r.growth, "the spacing gained per unit of distance (e.g. 0.2)")?;
    if !(growth > 0.0 && growth <= MAX_GROWTH) {
        return c.err("nodes.refine.growth", format!("must lie in (0, {MAX_GROWTH}] so that the density has no jumps, got {growth}"));
    }
    let known = || domain.parts.iter().map(|p| format!("\"{p}\"")).collect::<Vec<_>>().join(", ");
    let mut parts = Vec::new();
    for (k, name) in r.near.iter().flatten().enumerate() {
        match domain.parts.iter().position(|p| p == name) {
            Some(i) => parts.push(i),
            None => return c.err(format!("nodes.refine.near[{k}]"), format!("\"{name}\" is not a boundary part (known: {})", known())),
        }
    }
    let points: Vec<[f64; 2]> = r.points.iter().flatten().map(|p| p.0).collect();
    for p in &points {
        c.finite("nodes.refine.points", p)?;
    }
    if parts.is_empty() && points.is_empty() {
        return c.err("nodes.refine", "name what to refine towards: near = [\"part\", ...] and/or points = [[x, y], ...]");
    }
    Ok(Refinement { spacing, growth, parts, points })
}

/// Highest polynomial degree of a basis (the local systems grow as `(p+1)(p+2)/2`).
pub const MAX_DEGREE: u32 = 8;

/// The polynomial degree of `[approximation]` for a basis of `kind`.
fn degree(c: &Ctx, s: &ApproximationSpec, kind: BasisKind) -> Result<u32, ProblemError> {
    let d = s.degree.unwrap_or(2);
    let max = if kind.is_rbf_fd() { MAX_DEGREE } else { 6 };
    if !(2..=max).contains(&d) {
        return c.err(
            "approximation.degree",
            format!(
                "must be 2..{max} for basis \"{}\" (the Navier rows need second derivatives, which degree 1 cannot reproduce), got {d}",
                kind.name()
            ),
        );
    }
    Ok(d)
}

/// Accepted shape parameters of the Gaussian, MQ and IMQ kernels, in local spacings.
pub const SHAPE_RANGE: (f64, f64) = (1.0, 20.0);

/// The radial function of an RBF-FD basis of `kind` with augmentation `degree`.
fn radial(c: &Ctx, s: &ApproximationSpec, kind: BasisKind, degree: u32) -> Result<Radial, ProblemError> {
    if kind == BasisKind::Phs {
        let order = s.exponent.unwrap_or(3);
        if order < 3 || order.is_multiple_of(2) {
            return c.err(
                "approximation.exponent",
                format!("the PHS exponent must be odd and at least 3 (r^1 has no second derivative at 0), got {order}"),
            );
        }
        // r^beta is conditionally positive definite of order (beta + 1) / 2: the
        // monomials must include degree (beta - 1) / 2 for the local system to be solvable.
        if degree < (order - 1) / 2 {
            return c.err(
                "approximation.exponent",
                format!("r^{order} needs monomials up to degree {} at least; raise degree or lower exponent", (order - 1) / 2),
            );
        }
        return Ok(Radial::Phs { order });
    }
    let shape = c.need("approximation.shape", s.shape, "an RBF basis needs shape (in units of the node spacing)")?;
    // Below the range the radial functions become spikes, above it flat (the radial
    // part is lost to round-off), and the errors were O(1) (docs/methods/rbf-fd.md;
    // docs/notebook/round2-time-against-accuracy-basis-spacing.md, "From the code comments").
    if !(SHAPE_RANGE.0..=SHAPE_RANGE.1).contains(&shape) {
        return c.err(
            "approximation.shape",
            format!(
                "{shape} local spacings is outside [{}, {}], where the measured errors of gaussian, mq and imq stencils were O(1); use a shape in that range or basis = \"phs\" (no shape parameter)",
                SHAPE_RANGE.0, SHAPE_RANGE.1
            ),
        );
    }
    Ok(match kind {
        BasisKind::Gaussian => Radial::Gaussian { shape },
        BasisKind::Mq => Radial::Mq { shape },
        BasisKind::Imq => Radial::Imq { shape },
        BasisKind::Phs | BasisKind::Monomials | BasisKind::Tensor => unreachable!("PHS returns above; least squares has no radial function"),
    })
}

/// The basis of `[approximation]`: its kind with its degree, exponent or shape parameter.
fn basis(c: &Ctx, s: &ApproximationSpec) -> Result<Basis, ProblemError> {
    let kind: BasisKind = c.choose("approximation.basis", s.basis.as_deref())?;
    let degree = degree(c, s, kind)?;
    if s.shape.is_some() && !kind.has_shape() {
        return c.err("approximation.shape", format!("basis \"{}\" takes no shape parameter (only gaussian, mq and imq do)", kind.name()));
    }
    if s.exponent.is_some() && kind != BasisKind::Phs {
        return c.err("approximation.exponent", format!("only basis \"phs\" takes an exponent, not \"{}\"", kind.name()));
    }
    Ok(match kind {
        BasisKind::Monomials => Basis::Monomials { degree },
        BasisKind::Tensor => Basis::Tensor { degree },
        _ => Basis::RbfFd { radial: radial(c, s, kind, degree)?, degree },
    })
}

/// The weight of a least-squares basis (RBF-FD interpolates on its stencil: none).
fn weight(c: &Ctx, s: &ApproximationSpec, basis: &Basis) -> Result<Weight, ProblemError> {
    if let Basis::RbfFd { .. } = basis {
        for (field, given) in [("weight", s.weight.is_some()), ("sigma", s.sigma.is_some())] {
            if given {
                return c.err(
                    format!("approximation.{field}"),
                    "RBF-FD interpolates on its stencil and takes no least-squares weight; remove it",
                );
            }
        }
        return Ok(Weight::None);
    }
    Ok(match c.choose("approximation.weight", s.weight.as_deref())? {
        WeightKind::None => {
            if s.sigma.is_some() {
                return c.err("approximation.sigma", format!("weight = \"{}\" takes no sigma", WeightKind::None.name()));
            }
            Weight::None
        }
        WeightKind::Gaussian => Weight::Gaussian { sigma: c.positive("approximation.sigma", s.sigma.unwrap_or(1.0))? },
    })
}

/// `[approximation]`: basis, weight, support size, ghost nodes.
pub(super) fn approximation(c: &Ctx, s: &ApproximationSpec, fill: FillKind, dynamic: bool) -> Result<Approximation, ProblemError> {
    let basis = basis(c, s)?;
    let weight = weight(c, s, &basis)?;
    let m = basis.size();
    let support = match (s.support, basis) {
        (Some(n), _) => n,
        (None, Basis::RbfFd { .. }) => default_rbf_fd_support(m, fill),
        (None, _) => default_support(m, fill),
    };
    if support < 2 {
        return c.err("approximation.support", format!("must be at least 2, got {support}"));
    }
    if support < m {
        return c.err(
            "approximation.support",
            format!(
                "{support} nodes cannot determine the {m} coefficients of the basis ({}); use support >= {m} (about {} recommended)",
                basis.describe(),
                2 * m
            ),
        );
    }
    // Ghost nodes gave growing modes in explicit MLSM dynamics (docs/limits.md):
    // off by default for time-dependent scenes.
    let ghost_nodes = s.ghost_nodes.unwrap_or(DEFAULT_GHOST_NODES && !dynamic);
    Ok(Approximation { basis, weight, support, ghost_nodes })
}

/// About how many nodes a fill holds: `area / h^2` times the packing of the fill, or
/// for a graded spacing the integral of `1 / h(x)^2` ([`crate::domain::SpacingField::node_estimate`]).
///
/// A refinement towards boundary parts whose samples (every `h_min / 4` along them)
/// would number more than [`SAMPLED_REFINEMENT_LIMIT`] is estimated without them, by
/// the strip along the parts ([`strip_nodes`]): the count comes before any sampling at
/// the refinement's spacing, so that a tiny `[nodes.refine] spacing` is refused in
/// time proportional to the scene, not to the nodes it asks for.
pub fn expected_nodes(domain: &Domain, fill: &FillParams, area: f64) -> f64 {
    if fill.is_uniform() {
        return area / fill.spacing.powi(2) * packing(fill.kind);
    }
    if let (Some(r), None) = (&fill.refine, &fill.adapted) {
        if !r.parts.is_empty() {
            let length = crate::domain::boundary::parts_length(domain, &r.parts, fill.spacing);
            if length / (r.spacing / 4.0) > SAMPLED_REFINEMENT_LIMIT {
                return strip_nodes(length, r.spacing, r.growth, fill.spacing, area) * packing(fill.kind);
            }
        }
    }
    fill.field(domain).node_estimate(domain, 2.0 * MAX_NODES) * packing(fill.kind)
}

/// Most samples of refined boundary parts that [`expected_nodes`] takes to integrate
/// the graded spacing (a fraction of a second); above, [`strip_nodes`].
const SAMPLED_REFINEMENT_LIMIT: f64 = 1e5;

/// Nodes of a spacing graded from `h0` on boundary parts of total `length` with
/// `growth` g up to `far` = H, in a solid of `area`: the strip on the solid's side of
/// straight parts, `length int_0^((H - h0)/g) dt / (h0 + g t)^2 = length (1/h0 - 1/H) / g`,
/// plus the rest at H, `area / H^2` (curvature and corners change it by a factor of
/// order one; a refusal needs orders of magnitude).
pub fn strip_nodes(length: f64, h0: f64, growth: f64, far: f64, area: f64) -> f64 {
    let h0 = h0.min(far);
    length * (1.0 / h0 - 1.0 / far) / growth.max(f64::MIN_POSITIVE) + area / far.powi(2)
}

/// The fill must give at least two supports' worth of nodes and at most [`MAX_NODES`].
pub(super) fn check_node_count(
    c: &Ctx,
    domain: &Domain,
    fill: &FillParams,
    approximation: &Approximation,
    area: f64,
) -> Result<(), ProblemError> {
    let expected_nodes = expected_nodes(domain, fill, area);
    if let Some(reason) = super::too_few_nodes(fill.spacing, expected_nodes, approximation.support) {
        return Err(ProblemError { kind: crate::scene::problem::ProblemErrorKind::TooFewNodes, ..c.error("nodes.spacing", reason) });
    }
    if expected_nodes > MAX_NODES {
        return match &fill.refine {
            Some(r) if r.spacing < fill.spacing => c.err(
                "nodes.refine.spacing",
                format!(
                    "spacing {} graded from {:e} at the refinement targets (growth {}) gives about {expected_nodes:.1e} nodes \
                     (over 5e7); this machine cannot hold the system",
                    fill.spacing, r.spacing, r.growth
                ),
            ),
            _ => c.err(
                "nodes.spacing",
                format!("spacing {} gives about {expected_nodes:.1e} nodes (over 5e7); this machine cannot hold the system", fill.spacing),
            ),
        };
    }
    Ok(())
}

/// `approximation.pressure_stabilisation`: `tau` in [0, [`MAX_PRESSURE_STABILISATION`]]
/// (0 turns the stabilisation off), default [`PRESSURE_STABILISATION`]
/// (`navier::formulation`).
pub(super) fn pressure_stabilisation(c: &Ctx, s: &ApproximationSpec) -> Result<f64, ProblemError> {
    match s.pressure_stabilisation {
        None => Ok(PRESSURE_STABILISATION),
        Some(tau) if (0.0..=MAX_PRESSURE_STABILISATION).contains(&tau) => Ok(tau),
        Some(tau) => c.err(
            "approximation.pressure_stabilisation",
            format!(
                "{tau} must lie in [0, {MAX_PRESSURE_STABILISATION}] (0 turns the stabilisation off): above it the pressure Laplacian \
                 drowns the continuity equation (Lame at nu = 0.5, tau = 10: e_inf(u) 9.4e-3 against 8.1e-5 at 0.1)"
            ),
        ),
    }
}

/// `approximation.formulation`, resolved against the material and the run:
/// explicit dynamics runs the displacement form (`auto` included); an incompressible
/// solid (`nu = 1/2`, plane strain) needs the displacement-pressure form.
pub(super) fn formulation(c: &Ctx, s: &ApproximationSpec, material: &Material, dynamic: bool) -> Result<Formulation, ProblemError> {
    let chosen: Formulation = c.choose("approximation.formulation", s.formulation.as_deref())?;
    let formulation = match (chosen, dynamic) {
        (Formulation::Auto, true) => Formulation::Displacement,
        (Formulation::DisplacementPressure, true) => {
            return c.err(
                "approximation.formulation",
                "explicit dynamics runs the displacement form only; remove formulation or set it to \"displacement\"",
            )
        }
        (f, _) => f,
    };
    if material.is_incompressible() && formulation.unknowns(material) == Unknowns::Displacement {
        let (field, why) = if dynamic {
            ("material.nu", "nu = 0.5 (incompressible) has no displacement form and explicit dynamics has no other; use nu < 0.5")
        } else {
            (
                "approximation.formulation",
                "nu = 0.5 (incompressible) has infinite lambda: use formulation = \"displacement-pressure\" (or \"auto\")",
            )
        };
        return c.err(field, why);
    }
    Ok(formulation)
}
