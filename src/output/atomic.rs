//! Crash-safe file writing: [`write_atomic`] and the JSON/CSV writers built on it.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::{format_f64, OutputError};

/// Distinguishes temp files of concurrent writers within one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Removes the temporary file on drop unless the rename succeeded.
struct TempGuard {
    path: PathBuf,
    armed: bool,
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if self.armed {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Creates a fresh hidden temp file next to `path`, returning its name and handle.
fn create_temp(path: &Path) -> Result<(TempGuard, File), OutputError> {
    let name = path.file_name().ok_or_else(|| OutputError::invalid(path, "path has no file name"))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let pid = std::process::id();
    let mut last_err = None;
    for _ in 0..100 {
        let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".{pid}.{n}.tmp"));
        let tmp = dir.join(tmp_name);
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((TempGuard { path: tmp, armed: true }, f)),
            // A stale temp file of a crashed process with the same pid: try the next name.
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last_err = Some(e),
            Err(e) => return Err(OutputError::io(path, e)),
        }
    }
    Err(OutputError::io(path, last_err.unwrap_or_else(|| io::Error::other("could not create a temp file"))))
}

/// Core of all atomic writers: `fill` streams the content into a buffered temp file which is
/// then flushed, fsynced and renamed over `path`. On any error (including one returned by
/// `fill`) the temp file is removed and `path` is left as it was.
pub(crate) fn write_atomic_with<F>(path: &Path, fill: F) -> Result<(), OutputError>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
{
    let (mut guard, file) = create_temp(path)?;
    let mut w = BufWriter::with_capacity(1 << 16, file);
    fill(&mut w)?;
    let file = w.into_inner().map_err(|e| OutputError::io(path, e.into_error()))?;
    file.sync_all().map_err(|e| OutputError::io(path, e))?;
    drop(file);
    fs::rename(&guard.path, path).map_err(|e| OutputError::io(path, e))?;
    guard.armed = false;
    // Persist the directory entry too. Best effort: some file systems refuse to fsync a
    // directory, and the data itself is already safe at this point.
    #[cfg(unix)]
    if let Some(dir) = guard.path.parent() {
        let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}

/// Write bytes to `path` atomically: write a temp file in the same directory, fsync, rename.
/// A failure leaves any earlier file intact and no temp file behind.
///
/// The temp file is named `.<file name>.<pid>.<n>.tmp`. The new file gets default
/// permissions (those of the previous file are not copied), and if `path` is a symbolic link
/// the link itself is replaced. The parent directory must exist; it is not created.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomic_with(path, |w| w.write_all(bytes).map_err(|e| OutputError::io(path, e)))
}

/// Serialises `value` as pretty-printed JSON (with a trailing newline) and writes it
/// atomically (see [`write_atomic`]). Non-finite floats become `null`, as usual in `serde_json`.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), OutputError> {
    write_atomic_with(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value).map_err(|e| {
            if e.is_io() {
                OutputError::io(path, e.into())
            } else {
                OutputError::Json { path: path.to_path_buf(), source: e }
            }
        })?;
        w.write_all(b"\n").map_err(|e| OutputError::io(path, e))
    })
}

