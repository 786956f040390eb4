//! The static Navier run, stage by stage (no printing; stages report to the timer's
//! observer): nodes -> supports -> shapes -> assembly -> solve -> post-processing
//! (gradients, strain, stress, von Mises, errors against the exact solution).

use std::borrow::Cow;

use super::corner_defect::CornerRows;
use super::defect;
use super::discrete::Discretisation;
use super::equations::ComponentEquation;
use super::equilibrium::{self, Equilibrium};
use super::estimate::{ErrorEstimate, Estimate, EstimateMethod, ESTIMATE};
use super::low_order;
use super::sector;
use super::system::System;
use super::NavierParams;
use crate::domain::{NodeSet, Point};
use crate::linalg::{self, SolveReport, SolverParams, SparseMatrix};
use crate::parallel::distributed::agree;
use crate::physics::case::Case;
use crate::physics::elasticity::dofs::{DofMap, Unknowns};
use crate::physics::elasticity::stress::{Gradient, StressField};
use crate::physics::exact::ExactSolution;
use crate::quality::post::probe::{probe_values, NodalFields, ProbeValue};
use crate::quality::post::{ErrorNorms, ExactFields};
use crate::scene::choice::Choice;
use crate::stages::{stage, Progress, RunError, SolveProgress, StageTimer, StageTimings};
use std::time::Instant;

/// Everything a static Navier run computed.
pub struct Solution {
    /// Nodes.
    pub nodes: NodeSet,
    /// Equations of each boundary node (x and y).
    pub boundary_equations: Vec<[ComponentEquation; 2]>,
    /// Nodal displacements.
    pub displacement: Vec<[f64; 2]>,
    /// Nodal pressures `p = -lambda div u`, in the displacement-pressure form.
    pub pressure: Option<Vec<f64>>,
    /// Displacement gradients, when post-processing needed them.
    pub gradient: Option<Vec<Gradient>>,
    /// Stresses, when gradients exist.
    pub stress: Option<StressField>,
    /// Exact displacement and stress at the nodes, when an exact solution is known.
    pub exact: Option<ExactFields>,
    /// Error norms, when an exact solution is known.
    pub errors: Option<ErrorNorms>,
    /// Global force balance, when stresses exist (`equilibrium`).
    pub equilibrium: Option<Equilibrium>,
    /// The scene's probes read from this solution.
    pub probes: Vec<ProbeValue>,
    /// Estimated errors (`estimate`), with or without an exact solution.
    pub estimate: Estimate,
    /// Number of ghost nodes.
    pub ghost_nodes: usize,
    /// Supports widened to determine an RBF-FD polynomial part.
    pub widened_supports: usize,
    /// Re-entrant corners and holes whose equilibrium was imposed ([`sector`]).
    pub sector_balances: Vec<sector::SectorSummary>,
    /// The re-entrant corners and holes with traction edges that got no balance, and
    /// why (a note of the checks).
    pub unbalanced: Vec<sector::Unbalanced>,
    /// Number of unknowns.
    pub unknowns: usize,
    /// What each node carries (the resolved formulation).
    pub formulation: Unknowns,
    /// Nonzeros of the assembled matrix.
    pub nonzeros: usize,
    /// Operators computed, with the number of nodes each was computed at.
    pub operators_computed: Vec<(String, usize)>,
    /// Solver report.
    pub solver: SolveReport,
    /// The assembled system, when `params.keep_system` asked for it.
    pub system: Option<LinearSystem>,
    /// Stage timings.
    pub timings: StageTimings,
}

/// The assembled system `A x = b` of a run, with what each unknown is; with sector
/// balances it is the bordered system `[A G; C 0]` (`linalg::border`).
pub struct LinearSystem {
    /// `A`, as assembled (before the solver's row equilibration).
    pub matrix: SparseMatrix,
    /// `b`.
    pub rhs: Vec<f64>,
    /// The solution `x` (the multipliers last).
    pub x: Vec<f64>,
    /// The centre of the balance of each multiplier (three per balance: force x,
    /// force y, moment), the unknowns after the nodes' (`linalg::border`).
    pub multipliers: Vec<Point>,
    /// Unknown layout over nodes and ghosts.
    pub dofs: DofMap,
    /// Position of every node and ghost (ghosts after the nodes).
    pub points: Vec<Point>,
    /// Number of nodes (the rest of `points` are ghosts).
    pub nodes: usize,
}

