//! `[peridynamics]`: horizon, ratio m, kernel, quadrature rule, surface correction,
//! solver and force law, with the limits shared by `compare` and `--horizon`
//! ([`check_peridynamics`]).

use super::{Ctx, MAX_NODES};
use crate::scene::choice::Choice;
use crate::domain::Domain;
use crate::physics::elasticity::conditions::ConditionKind;
use crate::physics::elasticity::material::{Material, PlaneModel};
use crate::linalg::{SolverKind, SolverParams};
use crate::models::peridynamics::{BondForce, EdgeTreatment, Kernel, KernelKind, PdParams, PointSet, Quadrature, Solid, SurfaceCorrection};
use crate::models::peridynamics::fracture::{CriticalStretch, Fracture, MAX_CRACKS};
use crate::scene::problem::spec::{BoundarySpec, FractureSpec, PeridynamicsSpec};
use crate::scene::problem::ProblemError;

/// Largest ratio `m = delta / h` accepted (bonds per node grow like `pi m^2`).
pub const MAX_HORIZON_RATIO: f64 = 12.0;

/// Limits on the peridynamic numbers shared by the scene table and `compare`:
/// `(field, reason)` of the first violated one.
pub fn check_peridynamics(p: &PdParams, domain: &Domain) -> Result<(), (String, String)> {
    let fail = |f: &str, r: String| Err((f.to_string(), r));
    if !(p.horizon.is_finite() && p.horizon > 0.0) {
        return fail("horizon", format!("must be a positive finite number, got {}", p.horizon));
    }
    if !(p.ratio.is_finite() && p.ratio >= 1.0) {
        return fail(
            "m",
            format!(
                "m = delta / h = {} makes the horizon smaller than the node spacing: no node would have a bond; use m >= 1 (3 is usual)",
                p.ratio
            ),
        );
    }
    if p.ratio > MAX_HORIZON_RATIO {
        return fail(
            "m",
            format!(
                "m = {} gives about {:.0} bonds per node; at most {MAX_HORIZON_RATIO}",
                p.ratio,
                std::f64::consts::PI * p.ratio * p.ratio
            ),
        );
    }
    let (lo, hi) = domain.bounding_box();
    let extent = (hi[0] - lo[0]).min(hi[1] - lo[1]);
    if p.horizon > extent / 2.0 {
        return fail(
            "horizon",
            format!(
                "horizon {} is larger than {:.4e}, half the solid's smallest extent ({extent:.4e}): no node would have a complete family; use a smaller horizon",
                p.horizon,
                extent / 2.0
            ),
        );
    }
    let nodes = domain.area_estimate(400) / p.spacing().powi(2) * p.nodes_per_cell() as f64;
    if nodes > MAX_NODES {
        return fail("horizon", format!("horizon {} with m = {} gives about {nodes:.1e} nodes (over {MAX_NODES:e})", p.horizon, p.ratio));
    }
    Ok(())
}

/// Largest `|nu - nu_pd|` that is taken as the value bond-based peridynamics
/// represents (`nu_pd` = 1/4 in plane strain, 1/3 in plane stress) and snapped to it:
/// `0.333333` is 1/3 written to six digits (off by 3.3e-7), while a deliberate other
/// ratio such as 0.33 is 3.3e-3 away and is refused.
pub const POISSON_SNAP: f64 = 1e-5;

/// Snap a Poisson ratio within [`POISSON_SNAP`] of the peridynamic value to it (for
/// both models: one solid), with a note saying so.
pub(super) fn snap_poisson(material: &mut Material) -> Option<String> {
    let (target, name, plane) = match material.plane {
        PlaneModel::Strain => (0.25, "1/4", "plane strain"),
        PlaneModel::Stress => (1.0 / 3.0, "1/3", "plane stress"),
    };
    let nu = material.elastic.poisson;
    if nu == target || (nu - target).abs() > POISSON_SNAP {
        return None;
    }
    material.elastic.poisson = target;
    Some(format!("material.nu = {nu} taken as {name} (within {POISSON_SNAP:e}), the value bond-based peridynamics represents in {plane}"))
}

