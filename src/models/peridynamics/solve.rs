//! The static peridynamic run: nodes -> families -> bond weights -> stiffness ->
//! solve -> post-processing (nonlocal strain, errors against an exact solution on
//! the whole plate and on the interior region at distance >= delta from the boundary).

use super::dilatation::Dilatation;
use super::extension::{in_sight, Extension};
use super::family::Families;
use super::kernel::{fourth_moment, Micromodulus};
use super::nodes::{self, Body, PdNodes};
use super::operator::Bonds;
use super::weights::{bond_coefficients, halo_layers, search_radius, BondWeights};
use super::{loads, strain, PdParams};
use crate::physics::case::Case;
use crate::domain::{boundary::discretise_boundary, Domain, Point};
use crate::physics::elasticity::stress::{Gradient, StressField};
use crate::physics::exact::ExactSolution;
use crate::linalg::SolveReport;
use crate::parallel::petsc::World;
use crate::parallel::distributed;
use crate::parallel::share::Share;
use crate::stages::{stage, Progress, RunError, SolveProgress, Stage, StageTimer, StageTimings};
use crate::quality::post::probe::{probe_values, NodalFields, ProbeValue};

/// Family search.
pub const FAMILIES: Stage = Stage::new("families");
/// Bond weights (quadrature, correction, compatible weights).
pub const WEIGHTS: Stage = Stage::new("weights");
/// The dilatation's families and weights (linear peridynamic solid only).
pub const DILATATION: Stage = Stage::new("dilatation");
/// The extension of the fictitious nodes (traction and free edges, `boundary = "fictitious"`).
pub const EXTENSION: Stage = Stage::new("extension");
use crate::quality::post::{masked_errors, ErrorNorms, ExactFields};
use rayon::prelude::*;
use serde::Serialize;

/// Everything a static peridynamic run computed.
pub struct PdSolution {
    /// The parameters used.
    pub params: PdParams,
    /// Nodes (free first, then the constrained collar).
    pub nodes: PdNodes,
    /// Displacement of every node (prescribed values on the collar).
    pub displacement: Vec<[f64; 2]>,
    /// Body force density at the free nodes (tractions included).
    pub body_force: Vec<[f64; 2]>,
    /// Free nodes at distance >= delta from the boundary.
    pub interior: Vec<bool>,
    /// Free nodes carrying a traction layer load.
    pub layer_nodes: usize,
    /// Bonds (both directions counted).
    pub bonds: usize,
    /// Bonds not made by the sight rule at re-entrant corners ([`in_sight`]).
    pub cut_bonds: usize,
    /// Bond weighting report.
    pub weights: WeightsSummary,
    /// Unknowns and nonzeros.
    pub unknowns: usize,
    /// Nonzeros of the stiffness.
    pub nonzeros: usize,
    /// Nonlocal displacement gradient, when outputs need it.
    pub gradient: Option<Vec<Gradient>>,
    /// Stresses from the nonlocal gradient.
    pub stress: Option<StressField>,
    /// The scene's probes read from this solution (free nodes).
    pub probes: Vec<ProbeValue>,
    /// Exact displacement at the free nodes.
    pub exact: Option<ExactFields>,
    /// Errors on the whole plate and on the interior region.
    pub errors: Option<(ErrorNorms, Option<ErrorNorms>)>,
    /// Calibrated micromodulus.
    pub micromodulus: Micromodulus,
    /// Solver report.
    pub solver: SolveReport,
    /// Stage timings.
    pub timings: StageTimings,
    /// The estimated discretisation error at this horizon
    /// ([`super::discretisation::estimate`]), when the run asked for it: `Err` says why
    /// there is none.
    pub discretisation: Option<Result<DiscretisationEstimate, String>>,
}

/// The estimated discretisation error of a static peridynamic run at its horizon
/// ([`super::discretisation::estimate`]).
#[derive(Debug, Clone, Serialize)]
pub struct DiscretisationEstimate {
    /// `"fixed-horizon"`.
    pub method: &'static str,
    /// What the reference is.
    pub reference: String,
    /// Estimated relative max-norm error of the displacement, `max |e| / max |u|`.
    pub e_inf_u: f64,
    /// Estimated relative discrete L2 error of the displacement.
    pub rel_l2_u: f64,
    /// Where the estimated error is largest.
    pub largest_at: Point,
    /// The reference's `m` (twice the run's).
    pub reference_ratio: f64,
    /// The reference's free nodes.
    pub reference_nodes: usize,
    /// Wall-clock seconds of the estimate.
    pub seconds: f64,
}

