//! The plumbing every run shares, whatever the model: named stages, their timing, a
//! progress observer, and the errors a run can end with after validation.
//!
//! A model names its own stages (`navier::stage`, `peridynamics::stage`,
//! `dynamics::INTEGRATE`); a [`StageTimer`] runs each one, reports its start and end
//! to a [`Progress`] observer and records its wall-clock seconds in
//! [`StageTimings`], which `summary.json` writes as `timings_s` keyed by stage name.

use crate::linalg::SolveError;
use crate::mlsm::ShapeError;
use crate::output::OutputError;
use serde::ser::SerializeMap;
use serde::Serialize;
use std::time::Instant;

/// Interruption (Ctrl-C, SIGTERM, SIGHUP) of a time loop: while an
/// [`interrupt::Interruptible`] guard lives, an interrupt only raises a flag that the
/// loop polls once per step, so the run ends as [`RunError::Interrupted`] and its
/// writer can remove what it staged; outside a time loop the command line removes the
/// staged results ([`output::remove_uncommitted`](crate::output::remove_uncommitted))
/// and ends the process at once. [`interrupt::on_signals`] delivers the signals to
/// such a handler, with the signal's number, so that the message can name it.
pub mod interrupt {
    use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

    static LISTENING: AtomicBool = AtomicBool::new(false);
    static REQUESTED: AtomicBool = AtomicBool::new(false);
    /// The signal of the last request (0: none).
    static SIGNAL: AtomicI32 = AtomicI32::new(0);

    /// Ask the running time loop to stop because of `signal` (its number); `false`
    /// when no loop listens (the caller should then end the process itself).
    pub fn request(signal: i32) -> bool {
        SIGNAL.store(signal, Ordering::SeqCst);
        REQUESTED.store(true, Ordering::SeqCst);
        LISTENING.load(Ordering::SeqCst)
    }

    /// The name of the signal of the last request (`SIGINT`, `SIGTERM`, `SIGHUP`, or
    /// `signal N`), "an interrupt" when none was named.
    pub fn signal() -> String {
        name(SIGNAL.load(Ordering::SeqCst))
    }

    /// The name of signal number `signal`.
    pub fn name(signal: i32) -> String {
        #[cfg(unix)]
        match signal {
            libc::SIGINT => return "SIGINT".into(),
            libc::SIGTERM => return "SIGTERM".into(),
            libc::SIGHUP => return "SIGHUP".into(),
            _ => {}
        }
        if signal > 0 {
            format!("signal {signal}")
        } else {
            "an interrupt".into()
        }
    }

    /// Call `handler` with the signal's number on a thread of its own whenever the
    /// process receives SIGINT (Ctrl-C), SIGTERM (a job scheduler's stop) or SIGHUP
    /// (the terminal closed): `signal-hook`'s iterator, which does the
    /// async-signal-safe part (a self-pipe) and names the signal, where `ctrlc` cannot.
    /// Call it once, before other threads start.
    #[cfg(unix)]
    pub fn on_signals(handler: fn(i32)) -> std::io::Result<()> {
        let mut signals = signal_hook::iterator::Signals::new([libc::SIGINT, libc::SIGTERM, libc::SIGHUP])?;
        std::thread::Builder::new().name("signals".into()).spawn(move || {
            for signal in signals.forever() {
                handler(signal);
            }
        })?;
        Ok(())
    }

    /// Whether a stop was requested since the guard was made.
    pub fn requested() -> bool {
        REQUESTED.load(Ordering::Relaxed)
    }

    /// Listens for interrupts while it lives (one time loop).
    pub struct Interruptible(());

    impl Interruptible {
        /// Start listening (an earlier, unheeded request is forgotten).
        pub fn listen() -> Self {
            REQUESTED.store(false, Ordering::SeqCst);
            LISTENING.store(true, Ordering::SeqCst);
            Interruptible(())
        }
    }

    impl Drop for Interruptible {
        fn drop(&mut self) {
            LISTENING.store(false, Ordering::SeqCst);
        }
    }
}

/// A named stage of a run (`nodes`, `shapes`, `families`, `solve`, ...).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stage(&'static str);