/// The stages of the static run of `case` with `params`, each timed by `timer`, up to
/// the post-processing: the [`Solution`]'s `estimate` is [`Estimate::Off`] and its
/// `timings` empty until [`super::run::solve`] makes the estimate and closes the timer.
pub(super) fn stages(
    case: &Case,
    params: &NavierParams,
    exact: Option<&dyn ExactSolution>,
    timer: &mut StageTimer,
) -> Result<Solution, RunError> {
    let mut disc = Discretisation::new(case, params, exact, timer)?;
    let Solved { x, multipliers, nonzeros, report, system, sectors, unbalanced, correction } =
        assemble_and_solve(case, &mut disc, exact, params, timer)?;

    let n = disc.nodes.len();
    let Post { displacement, pressure, gradient, stress, exact_fields, errors, equilibrium, probes, estimate } =
        timer.run(stage::POST, || {
            let displacement = disc.dofs.displacements(&x, n);
            let pressure = disc.pressure(&case.material, &x);
            if case.outputs.needs_gradient() {
                disc.restore_gradient_shapes(&params.approximation)?;
            }
            let gradient = case.outputs.needs_gradient().then(|| disc.gradients(&x));
            let stress = gradient.as_ref().map(|g| disc.stress(&case.material, g, &x));
            let exact_fields = exact.map(|e| ExactFields::at(e, &disc.nodes.positions, true));
            let errors = exact_fields.as_ref().map(|ef| ErrorNorms::against(&displacement, stress.as_ref(), ef));
            let equilibrium = stress.as_ref().map(|s| equilibrium::balance(case, &disc.nodes, s, exact));
            let fields = NodalFields { positions: &disc.nodes.positions, displacement: &displacement, stress: stress.as_ref() };
            let probes = probe_values(&case.probes, &fields, exact)?;
            let note = match &errors {
                Some(e) => format!("e_inf(u) = {:.3e}", e.e_inf_u),
                None => String::new(),
            };
            let estimate = match (params.estimate.method, correction) {
                (m, Some(c)) if m.makes_defect() => defect_estimate(case, &disc, &x, (&displacement, stress.as_ref()), c),
                (m, None) if m.makes_defect() => {
                    let why = if disc.share.is_split() { "it is not made over MPI ranks" } else { "the scene has singular corners" };
                    Estimate::Unavailable(EstimateMethod::Defect.name(), why.into())
                }
                _ => Estimate::Off,
            };
            Ok((Post { displacement, pressure, gradient, stress, exact_fields, errors, equilibrium, probes, estimate }, note))
        })?;

    let system = system.map(|(matrix, rhs)| LinearSystem {
        matrix,
        rhs,
        x: x.iter().chain(&multipliers).copied().collect(),
        multipliers: sectors.iter().flat_map(|s| [s.centre; 3]).collect(),
        dofs: disc.dofs,
        points: (0..disc.dofs.nodes()).map(|i| disc.point(i)).collect(),
        nodes: disc.nodes.len(),
    });
    let ghost_nodes = disc.ghost_count();
    let widened_supports = disc.widened_supports;
    let unknowns = disc.dofs.len();
    let formulation = disc.dofs.unknowns();
    let Discretisation { nodes, boundary_equations, operators_computed, .. } = disc;
    Ok(Solution {
        nodes,
        boundary_equations,
        displacement,
        pressure,
        gradient,
        stress,
        exact: exact_fields,
        errors,
        equilibrium,
        probes,
        estimate,
        ghost_nodes,
        widened_supports,
        sector_balances: sectors,
        unbalanced,
        unknowns,
        formulation,
        nonzeros,
        operators_computed,
        solver: report,
        system,
        timings: StageTimings::default(),
    })
}

/// What the post-processing stage makes of a solved system (the fields of a
/// [`Solution`] of the same names).
struct Post {
    displacement: Vec<[f64; 2]>,
    pressure: Option<Vec<f64>>,
    gradient: Option<Vec<Gradient>>,
    stress: Option<StressField>,
    exact_fields: Option<ExactFields>,
    errors: Option<ErrorNorms>,
    equilibrium: Option<Equilibrium>,
    probes: Vec<ProbeValue>,
    estimate: Estimate,
}

