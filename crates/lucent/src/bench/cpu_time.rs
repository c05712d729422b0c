//! The CPU time this process has used, for benches on a shared machine: a software adapter
//! (lavapipe) draws on the CPU, and the CPU time its threads spend on a frame does not grow
//! when other jobs hold the cores, where the wall time does.

/// Nanoseconds of CPU time used by all of this process's threads so far (Linux: the sum of
/// `/proc/self/task/*/schedstat`'s first field); `None` where `/proc/self/task` is not readable.
/// Threads that ended before the call, or while it read, are not counted, so compare two calls
/// around work whose threads outlive it (a driver's or rayon's thread pool).
pub fn process_cpu_ns() -> Option<u64> {
    let tasks = std::fs::read_dir("/proc/self/task").ok()?;
    Some(
        tasks
            .filter_map(|task| std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok())
            .filter_map(|stat| stat.split_whitespace().next()?.parse::<u64>().ok())
            .sum(),
    )
}

/// [`process_cpu_ns`] in milliseconds, 0 where it is not readable.
pub fn process_cpu_ms() -> f64 {
    process_cpu_ns().map_or(0.0, |ns| ns as f64 * 1e-6)
}

#[cfg(test)]
mod tests {
    #[test]
    fn cpu_time_grows_with_work() {
        let Some(before) = super::process_cpu_ns() else {
            return; // not Linux: nothing to read
        };
        let mut x = 0u64;
        for i in 0..20_000_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
        }
        std::hint::black_box(x);
        let after = super::process_cpu_ns().expect("readable once");
        assert!(after > before, "{before} -> {after}");
    }
}
