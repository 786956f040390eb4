//! Process memory statistics: the peak resident memory of the process, and of a
//! stretch of it (a stage).
//!
//! The process peak ([`peak_memory_bytes`]) is Linux's high-water mark `VmHWM`, never
//! reset, so it is the peak that `/usr/bin/time` and any other outside tool see.
//! A stretch's peak is measured by the heap, not the kernel: every allocation goes
//! through an instrumented system allocator (`peakmem-alloc`, the crate's global
//! allocator), whose peak growth is restarted at each mark. The peak of a stretch is
//! the resident size at its start (`VmRSS`) plus the largest growth of the heap
//! within it ([`restart_peak`] folds the stretch before into a log, so nested
//! stretches stay correct, [`peak_since`]), at most the process peak (allocations
//! never touched count in the heap's growth, not in the resident size).
//!
//! The memory a run may still use ([`available_memory`]) is the smallest of the limits
//! that apply to the process: `MLSM_MEMORY_LIMIT`, `MemAvailable`, its cgroup's (v2 or
//! v1, at every level up to the root) and `ulimit -v`.

use peakmem_alloc::{PeakMemAlloc, PeakMemAllocTrait, INSTRUMENTED_SYSTEM};
use std::alloc::System;
use std::sync::Mutex;

/// The allocator of every binary and test built with this crate: the system's,
/// counting the peak growth of the heap since its last reset.
#[global_allocator]
static HEAP: &PeakMemAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Peaks of the stretches closed by [`restart_peak`], in order, and the resident size
/// at the start of the open one (bytes).
static STRETCHES: Mutex<(Vec<u64>, u64)> = Mutex::new((Vec::new(), 0));

/// The value of the line `key` (in kB) of /proc/self/status, in bytes.
fn status_bytes(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_status_kb(&status, key)
}

/// Peak resident memory of this process in bytes (`VmHWM`, module docs), if the
/// platform exposes it in /proc/self/status.
///
/// Returns `None` where `/proc/self/status` does not exist or has no parsable `VmHWM` line
/// (non-Linux systems, some sandboxes).
pub fn peak_memory_bytes() -> Option<u64> {
    status_bytes("VmHWM")
}

/// Memory available to a run, bytes: the smallest of the limits that apply
/// ([`available_memory`]); `None` when none is known.
pub fn available_memory_bytes() -> Option<f64> {
    available_memory().map(|l| l.bytes)
}

/// Where a [`MemoryLimit`] comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitSource {
    /// The environment variable `MLSM_MEMORY_LIMIT` (bytes).
    Environment,
    /// Linux's `MemAvailable` (/proc/meminfo).
    MemAvailable,
    /// The cgroup v2 `memory.max` minus `memory.current` (plus the reclaimable
    /// `inactive_file` of `memory.stat`) of the process's cgroup or an ancestor.
    CgroupV2,
    /// The cgroup v1 `memory.limit_in_bytes` minus `memory.usage_in_bytes` (plus the
    /// reclaimable `total_inactive_file` of `memory.stat`).
    CgroupV1,
    /// `ulimit -v` (`RLIMIT_AS`) minus the address space the process already maps.
    AddressSpace,
}

impl LimitSource {
    /// How a refusal names the limit.
    pub fn describe(self) -> &'static str {
        match self {
            LimitSource::Environment => "MLSM_MEMORY_LIMIT",
            LimitSource::MemAvailable => "MemAvailable of /proc/meminfo",
            LimitSource::CgroupV2 => "the cgroup's memory.max minus memory.current (cgroup v2)",
            LimitSource::CgroupV1 => "the cgroup's memory.limit_in_bytes minus memory.usage_in_bytes (cgroup v1)",
            LimitSource::AddressSpace => "ulimit -v (RLIMIT_AS) minus the address space in use",
        }
    }
}

/// The memory a run may still use, bytes, and the limit that sets it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryLimit {
    /// Bytes.
    pub bytes: f64,
    /// The limit that is the smallest.
    pub source: LimitSource,
}

