//! Richardson extrapolation of a scalar over refinement levels, with an error bar by
//! Roache's grid convergence index (GCI), following the three-level procedure of
//! Celik et al., "Procedure for estimation and reporting of uncertainty due to
//! discretization in CFD applications", J. Fluids Eng. 130 (2008) 078001.
//!
//! With `phi_1, phi_2, phi_3` on the finest, middle and coarsest levels (spacings
//! `h_1 < h_2 < h_3`, ratios `r_21 = h_2 / h_1`, `r_32 = h_3 / h_2`) and the differences
//! `e_21 = phi_2 - phi_1`, `e_32 = phi_3 - phi_2`:
//! - the observed order solves `p = |ln|e_32 / e_21| + q(p)| / ln r_21` with
//!   `q(p) = ln((r_21^p - s) / (r_32^p - s))`, `s = sign(e_32 / e_21)`;
//! - the extrapolated value is `phi_ext = phi_1 - e_21 / (r_21^p - 1)`;
//! - the error bar of the finest value is `GCI = F_s |e_21| / (r_21^p - 1)` with the
//!   factor of safety `F_s = 1.25` (three levels), and `3` with the formal order when
//!   only two levels exist.
//!
//! Guarded where the procedure breaks: oscillating differences (`s < 0`) give no
//! extrapolation and the range `max(|e_21|, |e_32|)` as error bar; growing
//! differences (`|e_21| >= |e_32|`) are reported as not converging, with the same
//! range; an observed order above `formal + 1` is capped there (a higher order on
//! three levels is more likely luck than a property of the scheme). With four or
//! more levels the triple before the last is checked too: if it is not monotone, or
//! its observed order differs from the last triple's by more than a factor 2, the
//! convergence is erratic (least squares on scattered nodes: three monotone levels
//! whose extrapolation missed the exact value by more than two error bars;
//! docs/verification.md, "Convergence studies"), and the range of the last three
//! levels is the error bar, not extrapolated.

use serde::Serialize;

/// How the values behave over the last three levels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Behaviour {
    /// Differences of one sign, shrinking: extrapolated with the observed order.
    Monotone,
    /// Differences of alternating sign: not extrapolated, the range is the error bar.
    Oscillating,
    /// Differences not shrinking: not extrapolated, the range is the error bar.
    NotConverging,
    /// The last triple is monotone but the one before disagrees: not extrapolated,
    /// the range is the error bar.
    Erratic,
    /// Two levels only: extrapolated with the formal order, factor of safety 3.
    TwoLevels,
    /// The last two values are equal: resolved to round-off.
    Resolved,
}

impl Behaviour {
    /// The name written in summaries.
    pub fn name(self) -> &'static str {
        match self {
            Behaviour::Monotone => "monotone",
            Behaviour::Oscillating => "oscillating",
            Behaviour::NotConverging => "not_converging",
            Behaviour::Erratic => "erratic",
            Behaviour::TwoLevels => "two_levels",
            Behaviour::Resolved => "resolved",
        }
    }
}

impl Serialize for Behaviour {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// An extrapolated value with its error bar.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Extrapolation {
    /// The best value: `phi_ext` (monotone, two levels), else the finest value.
    pub value: f64,
    /// Half-width of the interval around the finest value that the GCI claims holds
    /// the converged value.
    pub error_bar: f64,
    /// The observed order (three monotone levels), before the cap.
    pub observed_order: Option<f64>,
    /// The order used for the extrapolation.
    pub order_used: Option<f64>,
    /// How the values behave.
    pub behaviour: Behaviour,
}

