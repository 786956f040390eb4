//! Scene text -> [`SceneSpec`] (syntax, types, unknown keys) -> [`Problem`]
//! (physics and consistency). Every error names the file, the field and the reason.

use super::spec::*;
use super::{Model, Problem, ProblemError};
use crate::case::{Case, Outputs};
use crate::domain::{CsgOp, Domain, FillKind, FillParams, Primitive, Region};
use crate::dynamics::{Affine, DynamicsParams, Integrator};
use crate::elasticity::conditions::{BoundaryCondition, ComponentCondition, Value};
use crate::elasticity::material::{Material, PlaneModel, YoungPoisson};
use crate::exact::ExactKind;
use crate::linalg::{Preconditioner, SolverKind, SolverParams};
use crate::mlsm::{Approximation, Basis, RbfKind, Weight};
use crate::navier::NavierParams;
use crate::peridynamics::{BondForce, Kernel, PdParams, Quadrature, SurfaceCorrection};
use std::path::Path;

/// Default support size for a basis of `m` functions.
///
/// Scattered fills: `2 m` (12 for degree-2 monomials), a least-squares fit
/// over-determined by a factor 2. Grid fills: the smallest complete ring of lattice
/// neighbours (9, 13, 21, 25, 29, 37, 45, 49, ...) with at least `1.4 m` nodes, because
/// the `n` nearest of a lattice node are ambiguous when the n-th distance is shared
/// by several nodes; an arbitrary pick makes stencils asymmetric (measured on
/// manufactured_traction.toml: order 1.3-1.6 with 12 nodes, 1.9-2.0 with 9).
pub fn default_support(m: usize, fill: FillKind) -> usize {
    match fill {
        FillKind::Scattered => 2 * m,
        FillKind::Grid => {
            // Count lattice points within radius^2 = r2 for increasing r2.
            let mut r2 = 1;
            loop {
                let k = (r2 as f64).sqrt() as i64;
                let count = (-k..=k).flat_map(|i| (-k..=k).map(move |j| i * i + j * j)).filter(|&d| d <= r2).count();
                if count as f64 >= 1.4 * m as f64 {
                    return count;
                }
                r2 += 1;
            }
        }
    }
}

/// Largest node count a run may ask for (a sparse LU of 1e8 unknowns does not fit in memory).
pub const MAX_NODES: f64 = 5e7;

/// Ghost nodes outside traction boundaries unless the scene says otherwise (static
/// scenes; time-dependent ones default to none).
pub const DEFAULT_GHOST_NODES: bool = true;

/// Nodes per unit area of a fill at spacing `h`, relative to `1/h^2`: used to turn
/// `nodes.count` into a spacing (the scattered fill packs about 1.1 nodes per h^2).
pub(crate) fn packing(kind: FillKind) -> f64 {
    match kind {
        FillKind::Grid => 1.0,
        FillKind::Scattered => 1.1,
    }
}

/// TOML syntax, types and unknown keys; the message carries line, column and key path.
pub fn parse(text: &str, path: &Path) -> Result<SceneSpec, ProblemError> {
    let err = |field: String, reason: String| ProblemError { file: path.to_path_buf(), field, reason };
    let de = toml::Deserializer::parse(text).map_err(|e| err("(syntax)".into(), located(text, &e)))?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = e.path().to_string();
        let inner = e.into_inner();
        err(if field == "." { "(top level)".into() } else { field }, located(text, &inner))
    })
}

fn located(text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim().to_string();
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

struct Ctx<'a> {
    path: &'a Path,
}

impl Ctx<'_> {
    fn err<T>(&self, field: impl Into<String>, reason: impl Into<String>) -> Result<T, ProblemError> {
        Err(ProblemError { file: self.path.to_path_buf(), field: field.into(), reason: reason.into() })
    }

    fn positive(&self, field: &str, v: f64) -> Result<f64, ProblemError> {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            self.err(field, format!("must be a positive finite number, got {v}"))
        }
    }

    fn finite(&self, field: &str, v: &[f64]) -> Result<(), ProblemError> {
        match v.iter().find(|x| !x.is_finite()) {
            Some(x) => self.err(field, format!("must be finite, got {x}")),
            None => Ok(()),
        }
    }

    fn need<T>(&self, field: &str, v: Option<T>, what: &str) -> Result<T, ProblemError> {
        match v {
            Some(x) => Ok(x),
            None => self.err(field, format!("missing: {what}")),
        }
    }

    fn word<T: Copy>(&self, field: &str, got: &str, options: &[(&str, T)]) -> Result<T, ProblemError> {
        match options.iter().find(|(k, _)| *k == got) {
            Some((_, v)) => Ok(*v),
            None => {
                let known: Vec<_> = options.iter().map(|(k, _)| format!("\"{k}\"")).collect();
                self.err(field, format!("unknown value \"{got}\" (expected one of {})", known.join(", ")))
            }
        }
    }
}

