//! The degree, the first nodes and the order of `--target-error` (the `hp` choices of
//! [`super::target`]).
//!
//! On a plate whose solution is smooth (no singular corner: no re-entrant corner, no
//! clamped edge meeting a loaded or free one), the error of an RBF-FD run falls like
//! `h^q` with `q` growing with the degree, so the cheapest way to a small error is a
//! high degree on few nodes: on Lame and Kirsch PHS degree 6 reached every target from
//! 1e-3 down (e_inf(u) and e_inf(sigma)) in less time than degree 4
//! (benches/time_to_accuracy.sh, BENCHMARKS.md "Time to accuracy"). The loop therefore
//!
//! * raises an RBF-FD scene's degree to [`HP_DEGREE`] for targets at or below
//!   [`HP_TOLERANCE`] ([`raised_degree`]);
//! * starts from about [`PROBE_NODES`] nodes when the scene asks for more
//!   ([`probe`]): the first solve measures the error level, and the next spacing is
//!   predicted from it, so a fine scene spacing is not paid for twice;
//! * predicts each uniform step by the order the last two steps showed
//!   ([`observed_order`]), by the degree `p` until then ([`uniform_order`]).
//!
//! At singular corners the error falls like `h^lambda`, `lambda < 1`, whatever the
//! degree: there the scene's degree is kept and the loop refines locally around the
//! corners ([`crate::domain::adapt`]).

use crate::domain::{self, FillKind};
use crate::mlsm::{stencil::default_rbf_fd_support, Approximation, Basis};
use crate::scene::problem::Problem;

/// The degree of the polynomial part of an RBF-FD stencil that the loop raises a
/// smooth scene to.
pub const HP_DEGREE: u32 = 6;

/// Targets at or below which the loop raises the degree: from 1e-3 down degree 6 was
/// the faster of 4 and 6 on every target measured (module docs).
pub const HP_TOLERANCE: f64 = 1e-3;

/// Nodes of the first step when the scene asks for more (module docs): about 0.1-0.2 s
/// at degree 6, a small share of any step that reaches 1e-4 or less.
pub const PROBE_NODES: f64 = 1000.0;

/// Nodes of the coarse set on which singular corners are looked for: corners are
/// geometry, found on any node set that has a node at each corner.
const SURVEY_NODES: f64 = 2000.0;

/// Whether `p`'s solution is smooth: an exact solution (smooth by construction), or
/// no singular corner on a coarse node set of its domain (`nodes`: the node count
/// `p`'s fill is expected to make, [`Problem::expected_nodes`]).
pub fn is_smooth(p: &Problem, nodes: f64) -> bool {
    if p.case.exact.is_some() {
        return true;
    }
    let fill = if nodes > SURVEY_NODES { p.navier.fill.scaled((nodes / SURVEY_NODES).sqrt()) } else { p.navier.fill.clone() };
    crate::physics::case::singular_corners(&p.case, &domain::generate(&p.case.domain, &fill)).is_empty()
}

/// `p` with its RBF-FD degree raised to [`HP_DEGREE`] (its radial function kept, the
/// default stencil size of the new degree), and the note that says so; `None` when the
/// basis is not RBF-FD, its degree is already as high, `tolerance` is above
/// [`HP_TOLERANCE`], or the scene's nodes are too few for the larger stencils.
pub fn raised_degree(p: &Problem, tolerance: f64) -> Option<(Problem, String)> {
    let Basis::RbfFd { radial, degree } = p.navier.approximation.basis else { return None };
    if degree >= HP_DEGREE || tolerance > HP_TOLERANCE {
        return None;
    }
    let basis = Basis::RbfFd { radial, degree: HP_DEGREE };
    let support = default_rbf_fd_support(basis.size(), p.navier.fill.kind);
    let mut raised = p.clone();
    raised.navier.approximation = Approximation { basis, support, ..p.navier.approximation.clone() };
    // Refused like the scene itself would be when its nodes are too few for the stencils.
    let raised = raised.with_fill(raised.navier.fill.clone()).ok()?;
    let note = format!(
        "the solution is smooth (no singular corner): the loop raises the degree from {degree} to {HP_DEGREE} \
         ({support}-node stencils), the faster way to a target of {tolerance:.0e} (--target-degree scene keeps the scene's)"
    );
    Some((raised, note))
}