/// Counts from the weighting stage.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct WeightsSummary {
    /// Free nodes with a complete family.
    pub complete_families: usize,
    /// Rows with asymptotically compatible weights.
    pub compatible_rows: usize,
    /// Complete rows whose moment problem was singular (base weights kept).
    pub compatible_failures: usize,
}

/// The discrete peridynamic operator of a scene: nodes, families, bond weights.
pub struct Discretisation {
    /// Nodes (free first, then the constrained collar).
    pub nodes: PdNodes,
    /// Families of the free nodes.
    pub families: Families,
    /// Bond coefficients.
    pub weights: BondWeights,
    /// Calibrated micromodulus.
    pub micromodulus: Micromodulus,
    /// The dilatation term of the linear peridynamic solid ([`super::dilatation`]).
    pub dilatation: Option<Dilatation>,
    /// The extension of the fictitious nodes, when there are some ([`super::extension`]).
    pub extension: Option<Extension>,
    /// Bonds of the free nodes (both directions counted), over all ranks.
    pub bond_count: usize,
    /// Bonds not made by the sight rule ([`in_sight`]; this process's families).
    pub cut_bonds: usize,
    /// The free nodes this process works on: all of them, or when the solve is
    /// distributed over MPI ranks (`solver.kind = "petsc"`, a Morton split of their
    /// positions) the families and weights of its own nodes and of the halo they read
    /// only ([`halo_layers`]), and the rows of its own nodes.
    pub share: Share,
}

impl Discretisation {
    /// Build the nodes, families and bond weights of `case` with `params` (`exact`:
    /// the scene's exact solution, for prescribed values), each stage timed by `timer`.
    pub fn new(case: &Case, params: &PdParams, exact: Option<&dyn ExactSolution>, timer: &mut StageTimer) -> Result<Self, RunError> {
        let world = Share::splits(&params.solver).then(crate::parallel::petsc::world);
        Self::on_rank(case, params, exact, timer, world)
    }