/// Semantic validation: physics, geometry, consistency of names and options.
pub fn validate(spec: SceneSpec, path: &Path) -> Result<Problem, ProblemError> {
    let c = Ctx { path };
    let name = match &spec.name {
        Some(n) if n.is_empty() || n.contains(['/', '\\']) || n == "." || n == ".." => {
            return c.err("name", format!("\"{n}\" cannot name an output folder (no slashes, not empty)"))
        }
        Some(n) => n.clone(),
        None => path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into()),
    };
    let domain = domain(&c, &spec.domain)?;
    let (lo, hi) = domain.bounding_box();
    let area = domain.area_estimate(400);
    if !(hi[0] > lo[0] && hi[1] > lo[1]) || area <= 0.0 {
        return c.err("domain.region", "the regions leave no material (empty intersection or everything subtracted)");
    }
    let fill = nodes(&c, &spec.nodes, &domain, area)?;
    let approximation = approximation(&c, &spec.approximation, fill.kind, spec.dynamics.is_some())?;
    let expected_nodes = area / fill.spacing.powi(2) * packing(fill.kind);
    if expected_nodes < 2.0 * approximation.support as f64 {
        return c.err(
            "nodes.spacing",
            format!(
                "spacing {} gives about {expected_nodes:.0} nodes, too few for supports of {} nodes; use a smaller spacing",
                fill.spacing, approximation.support
            ),
        );
    }
    if expected_nodes > MAX_NODES {
        return c.err(
            "nodes.spacing",
            format!("spacing {} gives about {expected_nodes:.1e} nodes (over 5e7); this machine cannot hold the system", fill.spacing),
        );
    }
    let material = material(&c, &spec.material)?;
    let exact = match &spec.exact {
        Some(e) => {
            let kind = exact(&c, e)?;
            if let Err(pe) = crate::exact::from_kind(&kind, material) {
                return c.err(format!("exact.{}", pe.parameter), pe.to_string());
            }
            Some(kind)
        }
        None => None,
    };
    let exact_word = |field: &str, w: &str| -> Result<Value, ProblemError> {
        if w != "exact" {
            return c.err(field, format!("expected [x, y] or \"exact\", got \"{w}\""));
        }
        if exact.is_none() {
            return c.err(field, "\"exact\" needs an [exact] table naming the solution");
        }
        Ok(Value::Exact)
    };
    let body_force = match &spec.body_force {
        None => Value::Constant([0.0, 0.0]),
        Some(VectorOrExact::Vector(v)) => {
            c.finite("body_force", v)?;
            Value::Constant(*v)
        }
        Some(VectorOrExact::Word(w)) => exact_word("body_force", w)?,
    };
    if matches!(exact, Some(ExactKind::Manufactured)) && body_force != Value::Exact {
        return c.err("body_force", "the manufactured solution needs its own body force: set body_force = \"exact\"");
    }
    let mut present = vec![false; domain.parts.len()];
    for b in crate::domain::boundary::discretise_boundary(&domain, fill.spacing) {
        for (part, _) in b.touches {
            present[part] = true;
        }
    }
    let dynamics = match &spec.dynamics {
        Some(d) => Some(dynamics(&c, d)?),
        None => None,
    };
    let conditions = conditions(&c, &spec.boundary, &domain, &present, &exact_word, dynamics.is_some())?;
    let solver = solver(&c, &spec.solver)?;
    let outputs = outputs(&c, &spec.output, exact.is_some())?;
    let peridynamics = match &spec.peridynamics {
        Some(pd) => Some(peridynamics(&c, pd, &domain, &material, &conditions, &spec.boundary, spec.dynamics.is_some())?),
        None => None,
    };
    let model = match spec.model.as_deref() {
        None => Model::Navier,
        Some(m) => c.word("model", m, &[("navier", Model::Navier), ("peridynamics", Model::Peridynamics)])?,
    };
    if model == Model::Peridynamics && peridynamics.is_none() {
        return c.err("model", "model = \"peridynamics\" needs a [peridynamics] table (horizon, quadrature, ...)");
    }
    Ok(Problem {
        name,
        source: path.to_path_buf(),
        case: Case { domain, material, body_force, conditions, exact, outputs, dynamics },
        navier: NavierParams { fill, approximation, solver },
        peridynamics,
        model,
    })
}

