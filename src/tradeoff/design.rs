//! The designed sweep: families of configurations (one approximation setting each)
//! walk down a ladder of spacings, cheapest predicted run first; a family stops when
//! its next run would not fit the budget or the memory, when its error stops falling,
//! or when its runs are beaten by a family that converges at least as fast.

use super::front::dominates;
use super::variant::Setting;
pub use crate::scene::problem::preset::significant;

/// The ladder starts at this multiple of the scene's spacing (1/16 of its nodes)...
pub const LADDER_START: f64 = 4.0;
/// ...and divides the spacing by sqrt 2 per level (twice the nodes).
pub const LADDER_STEP: f64 = std::f64::consts::SQRT_2;
/// Levels of the ladder: down to 1/16 of the scene's spacing (256 times its nodes).
pub const LADDER_LEVELS: usize = 13;

/// A family stops when its error fell by less than this factor in each of its last two
/// steps (round-off or a singularity sets the floor).
pub const STALL_RATIO: f64 = 0.9;

/// A family stops when this many of its last runs are each beaten (dominated) by a
/// family that converges at least as fast: two were too few on the Lame ring, where
/// degree 6 loses to degree 4 on the coarsest levels and wins below 1e-4.
pub const DOMINATED_RUNS: usize = 3;

/// Time exponent assumed before a family has two runs: seconds ~ work^1.3, with work
/// the estimated nonzeros (sparse LU in 2D grows a little faster than linearly).
pub const DEFAULT_EXPONENT: f64 = 1.3;

/// Share of the budget given to runs; the rest is kept for writing the results.
pub const RUN_SHARE: f64 = 0.97;

/// Seconds between two looks at a running configuration: a run still going at the
/// deadline is stopped at most this late.
pub const POLL_S: f64 = 0.02;

/// The time budget of a sweep, in seconds. Its decisions take the seconds elapsed since
/// the sweep started as an argument (the caller reads the clock), so that they are
/// tested with the seconds a test sets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// The whole budget (seconds).
    pub seconds: f64,
}

impl Budget {
    /// Seconds after the start by which every run has ended: [`RUN_SHARE`] of the budget.
    pub fn deadline(&self) -> f64 {
        RUN_SHARE * self.seconds
    }

    /// Seconds left for runs `elapsed` seconds into the sweep (none past the deadline).
    pub fn left(&self, elapsed: f64) -> f64 {
        (self.deadline() - elapsed).max(0.0)
    }

    /// Why a run predicted to take `predicted` seconds is not started `elapsed` seconds
    /// into the sweep, or `None` to start it. The sweep's first run has no prediction
    /// and is started: if it outlasts the budget it is stopped at the deadline.
    pub fn skip(&self, predicted: Option<f64>, elapsed: f64) -> Option<String> {
        let left = self.left(elapsed);
        predicted.filter(|&t| t > left).map(|t| format!("predicted {t:.1} s, {left:.1} s of the budget left"))
    }

    /// Whether a run still going `elapsed` seconds into the sweep is stopped.
    pub fn ended(&self, elapsed: f64) -> bool {
        elapsed >= self.deadline()
    }
}

/// The far-field spacing of `level` for a scene of spacing `h`, to four significant
/// digits (so that the configuration files and snippets read well).
pub fn spacing(h: f64, level: usize) -> f64 {
    significant(h * LADDER_START / LADDER_STEP.powi(level as i32), 4)
}