    /// The same as rank `world.rank` of `world.size` builds it (`Some(world)`): the
    /// free nodes split by [`Share::as_rank`], the families and weights of this rank's
    /// nodes and their halo only; the counts are summed over the MPI ranks running
    /// (none to sum with in one process). `None`: everything.
    pub fn on_rank(
        case: &Case,
        params: &PdParams,
        exact: Option<&dyn ExactSolution>,
        timer: &mut StageTimer,
        world: Option<World>,
    ) -> Result<Self, RunError> {
        let body = Body::new(&case.domain, &case.conditions, exact, params);
        let nodes = timer.run(stage::NODES, || {
            let n = nodes::generate(&body, params);
            let note = format!("{} free nodes, {} constrained, h = {:.3e}", n.free, n.constrained(), n.spacing);
            Ok((n, note))
        })?;
        // Boundary values are read at the boundary samples of the traction layer (h/16, see `loads`).
        let samples = discretise_boundary(&case.domain, nodes.spacing / 16.0);
        let on_parts: Vec<(Point, usize)> = samples.iter().flat_map(|b| b.touches.iter().map(|&(part, _)| (b.position, part))).collect();
        case.check_formulas(&nodes.positions[..nodes.free], &on_parts)?;
        // The displacement formulas also hold in the collar, outside the solid.
        let collar: Vec<(Point, usize)> = nodes.positions[nodes.free..].iter().copied().zip(nodes.collar_part.iter().copied()).collect();
        case.check_formulas(&[], &collar).map_err(|e| match e {
            RunError::BadFormula { field, text, value, x, y, .. } => RunError::BadFormula {
                field,
                text,
                value,
                x,
                y,
                context: ", a node of the Dirichlet collar outside the solid (peridynamics evaluates displacement formulas there)".into(),
            },
            other => other,
        })?;
        let share = world.map_or_else(Share::whole, |w| Share::as_rank(&nodes.positions[..nodes.free], w));
        let own = |i: usize| share.owns(i);
        let (families, layer, cut_bonds) = timer.run(FAMILIES, || {
            let radius = search_radius(params);
            let (f, layer) = if share.is_split() {
                let (f, layer) = Families::around(&nodes.positions, nodes.free, radius, own, halo_layers(params).1);
                (f, Some(layer))
            } else {
                (Families::within(&nodes.positions, nodes.free, radius), None)
            };
            // Bonds that would read a fictitious node across another side of the solid are not made.
            let (f, cut) = if nodes.fictitious_count() > 0 { f.retain(|i, j| in_sight(&body, &nodes, i, j)) } else { (f, 0) };
            let mine = if layer.is_some() { " (this rank's nodes and halo)" } else { "" };
            let said = if cut > 0 { format!(", {cut} not made (fictitious nodes across a re-entrant corner or a narrow hole)") } else { String::new() };
            let note = format!("{} bonds{mine}, {:.1} per node{said}", f.bonds(), f.bonds() as f64 / nodes.free.max(1) as f64);
            Ok(((f, layer, cut), note))
        })?;
        let moment = fourth_moment(&case.material);
        let micromodulus = Micromodulus::calibrated(params.kernel, params.horizon, moment);
        let weights = timer.run(WEIGHTS, || {
            let mut w = bond_coefficients(&body, &nodes, &families, &micromodulus, params, moment, layer.as_deref());
            // Bonds across a pre-crack are broken from the start.
            let cut = params.fracture.map_or(0, |f| f.cuts(&case.domain).break_precracked(&nodes.positions, &families, &mut w.coefficients));
            let cracked = if cut > 0 { format!("; {cut} bonds across the pre-cracks and notches broken") } else { String::new() };
            let note = format!(
                "{} nodes with their whole horizon in the body, {} with weights fitted to reproduce the local operator{cracked}",
                w.complete_families, w.compatible_rows
            );
            Ok((w, note))
        })?;
        let dilatation = if params.has_dilatation() {
            Some(timer.run(DILATATION, || {
                let d = Dilatation::new(&body, &nodes, params, &case.material);
                let note = format!(
                    "beta = lambda - mu = {:.4e}, {} dilatation bonds, {} rows fitted to the continuum moments ({} singular)",
                    d.coefficient,
                    d.families.bonds(),
                    d.fitted_rows,
                    d.fit_failures
                );
                Ok((d, note))
            })?)
        } else {
            None
        };
        let extension = if nodes.fictitious_count() > 0 {
            Some(timer.run(EXTENSION, || {
                let e = Extension::new(&nodes, &case.material, &case.conditions).map_err(|g| RunError::Formula {
                    field: "peridynamics.boundary".into(),
                    reason: format!(
                        "the extension of the fictitious node at ({:.6e}, {:.6e}) is singular: fewer than {} free nodes near its foot, \
                         or all of them on a line; use a smaller horizon or boundary = \"surface\"",
                        nodes.positions[g][0],
                        nodes.positions[g][1],
                        super::extension::FIT_NODES
                    ),
                })?;
                let note = format!("{} fictitious nodes beyond traction and free edges, each a cubic fit of {} free nodes", nodes.fictitious_count(), super::extension::FIT_NODES);
                Ok((e, note))
            })?)
        } else {
            None
        };
        let mut disc = Discretisation {
            bond_count: families.bonds(),
            cut_bonds,
            nodes,
            families,
            weights,
            micromodulus,
            dilatation,
            extension,
            share: Share::whole(),
        };
        if layer.is_some() {
            // Every rank counted its own rows; the counts are of all of them.
            let w = &disc.weights;
            let own_bonds = (0..disc.nodes.free).filter(|&i| own(i)).map(|i| disc.families.of(i).len()).sum::<usize>();
            let mut counts = [own_bonds, w.complete_families, w.compatible_rows, w.compatible_failures].map(|c| c as f64);
            share.sum(&mut counts, "the bond counts");
            let [bonds, complete, compatible, failures] = counts.map(|c| c as usize);
            disc.bond_count = bonds;
            (disc.weights.complete_families, disc.weights.compatible_rows, disc.weights.compatible_failures) =
                (complete, compatible, failures);
        }
        disc.share = share;
        Ok(disc)
    }

    /// `(L_h u)_i` at every free node, bonds and (for the solid) dilatation, with `u` the
    /// displacement of every node (collar and fictitious ones included).
    pub fn operator(&self, u: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let mut lu = self.bonds().apply(u);
        if let Some(d) = &self.dilatation {
            let theta = d.theta(&self.nodes, u);
            lu.par_iter_mut().enumerate().for_each(|(i, f)| {
                let g = d.force_at(&self.nodes, &theta, i);
                f[0] += g[0];
                f[1] += g[1];
            });
        }
        lu
    }

