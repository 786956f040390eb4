//! States of a run kept over its history for an error estimate: a run keeps its own
//! [`history_steps`](super::driver::history_steps), and the reference it is compared
//! with keeps the states at the run's times. A reference time that falls between two
//! of its steps `t0 = k dt`, `t1 = t0 + dt` is made from the two states around it by
//! cubic Hermite interpolation of the displacement with the velocities as slopes,
//!
//! ```text
//! u(t0 + s dt) = (2s^3 - 3s^2 + 1) u0 + (s^3 - 2s^2 + s) dt v0 + (-2s^3 + 3s^2) u1 + (s^3 - s^2) dt v1,
//! ```
//!
//! exact for cubics in `t`, an error of order `dt^4`: below the time error of every
//! integrator here, RK4's included (a step of the reference is a quarter or less of
//! the run's error, `navier::estimate`).

use super::driver::history_steps;
use std::collections::BTreeMap;

/// The displacement at the nodes.
pub type Nodal = Vec<[f64; 2]>;

/// A state kept at one step: time, displacement, velocity.
pub type Kept = (f64, Nodal, Nodal);

/// How the state at one requested time is made.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Plan {
    /// The state of this step.
    At(usize),
    /// Hermite interpolation at `t` between step `k` and `k + 1`.
    Between(usize, f64),
}

/// The steps a run keeps and how its states at the requested times are made.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TimeSamples {
    /// The steps to keep, sorted, without repeats.
    pub steps: Vec<usize>,
    plans: Vec<Plan>,
    dt: f64,
}

impl TimeSamples {
    /// Nothing kept.
    pub fn none() -> Self {
        TimeSamples::default()
    }

    /// A run's own history on `steps` steps of `dt` ([`history_steps`]).
    pub fn own(steps: usize, dt: f64) -> Self {
        let kept = history_steps(steps);
        TimeSamples { plans: kept.iter().map(|&k| Plan::At(k)).collect(), steps: kept, dt }
    }

    /// The states at `times` on `steps` steps of `dt`: the step itself where `k dt`
    /// equals `t` to `tolerance` (or `t` lies beyond the last step by at most that),
    /// else the two steps around it.
    pub fn at_times(times: &[f64], dt: f64, steps: usize, tolerance: f64) -> Self {
        let mut kept = Vec::new();
        let plans = times
            .iter()
            .map(|&t| {
                let nearest = (t / dt).round().clamp(0.0, steps as f64) as usize;
                if (nearest as f64 * dt - t).abs() <= tolerance {
                    kept.push(nearest);
                    Plan::At(nearest)
                } else {
                    let k = ((t / dt).floor().max(0.0) as usize).min(steps.saturating_sub(1));
                    kept.extend([k, k + 1]);
                    Plan::Between(k, t)
                }
            })
            .collect();
        kept.sort_unstable();
        kept.dedup();
        TimeSamples { steps: kept, plans, dt }
    }

    /// Whether step `step` is kept.
    pub fn keeps(&self, step: usize) -> bool {
        self.steps.binary_search(&step).is_ok()
    }

    /// The states `(t, displacement)` at the requested times from the `kept` ones
    /// (every step of [`Self::steps`]).
    pub fn states(&self, kept: &BTreeMap<usize, Kept>) -> Vec<(f64, Nodal)> {
        self.plans
            .iter()
            .map(|plan| match *plan {
                Plan::At(k) => (kept[&k].0, kept[&k].1.clone()),
                Plan::Between(k, t) => {
                    let ((t0, u0, v0), (_, u1, v1)) = (&kept[&k], &kept[&(k + 1)]);
                    (t, hermite((u0, v0), (u1, v1), (t - t0) / self.dt, self.dt))
                }
            })
            .collect()
    }
}

/// The cubic Hermite interpolant (module docs) at `s` in [0, 1] of a step `dt`.
fn hermite((u0, v0): (&[[f64; 2]], &[[f64; 2]]), (u1, v1): (&[[f64; 2]], &[[f64; 2]]), s: f64, dt: f64) -> Nodal {
    let (s2, s3) = (s * s, s * s * s);
    let (h00, h10, h01, h11) = (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2);
    (0..u0.len()).map(|i| std::array::from_fn(|c| h00 * u0[i][c] + h10 * dt * v0[i][c] + h01 * u1[i][c] + h11 * dt * v1[i][c])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic in time, `u = 1 + 2t - t^2 + 0.5 t^3` (velocity `2 - 2t + 1.5 t^2`),
    /// kept at the steps of `dt = 0.1` that the plan asks for, is rebuilt exactly at
    /// times on and between the steps (to round-off); a time on a step is that step's
    /// state, not an interpolation.
    #[test]
    fn states_between_steps_are_exact_for_cubics() {
        let (u, v) = (|t: f64| 1.0 + 2.0 * t - t * t + 0.5 * t * t * t, |t: f64| 2.0 - 2.0 * t + 1.5 * t * t);
        let times = [0.3, 0.35, 0.47, 1.0, 1.0 + 1e-12];
        let samples = TimeSamples::at_times(&times, 0.1, 10, 1e-9);
        assert_eq!(samples.steps, [3, 4, 5, 10]);
        assert!(samples.keeps(5) && !samples.keeps(6));
        let kept: BTreeMap<usize, Kept> =
            samples.steps.iter().map(|&k| (k, (0.1 * k as f64, vec![[u(0.1 * k as f64), 0.0]], vec![[v(0.1 * k as f64), 0.0]]))).collect();
        let states = samples.states(&kept);
        for ((t, got), want) in states.iter().zip(times) {
            assert!((got[0][0] - u(*t)).abs() < 1e-13, "t = {want}: {} against {}", got[0][0], u(*t));
            assert_eq!(got[0][1], 0.0);
            assert!((t - want).abs() < 1e-9);
        }
        assert_eq!(states[0].0, 0.1 * 3.0, "on a step: that step's own time");
    }

    /// A run's own history is its `history_steps`, every one kept as it is.
    #[test]
    fn own_history_keeps_its_steps() {
        let samples = TimeSamples::own(100, 0.01);
        assert_eq!(samples.steps, history_steps(100));
        assert_eq!(samples.plans.len(), samples.steps.len());
        assert!(TimeSamples::none().steps.is_empty());
    }
}
