//! The threads a solve runs on: the plugin's own rayon pool, beside Bevy's task pools, so that
//! the solve (lucent-core's data-parallel stages, Mertens §5.5's per-frame work) can be kept off
//! the cores Bevy's main and render threads need while it runs.
//!
//! A solve is started on Bevy's `AsyncComputeTaskPool` and runs its work on this pool
//! (`ThreadPool::install`): the async compute thread only waits. Without a pool of its own the
//! solve would use rayon's global pool, one thread per core, which on a machine with few cores
//! competes with the frames.

use bevy::prelude::*;
use std::sync::Arc;

/// Stack of each solve thread, bytes: as lucent's command line (`crates/lucent/src/main.rs`),
/// since the face clustering of scanned meshes nests thousands of levels deep. Only what is
/// touched is committed.
const STACK_BYTES: usize = 512 << 20;

/// How many threads solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolveThreads {
    /// One per core (`std::thread::available_parallelism`): the fastest solve; Bevy's frames
    /// share every core with it while it runs (unless the threads run at a lower priority,
    /// [`crate::LucentPlugin::solve_nice`]). The plugin's default on Linux.
    All,
    /// One fewer than the cores, at least one: one core stays with Bevy's main and render
    /// threads while a solve runs. The plugin's default elsewhere (no per-thread priority).
    LeaveOne,
    /// Exactly this many (at least one).
    Count(usize),
}

impl SolveThreads {
    /// The number of threads on this machine (at least one).
    pub fn count(self) -> usize {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        match self {
            SolveThreads::All => cores,
            SolveThreads::LeaveOne => cores.saturating_sub(1).max(1),
            SolveThreads::Count(n) => n.max(1),
        }
    }
}

/// The pool every solve runs on (a resource the plugin inserts from
/// [`crate::LucentPlugin::solve_threads`] and [`crate::LucentPlugin::solve_nice`]; insert
/// another to change it at run time: solves started afterwards use it).
#[derive(Resource, Clone)]
pub struct SolvePool {
    pool: Arc<rayon::ThreadPool>,
    threads: usize,
    nice: u8,
}

impl SolvePool {
    /// A pool of `threads` threads, each `nice` steps (0..=19, Unix nice increments; 0 keeps the
    /// process's priority) below Bevy's threads in the OS scheduler. The priority is set on
    /// Linux only (elsewhere a thread's nice value is the whole process's, and is left alone).
    /// Errors (one line) if the OS refuses the threads.
    pub fn new(threads: SolveThreads, nice: u8) -> Result<Self, String> {
        let count = threads.count();
        let nice = nice.min(19);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(count)
            .stack_size(STACK_BYTES)
            .thread_name(|i| format!("lucent-solve-{i}"))
            .start_handler(move |_| lower_priority(nice))
            .build()
            .map_err(|e| format!("cannot start lucent's {count} solve threads: {e}"))?;
        Ok(SolvePool { pool: Arc::new(pool), threads: count, nice })
    }

    /// Threads in the pool.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Nice increment of its threads (0 = Bevy's priority).
    pub fn nice(&self) -> u8 {
        self.nice
    }

    /// The pool, for a solve to run on.
    pub(crate) fn pool(&self) -> Arc<rayon::ThreadPool> {
        self.pool.clone()
    }
}

/// Lowers the calling thread's scheduling priority by `nice` (Linux: per thread).
#[cfg(target_os = "linux")]
fn lower_priority(nice: u8) {
    if nice == 0 {
        return;
    }
    // SAFETY: gettid and setpriority take no pointers; `which = PRIO_PROCESS` with a thread id
    // changes only that thread on Linux.
    let failed = unsafe {
        let tid = libc::gettid() as libc::id_t;
        // The thread starts at the process's nice value (getpriority's -1 is a valid value
        // here: the call cannot fail for the calling thread).
        let current = libc::getpriority(libc::PRIO_PROCESS, tid);
        libc::setpriority(libc::PRIO_PROCESS, tid, (current + i32::from(nice)).min(19)) != 0
    };
    if failed {
        warn!("lucent: could not lower the solve thread's priority by {nice}");
    }
}

/// Lowers the calling thread's scheduling priority: not done outside Linux.
#[cfg(not(target_os = "linux"))]
fn lower_priority(_nice: u8) {}