fn dynamics(c: &Ctx, s: &DynamicsSpec) -> Result<DynamicsParams, ProblemError> {
    let density = c.positive("dynamics.density", c.need("dynamics.density", s.density, "the mass density rho (kg/m^3)")?)?;
    let end_time = c.positive("dynamics.end_time", c.need("dynamics.end_time", s.end_time, "the final time (s)")?)?;
    let integrator = c.word("dynamics.integrator", s.integrator.as_deref().unwrap_or("verlet"), &Integrator::ALL)?;
    let time_step = match s.time_step {
        Some(dt) => Some(c.positive("dynamics.time_step", dt)?),
        None => None,
    };
    if let Some(dt) = time_step {
        if dt > end_time {
            return c.err("dynamics.time_step", format!("{dt} is longer than end_time = {end_time}"));
        }
        if s.safety.is_some() {
            return c.err("dynamics.safety", "only used without a fixed time_step");
        }
    }
    let safety = s.safety.unwrap_or(0.8);
    if !(safety > 0.0 && safety <= 1.0) {
        return c.err("dynamics.safety", format!("must lie in (0, 1], got {safety}"));
    }
    let affine = |field: &str, a: Option<AffineSpec>| -> Result<Affine, ProblemError> {
        match a {
            None => Ok(Affine::ZERO),
            Some(a) => {
                c.finite(&format!("dynamics.{field}.x"), &a.x)?;
                c.finite(&format!("dynamics.{field}.y"), &a.y)?;
                Ok(Affine { x: a.x, y: a.y })
            }
        }
    };
    if s.snapshots.is_some() && s.snapshot_every.is_some() {
        return c.err("dynamics.snapshot_every", "give either snapshots (a count) or snapshot_every (steps), not both");
    }
    if s.snapshot_every == Some(0) {
        return c.err("dynamics.snapshot_every", "must be at least 1");
    }
    let snapshots = s.snapshots.unwrap_or(10);
    if snapshots > 10_000 {
        return c.err("dynamics.snapshots", format!("{snapshots} snapshots; at most 10000"));
    }
    Ok(DynamicsParams {
        density,
        end_time,
        integrator,
        time_step,
        safety,
        initial_displacement: affine("initial_displacement", s.initial_displacement)?,
        initial_velocity: affine("initial_velocity", s.initial_velocity)?,
        snapshots,
        snapshot_every: s.snapshot_every,
    })
}

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
                "horizon {} is larger than half the solid's smallest extent ({extent:.4e}): no node would have a complete family; use a smaller horizon",
                p.horizon
            ),
        );
    }
    let nodes = domain.area_estimate(400) / p.spacing().powi(2) * p.nodes_per_cell() as f64;
    if nodes > MAX_NODES {
        return fail("horizon", format!("horizon {} with m = {} gives about {nodes:.1e} nodes (over {MAX_NODES:e})", p.horizon, p.ratio));
    }
    Ok(())
}

fn peridynamics(
    c: &Ctx,
    s: &PeridynamicsSpec,
    domain: &Domain,
    material: &Material,
    conditions: &[BoundaryCondition],
    specs: &[BoundarySpec],
    dynamic: bool,
) -> Result<PdParams, ProblemError> {
    if !crate::peridynamics::kernel::representable(material) {
        let (need, plane) = match material.plane {
            PlaneModel::Strain => ("1/4", "plane strain"),
            PlaneModel::Stress => ("1/3", "plane stress"),
        };
        return c.err(
            "material.nu",
            format!(
                "bond-based peridynamics represents only in-plane lambda = mu, that is nu = {need} in {plane}; got nu = {} \
                 (remove the [peridynamics] table or set nu = {need})",
                material.elastic.poisson
            ),
        );
    }
    for (k, b) in specs.iter().enumerate() {
        if b.kind == "mixed" {
            return c.err(
                format!("boundary[{k}].kind"),
                "mixed (per-component) conditions have no peridynamic volume constraint here; use displacement or traction",
            );
        }
    }
    debug_assert!(conditions.iter().all(|bc| bc.components[0] == bc.components[1]));
    let horizon = c.need("peridynamics.horizon", s.horizon, "the horizon delta (m)")?;
    let kernel = match s.kernel.as_deref().unwrap_or("plain") {
        "plain" => {
            if s.alpha.is_some() {
                return c.err("peridynamics.alpha", "only the regularised kernel takes alpha");
            }
            Kernel::Plain
        }
        "regularised" => {
            let alpha = s.alpha.unwrap_or(-3.0);
            if !(alpha.is_finite() && alpha > -4.0 && alpha <= 10.0) {
                return c
                    .err("peridynamics.alpha", format!("must lie in (-4, 10] (the operator is unbounded for alpha <= -4), got {alpha}"));
            }
            Kernel::Regularised { alpha }
        }
        other => return c.err("peridynamics.kernel", format!("unknown kernel \"{other}\" (expected \"plain\" or \"regularised\")")),
    };
    let quadrature = c.word("peridynamics.quadrature", s.quadrature.as_deref().unwrap_or("ac"), &Quadrature::ALL)?;
    let correction = c.word(
        "peridynamics.correction",
        s.correction.as_deref().unwrap_or("none"),
        &[("none", SurfaceCorrection::None), ("volume", SurfaceCorrection::Volume)],
    )?;
    let solver = match &s.solver {
        // The PD stiffness is an M-matrix-like, diagonally dominant block Laplacian:
        // ILU(0)-preconditioned BiCGSTAB beat sparse LU 6x at 1.4e4 nodes (BENCHMARKS.md).
        None => SolverParams {
            kind: SolverKind::Bicgstab { preconditioner: Preconditioner::Ilu0, tolerance: 1e-10, max_iterations: 5000 },
            equilibrate: true,
        },
        Some(spec) => solver(c, spec).map_err(|mut e| {
            e.field = e.field.replacen("solver", "peridynamics.solver", 1);
            e
        })?,
    };
    let force = c.word(
        "peridynamics.force",
        s.force.as_deref().unwrap_or("linear"),
        &[("linear", BondForce::Linear), ("bond-stretch", BondForce::BondStretch)],
    )?;
    if force == BondForce::BondStretch && !dynamic {
        return c.err("peridynamics.force", "the static solve uses the linear law; \"bond-stretch\" needs a [dynamics] table");
    }
    let params = PdParams { horizon, ratio: s.m.unwrap_or(3.0), kernel, quadrature, correction, solver, force };
    check_peridynamics(&params, domain).map_err(|(f, r)| ProblemError {
        file: c.path.to_path_buf(),
        field: format!("peridynamics.{f}"),
        reason: r,
    })?;
    Ok(params)
}