/// `p` on about [`PROBE_NODES`] nodes when it would have more (`nodes`, as for
/// [`is_smooth`]; its spacing function scaled as a whole), with the note that says
/// so; `None` when it has no more or its fill is a grid (whose spacing the scene fixed
/// for its lattice).
pub fn probe(p: &Problem, nodes: f64) -> Option<(Problem, String)> {
    if nodes <= PROBE_NODES || p.navier.fill.kind == FillKind::Grid {
        return None;
    }
    let factor = (nodes / PROBE_NODES).sqrt();
    let coarse = p.with_fill(p.navier.fill.scaled(factor)).ok()?;
    let note = format!(
        "the first step has about {PROBE_NODES:.0} nodes (the scene's spacing x {factor:.2}, {nodes:.0} nodes): \
         it measures the error, from which the next spacing is predicted"
    );
    Some((coarse, note))
}

/// The order a uniform hp step is predicted with before two steps have shown one: the
/// polynomial degree `p` (at least 1). Degree 6 converged at order 5.4-6.3 in e_inf(u)
/// and e_inf(sigma) on Lame and Kirsch from 1e3 to 2e4 nodes; with the formal `p - 1`
/// of the local loop the step from the probe overshot its target 3-4x on Lame
/// (benches/time_to_accuracy.sh runs; docs/notebook/2026-11-29-time-to-accuracy.md).
pub fn uniform_order(a: &Approximation) -> f64 {
    (a.basis.polynomial_degree() as f64).max(1.0)
}

/// The order `q` the estimate showed between the last two steps of `history` (each
/// step's largest spacing `h` and its estimate `e`), `ln(e1 / e2) / ln(h1 / h2)`, when
/// both were refined uniformly at the same degree (`uniform`) and the estimate fell;
/// clamped to `[formal, formal + 2]` (a pre-asymptotic step can show any order; below
/// the formal one the prediction would overshoot, far above it fall short).
/// Otherwise `formal`.
pub fn observed_order(history: &[(f64, f64)], formal: f64, uniform: bool) -> f64 {
    let [.., a, b] = history else { return formal };
    let (ratio_h, ratio_e) = (a.0 / b.0, a.1 / b.1);
    if !uniform || !(ratio_h > 1.01 && ratio_e > 1.0 && ratio_e.is_finite()) {
        return formal;
    }
    (ratio_e.ln() / ratio_h.ln()).clamp(formal, formal + 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(spacing: f64, estimate: f64) -> (f64, f64) {
        (spacing, estimate)
    }

    /// The order of two uniform steps is the slope of the estimate against the spacing,
    /// clamped to [formal, formal + 2]; one step, a local step or a rising estimate
    /// give the formal order.
    #[test]
    fn observed_order_is_the_slope_of_the_last_two_steps() {
        let h = [1.0, 0.5];
        let e = |q: f64| [step(h[0], 1e-3), step(h[1], 1e-3 * 0.5f64.powf(q))];
        assert!((observed_order(&e(5.5), 5.0, true) - 5.5).abs() < 1e-12);
        assert_eq!(observed_order(&e(3.0), 5.0, true), 5.0);
        assert_eq!(observed_order(&e(9.0), 5.0, true), 7.0);
        assert_eq!(observed_order(&e(5.5), 5.0, false), 5.0);
        assert_eq!(observed_order(&e(5.5)[..1], 5.0, true), 5.0);
        assert_eq!(observed_order(&[step(1.0, 1e-3), step(0.5, 2e-3)], 5.0, true), 5.0);
    }
}