/// An assembled and solved system.
pub(super) struct Solved {
    /// The unknowns (displacements of nodes and ghosts).
    pub x: Vec<f64>,
    /// The multipliers of the sector balances (force x, force y, moment of each),
    /// the trailing unknowns of the bordered system (`linalg::border`).
    pub multipliers: Vec<f64>,
    /// Nonzeros of the matrix.
    pub nonzeros: usize,
    /// What the solver did.
    pub report: SolveReport,
    /// The matrix and right-hand side, when kept.
    pub system: Option<(SparseMatrix, Vec<f64>)>,
    /// The sector balances imposed at re-entrant corners and holes ([`sector`]; none
    /// over MPI).
    pub sectors: Vec<sector::SectorSummary>,
    /// The corners and holes with traction edges that got no balance, and why.
    pub unbalanced: Vec<sector::Unbalanced>,
    /// The `defect` estimate's correction, when the scene asks for it, or why there
    /// is none.
    pub correction: Option<Result<Correction, String>>,
}

/// The correction of the `defect` estimate ([`defect`]): `e ~ x - u*` over all
/// unknowns (multipliers excluded), and the fits it was measured with.
pub(super) struct Correction {
    e: Vec<f64>,
    fits: defect::Fits,
    /// `(node, G_H x)` at the nodes near singular corners, whose gradient's
    /// truncation error is `(G - G_H) x` ([`super::corner_defect`]).
    corner_gradients: Vec<(usize, Gradient)>,
    /// What the correction's solve did.
    solve: String,
    /// Seconds of the estimate stage.
    seconds: f64,
}

/// Assemble the rows of `disc` and solve them with `params.solver` (stages `assembly`,
/// `solve`); with `params.keep_system` return the system too. Every shape is released
/// before the solve ([`Discretisation::release_row_shapes`]; post-processing makes the
/// gradient's again). A
/// multigrid built on the low-order operator ([`low_order`]) gets its rows when the
/// solver builds it, inside the `solve` stage.
pub(super) fn assemble_and_solve(
    case: &Case,
    disc: &mut Discretisation,
    exact: Option<&dyn ExactSolution>,
    params: &NavierParams,
    timer: &mut StageTimer,
) -> Result<Solved, RunError> {
    let (solver, keep) = (&params.solver, params.keep_system);
    let defect = params.estimate.method.makes_defect();
    let positions: Vec<[f64; 2]> = (0..disc.dofs.nodes()).map(|i| disc.point(i)).collect();
    if disc.share.is_split() {
        return assemble_and_solve_distributed(case, disc, exact, &positions, solver, timer);
    }
    let (matrix, rhs, sectors, unbalanced, multipliers) = timer.run(stage::ASSEMBLY, || {
        let (m, rhs) = System { case, disc, exact }.assemble()?;
        let (balances, unbalanced) = sector::balances(case, &disc.survey, (&disc.nodes, &disc.dofs), &m, exact);
        let border = sector::border(&balances);
        let (m, rhs) = if border.is_empty() { (m, rhs) } else { border.bordered(m, &rhs) };
        let note = match border.len() {
            0 => format!("{} unknowns, {} nonzeros", disc.dofs.len(), m.nnz()),
            k => format!("{} unknowns and {k} multipliers, {} nonzeros", disc.dofs.len(), m.nnz()),
        };
        Ok(((m, rhs, balances.iter().map(|b| b.summary()).collect(), unbalanced, border.len()), note))
    })?;
    disc.release_row_shapes();
    // The rows near singular corners, as assembled, for the defect estimate's
    // higher-degree truncation error there ([`super::corner_defect`]).
    let corner_rows = if defect && !disc.share.is_split() {
        CornerRows::of(disc, &crate::physics::case::singular_corners(case, &disc.nodes), &matrix)
    } else {
        None
    };
    let nonzeros = matrix.nnz();
    let watch = SolveProgress(timer.progress());
    let (x, multipliers, report, kept, retained) = timer.run(stage::SOLVE, || {
        let layout = Some(linalg::NodeLayout { per_node: disc.dofs.unknowns().per_node(), positions: &positions, multipliers });
        let requested = disc.supports.requested();
        let disc_for_aux = &mut *disc;
        let auxiliary: linalg::Auxiliary = params.multigrid.low_order(requested).then(|| {
            let approximation = low_order::approximation(&params.approximation, params.fill.kind);
            Box::new(move || low_order::rows(case, disc_for_aux, exact, &approximation)) as Box<dyn FnOnce() -> Result<linalg::Csr, String>>
        });
        // Handed over unless kept: the solver frees it once it holds its own form. The
        // `defect` estimate keeps the solver (its rows and factors or preconditioner)
        // for its correction.
        let solve = |a: Cow<'_, linalg::Csr>| {
            if defect {
                linalg::solve_nodal_retained(a, &rhs, solver, layout, auxiliary, &watch)
            } else {
                linalg::solve_nodal(a, &rhs, solver, layout, auxiliary, &watch).map(|(x, report)| (x, report, None))
            }
        };
        let ((mut x, report, retained), kept) =
            if keep { (solve(Cow::Borrowed(&matrix))?, Some(matrix)) } else { (solve(Cow::Owned(matrix))?, None) };
        // The multipliers of the balances are not unknowns of the field.
        let lambda = x.split_off(x.len() - multipliers);
        let note = format!("{}: {} iterations, relative residual {:.1e}", report.method, report.iterations, report.relative_residual);
        Ok(((x, lambda, report, kept, retained), note))
    })?;
    let progress = timer.progress();
    let correction = defect.then(|| {
        timer.run(ESTIMATE, || {
            let t0 = Instant::now();
            let c = match &retained {
                Some(solver) => correct(case, disc, params, solver, (&x, corner_rows.as_ref()), progress),
                None => Err("the solve left no solver to reuse".to_string()),
            };
            let note = match &c {
                Ok(c) if !c.corner_gradients.is_empty() => {
                    format!("{} fit centres, {} nodes near singular corners; correction: {}", c.fits.centres(), c.corner_gradients.len(), c.solve)
                }
                Ok(c) => format!("{} fit centres; correction: {}", c.fits.centres(), c.solve),
                Err(why) => format!("unavailable: {why}"),
            };
            Ok((c.map(|c| Correction { seconds: t0.elapsed().as_secs_f64(), ..c }), note))
        })
    });
    drop(retained);
    let correction = correction.transpose()?;
    let system = kept.filter(|_| keep).map(|matrix| (linalg::csr::columns_of(matrix), rhs));
    Ok(Solved { x, multipliers, nonzeros, report, system, sectors, unbalanced, correction })
}