fn domain(c: &Ctx, spec: &DomainSpec) -> Result<Domain, ProblemError> {
    if spec.region.is_empty() {
        return c.err("domain.region", "at least one region is needed");
    }
    let mut parts: Vec<String> = Vec::new();
    let mut part_id = |name: &str| match parts.iter().position(|p| p == name) {
        Some(i) => i,
        None => {
            parts.push(name.to_string());
            parts.len() - 1
        }
    };
    let mut regions = Vec::new();
    for (k, r) in spec.region.iter().enumerate() {
        let f = |s: &str| format!("domain.region[{k}].{s}");
        let op = match &r.op {
            None => CsgOp::Union,
            Some(o) => c.word(&f("op"), o, &[("union", CsgOp::Union), ("subtract", CsgOp::Subtract), ("intersect", CsgOp::Intersect)])?,
        };
        if k == 0 && op != CsgOp::Union {
            return c.err(f("op"), "the first region must add material (op = \"union\" or no op)");
        }
        let not_for = |field: &str, present: bool, shape: &str| -> Result<(), ProblemError> {
            if present {
                c.err(f(field), format!("not used by a {shape}; remove it"))
            } else {
                Ok(())
            }
        };
        let (primitive, edge_parts) = match r.shape.as_str() {
            "rectangle" => {
                not_for("center", r.center.is_some(), "rectangle")?;
                not_for("radius", r.radius.is_some(), "rectangle")?;
                not_for("vertices", r.vertices.is_some(), "rectangle")?;
                not_for("name", r.name.is_some(), "rectangle (use names = { left = \"...\" })")?;
                not_for("edge_names", r.edge_names.is_some(), "rectangle (use names)")?;
                let min = c.need(&f("min"), r.min, "a rectangle needs min = [x, y]")?;
                let max = c.need(&f("max"), r.max, "a rectangle needs max = [x, y]")?;
                c.finite(&f("min"), &min)?;
                c.finite(&f("max"), &max)?;
                if !(max[0] > min[0] && max[1] > min[1]) {
                    return c.err(f("max"), format!("must exceed min in both coordinates (min = {min:?}, max = {max:?})"));
                }
                let d = RectangleNames::default();
                let n = r.names.as_ref().unwrap_or(&d);
                let ids = [("bottom", &n.bottom), ("right", &n.right), ("top", &n.top), ("left", &n.left)]
                    .iter()
                    .map(|(def, given)| part_id(given.as_deref().unwrap_or(def)))
                    .collect();
                (Primitive::Rectangle { min, max }, ids)
            }
            "disc" => {
                not_for("min", r.min.is_some(), "disc")?;
                not_for("max", r.max.is_some(), "disc")?;
                not_for("vertices", r.vertices.is_some(), "disc")?;
                not_for("names", r.names.is_some(), "disc (use name)")?;
                not_for("edge_names", r.edge_names.is_some(), "disc (use name)")?;
                let center = c.need(&f("center"), r.center, "a disc needs center = [x, y]")?;
                c.finite(&f("center"), &center)?;
                let radius = c.positive(&f("radius"), c.need(&f("radius"), r.radius, "a disc needs radius")?)?;
                let name = r.name.clone().unwrap_or_else(|| if op == CsgOp::Subtract { "hole".into() } else { "rim".into() });
                (Primitive::Disc { center, radius }, vec![part_id(&name)])
            }
            "polygon" => {
                not_for("min", r.min.is_some(), "polygon")?;
                not_for("max", r.max.is_some(), "polygon")?;
                not_for("center", r.center.is_some(), "polygon")?;
                not_for("radius", r.radius.is_some(), "polygon")?;
                not_for("names", r.names.is_some(), "polygon (use edge_names)")?;
                not_for("name", r.name.is_some(), "polygon (use edge_names)")?;
                let mut v = r.vertices.clone().unwrap_or_default();
                if v.len() < 3 {
                    return c.err(f("vertices"), format!("a polygon needs at least 3 vertices, got {}", v.len()));
                }
                for p in &v {
                    c.finite(&f("vertices"), p)?;
                }
                let mut names: Vec<String> = match &r.edge_names {
                    Some(n) if n.len() != v.len() => {
                        return c.err(f("edge_names"), format!("{} names for {} edges (edge k joins vertex k to k+1)", n.len(), v.len()))
                    }
                    Some(n) => n.clone(),
                    None => (0..v.len()).map(|i| format!("edge{i}")).collect(),
                };
                let area2: f64 = (0..v.len())
                    .map(|i| {
                        let (a, b) = (v[i], v[(i + 1) % v.len()]);
                        a[0] * b[1] - b[0] * a[1]
                    })
                    .sum();
                if area2.abs() <= 1e-14 * polygon_scale(&v).powi(2) {
                    return c.err(f("vertices"), "the polygon has zero area");
                }
                if let Some((i, j)) = self_intersection(&v) {
                    return c.err(f("vertices"), format!("edges {i} and {j} cross: the polygon must be simple"));
                }
                if area2 < 0.0 {
                    // Clockwise: reverse, keeping each edge's name with the same geometric edge.
                    v.reverse();
                    let n = names.len();
                    names = (0..n).map(|k| names[(2 * n - 2 - k) % n].clone()).collect();
                }
                let ids = names.iter().map(|s| part_id(s)).collect();
                (Primitive::Polygon { vertices: v }, ids)
            }
            other => return c.err(f("shape"), format!("unknown shape \"{other}\" (expected \"rectangle\", \"disc\" or \"polygon\")")),
        };
        regions.push(Region { primitive, op, edge_parts });
    }
    Ok(Domain { regions, parts })
}

