//! Stage progress on the terminal: a spinner per stage (a bar with an estimated time
//! to finish once a stepping stage reports steps), then one line with its time.

use crate::pipeline::{Progress, Stage};
use indicatif::{ProgressBar, ProgressStyle};
use std::sync::Mutex;
use std::time::Duration;

/// The terminal observer of a command (silent with `--quiet`).
pub(super) struct Terminal {
    quiet: bool,
    bar: Mutex<Option<ProgressBar>>,
}

impl Terminal {
    /// An observer that prints unless `quiet`.
    pub(super) fn new(quiet: bool) -> Self {
        Terminal { quiet, bar: Mutex::new(None) }
    }

    /// Print a stage line that was timed outside a stage (the writing of the results).
    pub(super) fn line(&self, stage: Stage, seconds: f64, note: &str) {
        if !self.quiet {
            eprintln!("  {:<9} {:>9.3} s  {}", stage.name(), seconds, note);
        }
    }
}

impl Progress for Terminal {
    fn start(&self, stage: Stage) {
        if self.quiet {
            return;
        }
        let bar = ProgressBar::new_spinner();
        bar.set_style(ProgressStyle::with_template("  {spinner} {msg} ({elapsed})").expect("valid template"));
        bar.set_message(stage.name());
        bar.enable_steady_tick(Duration::from_millis(120));
        *self.bar.lock().unwrap() = Some(bar);
    }

    fn advance(&self, done: u64, total: u64) {
        if let Some(bar) = self.bar.lock().unwrap().as_ref() {
            if bar.length().is_none() {
                bar.set_style(
                    ProgressStyle::with_template("  {msg} [{bar:30}] {pos}/{len} steps ({elapsed}, ETA {eta})").expect("valid template"),
                );
            }
            bar.set_length(total);
            bar.set_position(done);
        }
    }

    fn finish(&self, stage: Stage, seconds: f64, note: &str) {
        if let Some(bar) = self.bar.lock().unwrap().take() {
            bar.finish_and_clear();
        }
        self.line(stage, seconds, note);
    }
}
