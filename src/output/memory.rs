//! Process memory statistics: the peak resident memory of the process, and of a
//! stretch of it (a stage).
//!
//! Linux resets the high-water mark `VmHWM` to the current resident size when "5" is
//! written to `/proc/self/clear_refs`. [`restart_peak`] does that after folding the
//! peak so far into a log, so the process peak ([`peak_memory_bytes`]) is the largest
//! of the log and the current `VmHWM`, and the peak since a mark ([`peak_since`]) is
//! the largest of the current `VmHWM` and what was folded after the mark (nested
//! stretches stay correct). Where the reset is not allowed, `VmHWM` keeps growing and
//! [`peak_since`] is the process peak so far (an upper bound).

use std::sync::Mutex;

/// Peaks folded by [`restart_peak`], in order.
static FOLDED: Mutex<Vec<u64>> = Mutex::new(Vec::new());

/// `VmHWM` now, in bytes.
fn high_water_mark() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
}

/// Peak resident memory of this process in bytes (module docs), if the platform
/// exposes `VmHWM` in /proc/self/status.
///
/// Returns `None` where `/proc/self/status` does not exist or has no parsable `VmHWM` line
/// (non-Linux systems, some sandboxes).
pub fn peak_memory_bytes() -> Option<u64> {
    let now = high_water_mark()?;
    let folded = FOLDED.lock().map(|f| f.iter().copied().max().unwrap_or(0)).unwrap_or(0);
    Some(now.max(folded))
}

/// Memory available to a run, bytes: `MLSM_MEMORY_LIMIT` if set (a number of bytes,
/// e.g. `4e9`), else Linux's `MemAvailable`; `None` when neither is known.
pub fn available_memory_bytes() -> Option<f64> {
    if let Ok(v) = std::env::var("MLSM_MEMORY_LIMIT") {
        return v.trim().parse::<f64>().ok().filter(|x| *x > 0.0);
    }
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// A point from which [`peak_since`] measures.
#[derive(Debug, Clone, Copy)]
pub struct PeakMark(usize);

/// Start measuring a peak from now (module docs).
pub fn restart_peak() -> PeakMark {
    let Ok(mut folded) = FOLDED.lock() else { return PeakMark(usize::MAX) };
    if let Some(now) = high_water_mark() {
        folded.push(now);
        let _ = std::fs::write("/proc/self/clear_refs", "5");
    }
    PeakMark(folded.len())
}

/// Peak resident memory in bytes since `mark` (module docs).
pub fn peak_since(mark: PeakMark) -> Option<u64> {
    let now = high_water_mark()?;
    let folded = FOLDED.lock().map(|f| f.get(mark.0..).map_or(0, |tail| tail.iter().copied().max().unwrap_or(0))).unwrap_or(0);
    Some(now.max(folded))
}

/// Extracts `VmHWM` (reported in kB, i.e. KiB) from the text of `/proc/<pid>/status`.
fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut parts = line["VmHWM:".len()..].split_whitespace();
    let value: u64 = parts.next()?.parse().ok()?;
    match parts.next() {
        Some("kB") | None => value.checked_mul(1024),
        Some(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_status_text() {
        let text = "Name:\tx\nVmPeak:\t  999 kB\nVmHWM:\t    2048 kB\nVmRSS:\t 10 kB\n";
        assert_eq!(parse_vm_hwm(text), Some(2048 * 1024));
        assert_eq!(parse_vm_hwm("VmRSS: 1 kB\n"), None);
        assert_eq!(parse_vm_hwm("VmHWM: lots kB\n"), None);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn peak_grows_with_touched_allocation() {
        let before = peak_memory_bytes().expect("VmHWM on Linux");
        assert!(before > 0);
        // Touch 64 MiB more than the current peak could already include.
        let size = 64 << 20;
        let mut v = vec![0u8; size];
        for i in (0..size).step_by(4096) {
            v[i] = 1;
        }
        std::hint::black_box(&v);
        let after = peak_memory_bytes().unwrap();
        assert!(after >= size as u64, "peak {after} < {size}");
        assert!(after >= before);
        drop(v);
    }

    /// After a restart the stretch's peak sees what it touched and not more than the
    /// process peak; the process peak survives the restart.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_restarted_peak_measures_its_stretch() {
        let size = 96 << 20;
        let mut v = vec![0u8; size];
        for i in (0..size).step_by(4096) {
            v[i] = 1;
        }
        std::hint::black_box(&v);
        drop(v);
        let process = peak_memory_bytes().unwrap();
        let mark = restart_peak();
        assert!(peak_memory_bytes().unwrap() >= process, "the process peak is kept");
        let mut w = vec![0u8; size / 2];
        for i in (0..size / 2).step_by(4096) {
            w[i] = 1;
        }
        std::hint::black_box(&w);
        let stretch = peak_since(mark).unwrap();
        assert!(stretch >= (size / 2) as u64, "{stretch}");
        assert!(stretch <= peak_memory_bytes().unwrap());
    }
}