fn polygon_scale(v: &[[f64; 2]]) -> f64 {
    v.iter().map(|p| p[0].abs().max(p[1].abs())).fold(0.0, f64::max).max(1e-300)
}

/// First pair of non-adjacent polygon edges that intersect.
fn self_intersection(v: &[[f64; 2]]) -> Option<(usize, usize)> {
    let n = v.len();
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    for i in 0..n {
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (a, b, p, q) = (v[i], v[(i + 1) % n], v[j], v[(j + 1) % n]);
            let (d1, d2) = (cross(a, b, p), cross(a, b, q));
            let (d3, d4) = (cross(p, q, a), cross(p, q, b));
            if d1 * d2 <= 0.0 && d3 * d4 <= 0.0 {
                return Some((i, j));
            }
        }
    }
    None
}

fn nodes(c: &Ctx, s: &NodesSpec, domain: &Domain, area: f64) -> Result<FillParams, ProblemError> {
    let single_rectangle = domain.regions.len() == 1 && matches!(domain.regions[0].primitive, Primitive::Rectangle { .. });
    let kind = match &s.fill {
        None if single_rectangle => FillKind::Grid,
        None => FillKind::Scattered,
        Some(w) => c.word("nodes.fill", w, &[("grid", FillKind::Grid), ("scattered", FillKind::Scattered)])?,
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
        return c.err("nodes.spacing", format!("spacing {spacing} is more than half the domain size {size:.3e}"));
    }
    let relax = s.relax.unwrap_or(0);
    if relax > 1000 {
        return c.err("nodes.relax", format!("{relax} sweeps; the fill settles within tens (seed 002 uses about 10); at most 1000"));
    }
    Ok(FillParams { spacing, kind, seed: s.seed.unwrap_or(0), relax_iterations: relax })
}

