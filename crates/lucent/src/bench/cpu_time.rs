//! The CPU time this process has used, for benches on a shared machine: a software adapter
//! (lavapipe) draws on the CPU, and the CPU time its threads spend on a frame does not grow
//! when other jobs hold the cores, where the wall time does.

/// Nanoseconds of CPU time used by all of this process's threads so far, those that ended
/// included (`CLOCK_PROCESS_CPUTIME_ID`), so that it never falls between two calls; `None`
/// where there is no such clock (not Unix).
pub fn process_cpu_ns() -> Option<u64> {
    #[cfg(unix)]
    {
        let mut t = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: `t` is a valid timespec for the call to write.
        if unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut t) } != 0 {
            return None;
        }
        Some(t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64)
    }
    #[cfg(not(unix))]
    {
        None
    }
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
            return; // not Unix: no process clock
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
