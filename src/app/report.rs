//! The terminal summary `mlsm run` prints (stdout) after its results are written: the
//! sizes, the solver, the errors and the estimate, the probes, the largest
//! displacement and stress, and a dynamic run's step and energies.

use super::extremes::Extremes;
use super::number::plain;
use super::summary::{stability_limit, Dynamic};
use crate::scene::choice::Choice;
use crate::models::dynamics::driver::DynamicReport;
use crate::models::navier::Estimate;
use crate::quality::post::probe::ProbeValue;
use crate::quality::warnings;
use std::path::Path;

/// The result of a static Navier run.
pub(super) fn print_navier(sol: &crate::models::navier::Solution, extremes: Option<&Extremes>) {
    println!("nodes {}  unknowns {} ({})  nonzeros {}", sol.nodes.len(), sol.unknowns, sol.formulation.name(), sol.nonzeros);
    print!("solver {}: {} iterations, relative residual {:.2e}", sol.solver.method, sol.solver.iterations, sol.solver.relative_residual);
    match sol.solver.solver_error {
        Some(e) => println!(", own error ~{e:.1e} of max |u|"),
        None => println!(),
    }
    if let Some(why) = &sol.solver.choice {
        println!("  ({why})");
    }
    if let Some(e) = &sol.errors {
        print!("e_inf(u) = {:.4e}  rel_l2(u) = {:.4e}", e.e_inf_u, e.rel_l2_u);
        if let Some(s) = e.e_inf_sigma {
            print!("  e_inf(sigma) = {s:.4e}");
        }
        println!();
    }
    print_estimate(&sol.estimate);
    print_extremes(extremes);
    print_probes(&sol.probes);
    if let Some(q) = &sol.equilibrium {
        println!(
            "equilibrium: reactions ({:.3e}, {:.3e}) + loads ({:.3e}, {:.3e}) + body ({:.3e}, {:.3e}), relative imbalance {:.1e}",
            q.reactions[0], q.reactions[1], q.applied[0], q.applied[1], q.body[0], q.body[1], q.relative
        );
    }
}

/// The result of a static peridynamic run.
pub(super) fn print_pd(sol: &crate::models::peridynamics::PdSolution, extremes: Option<&Extremes>) {
    println!(
        "nodes {} (+{} constrained)  bonds {}  unknowns {}  nonzeros {}",
        sol.nodes.free,
        sol.nodes.constrained(),
        sol.bonds,
        sol.unknowns,
        sol.nonzeros
    );
    println!("solver {}: relative residual {:.2e}", sol.solver.method, sol.solver.relative_residual);
    if let Some((w, i)) = &sol.errors {
        print!("e_inf(u) = {:.4e}  rel_l2(u) = {:.4e}", w.e_inf_u, w.rel_l2_u);
        if let Some(i) = i {
            print!("  interior: e_inf(u) = {:.4e}  rel_l2(u) = {:.4e}", i.e_inf_u, i.rel_l2_u);
        }
        println!();
    }
    // The run's own error at its horizon (what warns), apart from its difference to
    // the local model ([`print_estimate`]).
    match &sol.discretisation {
        Some(Ok(d)) => println!(
            "estimated (discretisation at this horizon): e_inf(u) ~ {:.2e}  rel_l2(u) ~ {:.2e}  ({}: {})",
            d.e_inf_u, d.rel_l2_u, d.method, d.reference
        ),
        Some(Err(why)) => println!("estimated (discretisation at this horizon): unavailable ({why})"),
        None => {}
    }
    print_extremes(extremes);
    print_probes(&sol.probes);
}

/// The result of a time-dependent run written to `dir`: the step against its
/// stability limit, the energies, the cost, the final state's extremes, the estimate.
pub(super) fn print_dynamic(d: &Dynamic, loads_depend_on_time: bool, dir: &Path) {
    let (e0, e1) = (d.energies[0], d.energies.last().expect("recorded"));
    let r = d.report;
    println!("nodes {}  steps {}  {}", d.nodes, r.steps, time_step_line(r));
    // The drift as the energy-drift check measures it (relative to the largest
    // energies of the run, so a run starting at rest has a scale too); none when
    // the loads do work.
    let drift = if loads_depend_on_time {
        "total not conserved: the loads depend on t".to_string()
    } else {
        format!("total drift {:.2e} of its scale", warnings::energy_drift(d.energies))
    };
    println!("energy at t = 0: kinetic {:.6e}; at t = {:.3e}: kinetic {:.6e}, elastic {:.6e}; {drift}", e0[1], e1[0], e1[1], e1[2]);
    let per = r.seconds / r.steps.max(1) as f64 / d.nodes.max(1) as f64;
    println!("{per:.2e} s per step per node; written: {}", dir.display());
    print_extremes(d.extremes.as_ref());
    print_estimate(d.estimate);
}

