//! One configuration of the sweep run as its own `mlsm run` process: its peak memory is
//! its own, a crash stays in it, and it can be stopped at the budget's deadline.

use super::super::AppError;
use crate::output::OutputError;
use crate::quality::warnings::SINGULAR_ESTIMATE_FACTOR;
use crate::tradeoff::design::POLL_S;
use serde::Serialize;
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

/// Error norms of one solution (`summary.json`'s `errors` or `estimated_errors`).
#[derive(Debug, Clone, Copy, Serialize)]
pub(super) struct Norms {
    pub e_inf_u: f64,
    pub e_inf_sigma: Option<f64>,
    pub rel_l2_u: f64,
    pub rel_l2_sigma: Option<f64>,
}

impl Norms {
    /// e_inf of `field` (`None` for sigma when the run computed no stress).
    pub fn e_inf(&self, field: super::Field) -> Option<f64> {
        match field {
            super::Field::Sigma => self.e_inf_sigma,
            super::Field::U => Some(self.e_inf_u),
        }
    }

    /// The displacement norms multiplied by `factor`, the stress norms as they are.
    fn displacement_counted(self, factor: f64) -> Norms {
        Norms { e_inf_u: factor * self.e_inf_u, rel_l2_u: factor * self.rel_l2_u, ..self }
    }

    /// The norms of a `summary.json` object; `None` when it has none (`unavailable`).
    fn of(v: &Value) -> Option<Norms> {
        let get = |k: &str| v.get(k).and_then(Value::as_f64);
        Some(Norms {
            e_inf_u: get("e_inf_u")?,
            e_inf_sigma: get("e_inf_sigma"),
            rel_l2_u: get("rel_l2_u")?,
            rel_l2_sigma: get("rel_l2_sigma"),
        })
    }
}

/// What a finished run reported.
#[derive(Debug, Clone)]
pub(super) struct Report {
    pub nodes: u64,
    /// Seconds of the run as a user runs it: its error estimate included.
    pub seconds: f64,
    /// Seconds of its error estimate (part of `seconds`).
    pub estimate_seconds: f64,
    pub peak_memory_bytes: Option<f64>,
    pub exact: Option<Norms>,
    /// The run's estimate, its displacement norms counted x[`SINGULAR_ESTIMATE_FACTOR`]
    /// when the scene has singular corners (as the run's `estimate` check counts them).
    pub estimated: Option<Norms>,
    /// Whether the run found singular corners (`summary.json` `singular_corners`).
    pub singular_corners: bool,
    /// The checks that warned (`summary.json` `warnings[].check`).
    pub warnings: Vec<String>,
}

/// How a child run ended.
pub(super) enum Ending {
    Finished(Report),
    /// Non-zero exit: the code and the last lines of its error output.
    Failed(String),
    /// Stopped at the deadline.
    Stopped,
}

/// Run `mlsm --quiet run <config> --out <dir>` and wait for it, looking every
/// [`POLL_S`] whether the budget `ended` (then it is stopped); its error output goes to
/// `<dir>.log`.
pub(super) fn run(config: &Path, dir: &Path, ended: impl Fn() -> bool) -> Result<Ending, AppError> {
    let log_path = dir.with_extension("log");
    let io = |path: &Path, e: std::io::Error| AppError::Output(OutputError::io(path, e));
    let log = std::fs::File::create(&log_path).map_err(|e| io(&log_path, e))?;
    let exe = std::env::current_exe().map_err(|e| io(Path::new("mlsm"), e))?;
    let mut child = Command::new(exe)
        .arg("--quiet")
        .arg("run")
        .arg(config)
        .arg("--out")
        .arg(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(log)
        .spawn()
        .map_err(|e| io(config, e))?;
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| io(config, e))? {
            break status;
        }
        if ended() {
            let _ = child.kill();
            let _ = child.wait();
            return Ok(Ending::Stopped);
        }
        std::thread::sleep(Duration::from_secs_f64(POLL_S));
    };
    if !status.success() {
        let text = std::fs::read_to_string(&log_path).unwrap_or_default();
        let tail: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
        let tail = tail[tail.len().saturating_sub(2)..].join(" / ");
        return Ok(Ending::Failed(format!("exit {}: {tail}", status.code().map_or("by a signal".into(), |c| c.to_string()))));
    }
    let summary_path = dir.join("summary.json");
    let text = std::fs::read_to_string(&summary_path).map_err(|e| io(&summary_path, e))?;
    let s: Value =
        serde_json::from_str(&text).map_err(|e| AppError::Output(OutputError::Json { path: summary_path.clone(), source: e }))?;
    // The solution itself is not kept: the configuration file reproduces it.
    let _ = std::fs::remove_file(dir.join("solution.vtu"));
    let timing = |k: &str| s["timings_s"].get(k).and_then(Value::as_f64).unwrap_or(0.0);
    let singular = s["singular_corners"].as_array().is_some_and(|c| !c.is_empty());
    Ok(Ending::Finished(Report {
        nodes: s["nodes"].as_u64().unwrap_or(0),
        seconds: timing("total"),
        estimate_seconds: timing("estimate"),
        peak_memory_bytes: s["peak_memory_bytes"].as_f64(),
        exact: Norms::of(&s["errors"]),
        estimated: Norms::of(&s["estimated_errors"]).map(|n| if singular { n.displacement_counted(SINGULAR_ESTIMATE_FACTOR) } else { n }),
        singular_corners: singular,
        warnings: s["warnings"].as_array().map_or(Vec::new(), |w| w.iter().filter_map(|w| w["check"].as_str().map(String::from)).collect()),
    }))
}
