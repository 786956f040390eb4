//! The discretisation error of a static peridynamic run: how far its solution is from
//! the nonlocal model's own continuum solution at the same horizon, apart from the
//! model difference to the local (Navier) solution, which `mlsm compare` and the
//! `local-model` estimate measure.
//!
//! At a fixed horizon `delta` the quadrature of the bond integral converges as the
//! spacing `h = delta / m` shrinks. The run is solved again at `m -> 2m` (the same
//! horizon, half the spacing), the finer solution is interpolated to the run's free
//! nodes by moving least squares ([`crate::mlsm::interpolate`]), and
//!
//! ```text
//! e_h ~ (u_h - I u_{h/2}) / sqrt((1 - 2^-1)(1 - 2^-2)),
//! ```
//!
//! since `u_h - u_{h/2} = (1 - 2^-p) e_h` for an error of order `p`: the divisor is the
//! geometric mean of the factors of orders 1 and 2, so that the effectivity lies in
//! [0.82, 1.22] for any order from 1 to 2 (1.43 at order 3). Where the run does not
//! converge at its horizon (a load applied as a layer one spacing thick concentrates as
//! `h` shrinks), the difference is the size of the error, and the estimate warns.
//!
//! It costs one run with four times the nodes and four times the bonds per node
//! (about 10x the run measured on the shipped scenes: 0.004 s -> 0.045 s of solve).

use crate::mlsm::interpolate::mls_values_of_degree;
use crate::physics::case::Case;
use crate::quality::post::relative_errors;
use crate::stages::Silent;
use std::time::Instant;

use super::solve::DiscretisationEstimate;
use super::{solve, PdParams, PdSolution};

/// `sqrt((1 - 1/2)(1 - 1/4))`: the divisor of the difference (module docs).
pub const DIVISOR: f64 = 0.612_372_435_695_794_5;

/// The discretisation error of `sol` (a static run of `case` with `params`) against the
/// run at `m -> 2m` with the same horizon (module docs); `Err` says why there is none
/// (the reference's solve or interpolation failed).
pub fn estimate(case: &Case, params: &PdParams, sol: &PdSolution) -> Result<DiscretisationEstimate, String> {
    let t0 = Instant::now();
    let fine = PdParams { ratio: 2.0 * params.ratio, ..*params };
    let reference = solve(case, &fine, &Silent).map_err(|e| format!("the run at m = {} failed: {e}", fine.ratio))?;
    let (n, nf) = (sol.nodes.free, reference.nodes.free);
    let targets = &sol.nodes.positions[..n];
    let interpolated = mls_values_of_degree(&reference.nodes.positions[..nf], &reference.displacement[..nf], targets, 2)
        .map_err(|e| format!("the run at m = {} could not be interpolated to the run's nodes: {e}", fine.ratio))?;
    let u = &sol.displacement[..n];
    let (e_inf, rel_l2) = relative_errors(u, &interpolated);
    let largest = (0..n)
        .max_by(|&a, &b| {
            let d = |i: usize| (u[i][0] - interpolated[i][0]).abs().max((u[i][1] - interpolated[i][1]).abs());
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    Ok(DiscretisationEstimate {
        method: "fixed-horizon",
        reference: format!(
            "the run at half the spacing with the same horizon (m = {}, {nf} nodes), divided by {DIVISOR:.2} (orders 1 to 2)",
            fine.ratio
        ),
        e_inf_u: e_inf / DIVISOR,
        rel_l2_u: rel_l2 / DIVISOR,
        largest_at: targets.get(largest).copied().unwrap_or([0.0, 0.0]),
        reference_ratio: fine.ratio,
        reference_nodes: nf,
        seconds: t0.elapsed().as_secs_f64(),
    })
}