/// Quotes a CSV header cell if it contains a separator, quote or line break (RFC 4180).
fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// CSV with a header row; numbers in full precision ({:e} or shortest round-trip); atomic.
///
/// Each number is written with the shortest digits that parse back to the identical `f64`
/// (plain notation for 1e-4 <= |x| < 1e15, scientific otherwise; `NaN`, `inf`, `-inf` for
/// non-finite values). Lines end with `\n`. Every row must have exactly `header.len()`
/// values, otherwise [`OutputError::InvalidInput`] names the first bad row (0-based, not
/// counting the header) and nothing is written.
pub fn write_csv(path: &Path, header: &[&str], rows: &[Vec<f64>]) -> Result<(), OutputError> {
    if let Some((i, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != header.len()) {
        return Err(OutputError::invalid(path, format!("CSV row {i} has {} values but the header has {} columns", r.len(), header.len())));
    }
    write_atomic_with(path, |w| {
        let io = |e| OutputError::io(path, e);
        let head: Vec<String> = header.iter().map(|h| csv_cell(h)).collect();
        writeln!(w, "{}", head.join(",")).map_err(io)?;
        let mut line = String::new();
        for row in rows {
            line.clear();
            for (j, &x) in row.iter().enumerate() {
                if j > 0 {
                    line.push(',');
                }
                line.push_str(&format_f64(x));
            }
            line.push('\n');
            w.write_all(line.as_bytes()).map_err(io)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names of all entries of `dir` (to detect leftover temp files).
    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_replaces_content() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"first").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"first");
        write_atomic(&p, b"second, longer").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"second, longer");
        assert_eq!(entries(dir.path()), vec!["a.txt".to_string()]);
    }

    #[test]
    fn nonexistent_directory_is_an_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no_such_dir").join("out.json");
        let err = write_atomic(&p, b"x").unwrap_err();
        match &err {
            OutputError::Io { path, source } => {
                assert_eq!(path, &p);
                assert_eq!(source.kind(), io::ErrorKind::NotFound);
            }
            other => panic!("unexpected error {other:?}"),
        }
        assert!(err.to_string().contains("no_such_dir"), "{err}");
        assert_eq!(entries(dir.path()), Vec::<String>::new());
    }

    #[test]
    fn target_is_a_directory_fails_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("sub");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("keep.txt"), b"precious").unwrap();
        let err = write_atomic(&target, b"new").unwrap_err();
        assert!(matches!(err, OutputError::Io { ref path, .. } if path == &target));
        // The directory and its content are untouched, and no temp file remains.
        assert!(target.is_dir());
        assert_eq!(fs::read(target.join("keep.txt")).unwrap(), b"precious");
        assert_eq!(entries(dir.path()), vec!["sub".to_string()]);
    }

    #[test]
    fn failure_midway_keeps_previous_file_and_removes_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("result.csv");
        write_atomic(&p, b"old content").unwrap();
        // Simulate a failure after part of the new content was written (e.g. disk full).
        let err = write_atomic_with(&p, |w| {
            w.write_all(&[b'x'; 200_000]).unwrap(); // larger than the buffer: hits the temp file
            Err(OutputError::io(&p, io::Error::other("simulated")))
        })
        .unwrap_err();
        assert!(matches!(err, OutputError::Io { .. }));
        assert_eq!(fs::read(&p).unwrap(), b"old content");
        assert_eq!(entries(dir.path()), vec!["result.csv".to_string()]);
    }

    #[test]
    fn json_is_pretty_and_round_trips() {
        #[derive(serde::Serialize, serde::Deserialize, PartialEq, Debug)]
        struct S {
            a: f64,
            b: Vec<u32>,
            name: String,
        }
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.json");
        let s = S { a: 0.1 + 0.2, b: vec![1, 2, 3], name: "x\"y".into() };
        write_json(&p, &s).unwrap();
        let text = fs::read_to_string(&p).unwrap();
        assert!(text.contains("\n  \"a\""), "not pretty: {text}");
        assert!(text.ends_with("}\n"));
        let back: S = serde_json::from_str(&text).unwrap();
        assert_eq!(back, s);
        assert_eq!(back.a.to_bits(), (0.1f64 + 0.2).to_bits());
    }

    #[test]
    fn json_serialisation_error_is_reported_and_leaves_no_file() {
        use std::collections::BTreeMap;
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.json");
        // JSON object keys must be strings; a tuple key cannot be serialised.
        let mut m = BTreeMap::new();
        m.insert((1, 2), 3);
        let err = write_json(&p, &m).unwrap_err();
        assert!(matches!(err, OutputError::Json { .. }), "{err:?}");
        assert_eq!(entries(dir.path()), Vec::<String>::new());
    }

    #[test]
    fn csv_full_precision_and_header() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        let rows = vec![vec![1.0 / 3.0, -2.5e-300, 0.0], vec![1e20, f64::NAN, 123.456]];
        write_csv(&p, &["x", "err, rel", "h"], &rows).unwrap();
        let text = fs::read_to_string(&p).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), "x,\"err, rel\",h");
        for row in &rows {
            let parsed: Vec<f64> = lines.next().unwrap().split(',').map(|s| s.parse().unwrap()).collect();
            assert_eq!(parsed.len(), row.len());
            for (a, b) in parsed.iter().zip(row) {
                assert!(a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()));
            }
        }
        assert!(lines.next().is_none());
    }

    #[test]
    fn csv_row_width_mismatch_is_rejected_before_writing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        let err = write_csv(&p, &["a", "b"], &[vec![1.0, 2.0], vec![3.0]]).unwrap_err();
        assert!(err.to_string().contains("row 1"), "{err}");
        assert!(!p.exists());
    }
}