/// The solid of `peridynamics.solid` for `material`: `auto` is bond-based where bond-based
/// peridynamics represents the material and the linear peridynamic solid elsewhere; an
/// explicit `bond-based` with another `nu` is refused.
fn solid(c: &Ctx, s: &PeridynamicsSpec, material: &Material) -> Result<Solid, ProblemError> {
    let representable = crate::models::peridynamics::kernel::representable(material);
    let chosen: Solid = c.choose("peridynamics.solid", s.solid.as_deref())?;
    match chosen {
        Solid::Auto if representable => Ok(Solid::BondBased),
        Solid::Auto | Solid::Linear => Ok(Solid::Linear),
        Solid::BondBased if representable => Ok(Solid::BondBased),
        Solid::BondBased => {
            let (need, plane) = match material.plane {
                PlaneModel::Strain => ("1/4", "plane strain"),
                PlaneModel::Stress => ("1/3", "plane stress"),
            };
            c.err(
                "peridynamics.solid",
                format!(
                    "bond-based peridynamics represents only in-plane lambda = mu, that is nu = {need} in {plane}; got nu = {} \
                     (use solid = \"lps\", the linear peridynamic solid, or leave solid out: \"auto\" picks it)",
                    material.elastic.poisson
                ),
            )
        }
    }
}

/// Why the peridynamic model cannot run on `material`, if it cannot: plane strain
/// nu = 1/2 makes lambda infinite, and the solid has no pressure unknown. Checked when
/// the peridynamic model runs (the scene's model, `--model peridynamics`, `compare`),
/// not for a Navier scene that only carries the table.
pub fn material_refusal(material: &Material) -> Option<String> {
    (!crate::models::peridynamics::dilatation::coefficient(material).is_finite()).then(|| {
        format!(
            "nu = {} in plane strain makes lambda infinite: the peridynamic solid has no pressure unknown (the Navier model \
             solves it in u-p form: --model navier); use nu < 0.5 (below 0.495 without a warning)",
            material.elastic.poisson
        )
    })
}

/// Whether `[peridynamics]` asks for the linear peridynamic solid by name (then the
/// Poisson ratio is taken as given, not snapped to the bond-based value).
pub(super) fn names_lps(s: &PeridynamicsSpec) -> bool {
    s.solid.as_deref() == Some(Solid::Linear.name())
}

/// `kernel` and its `alpha`.
fn kernel(c: &Ctx, s: &PeridynamicsSpec) -> Result<Kernel, ProblemError> {
    Ok(match c.choose("peridynamics.kernel", s.kernel.as_deref())? {
        KernelKind::Plain => {
            if s.alpha.is_some() {
                return c.err("peridynamics.alpha", "only the regularised kernel takes alpha");
            }
            Kernel::Plain
        }
        KernelKind::Regularised => {
            let alpha = s.alpha.unwrap_or(-3.0);
            if !(alpha.is_finite() && alpha > -4.0 && alpha <= 10.0) {
                return c
                    .err("peridynamics.alpha", format!("must lie in (-4, 10] (the operator is unbounded for alpha <= -4), got {alpha}"));
            }
            Kernel::Regularised { alpha }
        }
    })
}