/// The texts a memory limit is read from (each `None` where the file or setting does
/// not exist): the input of [`smallest_limit`], so that it can be tested on any text.
#[derive(Debug, Clone, Default)]
pub struct LimitTexts {
    /// `MLSM_MEMORY_LIMIT`.
    pub environment: Option<String>,
    /// /proc/meminfo.
    pub meminfo: Option<String>,
    /// `(memory.max, memory.current, memory.stat)` of the process's cgroup v2 and of
    /// each of its ancestors.
    pub cgroup_v2: Vec<(String, String, Option<String>)>,
    /// `(memory.limit_in_bytes, memory.usage_in_bytes, memory.stat)` of the process's
    /// cgroup v1 memory controller and of each of its ancestors.
    pub cgroup_v1: Vec<(String, String, Option<String>)>,
    /// The soft `RLIMIT_AS` in bytes (`None`: unlimited).
    pub address_space_limit: Option<u64>,
    /// /proc/self/status (its `VmSize`, the address space in use).
    pub status: Option<String>,
}

/// cgroup v1 reports "no limit" as a number near 2^63: anything above 2^60 bytes is no limit.
const NO_LIMIT: f64 = (1u64 << 60) as f64;

/// The smallest of the limits in `texts` that apply: `MLSM_MEMORY_LIMIT` (a positive
/// number of bytes; it can lower the limit, never raise it), `MemAvailable`, every
/// cgroup level's limit less its usage (the reclaimable page cache counted as free),
/// `RLIMIT_AS` less `VmSize`. A malformed value is ignored here (`MLSM_MEMORY_LIMIT`
/// is refused by the memory check).
pub fn smallest_limit(texts: &LimitTexts) -> Option<MemoryLimit> {
    let number = |t: &str| t.trim().parse::<f64>().ok().filter(|x| x.is_finite() && *x >= 0.0);
    let field = |text: &str, key: &str| {
        text.lines().find_map(|l| {
            let mut w = l.split_whitespace();
            (w.next()?.trim_end_matches(':') == key).then(|| w.next().and_then(number)).flatten()
        })
    };
    let cgroup = |levels: &[(String, String, Option<String>)], inactive: &str| {
        levels
            .iter()
            .filter_map(|(limit, usage, stat)| {
                let limit = number(limit).filter(|l| *l < NO_LIMIT)?;
                let cache = stat.as_deref().and_then(|s| field(s, inactive)).unwrap_or(0.0);
                Some((limit - number(usage)? + cache).clamp(0.0, limit))
            })
            .reduce(f64::min)
    };
    let candidates = [
        (texts.environment.as_deref().and_then(number).filter(|x| *x > 0.0), LimitSource::Environment),
        (texts.meminfo.as_deref().and_then(|m| field(m, "MemAvailable")).map(|kb| kb * 1024.0), LimitSource::MemAvailable),
        (cgroup(&texts.cgroup_v2, "inactive_file"), LimitSource::CgroupV2),
        (cgroup(&texts.cgroup_v1, "total_inactive_file"), LimitSource::CgroupV1),
        (
            texts.address_space_limit.map(|l| l as f64).filter(|l| *l < NO_LIMIT).map(|l| {
                let used = texts.status.as_deref().and_then(|s| field(s, "VmSize")).map_or(0.0, |kb| kb * 1024.0);
                (l - used).max(0.0)
            }),
            LimitSource::AddressSpace,
        ),
    ];
    candidates.into_iter().filter_map(|(bytes, source)| bytes.map(|bytes| MemoryLimit { bytes, source })).reduce(|a, b| {
        if b.bytes < a.bytes {
            b
        } else {
            a
        }
    })
}