/// [`assemble_and_solve`] over MPI ranks: each rank writes the rows of the nodes it
/// owns and PETSc solves them together ([`Share::solve`](crate::parallel::share::Share::solve)); the system is not
/// kept (no rank holds it whole).
fn assemble_and_solve_distributed(
    case: &Case,
    disc: &mut Discretisation,
    exact: Option<&dyn ExactSolution>,
    positions: &[[f64; 2]],
    solver: &SolverParams,
    timer: &mut StageTimer,
) -> Result<Solved, RunError> {
    let dofs = disc.dofs;
    let (rows, rhs) = timer.run(stage::ASSEMBLY, || {
        let (m, rhs) = agree(System { case, disc, exact }.assemble())?;
        let note = format!("{} unknowns, {} entries in this rank's rows", dofs.len(), m.nnz());
        Ok(((m, rhs), note))
    })?;
    disc.release_row_shapes();
    let (x, report) = timer.run(stage::SOLVE, || {
        let (x, report) = disc.share.solve(dofs.unknowns().per_node(), rows.entries(), &rhs, positions, solver)?;
        let note = format!("{}: {} iterations, relative residual {:.1e}", report.method, report.iterations, report.relative_residual);
        Ok(((x, report), note))
    })?;
    let nonzeros = report.ranks.as_ref().map_or(0, |r| r.nonzeros.iter().sum());
    let unbalanced = disc.survey.none_balanced("its rows are split over MPI ranks (solver.kind = \"petsc\")");
    Ok(Solved { x, multipliers: Vec::new(), nonzeros, report, system: None, sectors: Vec::new(), unbalanced, correction: None })
}