fn approximation(c: &Ctx, s: &ApproximationSpec, fill: FillKind, dynamic: bool) -> Result<Approximation, ProblemError> {
    let kind = s.basis.as_deref().unwrap_or("monomials");
    let poly = |deg: Option<u32>| -> Result<u32, ProblemError> {
        let d = deg.unwrap_or(2);
        if !(2..=6).contains(&d) {
            return c.err("approximation.degree", format!("must be 2..6 (the Navier equations need second derivatives), got {d}"));
        }
        Ok(d)
    };
    let basis = match kind {
        "monomials" => Basis::Monomials { degree: poly(s.degree)? },
        "tensor" => Basis::Tensor { degree: poly(s.degree)? },
        "gaussian" | "mq" | "imq" => {
            if s.degree.is_some() {
                return c.err("approximation.degree", "RBF bases have no degree; remove it");
            }
            let rbf = match kind {
                "gaussian" => RbfKind::Gaussian,
                "mq" => RbfKind::Mq,
                _ => RbfKind::Imq,
            };
            let shape = c.positive(
                "approximation.shape",
                c.need("approximation.shape", s.shape, "an RBF basis needs shape (in units of the node spacing)")?,
            )?;
            Basis::Rbf { rbf, shape }
        }
        other => {
            return c.err(
                "approximation.basis",
                format!("unknown basis \"{other}\" (expected \"monomials\", \"tensor\", \"gaussian\", \"mq\" or \"imq\")"),
            )
        }
    };
    if s.shape.is_some() && !matches!(basis, Basis::Rbf { .. }) {
        return c.err("approximation.shape", "only RBF bases take a shape parameter");
    }
    let weight = match s.weight.as_deref().unwrap_or("gaussian") {
        "none" => {
            if s.sigma.is_some() {
                return c.err("approximation.sigma", "weight = \"none\" takes no sigma");
            }
            Weight::None
        }
        "gaussian" => Weight::Gaussian { sigma: c.positive("approximation.sigma", s.sigma.unwrap_or(1.0))? },
        other => return c.err("approximation.weight", format!("unknown weight \"{other}\" (expected \"gaussian\" or \"none\")")),
    };
    let m = basis.size(usize::MAX);
    let support = match (s.support, basis) {
        (Some(n), _) => n,
        (None, Basis::Rbf { .. }) => 9,
        (None, _) => default_support(m, fill),
    };
    if support < 2 {
        return c.err("approximation.support", format!("must be at least 2, got {support}"));
    }
    if !matches!(basis, Basis::Rbf { .. }) && support < m {
        return c.err(
            "approximation.support",
            format!(
                "{support} nodes cannot determine the {m} coefficients of the basis ({}); use support >= {m} (about {} recommended)",
                basis.describe(),
                2 * m
            ),
        );
    }
    // Ghost nodes gave growing modes in explicit MLSM dynamics (README, known limits):
    // off by default for time-dependent scenes.
    let ghost_nodes = s.ghost_nodes.unwrap_or(DEFAULT_GHOST_NODES && !dynamic);
    Ok(Approximation { basis, weight, support, ghost_nodes })
}

fn material(c: &Ctx, s: &MaterialSpec) -> Result<Material, ProblemError> {
    let plane = c.word("material.plane", &s.plane, &[("stress", PlaneModel::Stress), ("strain", PlaneModel::Strain)])?;
    let elastic = match (s.young, s.nu, s.lambda, s.mu) {
        (Some(e), Some(nu), None, None) => {
            c.positive("material.E", e)?;
            if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
                return c.err("material.nu", format!("Poisson's ratio must lie in (-1, 0.5), got {nu}"));
            }
            YoungPoisson { young: e, poisson: nu }
        }
        (None, None, Some(l), Some(m)) => {
            c.positive("material.mu", m)?;
            if !(l.is_finite() && l + 2.0 * m / 3.0 > 0.0) {
                return c.err("material.lambda", format!("the bulk modulus lambda + 2 mu / 3 must be positive, got lambda = {l}"));
            }
            YoungPoisson::from_lame_3d(l, m)
        }
        _ => return c.err("material", "give exactly one pair: E and nu, or lambda and mu"),
    };
    Ok(Material { elastic, plane })
}

fn exact(c: &Ctx, s: &ExactSpec) -> Result<ExactKind, ProblemError> {
    let allowed: &[&str] = match s.kind.as_str() {
        "cantilever" => &["load", "length", "depth"],
        "kirsch" => &["tension", "radius"],
        "lame" => &["pressure", "inner", "outer"],
        "manufactured" => &[],
        "tension" => &["tension"],
        "polynomial" => &["ux", "uy"],
        other => {
            return c.err(
                "exact.kind",
                format!(
                    "unknown solution \"{other}\" (expected \"cantilever\", \"kirsch\", \"lame\", \"manufactured\", \"tension\" or \"polynomial\")"
                ),
            )
        }
    };
    for (k, v) in [("ux", s.ux.is_some()), ("uy", s.uy.is_some())] {
        if v && !allowed.contains(&k) {
            return c.err(format!("exact.{k}"), format!("not a parameter of the {} solution (it takes: {})", s.kind, allowed.join(", ")));
        }
    }
    let coefficients = |k: &str, v: &Option<Vec<f64>>| -> Result<[f64; 10], ProblemError> {
        let field = format!("exact.{k}");
        let v = c.need(&field, v.as_ref(), "the polynomial solution needs ux and uy (10 coefficients each)")?;
        let a: [f64; 10] = v.as_slice().try_into().or_else(|_| {
            c.err(&field, format!("needs 10 coefficients (of 1, x, y, x^2, x y, y^2, x^3, x^2 y, x y^2, y^3), got {}", v.len()))
        })?;
        c.finite(&field, &a)?;
        Ok(a)
    };
    let given = [
        ("load", s.load),
        ("length", s.length),
        ("depth", s.depth),
        ("tension", s.tension),
        ("radius", s.radius),
        ("pressure", s.pressure),
        ("inner", s.inner),
        ("outer", s.outer),
    ];
    for (k, v) in given {
        if v.is_some() && !allowed.contains(&k) {
            return c.err(format!("exact.{k}"), format!("not a parameter of the {} solution (it takes: {})", s.kind, allowed.join(", ")));
        }
    }
    let get = |k: &str| -> Result<f64, ProblemError> {
        let v = given.iter().find(|(n, _)| *n == k).and_then(|(_, v)| *v);
        let v = c.need(&format!("exact.{k}"), v, &format!("the {} solution needs {k}", s.kind))?;
        if k == "load" || k == "tension" || k == "pressure" {
            c.finite(&format!("exact.{k}"), &[v])?;
            Ok(v)
        } else {
            c.positive(&format!("exact.{k}"), v)
        }
    };
    Ok(match s.kind.as_str() {
        "cantilever" => ExactKind::Cantilever { load: get("load")?, length: get("length")?, depth: get("depth")? },
        "kirsch" => ExactKind::Kirsch { tension: get("tension")?, radius: get("radius")? },
        "lame" => {
            let (inner, outer) = (get("inner")?, get("outer")?);
            if outer <= inner {
                return c.err("exact.outer", format!("must exceed inner ({outer} <= {inner})"));
            }
            ExactKind::Lame { pressure: get("pressure")?, inner, outer }
        }
        "tension" => ExactKind::Tension { tension: get("tension")? },
        "polynomial" => ExactKind::Polynomial { ux: coefficients("ux", &s.ux)?, uy: coefficients("uy", &s.uy)? },
        _ => ExactKind::Manufactured,
    })
}