/// `[peridynamics]`.
pub(super) fn peridynamics(
    c: &Ctx,
    s: &PeridynamicsSpec,
    domain: &Domain,
    material: &Material,
    specs: &[BoundarySpec],
    dynamic: bool,
) -> Result<PdParams, ProblemError> {
    let solid = solid(c, s, material)?;
    let horizon = c.need("peridynamics.horizon", s.horizon, "the horizon delta (m)")?;
    let kernel = kernel(c, s)?;
    let quadrature: Quadrature = c.choose("peridynamics.quadrature", s.quadrature.as_deref())?;
    let correction: SurfaceCorrection = c.choose("peridynamics.correction", s.correction.as_deref())?;
    let solver = match &s.solver {
        // The PD stiffness is an M-matrix-like, diagonally dominant block Laplacian, on
        // which the multigrid's iterations stay flat with the size: GMRES + AMG is far
        // faster than BiCGSTAB + ILU(0), the default before, and than sparse LU
        // (docs/notebook/2026-11-26-peridynamics-1e6-gmres-amg.md).
        None => SolverParams { kind: SolverKind::default_gmres(), equilibrate: true },
        Some(spec) if spec.multigrid.is_some() => {
            return c
                .err("peridynamics.solver.multigrid", "the low-order operator is an MLSM discretisation; the peridynamic solve has none");
        }
        Some(spec) => super::solver::solver(c, spec).map_err(|mut e| {
            e.field = e.field.replacen("solver", "peridynamics.solver", 1);
            e
        })?,
    };
    let force: BondForce = c.choose("peridynamics.force", s.force.as_deref())?;
    if force == BondForce::BondStretch && !dynamic {
        return c.err("peridynamics.force", format!("the static solve uses the linear law; \"{}\" needs a [dynamics] table", force.name()));
    }
    if force == BondForce::BondStretch && solid == Solid::Linear {
        return c.err(
            "peridynamics.force",
            format!("\"{}\" is a bond-based law; the linear peridynamic solid (nu = {}) runs the linear law", force.name(), material.elastic.poisson),
        );
    }
    let boundary = match (s.boundary.as_deref(), dynamic) {
        (None, true) => EdgeTreatment::Surface,
        (given, _) => c.choose("peridynamics.boundary", given)?,
    };
    for (k, b) in specs.iter().enumerate() {
        if b.kind == ConditionKind::Mixed.name() && boundary == EdgeTreatment::Surface {
            return c.err(
                format!("boundary[{k}].kind"),
                "mixed (per-component) conditions have no volume constraint on the nonlocal surface; they need \
                 peridynamics.boundary = \"fictitious\" (static runs)",
            );
        }
    }
    if boundary == EdgeTreatment::Fictitious && dynamic {
        return c.err(
            "peridynamics.boundary",
            "the fictitious nodes' extension is not the variation of an energy, so explicit dynamics keeps the nonlocal surface; \
             use boundary = \"surface\" (the default with [dynamics])",
        );
    }
    let fracture = s.fracture.as_ref().map(|f| fracture(c, f, solid, dynamic)).transpose()?;
    let perturbation = s.perturbation.unwrap_or(0.0);
    if !(0.0..=1.0).contains(&perturbation) {
        return c.err("peridynamics.perturbation", format!("must be between 0 and 1 (a share of the cell size h), got {perturbation}"));
    }
    if perturbation > 0.0 && !(matches!(quadrature, Quadrature::FullArea | Quadrature::Gauss2x2) && correction == SurfaceCorrection::None) {
        return c.err(
            "peridynamics.perturbation",
            "a perturbed lattice is built for the cell-interior rules full-area and gauss2x2 without a surface correction (the \
             seed's \"random\" rows): the other rules and corrections count on the lattice's families",
        );
    }
    let points: PointSet = c.choose("peridynamics.points", s.points.as_deref())?;
    let cut_cells = s.cut_cells.unwrap_or(false);
    if points == PointSet::Delaunay {
        triangulated_limits(c, quadrature, correction, solid, boundary, perturbation, cut_cells)?;
    }
    if cut_cells && quadrature.shares_points() {
        return c.err(
            "peridynamics.cut_cells",
            format!("\"{}\" shares its points between cells, whose cut areas are not the points' own; use a rule with points inside the cells", quadrature.name()),
        );
    }
    let params = PdParams {
        horizon,
        ratio: s.m.unwrap_or(3.0),
        kernel,
        quadrature,
        correction,
        solver,
        force,
        solid,
        boundary,
        fracture,
        perturbation,
        points,
        cut_cells,
    };
    check_peridynamics(&params, domain).map_err(|(f, r)| c.error(format!("peridynamics.{f}"), r))?;
    Ok(params)
}