/// The `defect` correction of the run `x` of `disc` ([`defect`]): fits of `x`, the
/// truncation error `D tau` of the rows the run solved (`D A`, kept with their
/// factors or preconditioner in `solver`), and `e = -(D A)^-1 D tau` by `solver` to
/// [`defect::CORRECTION_TOLERANCE`]: no second factorisation or multigrid. Near
/// singular corners (`corner_rows`) `tau` is `(A - A_H) x` and the correction's
/// operator takes the higher-degree rows `A_H` there ([`super::corner_defect`]).
/// `progress` is told the fits made, then the residual digits of the solve.
fn correct(
    case: &Case,
    disc: &mut Discretisation,
    params: &NavierParams,
    solver: &linalg::Retained,
    (x, corner_rows): (&[f64], Option<&CornerRows>),
    progress: &dyn Progress,
) -> Result<Correction, String> {
    let p = params.approximation.basis.polynomial_degree();
    let fits = defect::Fits::of(disc, x, p, &|k, n| progress.advance(k as u64, n as u64, "fit centres"))?;
    // The solved rows: held by the solver, or made once from its columns and kept
    // for `solve_replaced`.
    let solved = solver.rows();
    let mut rhs = defect::truncation_error(disc, solved, &fits);
    let (mut corner_gradients, mut replaced) = (Vec::new(), Vec::new());
    if let Some(rows) = corner_rows {
        let approximation = super::estimate::reference_approximation(&params.approximation, params.fill.kind, disc.nodes.len())?;
        let measured = rows.measure(case, disc, &approximation, solved, x)?;
        for &(r, t) in &measured.tau {
            rhs[r] = t;
        }
        (corner_gradients, replaced) = (measured.gradients, measured.rows);
    }
    rhs.iter_mut().for_each(|t| *t = -*t);
    let (mut e, solve) = solver
        .solve_replaced(&rhs, &replaced, defect::CORRECTION_TOLERANCE, &SolveProgress(progress))
        .map_err(|err| format!("the correction's solve failed: {err}"))?;
    e.truncate(disc.dofs.len());
    Ok(Correction { e, fits, corner_gradients, solve, seconds: 0.0 })
}

/// The `defect` estimate of the run `(x, displacement, stress)` from its `correction`
/// (`stress` made from `disc`'s gradient shapes, in place): the reference is `x - e`
/// and its stress `G (x - e) - tau_G` ([`defect`]).
fn defect_estimate(
    case: &Case,
    disc: &Discretisation,
    x: &[f64],
    (displacement, stress): (&[[f64; 2]], Option<&StressField>),
    correction: Result<Correction, String>,
) -> Estimate {
    let t0 = Instant::now();
    let c = match correction {
        Ok(c) => c,
        Err(why) => return Estimate::Unavailable(EstimateMethod::Defect.name(), why),
    };
    let n = disc.nodes.len();
    let reference_x: Vec<f64> = x.iter().zip(&c.e).map(|(x, e)| x - e).collect();
    let sigma = stress.map(|_| {
        let mut g = disc.gradients(&reference_x);
        let mut tau = defect::gradient_truncation_error(disc, &c.fits);
        for &(i, high) in &c.corner_gradients {
            let own = disc.gradient_at(i, x);
            tau[i] = std::array::from_fn(|r| std::array::from_fn(|d| own[r][d] - high[r][d]));
        }
        for (g, t) in g.iter_mut().zip(tau) {
            for (gc, tc) in g.iter_mut().zip(t) {
                gc[0] -= tc[0];
                gc[1] -= tc[1];
            }
        }
        disc.stress(&case.material, &g, &reference_x).sigma
    });
    let reference = ExactFields { displacement: disc.dofs.displacements(&reference_x, n), stress: sigma };
    let q = c.fits.exact_degree + 2;
    let corners = match c.corner_gradients.len() {
        0 => String::new(),
        k => format!(", the higher-degree operator's rows at {k} nodes near singular corners"),
    };
    let description = format!("fits of degree {q} at {} centres{corners}; the run's operator ({})", c.fits.centres(), c.solve);
    let mut e = ErrorEstimate::between(EstimateMethod::Defect, description, &disc.nodes.positions, displacement, stress, &reference, t0);
    e.reference_degree = q;
    e.seconds += c.seconds;
    Estimate::Done(Box::new(e))
}