fn conditions(
    c: &Ctx,
    specs: &[BoundarySpec],
    domain: &Domain,
    present: &[bool],
    exact_word: &dyn Fn(&str, &str) -> Result<Value, ProblemError>,
    dynamic: bool,
) -> Result<Vec<BoundaryCondition>, ProblemError> {
    let mut out: Vec<Option<BoundaryCondition>> = vec![None; domain.parts.len()];
    let known = || domain.parts.iter().map(|p| format!("\"{p}\"")).collect::<Vec<_>>().join(", ");
    for (k, b) in specs.iter().enumerate() {
        let f = |s: &str| format!("boundary[{k}].{s}");
        let Some(part) = domain.parts.iter().position(|p| *p == b.part) else {
            return c.err(f("part"), format!("\"{}\" is not a boundary part of the domain (known: {})", b.part, known()));
        };
        if !present[part] {
            return c.err(
                f("part"),
                format!(
                    "\"{}\" does not reach the boundary of the solid (it lies inside or outside the other regions); remove this condition",
                    b.part
                ),
            );
        }
        if out[part].is_some() {
            return c.err(f("part"), format!("\"{}\" already has a condition; give one [[boundary]] per part", b.part));
        }
        let comp = |field: &str, w: &Option<String>| -> Result<ComponentCondition, ProblemError> {
            match w {
                None => c.err(f(field), "a mixed condition names the condition of each component: x = \"displacement\" or \"traction\""),
                Some(w) => {
                    c.word(&f(field), w, &[("displacement", ComponentCondition::Displacement), ("traction", ComponentCondition::Traction)])
                }
            }
        };
        let components = match b.kind.as_str() {
            "displacement" | "traction" => {
                if b.x.is_some() || b.y.is_some() {
                    return c.err(f("x"), format!("per-component conditions need kind = \"mixed\", not \"{}\"", b.kind));
                }
                let cc = if b.kind == "displacement" { ComponentCondition::Displacement } else { ComponentCondition::Traction };
                [cc, cc]
            }
            "mixed" => [comp("x", &b.x)?, comp("y", &b.y)?],
            other => {
                return c.err(f("kind"), format!("unknown condition \"{other}\" (expected \"displacement\", \"traction\" or \"mixed\")"))
            }
        };
        let value = match &b.value {
            None => Value::Constant([0.0, 0.0]),
            Some(VectorOrExact::Vector(v)) => {
                c.finite(&f("value"), v)?;
                Value::Constant(*v)
            }
            Some(VectorOrExact::Word(w)) => exact_word(&f("value"), w)?,
        };
        out[part] = Some(BoundaryCondition { components, value });
    }
    let mut conditions = Vec::new();
    for (i, o) in out.into_iter().enumerate() {
        match o {
            Some(bc) => conditions.push(bc),
            // A part with no boundary nodes (e.g. an edge cut away by a subtraction) needs no condition.
            None if !present[i] => conditions.push(BoundaryCondition { components: [ComponentCondition::Traction; 2], value: Value::Constant([0.0, 0.0]) }),
            None => {
                return c.err(
                    "boundary",
                    format!(
                        "part \"{}\" has no condition; add [[boundary]] part = \"{}\" with kind = \"traction\" (free edge: value = [0, 0]) or another condition",
                        domain.parts[i], domain.parts[i]
                    ),
                )
            }
        }
    }
    // A static problem needs each component fixed somewhere; a time-dependent one is
    // well posed with free edges only (initial conditions fix the motion).
    for comp in 0..2 {
        if dynamic {
            break;
        }
        if !conditions.iter().zip(present).any(|(bc, &here)| here && bc.components[comp] == ComponentCondition::Displacement) {
            let axis = ["x", "y"][comp];
            return c.err(
                "boundary",
                format!("no part prescribes the {axis} displacement: the solution is then fixed only up to a rigid motion; constrain it on at least one part"),
            );
        }
    }
    Ok(conditions)
}