impl Stage {
    /// A stage called `name` in the terminal and in `summary.json`.
    pub const fn new(name: &'static str) -> Self {
        Stage(name)
    }

    /// Name as printed and as used in `summary.json`.
    pub fn name(self) -> &'static str {
        self.0
    }
}

/// Stages every model has; a model adds its own (`navier::stage`,
/// `peridynamics::stage`, `dynamics::INTEGRATE`).
pub mod stage {
    use super::Stage;
    /// Node generation.
    pub const NODES: Stage = Stage::new("nodes");
    /// Matrix assembly (for dynamics: the operator, loads and its factorisations).
    pub const ASSEMBLY: Stage = Stage::new("assembly");
    /// Linear solve.
    pub const SOLVE: Stage = Stage::new("solve");
    /// Strain, stress, errors.
    pub const POST: Stage = Stage::new("post");
    /// Writing the results (timed by the command that writes them).
    pub const OUTPUT: Stage = Stage::new("output");
}

pub use stage::OUTPUT;

/// Observer of stage starts and ends (the CLI shows progress with it).
pub trait Progress: Sync {
    /// A stage begins.
    fn start(&self, stage: Stage);
    /// A stage ended after `seconds`, with a short note (sizes).
    fn finish(&self, stage: Stage, seconds: f64, note: &str);
    /// `done` of `total` `unit`s of the current stage are complete (the steps of time
    /// integration, the residual digits of an iterative solve).
    fn advance(&self, _done: u64, _total: u64, _unit: &'static str) {}
}

/// The progress of a run made inside a stage (the estimate's reference run): its own
/// stages are not shown, its steps and residual digits are the outer stage's.
pub struct Within<'a>(pub &'a dyn Progress);

impl Progress for Within<'_> {
    fn start(&self, _: Stage) {}
    fn finish(&self, _: Stage, _: f64, _: &str) {}
    fn advance(&self, done: u64, total: u64, unit: &'static str) {
        self.0.advance(done, total, unit);
    }
}

/// What an iterative solve tells the solve stage's progress ([`crate::linalg::watch`]):
/// the digits of the residual gained of those the tolerance asks for.
pub struct SolveProgress<'a>(pub &'a dyn Progress);

impl crate::linalg::watch::Watch for SolveProgress<'_> {
    fn residual(&self, reached: f64, target: f64) {
        if let Some((done, total)) = crate::linalg::watch::digits_gained(reached, target) {
            self.0.advance(done, total, "residual digits");
        }
    }
}

/// A progress observer that does nothing.
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _: Stage) {}
    fn finish(&self, _: Stage, _: f64, _: &str) {}
}

/// Wall-clock seconds per stage, in the order the stages ran; serialised as a map
/// `{stage name: seconds}`. Beside them, the peak resident memory of each stage
/// ([`StageTimings::peaks`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageTimings(Vec<(Stage, f64)>, Vec<(Stage, u64)>);

impl StageTimings {
    /// Add `seconds` to `stage` (a stage that runs twice is summed).
    pub fn record(&mut self, stage: Stage, seconds: f64) {
        match self.0.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, t)) => *t += seconds,
            None => self.0.push((stage, seconds)),
        }
    }

    /// `(stage name, seconds)` of every stage that ran, in order.
    pub fn named(&self) -> Vec<(String, f64)> {
        self.0.iter().map(|(s, t)| (s.name().to_string(), *t)).collect()
    }

    /// Seconds spent in `stage` (0 if it did not run).
    pub fn get(&self, stage: Stage) -> f64 {
        self.0.iter().find(|(s, _)| *s == stage).map_or(0.0, |(_, t)| *t)
    }

    /// Stages in the order they ran, with their seconds.
    pub fn iter(&self) -> impl Iterator<Item = (Stage, f64)> + '_ {
        self.0.iter().copied()
    }

    /// Keep `bytes` as the peak of `stage` if larger than the one recorded.
    pub fn record_peak(&mut self, stage: Stage, bytes: u64) {
        match self.1.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, b)) => *b = (*b).max(bytes),
            None => self.1.push((stage, bytes)),
        }
    }

    /// Peak resident memory of each stage that ran under a [`StageTimer`], in bytes,
    /// serialised as a map `{stage name: bytes}`.
    pub fn peaks(&self) -> StagePeaks<'_> {
        StagePeaks(&self.1)
    }
}

