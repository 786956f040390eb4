//! Writing results to disk: ParaView files (`.vtu`, `.pvd`), JSON and CSV.
//!
//! Everything here is self-contained and independent of the solver:
//!
//! * [`write_atomic`], [`write_json`], [`write_csv`]: crash-safe file output (temp file in the
//!   target directory, `fsync`, `rename`), so a reader never sees a half-written file and a
//!   failed write leaves an earlier file intact.
//! * [`StagedDir`]: a whole result directory written beside the old one and swapped in at
//!   the end, so a re-run leaves no stale file and a failed run leaves the old one intact.
//! * [`write_vtu`] / [`read_vtu`]: XML unstructured grid with triangle cells and point data,
//!   written with `vtkio` (inline base64, Float64/Int32 arrays, so values are bit-exact).
//! * [`write_pvd`]: a ParaView collection (time series) file, written by hand.
//! * [`write_loglog_svg`], [`write_loglog_plot`], [`write_front_plot`]: log-log plots labelled at every decade (SVG, plotters; PNG by resvg).
//! * [`write_system`]: an assembled linear system for other solvers (MatrixMarket by
//!   `nalgebra-sparse`, PETSc binary).
//! * [`peak_memory_bytes`], [`restart_peak`], [`peak_since`]: peak resident memory of
//!   the process (Linux `VmHWM`, never reset) and of one stage (the resident size at its
//!   start plus the heap's peak growth, counted by the global allocator).
//! * [`available_memory`]: the memory a run may still use, the smallest of
//!   `MLSM_MEMORY_LIMIT`, `MemAvailable`, the cgroup's limit and `ulimit -v`
//!   ([`smallest_limit`] reads them from their texts).
//!
//! Errors are reported as [`OutputError`]; every variant names the file or field concerned.
//! I/O and JSON errors end their message with the underlying reason (for I/O the
//! operating system's, e.g. "Not a directory (os error 20)") and also keep that error
//! as [`std::error::Error::source`]; printing the message alone is enough.

use std::path::PathBuf;

mod atomic;
mod memory;
mod plot;
mod staged;
mod system;
mod vtk;

pub use atomic::{write_atomic, write_csv, write_json};
pub use memory::{
    available_memory, available_memory_bytes, peak_memory_bytes, peak_since, restart_peak, smallest_limit, LimitSource, LimitTexts,
    MemoryLimit, PeakMark,
};
pub use plot::{svg_to_png, write_front_plot, write_loglog_plot, write_loglog_svg, FrontPanel, PointGroup, Series};
pub use staged::{remove_uncommitted, Owns, StagedDir};
pub use system::{write_system, ColumnMatrix, PETSC_MAT_CLASSID, PETSC_VEC_CLASSID};
pub use vtk::{read_vtu, write_pvd, write_vtu, write_vtu_with, FieldValues, PointField, VtuContents};

/// Error returned by every fallible function of this module.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An operating-system I/O operation on `path` failed (for atomic writes `path` is the
    /// *target* file, not the hidden temporary file). The message ends with the
    /// operating system's reason.
    #[error("I/O error on `{}`: {source}", path.display())]
    Io {
        /// The file being written or read.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// `vtkio` failed to build, serialise or parse a VTK file, or the file read back does not
    /// have the expected structure.
    #[error("VTK error for `{}`: {detail}", path.display())]
    Vtk {
        /// The VTK file concerned.
        path: PathBuf,
        /// Human-readable description (includes the `vtkio` error text).
        detail: String,
    },
    /// `serde_json` could not serialise the value (e.g. a map with non-string keys).
    #[error("JSON serialisation error for `{}`: {source}", path.display())]
    Json {
        /// The JSON file being written.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: serde_json::Error,
    },
    /// A point-data field is malformed (wrong length, zero components, duplicate or empty name).
    #[error("invalid field `{name}`: {detail}")]
    InvalidField {
        /// Name of the offending field.
        name: String,
        /// What is wrong with it.
        detail: String,
    },
    /// Any other invalid argument (non-finite point, triangle index out of range, CSV row of
    /// the wrong width, non-finite time step, path without a file name, ...).
    #[error("invalid input for `{}`: {detail}", path.display())]
    InvalidInput {
        /// The file that was to be written.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
}

impl OutputError {
    /// Shorthand for [`OutputError::Io`].
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        OutputError::Io { path: path.to_path_buf(), source }
    }

    /// Shorthand for [`OutputError::Vtk`].
    pub(crate) fn vtk(path: &std::path::Path, detail: impl ToString) -> Self {
        OutputError::Vtk { path: path.to_path_buf(), detail: detail.to_string() }
    }

    /// Shorthand for [`OutputError::InvalidInput`].
    pub(crate) fn invalid(path: &std::path::Path, detail: impl Into<String>) -> Self {
        OutputError::InvalidInput { path: path.to_path_buf(), detail: detail.into() }
    }
}

/// Formats a float so that parsing it back gives the identical `f64` (shortest round-trip
/// digits), in plain notation for moderate magnitudes and scientific notation otherwise.
/// Non-finite values are written as `NaN`, `inf`, `-inf` (understood by numpy/pandas and by
/// Rust's `str::parse`).
pub(crate) fn format_f64(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_f64_round_trips_exactly() {
        let values = [
            0.0,
            -0.0,
            1.0,
            0.1,
            1.0 / 3.0,
            -2.5e-300,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            123_456_789.123_456_79,
            1e15,
            9.999e-5,
            std::f64::consts::PI * 1e7,
        ];
        for &v in &values {
            let s = format_f64(v);
            let back: f64 = s.parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v} -> {s}");
            assert!(s.len() < 30, "unexpectedly long rendering {s}");
        }
        assert_eq!(format_f64(f64::NAN), "NaN");
        assert_eq!(format_f64(f64::INFINITY), "inf");
        assert_eq!(format_f64(f64::NEG_INFINITY), "-inf");
        assert!(format_f64(f64::NAN).parse::<f64>().unwrap().is_nan());
    }

    #[test]
    fn error_messages_name_the_path_and_field() {
        let e = OutputError::io(std::path::Path::new("/x/y.vtu"), std::io::Error::other("boom"));
        assert!(e.to_string().contains("/x/y.vtu") && e.to_string().ends_with(": boom"), "{e}");
        assert!(std::error::Error::source(&e).is_some());
        let e = OutputError::InvalidField { name: "u".into(), detail: "bad".into() };
        assert!(e.to_string().contains("`u`"));
    }
}
