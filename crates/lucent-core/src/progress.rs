//! Progress of a long solve, for a front end to poll from another thread (the CLI draws it;
//! lucent-core draws nothing). The hierarchical refinement adds the leaves of each receiver
//! subtree it finishes (one relaxed atomic add per subtree of at most 256 leaves, never per
//! link); the exact solve adds each receiver it finishes.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Shared progress counter: a stage name, units done and units in all.
#[derive(Debug, Default)]
pub struct Progress {
    stage: Mutex<&'static str>,
    done: AtomicUsize,
    total: AtomicUsize,
}

impl Progress {
    /// A counter with no stage yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts `stage` (e.g. "link", "on-the-fly") with `total` units to do, none done.
    pub fn start(&self, stage: &'static str, total: usize) {
        *self.stage.lock().unwrap_or_else(|e| e.into_inner()) = stage;
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
    }

    /// Adds `n` units done.
    #[inline]
    pub fn add(&self, n: usize) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }

    /// `(stage, done, total)` now.
    pub fn snapshot(&self) -> (&'static str, usize, usize) {
        let stage = *self.stage.lock().unwrap_or_else(|e| e.into_inner());
        (stage, self.done.load(Ordering::Relaxed), self.total.load(Ordering::Relaxed))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_restarts() {
        let p = Progress::new();
        p.start("link", 10);
        p.add(3);
        p.add(4);
        assert_eq!(p.snapshot(), ("link", 7, 10));
        p.start("gather", 5);
        assert_eq!(p.snapshot(), ("gather", 0, 5));
    }
}