    /// The traction parts of the fictitious nodes' extension for the tractions of
    /// `conditions` ([`Extension::traction_parts`]; empty without fictitious nodes).
    pub fn traction_parts(&self, conditions: &[crate::physics::elasticity::conditions::BoundaryCondition], exact: Option<&dyn ExactSolution>) -> Result<Vec<[f64; 2]>, RunError> {
        self.extension.as_ref().map_or(Ok(Vec::new()), |e| e.traction_parts(&self.nodes, conditions, exact))
    }

    /// The displacement of every node for the free nodes' `u`: the collar's
    /// prescribed values and the fictitious nodes' extension (`traction_parts` from
    /// [`Discretisation::traction_parts`]).
    pub fn all_displacements(&self, mut u: Vec<[f64; 2]>, traction_parts: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let nodes = &self.nodes;
        u.extend_from_slice(&nodes.prescribed[..nodes.fictitious - nodes.free]);
        if let Some(e) = &self.extension {
            let ghosts = e.values(&u[..nodes.free], traction_parts);
            u.extend(ghosts);
        }
        u
    }

    /// Whether this rank assembles free node `i`'s rows (always, unless distributed).
    pub fn owns(&self, i: usize) -> bool {
        self.share.owns(i)
    }

    /// The operator `L_h` over these bonds.
    pub fn bonds(&self) -> Bonds<'_> {
        Bonds { nodes: &self.nodes, families: &self.families, coefficients: &self.weights.coefficients }
    }
}

/// Whether each point lies in the interior region, at distance >= `horizon` from the
/// boundary (where the comparisons and errors are also reported separately).
pub fn interior_flags(domain: &Domain, points: &[Point], horizon: f64) -> Vec<bool> {
    points.par_iter().map(|p| domain.signed_distance(*p) <= -horizon).collect()
}

/// The error of `values` (at the free nodes `points` of volumes `volumes`) against a
/// reference solution (`reference_values` at `reference_points`, interpolated there by
/// degree-2 MLS, [`crate::mlsm::interpolate::mls_values`]), over the nodes `interior` marks:
/// `(max_i |e_i|, sum_i V_i |e_i| / sum_i V_i)` with `|e_i|` the larger component
/// difference: the largest error and its volume-weighted mean (an L1 error per unit
/// area, the norm in which a discontinuous field still converges).
pub fn interior_errors(
    points: &[Point],
    values: &[[f64; 2]],
    volumes: &[f64],
    interior: &[bool],
    reference_points: &[Point],
    reference_values: &[[f64; 2]],
) -> Result<(f64, f64), crate::mlsm::ShapeError> {
    let picked: Vec<usize> = (0..points.len()).filter(|&i| interior[i]).collect();
    let targets: Vec<Point> = picked.iter().map(|&i| points[i]).collect();
    let reference = crate::mlsm::interpolate::mls_values(reference_points, reference_values, &targets)?;
    let (mut largest, mut sum, mut volume) = (0.0f64, 0.0, 0.0);
    for (&i, r) in picked.iter().zip(&reference) {
        let e = (values[i][0] - r[0]).abs().max((values[i][1] - r[1]).abs());
        largest = largest.max(e);
        sum += volumes[i] * e;
        volume += volumes[i];
    }
    Ok((largest, if volume > 0.0 { sum / volume } else { 0.0 }))
}

/// What the post-processing of a static run computes.
struct Post {
    displacement: Vec<[f64; 2]>,
    interior: Vec<bool>,
    gradient: Option<Vec<Gradient>>,
    stress: Option<StressField>,
    probes: Vec<ProbeValue>,
    exact: Option<ExactFields>,
    errors: Option<(ErrorNorms, Option<ErrorNorms>)>,
}

