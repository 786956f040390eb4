//! How far a converged Krylov iterate may still be from the solution of its linear
//! system: a residual of 1e-10 bounds nothing by itself (the error is `A⁻¹ r`, and
//! `‖A⁻¹‖` is large for collocation matrices). The correction `δ ≈ A⁻¹ r` is
//! approximated by right-preconditioned GMRES on `A δ = r` from zero to half a
//! decade, with the preconditioner the solve already built (a few iterations more),
//! and reported relative to the displacement: `max |δ_u| / max |x_u|`
//! over the displacement unknowns. It is not added to the solution: the report is of
//! the solution returned.

use super::{gmres, NodeLayout};

/// Most steps of GMRES on the residual equation.
pub const STEPS: usize = 30;

/// Reduction of the residual equation's residual at which the correction stops: half
/// a decade came close to the true distance to the system's solution on the scenes
/// tried, one step cheaper than a full decade, and costs a few steps at 1e6 nodes
/// (docs/notebook/2026-11-27-solver-own-error.md).
pub const REDUCTION: f64 = 0.3;

/// `δ ≈ A⁻¹ r`: right-preconditioned GMRES on `A δ = r` from zero until its residual
/// falls by [`REDUCTION`] or [`STEPS`] steps, `A` given by its product `apply(x, y)`:
/// `y ← A x`.
pub fn correction(apply: impl Fn(&[f64], &mut [f64]), r: &[f64], precondition: impl Fn(&[f64], &mut [f64])) -> Vec<f64> {
    gmres::solve_gmres_with(apply, r, precondition, (REDUCTION, STEPS, STEPS, gmres::STAGNATION), &()).x
}

/// `max |δ_k| / max |x_k|` over the displacement unknowns `k` (the first two of each
/// node's, `layout`; every unknown without one): the solver's error relative to the
/// largest displacement, the normalisation of `e_inf(u)`.
pub fn relative_to_displacement(delta: &[f64], x: &[f64], layout: Option<&NodeLayout>) -> f64 {
    let displacement = |k: usize| match layout {
        Some(l) => k < x.len() - l.multipliers && k % l.per_node < 2,
        None => true,
    };
    let (mut d, mut u) = (0.0f64, 0.0f64);
    for k in (0..x.len()).filter(|&k| displacement(k)) {
        d = d.max(delta[k].abs());
        u = u.max(x[k].abs());
    }
    if u > 0.0 {
        d / u
    } else {
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// With an exact preconditioner one step recovers the error `x* − x` exactly, and
    /// only the displacement unknowns count: a pressure (third of each node's three)
    /// and a trailing multiplier with large corrections leave the measure unchanged.
    #[test]
    fn the_correction_is_the_error_and_only_displacements_count() {
        let diagonal = [2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 1.0];
        let exact = [1.0, -2.0, 5.0, 0.5, 0.25, 7.0, 9.0];
        let x = [1.0 + 1e-6, -2.0, 5.0 + 3.0, 0.5, 0.25 - 2e-6, 7.0 - 4.0, 9.0 + 100.0];
        let r: Vec<f64> = (0..7).map(|k| diagonal[k] * (exact[k] - x[k])).collect();
        let apply = |v: &[f64], y: &mut [f64]| y.iter_mut().zip(v).zip(&diagonal).for_each(|((y, v), d)| *y = d * v);
        let inverse = |v: &[f64], z: &mut [f64]| z.iter_mut().zip(v).zip(&diagonal).for_each(|((z, v), d)| *z = v / d);
        let delta = correction(apply, &r, inverse);
        for k in 0..7 {
            assert!((delta[k] - (exact[k] - x[k])).abs() < 1e-12 * (1.0 + (exact[k] - x[k]).abs()), "{k}: {delta:?}");
        }
        // Nodes of (u_x, u_y, p): 0, 1 | 3, 4 are displacements; 2, 5 pressures; 6 a multiplier.
        let layout = NodeLayout { per_node: 3, positions: &[[0.0, 0.0]; 2], multipliers: 1 };
        let largest_u = [x[0], x[1], x[3], x[4]].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let measured = relative_to_displacement(&delta, &x, Some(&layout));
        assert!((measured - 2e-6 / largest_u).abs() < 1e-12, "{measured:e}");
        assert!(relative_to_displacement(&delta, &x, None) > 0.9, "without a layout every unknown counts");
    }
}
