//! The checks of a peridynamic run: a horizon spanning too few nodes (`m < 3`), the
//! estimated discretisation error at its horizon (a warning above the threshold, as for
//! a Navier run), and the `local-model` estimate (a note above the threshold: the model
//! difference of the horizon; a Navier reference too coarse to judge it is warned).

use super::{exceeds, linear_solve, unestimated, Checks, Warning};
use crate::models::navier::Estimate;
use crate::models::peridynamics::solve::DiscretisationEstimate;
use crate::models::peridynamics::PdSolution;

/// Horizon-to-spacing ratio `m = delta / h` below which the bond-based quadrature
/// is too coarse to approximate the nonlocal integral: the error no longer falls with
/// the horizon (docs/guide/estimate-and-warnings.md, "Outcomes at the extremes").
pub const PD_MIN_RATIO: f64 = 3.0;

/// In-plane `lambda / mu` above which a linear peridynamic solid is warned as near
/// incompressible (`nu > 0.495` in plane strain): with no pressure unknown its error at
/// coarse horizons grows with `lambda / mu` and the iterative solve slows, then fails
/// (pd_manufactured, docs/methods/peridynamics.md, "Any Poisson ratio").
pub const PD_LAMBDA_OVER_MU: f64 = 100.0;

/// The warning of a peridynamic run on a near-incompressible material
/// (`lambda / mu` above [`PD_LAMBDA_OVER_MU`]), if it is one.
pub fn near_incompressible(material: &crate::physics::elasticity::material::Material) -> Option<Warning> {
    let l = material.lame();
    let ratio = l.lambda / l.mu;
    (ratio > PD_LAMBDA_OVER_MU).then(|| Warning {
        check: "pd-near-incompressible",
        message: format!(
            "nu = {} gives lambda / mu = {ratio:.0} (above {PD_LAMBDA_OVER_MU}): the peridynamic solid has no pressure unknown, so its \
             error at coarse horizons grows with lambda / mu (pd_manufactured at nu = 0.49999: 0.63 at delta = 0.2, 1.1e-3 at \
             0.025) and GMRES + AMG slows, then fails (nu >= 0.4999); use a smaller horizon, [peridynamics.solver] kind = \"lu\", \
             or --model navier (u-p formulation)",
            material.elastic.poisson
        ),
    })
}

/// The checks of a static peridynamic run: `m < 3` is warned (a discretisation that
/// cannot approximate the nonlocal integral), and the `local-model` estimate is read by
/// [`estimate_of_peridynamics`]. The difference to an exact *local* solution is a
/// note, not a warning: at `m >= 3` it is mostly the model difference of the finite
/// horizon, which the user chose.
pub fn peridynamics_static(sol: &PdSolution, estimate: &Estimate, threshold: f64) -> Checks {
    let mut checks = Checks { warnings: linear_solve(&sol.solver), ..Checks::default() };
    let m = sol.params.ratio;
    if m < PD_MIN_RATIO {
        checks.warnings.push(Warning {
            check: "pd-horizon-ratio",
            message: format!(
                "peridynamics.m = {m} is below {PD_MIN_RATIO}: a horizon spans too few nodes for the bond quadrature, \
                 and errors of order 0.1 to 0.5 are to be expected whatever the horizon (docs/guide/estimate-and-warnings.md, \"Outcomes at the extremes\"); \
                 use m >= 3"
            ),
        });
    }
    if sol.cut_bonds > 0 {
        checks.warnings.push(Warning {
            check: "pd-reentrant-corner",
            message: format!(
                "{} bonds were not made because they would read fictitious nodes across a re-entrant corner (or a hole narrower \
                 than the horizon band): the peridynamic solution does not converge to the local one there (the bracket differs \
                 by 1.5-4.5 % at horizons 7e-3 to 1.75e-3, and by 63 % without its holes at 8e-3: docs/limits.md); compare it \
                 with --model navier",
                sol.cut_bonds
            ),
        });
    }
    if let Some(e) = sol.errors.map(|e| e.0).filter(|e| exceeds(e.e_inf_u, threshold)) {
        checks.notes.push(format!(
            "the nonlocal solution differs from the exact local one by e_inf(u) = {:.2e} (above {threshold:.0e}); \
             at m >= 3 this is mostly the model difference of the horizon {:.3e}, which shrinks with it",
            e.e_inf_u, sol.params.horizon
        ));
    }
    // With an exact solution, its note above says what the estimate's would.
    estimate_of_peridynamics(estimate, threshold, sol.params.horizon, sol.errors.is_none(), &mut checks);
    discretisation(sol.discretisation.as_ref(), (sol.params.horizon, sol.params.ratio), threshold, &mut checks);
    checks
}