/// Peak memory per stage (see [`StageTimings::peaks`]).
pub struct StagePeaks<'a>(&'a [(Stage, u64)]);

impl Serialize for StagePeaks<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (stage, bytes) in self.0 {
            map.serialize_entry(stage.name(), bytes)?;
        }
        map.end()
    }
}

impl Serialize for StageTimings {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (stage, t) in &self.0 {
            map.serialize_entry(stage.name(), t)?;
        }
        map.end()
    }
}

/// Runs the stages of one run: reports each to the observer and records its time.
pub struct StageTimer<'a> {
    progress: &'a dyn Progress,
    timings: StageTimings,
}

impl<'a> StageTimer<'a> {
    /// A timer reporting to `progress`, with nothing recorded yet.
    pub fn new(progress: &'a dyn Progress) -> Self {
        StageTimer { progress, timings: StageTimings::default() }
    }

    /// The observer the stages report to (for stepping stages that advance it).
    pub fn progress(&self) -> &'a dyn Progress {
        self.progress
    }

    /// Run `work` as `stage`; it returns its value and a short note for the terminal.
    /// Records its seconds and its peak resident memory.
    pub fn run<T>(&mut self, stage: Stage, work: impl FnOnce() -> Result<(T, String), RunError>) -> Result<T, RunError> {
        self.progress.start(stage);
        let mark = crate::output::restart_peak();
        let t0 = Instant::now();
        let (value, note) = work()?;
        let seconds = t0.elapsed().as_secs_f64();
        self.timings.record(stage, seconds);
        if let Some(bytes) = crate::output::peak_since(mark) {
            self.timings.record_peak(stage, bytes);
        }
        self.progress.finish(stage, seconds, &note);
        Ok(value)
    }

    /// Record `seconds` of `stage` that was timed elsewhere.
    pub fn record(&mut self, stage: Stage, seconds: f64) {
        self.timings.record(stage, seconds);
    }

    /// The timings recorded so far.
    pub fn timings(&self) -> &StageTimings {
        &self.timings
    }

    /// The recorded timings.
    pub fn finish(self) -> StageTimings {
        self.timings
    }
}

/// Why a run failed after validation.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// A fixed time step above the stability limit of the scheme.
    #[error("time step {given:.3e} s exceeds the stable step {limit:.3e} s of the {integrator} scheme (central-difference bound sqrt(2 rho / max_i sum_j |c_ij| |xi|^2)); use a smaller dynamics.time_step or leave it out")]
    UnstableTimeStep { given: f64, limit: f64, integrator: &'static str },
    /// An explicit run longer than `dynamics::driver::MAX_STEPS` steps without `--allow-long`.
    #[error(
        "the run needs {steps:.2e} steps of {dt:.3e} s (more than 1e8): shorten dynamics.end_time, coarsen the nodes, or pass --allow-long"
    )]
    TooManySteps { steps: f64, dt: f64 },
    /// The solution became non-finite during time integration.
    #[error("the solution became non-finite at step {step} (t = {t:.4e} s): the time integration diverged")]
    Diverged { step: usize, t: f64 },
    /// Too few nodes for the support size.
    #[error("the node set has {nodes} nodes, fewer than the support size {support}; use a smaller nodes.spacing")]
    TooFewNodes { nodes: usize, support: usize },
    /// A local least-squares problem is rank deficient.
    #[error(transparent)]
    Shape(#[from] ShapeError),
    /// The linear solver failed.
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
    /// A non-finite coefficient or right-hand side in a row (an overflow, or NaN).
    #[error(
        "non-finite number in the equations of node {node} at ({x:.6e}, {y:.6e}): a coefficient or load \
         overflowed the double range (1.8e308) or is NaN; rescale the units of the loads and moduli"
    )]
    NotFinite { node: usize, x: f64, y: f64 },
    /// A formula of the scene is not finite at a point where the run needs it.
    /// `context`: where or when, if not at a node at t = 0 (" at t = ...", or a node
    /// of the peridynamic collar).
    #[error(
        "{field} = \"{text}\" is {value} at ({x:.6e}, {y:.6e}){context}: a formula must give a finite number at every node \
         where it is used (division by zero, sqrt or log of a negative number?)"
    )]
    BadFormula { field: String, text: String, value: f64, x: f64, y: f64, context: String },
    /// A formula of the scene cannot be used by this run (e.g. not differentiable in
    /// `t` where the run needs its rate).
    #[error("{field}: {reason}")]
    Formula { field: String, reason: String },
    /// Writing a snapshot during time integration failed.
    #[error(transparent)]
    Snapshot(OutputError),
    /// An error target was set, but the run's error could not be estimated.
    #[error("--target-error needs the error estimate, which is unavailable: {reason}")]
    Estimate { reason: String },
    /// A signal (Ctrl-C, SIGTERM, SIGHUP; named by `signal`) interrupted the time loop.
    #[error("interrupted at step {step} (t = {t:.4e} s) by {signal}; the partial results were removed, earlier results are untouched")]
    Interrupted { step: usize, t: f64, signal: String },
}

