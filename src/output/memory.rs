//! Process memory statistics.

/// Peak resident memory of this process in bytes (VmHWM from /proc/self/status) if the platform exposes it.
///
/// Returns `None` where `/proc/self/status` does not exist or has no parsable `VmHWM` line
/// (non-Linux systems, some sandboxes).
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
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
}
