//! Stage progress on the terminal: a spinner per stage (a bar with an estimated time
//! to finish once a stepping stage reports steps), then one line with its time.
//!
//! When stderr is not a terminal (a log file, CI), where a spinner draws nothing, a
//! stage that lasts longer than [`PLAIN_INTERVAL`] prints a plain line at that
//! interval instead: stage name, percent and steps when the stage reports steps,
//! elapsed time and the estimated time to finish. `MLSM_PROGRESS_INTERVAL` (seconds)
//! overrides the interval. `--quiet` silences both.

use crate::stages::{Progress, Stage};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Interval of the plain progress lines when stderr is not a terminal.
pub(super) const PLAIN_INTERVAL: Duration = Duration::from_secs(5);

/// Environment variable overriding [`PLAIN_INTERVAL`] (seconds, e.g. `0.5`).
pub(super) const INTERVAL_VARIABLE: &str = "MLSM_PROGRESS_INTERVAL";

/// The terminal observer of a command (silent with `--quiet`).
pub(super) struct Terminal {
    quiet: bool,
    /// The interval of plain lines when stderr is not a terminal, else `None`.
    plain: Option<Duration>,
    bar: Mutex<Option<ProgressBar>>,
    ticker: Mutex<Option<Ticker>>,
}

impl Terminal {
    /// An observer that prints unless `quiet`: spinners on a terminal, plain lines
    /// every [`PLAIN_INTERVAL`] (or `MLSM_PROGRESS_INTERVAL`) otherwise.
    pub(super) fn new(quiet: bool) -> Self {
        let plain = (!quiet && !std::io::stderr().is_terminal()).then(plain_interval);
        Terminal { quiet, plain, bar: Mutex::new(None), ticker: Mutex::new(None) }
    }

    /// Print a stage line that was timed outside a stage (the writing of the results).
    pub(super) fn line(&self, stage: Stage, seconds: f64, note: &str) {
        if !self.quiet {
            eprintln!("  {:<9} {:>9.3} s  {}", stage.name(), seconds, note);
        }
    }
}

/// [`PLAIN_INTERVAL`], or the positive number of seconds in `MLSM_PROGRESS_INTERVAL`
/// (an invalid value is reported and ignored).
fn plain_interval() -> Duration {
    let Ok(text) = std::env::var(INTERVAL_VARIABLE) else { return PLAIN_INTERVAL };
    match text.trim().parse::<f64>() {
        Ok(s) if s > 0.0 && s.is_finite() => Duration::from_secs_f64(s),
        _ => {
            eprintln!(
                "note: {INTERVAL_VARIABLE}={text:?} is not a positive number of seconds; progress every {} s",
                PLAIN_INTERVAL.as_secs()
            );
            PLAIN_INTERVAL
        }
    }
}

impl Progress for Terminal {
    fn start(&self, stage: Stage) {
        if self.quiet {
            return;
        }
        if let Some(every) = self.plain {
            let old = self.ticker.lock().unwrap().replace(Ticker::start(stage, every));
            drop(old);
            return;
        }
        let bar = ProgressBar::new_spinner();
        bar.set_style(ProgressStyle::with_template("  {spinner} {msg} ({elapsed})").expect("valid template"));
        bar.set_message(stage.name());
        bar.enable_steady_tick(Duration::from_millis(120));
        *self.bar.lock().unwrap() = Some(bar);
    }

    fn advance(&self, done: u64, total: u64, unit: &'static str) {
        if let Some(t) = self.ticker.lock().unwrap().as_ref() {
            *t.steps.lock().unwrap() = Some((done, total, unit));
        }
        if let Some(bar) = self.bar.lock().unwrap().as_ref() {
            if bar.length().is_none() {
                let template = format!("  {{msg}} [{{bar:30}}] {{pos}}/{{len}} {unit} ({{elapsed}}, ETA {{eta}})");
                bar.set_style(ProgressStyle::with_template(&template).expect("valid template"));
            }
            bar.set_length(total);
            bar.set_position(done);
        }
    }

    fn finish(&self, stage: Stage, seconds: f64, note: &str) {
        let ticker = self.ticker.lock().unwrap().take();
        drop(ticker);
        if let Some(bar) = self.bar.lock().unwrap().take() {
            bar.finish_and_clear();
        }
        self.line(stage, seconds, note);
    }
}

/// Units done, their total and their name (the last `Progress::advance`).
type Advance = (u64, u64, &'static str);

/// A thread printing a plain progress line of one stage at a fixed interval; stops
/// when dropped.
struct Ticker {
    /// Steps done and total, once the stage reports them.
    steps: Arc<Mutex<Option<Advance>>>,
    stop: Option<Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl Ticker {
    /// Print a line about `stage` every `every` until dropped.
    fn start(stage: Stage, every: Duration) -> Ticker {
        let steps = Arc::new(Mutex::new(None));
        let (stop, stopped) = mpsc::channel::<()>();
        let shared = Arc::clone(&steps);
        let t0 = Instant::now();
        let thread = std::thread::spawn(move || {
            while let Err(RecvTimeoutError::Timeout) = stopped.recv_timeout(every) {
                let now = *shared.lock().unwrap();
                eprintln!("{}", plain_line(stage.name(), t0.elapsed(), now));
            }
        });
        Ticker { steps, stop: Some(stop), thread: Some(thread) }
    }
}

impl Drop for Ticker {
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// `  [integrate] 42.0 % (4200/10000 steps), elapsed 12.3 s, ETA 17.0 s`, or without
/// steps `  [solve] running, elapsed 12.3 s`.
fn plain_line(stage: &str, elapsed: Duration, steps: Option<(u64, u64, &str)>) -> String {
    let e = elapsed.as_secs_f64();
    match steps {
        Some((done, total, unit)) if total > 0 => {
            let fraction = done as f64 / total as f64;
            let eta = if done > 0 { format!("{:.1} s", e * (total - done.min(total)) as f64 / done as f64) } else { "-".into() };
            format!("  [{stage}] {:.1} % ({done}/{total} {unit}), elapsed {e:.1} s, ETA {eta}", 100.0 * fraction)
        }
        _ => format!("  [{stage}] running, elapsed {e:.1} s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_lines_give_percent_elapsed_and_eta() {
        let l = plain_line("integrate", Duration::from_secs(10), Some((250, 1000, "steps")));
        assert_eq!(l, "  [integrate] 25.0 % (250/1000 steps), elapsed 10.0 s, ETA 30.0 s");
        let l = plain_line("solve", Duration::from_secs(6), Some((3, 10, "residual digits")));
        assert_eq!(l, "  [solve] 30.0 % (3/10 residual digits), elapsed 6.0 s, ETA 14.0 s");
        let l = plain_line("integrate", Duration::from_secs(1), Some((0, 1000, "steps")));
        assert!(l.contains("0.0 %") && l.contains("ETA -"), "{l}");
        assert_eq!(plain_line("solve", Duration::from_millis(1500), None), "  [solve] running, elapsed 1.5 s");
    }
}