/// The estimated discretisation error at a static or dynamic peridynamic run's horizon
/// (with its `m`, `ratio`) above `threshold` is warned
/// (`pd-discretisation`), like a Navier run's estimate: the run is not resolved at its
/// own horizon, whatever its difference to the local model. An estimate that failed is
/// warned (`no-discretisation-estimate`).
pub fn discretisation(
    estimate: Option<&Result<DiscretisationEstimate, String>>,
    (horizon, ratio): (f64, f64),
    threshold: f64,
    checks: &mut Checks,
) {
    match estimate {
        Some(Ok(d)) if exceeds(d.e_inf_u, threshold) => checks.warnings.push(Warning {
            check: "pd-discretisation",
            message: format!(
                "the discretisation error at the horizon {:.3e} is estimated at e_inf(u) ~ {:.1e} (largest at ({:.4e}, {:.4e})), above \
                 the threshold {threshold:.0e}: the run is not resolved at its own horizon ({}); use a larger peridynamics.m (now {}) \
                 at this horizon",
                horizon, d.e_inf_u, d.largest_at[0], d.largest_at[1], d.reference, ratio
            ),
        }),
        Some(Err(why)) => checks.warnings.push(Warning {
            check: "no-discretisation-estimate",
            message: format!("the discretisation error at this horizon could not be estimated: {why}"),
        }),
        _ => {}
    }
}

/// How much closer to the local solution than the peridynamic run the Navier reference
/// of a `local-model` estimate must be (by its own estimate) for the estimate to be
/// trusted: its own estimate misses the interpolation to the peridynamic nodes and may
/// itself be low on coarse nodes (pd_manufactured, Navier spacing 0.1, delta = 0.05:
/// own estimate 3.8e-4, estimate 1.9e-3 against a true 9.3e-4; a margin of 3 let it
/// pass).
pub const LOCAL_REFERENCE_MARGIN: f64 = 10.0;

/// The checks of a peridynamic run's `local-model` estimate: above `threshold` a note
/// when `note_above` (the model difference of the horizon, like the exact error); a Navier reference
/// whose own estimated error is not [`LOCAL_REFERENCE_MARGIN`] times below the
/// estimate is warned (`estimate-reference`); no estimate is warned (`no-estimate`).
pub(super) fn estimate_of_peridynamics(estimate: &Estimate, threshold: f64, horizon: f64, note_above: bool, checks: &mut Checks) {
    let Some(e) = unestimated(estimate, checks) else { return };
    let est = e.norms.e_inf_u;
    if note_above && exceeds(est, threshold) {
        checks.notes.push(format!(
            "the nonlocal solution is estimated to differ from the local model by e_inf(u) ~ {est:.1e} (above {threshold:.0e}, \
             largest at ({:.4e}, {:.4e})); at m >= 3 this is mostly the model difference of the horizon {horizon:.3e}, which shrinks with it",
            e.largest_u_at[0], e.largest_u_at[1]
        ));
    }
    if let Some(own) = e.reference_estimated_e_inf_u.filter(|own| exceeds(own * LOCAL_REFERENCE_MARGIN, est)) {
        checks.warnings.push(Warning {
            check: "estimate-reference",
            message: format!(
                "the local-model estimate e_inf(u) ~ {est:.1e} is uncertain: the Navier reference's own estimated error is {own:.1e}, \
                 not {LOCAL_REFERENCE_MARGIN} times smaller; refine the Navier nodes (nodes.spacing) for a better reference"
            ),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::elasticity::material::{Material, PlaneModel, YoungPoisson};

    /// `lambda / mu = 2 nu / (1 - 2 nu)` in plane strain passes 100 just above nu = 0.495;
    /// plane stress never comes near it (`lambda* / mu = 2 nu / (1 - nu)` <= 2).
    #[test]
    fn near_incompressible_solids_are_warned_in_plane_strain_only() {
        let mat = |nu, plane| Material { elastic: YoungPoisson { young: 1.0, poisson: nu }, plane };
        assert!(near_incompressible(&mat(0.499, PlaneModel::Strain)).is_some_and(|w| w.check == "pd-near-incompressible"));
        assert!(near_incompressible(&mat(0.494, PlaneModel::Strain)).is_none());
        assert!(near_incompressible(&mat(0.4999, PlaneModel::Stress)).is_none());
    }
}