/// Displacement of every node, nonlocal strain and stress, errors on the whole plate
/// and on the interior region, the probes.
fn post(case: &Case, params: &PdParams, disc: &Discretisation, exact: Option<&dyn ExactSolution>, x: &[f64]) -> Result<Post, RunError> {
    let nodes = &disc.nodes;
    let parts = disc.traction_parts(&case.conditions, exact)?;
    let u = disc.all_displacements(nodes.dofs().displacements(x, nodes.free), &parts);
    let free = &nodes.positions[..nodes.free];
    let interior = interior_flags(&case.domain, free, params.horizon);
    // Distributed: each rank computes its own nodes' gradients, the sum over ranks fills in the rest.
    let gradient = case.outputs.needs_gradient().then(|| {
        let mut g = strain::gradients(nodes, &disc.families, &u, |i| disc.owns(i));
        disc.share.sum(g.as_flattened_mut().as_flattened_mut(), "the gradients over the ranks");
        g
    });
    let stress = gradient.as_ref().map(|g| StressField::from_gradients(&case.material, g));
    let fields = NodalFields { positions: free, displacement: &u[..nodes.free], stress: stress.as_ref() };
    let probes = probe_values(&case.probes, &fields, exact)?;
    let exact = exact.map(|e| ExactFields::at(e, free, false));
    let errors = exact.as_ref().map(|ef| {
        let whole = masked_errors(&u, &ef.displacement, |_| true).expect("at least one free node");
        (whole, masked_errors(&u, &ef.displacement, |i| interior[i]))
    });
    Ok(Post { displacement: u, interior, gradient, stress, probes, exact, errors })
}

/// Solve the static peridynamic problem of `case` with `params`.
pub fn solve(case: &Case, params: &PdParams, progress: &dyn Progress) -> Result<PdSolution, RunError> {
    let mut timer = StageTimer::new(progress);
    let exact = case.exact_solution();
    let exact = exact.as_deref();
    let disc = Discretisation::new(case, params, exact, &mut timer)?;
    // With PETSc each rank assembles the rows of the free nodes it owns (a Morton split
    // of their positions, as for the Navier model).
    let (system, body_force, traction_parts, layer_nodes) = timer.run(stage::ASSEMBLY, || {
        let (b, layer) = loads::body_forces(&case.domain, &case.conditions, &case.body_force, exact, &disc.nodes)?;
        let parts = disc.traction_parts(&case.conditions, exact)?;
        let system = disc.system(&b, &parts, &params.solver)?;
        let rows = if disc.share.is_split() { " in this rank's rows" } else { "" };
        let applied = if system.dilatation_applied() { " (the bonds'; the dilatation applied by its product)" } else { "" };
        let note = format!("{} unknowns, {} nonzeros{rows}{applied}, {layer} nodes in loaded layers", system.rhs.len(), system.matrix.nnz());
        Ok(((system, b, parts, layer), note))
    })?;
    let nonzeros = system.matrix.nnz();
    let watch = SolveProgress(timer.progress());
    let (x, report) = timer.run(stage::SOLVE, || {
        let (x, report) = disc.solve_system(system, (&body_force, &traction_parts), &params.solver, &watch)?;
        let note = format!("{}: relative residual {:.1e}", report.method, report.relative_residual);
        Ok(((x, report), note))
    })?;
    // Over ranks, the entries of every rank's rows.
    let nonzeros = report.ranks.as_ref().map_or(nonzeros, |r| r.nonzeros.iter().sum());
    let post = timer.run(stage::POST, || {
        let post = post(case, params, &disc, exact, &x)?;
        let note = match &post.errors {
            Some((w, i)) => format!("e_inf(u) = {:.3e} (interior {})", w.e_inf_u, i.map_or("-".into(), |i| format!("{:.3e}", i.e_inf_u))),
            None => String::new(),
        };
        Ok((post, note))
    })?;
    let Discretisation { nodes, weights, micromodulus, bond_count, cut_bonds, .. } = disc;
    let timings = timer.finish();
    let mut report = report;
    if let Some(ranks) = report.ranks.as_mut() {
        ranks.stage_seconds = distributed::stage_seconds_per_rank(&timings.named())?;
    }
    Ok(PdSolution {
        params: *params,
        unknowns: nodes.dofs().len(),
        bonds: bond_count,
        cut_bonds,
        weights: WeightsSummary {
            complete_families: weights.complete_families,
            compatible_rows: weights.compatible_rows,
            compatible_failures: weights.compatible_failures,
        },
        nodes,
        displacement: post.displacement,
        body_force,
        interior: post.interior,
        layer_nodes,
        nonzeros,
        gradient: post.gradient,
        stress: post.stress,
        probes: post.probes,
        exact: post.exact,
        errors: post.errors,
        micromodulus,
        solver: report,
        timings,
        discretisation: None,
    })
}
