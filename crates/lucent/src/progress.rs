//! Progress of long solves on the command line: a thread polls a core
//! [`lucent_core::solver::Progress`] counter and, once a stage has run for about a second,
//! draws an indicatif bar (stage, done/total, rate) on a terminal, or prints a plain line every
//! few seconds when stderr is not one. lucent-core only counts; it draws nothing.

use indicatif::{ProgressBar, ProgressStyle};
use lucent_core::solver::Progress;
use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A stage shows nothing until it has run this long.
const QUIET: Duration = Duration::from_secs(1);
/// Plain lines (no terminal) at most this often.
const PLAIN_EVERY: Duration = Duration::from_secs(5);
const POLL: Duration = Duration::from_millis(100);

/// Watches a [`Progress`] counter until dropped.
pub struct Watch {
    progress: Arc<Progress>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Watch {
    /// Starts watching a fresh counter; hand [`Watch::progress`] to the solver.
    pub fn new() -> Self {
        let progress = Arc::new(Progress::new());
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (p, stop) = (progress.clone(), stop.clone());
            std::thread::Builder::new()
                .name("progress".into())
                .spawn(move || watch(&p, &stop, std::io::stderr().is_terminal()))
                .ok()
        };
        Watch { progress, stop, thread }
    }

    /// The counter the solver adds to.
    pub fn progress(&self) -> Arc<Progress> {
        self.progress.clone()
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One stage of a [`Progress`] counter as a front end shows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StageView {
    /// The stage's name ("link", "on-the-fly", "exact").
    pub stage: &'static str,
    /// Units done (faces of finished receiver subtrees, or receivers).
    pub done: usize,
    /// Units in all.
    pub total: usize,
    /// Units per second since the stage started.
    pub per_s: f64,
    /// Seconds since the stage started.
    pub elapsed_s: f64,
}

/// Follows a [`Progress`] counter's stages: a stage is a run of snapshots with the same name and
/// total and a non-decreasing count. Serves the CLI's bar and the viewer's panel alike.
#[derive(Debug)]
pub struct StageClock {
    current: (&'static str, usize, usize),
    since: Instant,
}

impl Default for StageClock {
    fn default() -> Self {
        StageClock { current: ("", 0, 0), since: Instant::now() }
    }
}

impl StageClock {
    /// Takes a snapshot of `p`; returns true when it begins a new stage.
    pub fn observe(&mut self, p: &Progress) -> bool {
        let (stage, done, total) = p.snapshot();
        let (s0, d0, t0) = self.current;
        let new_stage = stage != s0 || total != t0 || done < d0;
        if new_stage {
            self.since = Instant::now();
        }
        self.current = (stage, done, total);
        new_stage
    }

    /// The stage last observed, once it has run for [`QUIET`] and while it is unfinished.
    pub fn shown(&self) -> Option<StageView> {
        let (stage, done, total) = self.current;
        let elapsed = self.since.elapsed();
        if total == 0 || done >= total || elapsed < QUIET {
            return None;
        }
        let elapsed_s = elapsed.as_secs_f64();
        Some(StageView { stage, done, total, per_s: done as f64 / elapsed_s, elapsed_s })
    }
}

/// The polling loop: shows each stage of `p` once it has lasted [`QUIET`] and is unfinished.
fn watch(p: &Progress, stop: &AtomicBool, terminal: bool) {
    let mut clock = StageClock::default();
    let mut last_line = Instant::now();
    let mut bar: Option<ProgressBar> = None;
    let finish = |bar: &mut Option<ProgressBar>| {
        if let Some(b) = bar.take() {
            b.finish_and_clear();
        }
    };
    while !stop.load(Ordering::Relaxed) {
        std::thread::sleep(POLL);
        if clock.observe(p) {
            finish(&mut bar);
            last_line = Instant::now();
        }
        let Some(v) = clock.shown() else {
            finish(&mut bar);
            continue;
        };
        if terminal {
            let b = bar.get_or_insert_with(|| {
                let b = ProgressBar::new(v.total as u64).with_style(
                    ProgressStyle::with_template(
                        "{msg:>12} {bar:40} {pos}/{len} ({per_sec}, {elapsed}, eta {eta})",
                    )
                    .expect("valid template"),
                );
                b.set_message(v.stage);
                b
            });
            b.set_position(v.done as u64);
        } else if last_line.elapsed() >= PLAIN_EVERY {
            last_line = Instant::now();
            eprintln!(
                "{}: {}/{} ({:.0}%), {:.0}/s, {:.0} s",
                v.stage,
                v.done,
                v.total,
                100.0 * v.done as f64 / v.total as f64,
                v.per_s,
                v.elapsed_s
            );
        }
    }
    finish(&mut bar);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stage_shows_after_a_quiet_second_and_until_done() {
        let p = Progress::new();
        let mut clock = StageClock::default();
        p.start("link", 10);
        assert!(clock.observe(&p));
        p.add(4);
        assert!(!clock.observe(&p), "same stage, more done");
        assert_eq!(clock.shown(), None, "quiet during the first second");
        clock.since -= QUIET;
        let v = clock.shown().expect("shown after a second");
        assert_eq!((v.stage, v.done, v.total), ("link", 4, 10));
        assert!(v.per_s > 0.0 && v.per_s <= 4.0 / QUIET.as_secs_f64());
        p.add(6);
        clock.observe(&p);
        assert_eq!(clock.shown(), None, "finished stages are not shown");
        p.start("link", 10);
        assert!(clock.observe(&p), "a restart with a lower count is a new stage");
    }
}