/// What a Delaunay point set (`peridynamics.points = "delaunay"`) runs with: a triangle
/// rule, the nonlocal surface at free and traction edges, bond-based, no volume
/// correction, no perturbation, no cut cells; each refusal says why.
fn triangulated_limits(
    c: &Ctx,
    quadrature: Quadrature,
    correction: SurfaceCorrection,
    solid: Solid,
    boundary: EdgeTreatment,
    perturbation: f64,
    cut_cells: bool,
) -> Result<(), ProblemError> {
    let field = "peridynamics.points";
    if quadrature.triangle_rule().is_none() {
        return c.err(
            field,
            format!(
                "a Delaunay point set is integrated by a triangle rule; \"{}\" is a rule of square cells (use one of \"triangle-vertex\", \"triangle-edge\", \"triangle-p3\", \"triangle-p2\", \"triangle-p1\", \"triangle-hillion\")",
                quadrature.name()
            ),
        );
    }
    let reason = if boundary == EdgeTreatment::Fictitious {
        Some("its traction and free edges keep the nonlocal surface: fictitious nodes are laid on the lattice; set peridynamics.boundary = \"surface\"")
    } else if solid == Solid::Linear {
        Some("the linear peridynamic solid tells complete families by the lattice's bond count; a triangulation has none (bond-based only)")
    } else if correction == SurfaceCorrection::Volume {
        Some("the volume correction divides by a lattice point's full family volume; a triangulation has none")
    } else if perturbation > 0.0 {
        Some("perturbation moves lattice points; a Delaunay set is irregular already")
    } else if cut_cells {
        Some("its triangles follow the boundary: there are no cut cells to weigh")
    } else {
        None
    };
    match reason {
        Some(r) => c.err(field, format!("\"delaunay\" runs without this: {r}")),
        None => Ok(()),
    }
}

/// `[peridynamics.fracture]`: one of `critical_stretch` and `energy_release_rate`
/// (positive; dynamic runs of the bond-based model only) or neither (pre-cracks only),
/// and up to [`MAX_CRACKS`] pre-cracks of positive length.
fn fracture(c: &Ctx, f: &FractureSpec, solid: Solid, dynamic: bool) -> Result<Fracture, ProblemError> {
    let positive = |field: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            c.err(format!("peridynamics.fracture.{field}"), format!("must be a positive finite number, got {v}"))
        }
    };
    let breaking = match (f.critical_stretch, f.energy_release_rate) {
        (Some(_), Some(_)) => {
            return c.err(
                "peridynamics.fracture",
                "give critical_stretch or energy_release_rate (from which the critical stretch follows), not both",
            )
        }
        (Some(s0), None) => Some(CriticalStretch::Given(positive("critical_stretch", s0)?)),
        (None, Some(g0)) => Some(CriticalStretch::EnergyReleaseRate(positive("energy_release_rate", g0)?)),
        (None, None) => None,
    };
    if breaking.is_some() && !dynamic {
        return c.err(
            "peridynamics.fracture",
            "bonds break along a load history; a static run solves the linear system once (no quasi-static loop is built), \
             so breaking needs a [dynamics] table (pre-cracks alone, `cracks`, run statically)",
        );
    }
    if solid == Solid::Linear {
        return c.err(
            "peridynamics.fracture",
            "fracture is built for the bond-based model only: the linear peridynamic solid's dilatation would need its weights \
             refitted around every broken bond; use a material with nu = 1/4 (plane strain) or 1/3 (plane stress)",
        );
    }
    let cracks = f.cracks.as_deref().unwrap_or(&[]);
    if cracks.len() > MAX_CRACKS {
        return c.err("peridynamics.fracture.cracks", format!("{} pre-cracks given; at most {MAX_CRACKS}", cracks.len()));
    }
    for (k, seg) in cracks.iter().enumerate() {
        if seg.iter().any(|v| !v.is_finite()) || (seg[2] - seg[0]).hypot(seg[3] - seg[1]) == 0.0 {
            return c.err(
                format!("peridynamics.fracture.cracks[{k}]"),
                format!("a pre-crack is a segment [x0, y0, x1, y1] of finite, distinct end points, got {seg:?}"),
            );
        }
    }
    Ok(Fracture::new(breaking, cracks).expect("at most MAX_CRACKS, checked above"))
}
