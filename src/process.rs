//! What the process itself has used: its peak resident memory, per stage of a long command
//! (training logs each stage's time and peak memory).

/// The process's peak resident set since it started or since the last [`reset_peak_memory`]
/// (`VmHWM` of `/proc/self/status`), in MB; `None` where that file does not exist.
pub fn peak_memory_mb() -> Option<f64> {
    status_mb("VmHWM:")
}

/// The process's current resident set (`VmRSS` of `/proc/self/status`), in MB; `None` where
/// that file does not exist.
pub fn resident_memory_mb() -> Option<f64> {
    status_mb("VmRSS:")
}

fn status_mb(key: &str) -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// Starts a new peak: resets `VmHWM` to the current resident set (writing 5 to
/// `/proc/self/clear_refs`, Linux 4.0+). False where that is not possible (then
/// [`peak_memory_mb`] keeps the peak since the process started).
pub fn reset_peak_memory() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

#[cfg(test)]
mod tests {
    /// Other unit tests run on other threads of this process and allocate and free a few MB
    /// meanwhile, so the block is large (256 MB) and the bounds leave 56 MB for them; the
    /// resident set is read just before the allocation, not the peak (which may be an earlier,
    /// higher moment of another test).
    #[test]
    fn the_peak_follows_an_allocation_and_resets() {
        const MB: usize = 256;
        let Some(resident) = super::resident_memory_mb() else { return };
        let block = vec![1u8; MB << 20];
        std::hint::black_box(&block);
        let during = super::peak_memory_mb().unwrap_or(0.0);
        assert!(
            during >= resident + 200.0,
            "peak {during} MB after {MB} MB more than a resident {resident} MB"
        );
        drop(block);
        if super::reset_peak_memory() {
            let after = super::peak_memory_mb().unwrap_or(f64::INFINITY);
            assert!(after < during - 200.0, "reset peak {after} MB, was {during} MB");
        }
    }
}
