//! Error norms against an exact solution (verification.md, "Error norms"):
//! `e_inf(u) = max_{i,c} |u_h - u| / max_{i,c} |u|`, the same for the stress
//! components `(sigma_xx, sigma_yy, sigma_xy)`, and discrete relative L2 norms
//! `sqrt(sum |u_h - u|^2 / sum |u|^2)` over the nodes; [`probe`]: point values a
//! scene asks for; [`richardson`]: extrapolation over refinement levels with an
//! error bar.

pub mod probe;
pub mod richardson;

use crate::domain::Point;
use crate::physics::elasticity::stress::StressField;
use crate::physics::exact::ExactSolution;
use rayon::prelude::*;
use serde::Serialize;

/// The exact displacement (and stress, when asked for) at a set of points.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactFields {
    /// `u(x_i)`.
    pub displacement: Vec<[f64; 2]>,
    /// `[sigma_xx, sigma_yy, sigma_xy](x_i)`.
    pub stress: Option<Vec<[f64; 3]>>,
}

impl ExactFields {
    /// `exact` evaluated at `points` (in parallel).
    pub fn at(exact: &dyn ExactSolution, points: &[Point], with_stress: bool) -> Self {
        let displacement = points.par_iter().map(|p| exact.displacement(*p)).collect();
        let stress = with_stress.then(|| points.par_iter().map(|p| exact.stress(*p)).collect());
        ExactFields { displacement, stress }
    }
}

/// Errors of one run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ErrorNorms {
    /// Relative max-norm error of the displacement.
    pub e_inf_u: f64,
    /// Relative max-norm error of the stress components.
    pub e_inf_sigma: Option<f64>,
    /// Relative discrete L2 error of the displacement.
    pub rel_l2_u: f64,
    /// Relative discrete L2 error of the stress components.
    pub rel_l2_sigma: Option<f64>,
}

impl ErrorNorms {
    /// Norms of `displacement` and, where both exist, of `stress` against `exact`.
    pub fn against(displacement: &[[f64; 2]], stress: Option<&StressField>, exact: &ExactFields) -> Self {
        let (e_inf_u, rel_l2_u) = relative_errors(displacement, &exact.displacement);
        let sigma = match (stress, &exact.stress) {
            (Some(s), Some(se)) => Some(relative_errors(&s.sigma, se)),
            _ => None,
        };
        ErrorNorms { e_inf_u, e_inf_sigma: sigma.map(|s| s.0), rel_l2_u, rel_l2_sigma: sigma.map(|s| s.1) }
    }
}

/// `(max |a - b| / max |b|, sqrt(sum |a - b|^2 / sum |b|^2))` over all components;
/// 0 when `a == b` (also when both vanish), infinite when only `b` vanishes.
pub fn relative_errors<const K: usize>(numerical: &[[f64; K]], exact: &[[f64; K]]) -> (f64, f64) {
    // Sums of squares are taken relative to the largest entry, so that fields near
    // the ends of the double range (loads of 1e300 or 1e-300) neither overflow nor
    // underflow.
    let pairs = || numerical.iter().zip(exact).flat_map(|(a, b)| (0..K).map(move |k| ((a[k] - b[k]).abs(), b[k].abs())));
    let (max_d, max_e) = pairs().fold((0.0f64, 0.0f64), |(md, me), (d, e)| (md.max(d), me.max(e)));
    let unit = if max_e > 0.0 && max_e.is_finite() { max_e } else { 1.0 };
    let (sum_d, sum_e) = pairs().fold((0.0, 0.0), |(sd, se), (d, e)| (sd + (d / unit).powi(2), se + (e / unit).powi(2)));
    // Both zero (a zero solution reproduced exactly): no error, not 0/0.
    let ratio = |d: f64, e: f64| if d == 0.0 { 0.0 } else { d / e };
    (ratio(max_d, max_e), ratio(sum_d, sum_e).sqrt())
}

/// Displacement error norms over the entries `i < reference.len()` selected by `keep`
/// (`None` when none is selected); stress norms are left empty.
pub fn masked_errors(u: &[[f64; 2]], reference: &[[f64; 2]], keep: impl Fn(usize) -> bool) -> Option<ErrorNorms> {
    let (a, b): (Vec<[f64; 2]>, Vec<[f64; 2]>) = (0..reference.len()).filter(|&i| keep(i)).map(|i| (u[i], reference[i])).unzip();
    (!a.is_empty()).then(|| {
        let (e_inf_u, rel_l2_u) = relative_errors(&a, &b);
        ErrorNorms { e_inf_u, e_inf_sigma: None, rel_l2_u, rel_l2_sigma: None }
    })
}

/// Least-squares slope of `log e` against `log h`: the observed order of convergence.
pub fn observed_order(h: &[f64], e: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = h.iter().zip(e).filter(|(h, e)| **h > 0.0 && **e > 0.0).map(|(h, e)| (h.ln(), e.ln())).collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_power_law() {
        let h = [0.1, 0.05, 0.025];
        let e: Vec<f64> = h.iter().map(|h: &f64| 3.0 * h.powf(2.5)).collect();
        assert!((observed_order(&h, &e).unwrap() - 2.5).abs() < 1e-12);
    }

    #[test]
    fn relative_errors_scale_free() {
        let (i, l) = relative_errors(&[[1.1, 0.0], [2.0, 0.0]], &[[1.0, 0.0], [2.0, 0.0]]);
        assert!((i - 0.05).abs() < 1e-15);
        assert!((l - (0.01f64 / 5.0).sqrt()).abs() < 1e-15);
    }
}