/// The families of a sweep: the scene's own setting (`None`) and the settings that
/// were on the measured fronts of the shipped scenes: degree-2 least squares for cheap
/// runs; PHS r^3 with degree 4 (default stencil, a 1.5x stencil, sparse LU instead of
/// the scene's solver, which `auto` leaves for GMRES + AMG above a few thousand nodes)
/// and degree 6 for accurate ones (docs/notebook/round2-fronts-and-presets.md;
/// docs/notebook/2026-11-27-auto-by-time.md).
/// `phs4_support` is the default stencil of PHS degree 4 on the scene's nodes.
pub fn families(phs4_support: usize) -> Vec<(String, Option<Setting>)> {
    let phs = |degree, support, solver| Setting { basis: "phs", degree, support, solver };
    let wide = (phs4_support * 3).div_ceil(2);
    vec![
        ("shipped".into(), None),
        ("least squares p=2".into(), Some(Setting { basis: "monomials", degree: 2, support: None, solver: None })),
        ("phs p=4".into(), Some(phs(4, None, None))),
        (format!("phs p=4, {wide}-node stencil"), Some(phs(4, Some(wide), None))),
        ("phs p=4, lu".into(), Some(phs(4, None, Some("lu")))),
        ("phs p=6".into(), Some(phs(6, None, None))),
    ]
}

/// What a finished run tells the sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    /// Estimated work (nonzeros of the system) of the run.
    pub work: f64,
    /// Seconds the run took.
    pub seconds: f64,
    /// Its error (the measure of the sweep), if it has one.
    pub error: Option<f64>,
}

/// One family's progress down the ladder.
#[derive(Debug, Clone, Default)]
pub struct FamilyState {
    /// The next level to run.
    pub next_level: usize,
    /// Its finished runs, coarse to fine.
    pub runs: Vec<Measured>,
    /// Why it stopped, once it did.
    pub stopped: Option<String>,
}

impl FamilyState {
    /// Fitted log-log slope of error against seconds over the last two runs (negative:
    /// steeper is better), if both have an error.
    fn slope(&self) -> Option<f64> {
        let [.., a, b] = self.runs.as_slice() else { return None };
        let (ea, eb) = (a.error?, b.error?);
        let dt = (b.seconds / a.seconds).ln();
        (dt.abs() > 1e-9 && ea > 0.0 && eb > 0.0).then(|| (eb / ea).ln() / dt)
    }
}

/// The state of a sweep over `names.len()` families.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// Family names (for the reasons of domination).
    pub names: Vec<String>,
    /// Their progress.
    pub families: Vec<FamilyState>,
}

impl Sweep {
    /// A sweep of the named families, none run.
    pub fn new(names: Vec<String>) -> Self {
        let families = vec![FamilyState::default(); names.len()];
        Sweep { names, families }
    }

    /// Predicted seconds of a run of family `f` with estimated `work`: from the
    /// family's last run and its own growth exponent (clamped to [1, 2]) when it has
    /// runs, else from the most expensive rate (seconds / work^1.3) seen in any family.
    /// `None` before the first run of the sweep.
    pub fn predict(&self, f: usize, work: f64) -> Option<f64> {
        let own = &self.families[f].runs;
        if let Some(last) = own.last() {
            let exponent = match own.as_slice() {
                [.., a, b] if b.work > a.work * 1.05 => ((b.seconds / a.seconds).ln() / (b.work / a.work).ln()).clamp(1.0, 2.0),
                _ => DEFAULT_EXPONENT,
            };
            return Some(last.seconds * (work / last.work).powf(exponent));
        }
        let rate = self.families.iter().flat_map(|s| s.runs.iter()).map(|m| m.seconds / m.work.powf(DEFAULT_EXPONENT)).reduce(f64::max)?;
        Some(rate * work.powf(DEFAULT_EXPONENT))
    }

    /// The active family whose next run is predicted cheapest (`work(f, level)` gives
    /// the estimated work), with the prediction; `None` when every family stopped.
    pub fn next(&self, work: impl Fn(usize, usize) -> f64) -> Option<(usize, Option<f64>)> {
        (0..self.families.len())
            .filter(|&f| self.families[f].stopped.is_none())
            .map(|f| (f, self.predict(f, work(f, self.families[f].next_level))))
            .min_by(|a, b| a.1.unwrap_or(0.0).total_cmp(&b.1.unwrap_or(0.0)).then(a.0.cmp(&b.0)))
    }

    /// Stop family `f` with `reason`.
    pub fn stop(&mut self, f: usize, reason: String) {
        self.families[f].stopped.get_or_insert(reason);
    }