/// The step used against the stability limit of the run's scheme, e.g. `time step
/// 7.519e-6 s <= 9.412e-6 s, the rk4 stability limit (0.80 of it; sqrt 2 x the
/// central-difference limit 6.655e-6 s)`; a step over the limit says so.
pub(super) fn time_step_line(r: &DynamicReport) -> String {
    let limit = stability_limit(r);
    let fraction = r.time_step / limit;
    let scheme = r.integrator.name();
    let relation = if r.time_step <= limit { "<=" } else { ">" };
    let mut line = format!("time step {:.3e} s {relation} {limit:.3e} s, the {scheme} stability limit ({fraction:.2} of it", r.time_step);
    let factor = r.integrator.stability_factor();
    if factor != 1.0 {
        let name = if factor == 2f64.sqrt() { "sqrt 2".to_string() } else { plain(factor) };
        line.push_str(&format!("; {name} x the central-difference limit {:.3e} s", r.stable_time_step));
    }
    line.push(')');
    if r.time_step > limit {
        line.push_str(": OVER the stability limit, the run may blow up");
    }
    line
}

/// The extremes line, when there are extremes.
fn print_extremes(extremes: Option<&Extremes>) {
    if let Some(e) = extremes {
        println!("{}", e.line());
    }
}

/// The estimated errors, the method, its reference and cost (or why there are none).
pub(super) fn print_estimate(estimate: &Estimate) {
    match estimate {
        Estimate::Done(e) => {
            // A peridynamic run's difference to the local model is the horizon's model
            // difference (its convergence in delta is `mlsm compare`'s result), not its
            // error: its own estimate is the discretisation line of [`print_pd`].
            let label = if e.method == "local-model" { "difference to the local model" } else { "estimated" };
            print!("{label}: e_inf(u) ~ {:.2e}", e.norms.e_inf_u);
            if let Some(t) = e.largest_u_time {
                print!(" (largest at t = {t:.3e} s)");
            }
            print!("  rel_l2(u) ~ {:.2e}", e.norms.rel_l2_u);
            if let Some(s) = e.norms.e_inf_sigma {
                print!("  e_inf(sigma) ~ {s:.2e}");
            }
            println!("  ({}: {}; {:.2} s)", e.method, e.reference, e.seconds);
        }
        Estimate::Unavailable(method, why) => println!("estimated: unavailable ({method}: {why})"),
        Estimate::Off => println!("estimated: off (estimate.method = \"none\")"),
    }
}

/// One line per probe: its value, and its exact value and error where known.
fn print_probes(probes: &[ProbeValue]) {
    for p in probes {
        print!("probe {} ({} at [{}, {}]) = {:.6e}", p.name, p.quantity.name(), p.at[0], p.at[1], p.value);
        if let Some(e) = p.exact {
            print!("  exact {e:.6e}, relative error {:.2e}", (p.value - e).abs() / e.abs().max(f64::MIN_POSITIVE));
        }
        println!();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::dynamics::Integrator;

    fn report(integrator: Integrator, time_step: f64) -> DynamicReport {
        DynamicReport { integrator, time_step, stable_time_step: 6.655e-6, steps: 133, force_evaluations: 1, seconds: 0.1, median_step_seconds: 1e-3 }
    }

    /// The step is printed against its own scheme's limit, never against a smaller
    /// number that reads as a limit it exceeds (issue 50: `dt 7.5e-6 s (stable 6.7e-6 s)`).
    #[test]
    fn the_time_step_is_shown_against_its_schemes_limit() {
        let rk4 = time_step_line(&report(Integrator::Rk4, 7.519e-6));
        assert_eq!(
            rk4,
            "time step 7.519e-6 s <= 9.412e-6 s, the rk4 stability limit (0.80 of it; sqrt 2 x the central-difference limit 6.655e-6 s)"
        );
        let verlet = time_step_line(&report(Integrator::Verlet, 5.324e-6));
        assert_eq!(verlet, "time step 5.324e-6 s <= 6.655e-6 s, the verlet stability limit (0.80 of it)");
        let over = time_step_line(&report(Integrator::Verlet, 7e-6));
        assert!(over.starts_with("time step 7.000e-6 s > 6.655e-6 s") && over.contains("OVER the stability limit"), "{over}");
    }
}