/// The cgroup directories of this process under the controller mount `root`, from its
/// own up to the root: `(hierarchy path, directory)` for the line of /proc/self/cgroup
/// that `line_matches`.
fn cgroup_dirs(cgroup: &str, root: &str, line_matches: impl Fn(&str) -> bool) -> Vec<std::path::PathBuf> {
    let Some(path) = cgroup.lines().find_map(|l| {
        let mut parts = l.splitn(3, ':');
        let (_, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        line_matches(controllers).then_some(path)
    }) else {
        return Vec::new();
    };
    let mut dirs = Vec::new();
    let mut p = std::path::Path::new(path.trim());
    loop {
        dirs.push(std::path::Path::new(root).join(p.strip_prefix("/").unwrap_or(p)));
        match p.parent() {
            Some(parent) => p = parent,
            None => break,
        }
    }
    dirs
}

/// The limit files of each directory of `dirs` that has them.
fn cgroup_levels(dirs: &[std::path::PathBuf], limit: &str, usage: &str) -> Vec<(String, String, Option<String>)> {
    let read = |p: std::path::PathBuf| std::fs::read_to_string(p).ok();
    dirs.iter().filter_map(|d| Some((read(d.join(limit))?, read(d.join(usage))?, read(d.join("memory.stat"))))).collect()
}

/// The texts of this process's limits ([`LimitTexts`]).
fn limit_texts() -> LimitTexts {
    let cgroup = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    // cgroup v2: the unified hierarchy at /sys/fs/cgroup, or /sys/fs/cgroup/unified on
    // a hybrid system; v1: the memory controller's own hierarchy.
    let mut v2 = Vec::new();
    for root in ["/sys/fs/cgroup", "/sys/fs/cgroup/unified"] {
        v2 = cgroup_levels(&cgroup_dirs(&cgroup, root, |c| c.is_empty()), "memory.max", "memory.current");
        if !v2.is_empty() {
            break;
        }
    }
    let v1_dirs = cgroup_dirs(&cgroup, "/sys/fs/cgroup/memory", |c| c.split(',').any(|c| c == "memory"));
    LimitTexts {
        environment: std::env::var("MLSM_MEMORY_LIMIT").ok(),
        meminfo: std::fs::read_to_string("/proc/meminfo").ok(),
        cgroup_v2: v2,
        cgroup_v1: cgroup_levels(&v1_dirs, "memory.limit_in_bytes", "memory.usage_in_bytes"),
        address_space_limit: address_space_limit(),
        status: std::fs::read_to_string("/proc/self/status").ok(),
    }
}

/// The soft `RLIMIT_AS` (`ulimit -v`) in bytes, `None` when unlimited.
fn address_space_limit() -> Option<u64> {
    #[cfg(unix)]
    {
        let mut r = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
        // SAFETY: getrlimit writes into the struct it is given.
        if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } == 0 && r.rlim_cur != libc::RLIM_INFINITY {
            return Some(r.rlim_cur as u64);
        }
    }
    None
}

/// The memory a run may still use and the limit that sets it: the smallest of
/// `MLSM_MEMORY_LIMIT`, `MemAvailable`, the cgroup's (v2 or v1, every level up to the
/// root) and `ulimit -v` ([`smallest_limit`]); `None` when none is known.
pub fn available_memory() -> Option<MemoryLimit> {
    smallest_limit(&limit_texts())
}

/// A point from which [`peak_since`] measures.
#[derive(Debug, Clone, Copy)]
pub struct PeakMark(usize);

/// The peak of the open stretch: its start's resident size plus the heap's peak growth.
fn open_stretch(start: u64) -> u64 {
    start + HEAP.get_peak_memory() as u64
}

/// Start measuring a peak from now (module docs).
pub fn restart_peak() -> PeakMark {
    let Ok(mut stretches) = STRETCHES.lock() else { return PeakMark(usize::MAX) };
    let closed = open_stretch(stretches.1);
    stretches.0.push(closed);
    HEAP.reset_peak_memory();
    stretches.1 = status_bytes("VmRSS").unwrap_or(0);
    PeakMark(stretches.0.len())
}

/// Peak resident memory in bytes since `mark` (module docs); `None` where the
/// resident size is not known.
pub fn peak_since(mark: PeakMark) -> Option<u64> {
    let stretches = STRETCHES.lock().ok()?;
    if stretches.1 == 0 {
        return None;
    }
    let closed = stretches.0.get(mark.0..).map_or(0, |tail| tail.iter().copied().max().unwrap_or(0));
    let stretch = open_stretch(stretches.1).max(closed);
    // Allocations never touched count in the heap, not in the resident size: the
    // process peak bounds any stretch's.
    Some(peak_memory_bytes().map_or(stretch, |process| stretch.min(process)))
}

/// Extracts the line `key` (reported in kB, i.e. KiB) from the text of
/// `/proc/<pid>/status`, in bytes.
fn parse_status_kb(status: &str, key: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.split(':').next() == Some(key))?;
    let mut parts = line[key.len() + 1..].split_whitespace();
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
        assert_eq!(parse_status_kb(text, "VmHWM"), Some(2048 * 1024));
        assert_eq!(parse_status_kb(text, "VmRSS"), Some(10 * 1024));
        assert_eq!(parse_status_kb("VmRSS: 1 kB\n", "VmHWM"), None);
        assert_eq!(parse_status_kb("VmHWM: lots kB\n", "VmHWM"), None);
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

    /// After a restart the stretch's peak sees what it allocated, and the process peak
    /// (`VmHWM`, what outside tools read) is not reset by it. (No upper bound on the
    /// stretch: tests of this binary run in parallel and allocate into it.)
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
        assert!(peak_memory_bytes().unwrap() >= process, "the process peak is kept");
    }
}