    /// Record a finished run of family `f` at its next level, then apply the stopping
    /// rules: the end of the ladder, a stalled error, domination.
    pub fn record(&mut self, f: usize, m: Measured) {
        let s = &mut self.families[f];
        s.runs.push(m);
        s.next_level += 1;
        if s.next_level >= LADDER_LEVELS {
            self.stop(f, "end of the spacing ladder".into());
        }
        if let [.., a, b, c] = self.families[f].runs.as_slice() {
            if let (Some(ea), Some(eb), Some(ec)) = (a.error, b.error, c.error) {
                if eb > STALL_RATIO * ea && ec > STALL_RATIO * eb {
                    self.stop(f, format!("its error stopped falling at {ec:.2e}"));
                }
            }
        }
        for g in 0..self.families.len() {
            if self.families[g].stopped.is_none() {
                if let Some(by) = self.dominator(g) {
                    let reason = format!("its last three runs are beaten by \"{}\", which converges at least as fast", self.names[by]);
                    self.stop(g, reason);
                }
            }
        }
    }

    /// A family `h != g` with two runs or more, converging at least as fast as `g`
    /// (slope of error against seconds at least as steep), whose runs dominate each
    /// of `g`'s last [`DOMINATED_RUNS`] runs.
    fn dominator(&self, g: usize) -> Option<usize> {
        let own = &self.families[g];
        let point = |m: &Measured| m.error.map(|e| (m.seconds, e));
        let last: Vec<(f64, f64)> = own.runs[own.runs.len().checked_sub(DOMINATED_RUNS)?..].iter().map(point).collect::<Option<_>>()?;
        let slope_g = own.slope()?;
        (0..self.families.len()).find(|&h| {
            let other = &self.families[h];
            h != g
                && other.slope().is_some_and(|s| s <= slope_g)
                && last.iter().all(|&p| other.runs.iter().filter_map(point).any(|q| dominates(q, p)))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(work: f64, seconds: f64, error: f64) -> Measured {
        Measured { work, seconds, error: Some(error) }
    }

    /// The budget's decisions with the seconds the test sets: a family whose last run
    /// (work 1e4) took 3 s prices its next (work 4e4) at 3 x 4^2 = 48 s with its own
    /// growth exponent (2, clamped: 0.75 s -> 3 s for twice the work); with a 60 s budget,
    /// 40 s into the sweep, 18.2 s are left for runs (0.97 x 60 - 40), and the run is
    /// skipped with both numbers; 5 s in it starts.
    #[test]
    fn a_run_predicted_past_the_budget_is_skipped() {
        let mut s = Sweep::new(vec!["a".into()]);
        s.record(0, m(5e3, 0.75, 1e-2));
        s.record(0, m(1e4, 3.0, 1e-3));
        let predicted = s.predict(0, 4e4);
        assert!((predicted.unwrap() - 48.0).abs() < 1e-9, "{predicted:?}");
        let budget = Budget { seconds: 60.0 };
        assert!((budget.left(40.0) - 18.2).abs() < 1e-12);
        assert_eq!(budget.skip(predicted, 40.0).as_deref(), Some("predicted 48.0 s, 18.2 s of the budget left"));
        assert_eq!(budget.skip(predicted, 5.0), None);
        // Past the deadline nothing is left; a first run (no prediction) still starts,
        // and is stopped at once.
        assert_eq!(budget.left(59.0), 0.0);
        assert_eq!(budget.skip(Some(1e-3), 59.0).as_deref(), Some("predicted 0.0 s, 0.0 s of the budget left"));
        assert_eq!(budget.skip(None, 59.0), None);
        assert!(budget.ended(59.0) && !budget.ended(58.0));
    }

    /// The bound: a sweep ends within 10 % past its budget. Every run ends by
    /// the deadline plus one look ([`POLL_S`]); what is left below 1.1 x the budget is
    /// the time to stop the last run and write the results: at least a tenth of the
    /// budget for budgets from 1 s (0.76 s of a 6 s budget).
    #[test]
    fn runs_end_early_enough_to_write_the_results_within_the_bound() {
        for seconds in [1.0, 6.0, 120.0, 3.2e7] {
            let budget = Budget { seconds };
            let runs_end = budget.deadline() + POLL_S;
            assert!(runs_end <= seconds, "{seconds} s: runs end at {runs_end}");
            let writing = 1.1 * seconds - runs_end;
            assert!(writing >= 0.1 * seconds, "{seconds} s: {writing} s to write");
            assert!(budget.ended(budget.deadline()) && !budget.ended(budget.deadline() - 1e-9 * seconds));
        }
        assert!((1.1 * 6.0 - (Budget { seconds: 6.0 }.deadline() + POLL_S) - 0.76).abs() < 1e-12);
    }

    #[test]
    fn ladder_halves_the_spacing_every_two_levels() {
        assert!((spacing(0.1, 0) - 0.4).abs() < 1e-15);
        assert!((spacing(0.1, 8) - 0.025).abs() < 1e-15);
        assert_eq!(spacing(0.025, 2), 0.05);
        assert_eq!(spacing(0.025, 3), 0.03536);
        assert_eq!(spacing(2.5e-4, 7), 8.839e-5);
        assert_eq!(significant(123456.0, 3), 123000.0);
    }

    #[test]
    fn cheapest_prediction_first_and_growth_fitted() {
        let mut s = Sweep::new(vec!["a".into(), "b".into()]);
        assert_eq!(s.next(|_, _| 1.0), Some((0, None)));
        s.record(0, m(1e4, 0.1, 1e-2));
        // b has no run: priced at a's rate, work 4e4 -> 0.1 * 4^1.3.
        let p = s.predict(1, 4e4).unwrap();
        assert!((p - 0.1 * 4f64.powf(1.3)).abs() < 1e-12);
        s.record(0, m(2e4, 0.4, 4e-3));
        // a's own exponent: 0.4 / 0.1 over a doubling of work = 2 (clamped to 2).
        assert!((s.predict(0, 4e4).unwrap() - 1.6).abs() < 1e-12);
        // The work of b's next run (1e4) makes it the cheapest.
        assert_eq!(s.next(|f, _| if f == 0 { 4e4 } else { 1e4 }).map(|x| x.0), Some(1));
    }

    #[test]
    fn a_stalled_family_stops() {
        let mut s = Sweep::new(vec!["a".into()]);
        for (k, e) in [1e-6, 1e-9, 0.95e-9, 0.93e-9].into_iter().enumerate() {
            s.record(0, m(1e4 * 2f64.powi(k as i32), 0.1 * 2f64.powi(k as i32), e));
        }
        assert!(s.families[0].stopped.as_deref().unwrap().contains("stopped falling at 9.30e-10"));
    }

    #[test]
    fn beaten_family_stops_only_against_a_faster_converging_one() {
        let mut s = Sweep::new(vec!["slow".into(), "fast".into()]);
        // "fast" is cheaper and more accurate at every level and converges faster.
        s.record(0, m(1e4, 0.2, 1e-2));
        s.record(0, m(2e4, 0.4, 5e-3));
        s.record(1, m(1e4, 0.1, 1e-3));
        assert!(s.families[0].stopped.is_none(), "one run of fast: no slope yet");
        s.record(1, m(2e4, 0.2, 1e-4));
        assert!(s.families[0].stopped.is_none(), "two runs of slow beaten: not yet");
        s.record(0, m(4e4, 0.8, 2.5e-3));
        assert!(s.families[0].stopped.as_deref().unwrap().contains("\"fast\""));
        assert!(s.families[1].stopped.is_none());
        // A family beaten by one that converges more slowly goes on (it may cross over).
        let mut s = Sweep::new(vec!["steep".into(), "flat".into()]);
        s.record(0, m(1e4, 0.2, 1e-2));
        s.record(0, m(2e4, 0.4, 1e-3));
        s.record(1, m(1e4, 0.1, 5e-3));
        s.record(1, m(2e4, 0.3, 9e-4));
        assert!(s.families[0].stopped.is_none());
    }
}