fn solver(c: &Ctx, s: &SolverSpec) -> Result<SolverParams, ProblemError> {
    let equilibrate = s.equilibrate.unwrap_or(true);
    let kind = s.kind.as_deref().unwrap_or("lu");
    let iterative_only = [
        ("preconditioner", s.preconditioner.is_some()),
        ("drop", s.drop.is_some()),
        ("fill", s.fill.is_some()),
        ("tolerance", s.tolerance.is_some()),
        ("max_iterations", s.max_iterations.is_some()),
    ];
    let kind = match kind {
        "lu" => {
            if let Some((k, _)) = iterative_only.iter().find(|(_, p)| *p) {
                return c.err(format!("solver.{k}"), "only used by kind = \"bicgstab\"");
            }
            SolverKind::Lu
        }
        "bicgstab" => {
            let SolverKind::Bicgstab { preconditioner: def_p, tolerance: def_t, max_iterations: def_m } = SolverKind::default_bicgstab()
            else {
                unreachable!("default_bicgstab is a BiCGSTAB configuration")
            };
            let (def_drop, def_fill) = match def_p {
                Preconditioner::Ilut { drop, fill } => (drop, fill),
                _ => (1e-5, 20),
            };
            let pname = s.preconditioner.as_deref().unwrap_or("ilut");
            let preconditioner = match pname {
                "ilut" => {
                    let drop = s.drop.unwrap_or(def_drop);
                    if !(drop.is_finite() && drop >= 0.0) {
                        return c.err("solver.drop", format!("must be >= 0, got {drop}"));
                    }
                    let fill = s.fill.unwrap_or(def_fill);
                    if fill == 0 {
                        return c.err("solver.fill", "must be at least 1");
                    }
                    Preconditioner::Ilut { drop, fill }
                }
                "ilu0" | "jacobi" => {
                    if s.drop.is_some() || s.fill.is_some() {
                        return c.err("solver.drop", format!("drop and fill belong to preconditioner = \"ilut\", not \"{pname}\""));
                    }
                    if pname == "ilu0" {
                        Preconditioner::Ilu0
                    } else {
                        Preconditioner::Jacobi
                    }
                }
                other => {
                    return c.err(
                        "solver.preconditioner",
                        format!("unknown preconditioner \"{other}\" (expected \"ilut\", \"ilu0\" or \"jacobi\")"),
                    )
                }
            };
            let tolerance = s.tolerance.unwrap_or(def_t);
            if !(tolerance > 0.0 && tolerance < 1.0) {
                return c.err("solver.tolerance", format!("must lie in (0, 1), got {tolerance}"));
            }
            let max_iterations = s.max_iterations.unwrap_or(def_m);
            if max_iterations == 0 {
                return c.err("solver.max_iterations", "must be at least 1");
            }
            SolverKind::Bicgstab { preconditioner, tolerance, max_iterations }
        }
        other => return c.err("solver.kind", format!("unknown solver \"{other}\" (expected \"lu\" or \"bicgstab\")")),
    };
    Ok(SolverParams { kind, equilibrate })
}

fn outputs(c: &Ctx, s: &OutputSpec, has_exact: bool) -> Result<Outputs, ProblemError> {
    let default: Vec<String> =
        ["displacement", "stress", "von_mises"].iter().map(|s| s.to_string()).chain(has_exact.then(|| "error".to_string())).collect();
    let fields = s.fields.clone().unwrap_or(default);
    let mut o = Outputs::default();
    for (k, f) in fields.iter().enumerate() {
        let slot = match f.as_str() {
            "displacement" => &mut o.displacement,
            "strain" => &mut o.strain,
            "stress" => &mut o.stress,
            "von_mises" => &mut o.von_mises,
            "error" => &mut o.error,
            other => {
                return c.err(
                    format!("output.fields[{k}]"),
                    format!("unknown field \"{other}\" (expected displacement, strain, stress, von_mises, error)"),
                )
            }
        };
        *slot = true;
    }
    if o.error && !has_exact {
        return c.err("output.fields", "\"error\" needs an [exact] solution to compare with");
    }
    // The displacement is the solution itself: always written.
    o.displacement = true;
    Ok(o)
}