impl RunError {
    /// [`RunError::NotFinite`] at node `node`, position `p`.
    pub fn not_finite_at(node: usize, p: [f64; 2]) -> Self {
        RunError::NotFinite { node, x: p[0], y: p[1] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: Stage = Stage::new("a");
    const B: Stage = Stage::new("b");

    #[test]
    fn timings_keep_order_and_sum_repeated_stages() {
        let mut t = StageTimings::default();
        t.record(B, 1.0);
        t.record(A, 2.0);
        t.record(B, 0.5);
        assert_eq!(t.iter().collect::<Vec<_>>(), vec![(B, 1.5), (A, 2.0)]);
        assert_eq!(t.get(A), 2.0);
        assert_eq!(t.get(Stage::new("c")), 0.0);
        assert_eq!(serde_json::to_string(&t).unwrap(), r#"{"b":1.5,"a":2.0}"#);
    }

    /// A solve's residual reaches the stage's progress as whole digits gained of
    /// those the tolerance asks for.
    #[test]
    fn a_solve_advances_by_residual_digits() {
        use crate::linalg::watch::Watch;
        struct Log(std::sync::Mutex<Vec<(u64, u64, &'static str)>>);
        impl Progress for Log {
            fn start(&self, _: Stage) {}
            fn finish(&self, _: Stage, _: f64, _: &str) {}
            fn advance(&self, done: u64, total: u64, unit: &'static str) {
                self.0.lock().unwrap().push((done, total, unit));
            }
        }
        let log = Log(Default::default());
        let watch = SolveProgress(&log);
        for r in [0.5, 2e-4, 1e-11] {
            watch.residual(r, 1e-10);
        }
        let unit = "residual digits";
        assert_eq!(log.0.into_inner().unwrap(), vec![(0, 10, unit), (3, 10, unit), (10, 10, unit)]);
    }

    #[test]
    fn timer_reports_and_stops_at_the_first_error() {
        struct Log(std::sync::Mutex<Vec<String>>);
        impl Progress for Log {
            fn start(&self, s: Stage) {
                self.0.lock().unwrap().push(format!("start {}", s.name()));
            }
            fn finish(&self, s: Stage, _: f64, note: &str) {
                self.0.lock().unwrap().push(format!("finish {} {note}", s.name()));
            }
        }
        let log = Log(Default::default());
        let mut timer = StageTimer::new(&log);
        assert_eq!(timer.run(A, || Ok((7, "seven".into()))).unwrap(), 7);
        let err = timer.run(B, || Err::<((), String), _>(RunError::Diverged { step: 3, t: 0.5 })).unwrap_err();
        assert!(matches!(err, RunError::Diverged { step: 3, .. }));
        assert_eq!(*log.0.lock().unwrap(), ["start a", "finish a seven", "start b"]);
        let t = timer.finish();
        assert_eq!(t.iter().map(|(s, _)| s).collect::<Vec<_>>(), vec![A]);
    }
}