/// Extrapolate `values` at spacings `h` (coarse to fine, at least two levels; the
/// last three are used) for a scheme of formal order `formal`.
pub fn extrapolate(h: &[f64], values: &[f64], formal: f64) -> Option<Extrapolation> {
    let n = h.len().min(values.len());
    if n < 2 {
        return None;
    }
    let (phi1, phi2) = (values[n - 1], values[n - 2]);
    let r21 = h[n - 2] / h[n - 1];
    let e21 = phi2 - phi1;
    if e21 == 0.0 {
        return Some(Extrapolation { value: phi1, error_bar: 0.0, observed_order: None, order_used: None, behaviour: Behaviour::Resolved });
    }
    if n == 2 {
        let p = formal;
        return Some(Extrapolation {
            value: phi1 - e21 / (r21.powf(p) - 1.0),
            error_bar: 3.0 * e21.abs() / (r21.powf(p) - 1.0),
            observed_order: None,
            order_used: Some(p),
            behaviour: Behaviour::TwoLevels,
        });
    }
    let phi3 = values[n - 3];
    let r32 = h[n - 3] / h[n - 2];
    let e32 = phi3 - phi2;
    let range = e21.abs().max(e32.abs());
    let unextrapolated = |behaviour| Extrapolation { value: phi1, error_bar: range, observed_order: None, order_used: None, behaviour };
    if e32 / e21 < 0.0 {
        return Some(unextrapolated(Behaviour::Oscillating));
    }
    if e21.abs() >= e32.abs() {
        return Some(unextrapolated(Behaviour::NotConverging));
    }
    let ratio = (e32 / e21).abs().ln();
    let mut p = ratio / r21.ln();
    for _ in 0..100 {
        let q = ((r21.powf(p) - 1.0) / (r32.powf(p) - 1.0)).ln();
        let next = (ratio + q).abs() / r21.ln();
        if (next - p).abs() <= 1e-12 * p.abs() {
            p = next;
            break;
        }
        p = next;
    }
    if n >= 4 {
        let before = extrapolate(&h[..n - 1], &values[..n - 1], formal).expect("three levels");
        let agrees = match (before.behaviour, before.observed_order) {
            (Behaviour::Monotone, Some(q)) => q / p <= 2.0 && p / q <= 2.0,
            (b, _) => b == Behaviour::Resolved,
        };
        if !agrees {
            return Some(unextrapolated(Behaviour::Erratic));
        }
    }
    let used = p.min(formal + 1.0);
    let denominator = r21.powf(used) - 1.0;
    Some(Extrapolation {
        value: phi1 - e21 / denominator,
        error_bar: 1.25 * e21.abs() / denominator,
        observed_order: Some(p),
        order_used: Some(used),
        behaviour: Behaviour::Monotone,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `phi(h) = 1 + 3 h^2` at unequal ratios: the observed order is 2 and the limit
    /// is found to round-off; the error bar covers the finest value's true error
    /// by the factor of safety 1.25.
    #[test]
    fn power_law_is_extrapolated_exactly() {
        let h = [0.1, 0.06, 0.025];
        let v: Vec<f64> = h.iter().map(|h| 1.0 + 3.0 * h * h).collect();
        let e = extrapolate(&h, &v, 2.0).unwrap();
        assert_eq!(e.behaviour, Behaviour::Monotone);
        assert!((e.observed_order.unwrap() - 2.0).abs() < 1e-8, "{:?}", e);
        assert!((e.value - 1.0).abs() < 1e-12, "{:?}", e);
        assert!((e.error_bar - 1.25 * 3.0 * 0.025f64.powi(2)).abs() < 1e-12, "{:?}", e);
    }

    /// A high observed order is capped at formal + 1: the bar is wider than the
    /// uncapped GCI would make it.
    #[test]
    fn high_orders_are_capped() {
        let h = [0.4, 0.2, 0.1];
        let v: Vec<f64> = h.iter().map(|h: &f64| 2.0 + h.powi(6)).collect();
        let e = extrapolate(&h, &v, 2.0).unwrap();
        assert!((e.observed_order.unwrap() - 6.0).abs() < 1e-8);
        assert_eq!(e.order_used, Some(3.0));
        assert!(e.error_bar > 1.25 * (v[2] - 2.0), "{:?}", e);
    }

    #[test]
    fn oscillating_growing_and_two_levels() {
        let osc = extrapolate(&[0.4, 0.2, 0.1], &[1.0, 1.2, 1.1], 2.0).unwrap();
        assert_eq!(osc.behaviour, Behaviour::Oscillating);
        assert!(osc.value == 1.1 && (osc.error_bar - 0.2).abs() < 1e-15, "{:?}", osc);
        let grow = extrapolate(&[0.4, 0.2, 0.1], &[1.0, 1.1, 1.3], 2.0).unwrap();
        assert_eq!(grow.behaviour, Behaviour::NotConverging);
        let two = extrapolate(&[0.2, 0.1], &[1.0 + 0.04, 1.0 + 0.01], 2.0).unwrap();
        assert_eq!(two.behaviour, Behaviour::TwoLevels);
        assert!((two.value - 1.0).abs() < 1e-14 && (two.error_bar - 0.03).abs() < 1e-14);
        assert_eq!(extrapolate(&[0.1], &[1.0], 2.0), None);
        assert_eq!(extrapolate(&[0.2, 0.1], &[1.0, 1.0], 2.0).unwrap().behaviour, Behaviour::Resolved);
    }

    /// Four levels of a power law: the earlier triple agrees, extrapolated as with three.
    /// The inner displacement of the Lame ring by least squares of degree 2 (measured,
    /// exact 9.079365e-6): the last triple looks monotone (order 1.96) and its
    /// extrapolation 9.0723e-6 +- 2.7e-9 misses the exact value; the triple before
    /// oscillates, so the four levels are erratic and the range covers the exact value.
    #[test]
    fn an_erratic_fourth_level_widens_the_bar() {
        let h = [0.8, 0.4, 0.2, 0.1];
        let v: Vec<f64> = h.iter().map(|h: &f64| 1.0 + h * h).collect();
        let e = extrapolate(&h, &v, 2.0).unwrap();
        assert_eq!(e.behaviour, Behaviour::Monotone);
        assert!((e.value - 1.0).abs() < 1e-12);
        let h = [1.0121e-3, 5.198e-4, 2.637e-4, 1.330e-4];
        let v = [9.076325e-6, 9.103291e-6, 9.080483e-6, 9.074422e-6];
        let three = extrapolate(&h[1..], &v[1..], 1.0).unwrap();
        assert_eq!(three.behaviour, Behaviour::Monotone);
        assert!((three.value - 9.079365e-6).abs() > three.error_bar);
        let four = extrapolate(&h, &v, 1.0).unwrap();
        assert_eq!(four.behaviour, Behaviour::Erratic);
        assert!((four.value - 9.079365e-6).abs() < four.error_bar, "{four:?}");
    }
}
