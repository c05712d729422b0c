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

/// The polling loop: a stage is a run of snapshots with the same name and total and a
/// non-decreasing count; it is shown once it has lasted [`QUIET`] and is still unfinished.
fn watch(p: &Progress, stop: &AtomicBool, terminal: bool) {
    let mut current = ("", 0usize, 0usize);
    let mut since = Instant::now();
    let mut last_line = since;
    let mut bar: Option<ProgressBar> = None;
    let finish = |bar: &mut Option<ProgressBar>| {
        if let Some(b) = bar.take() {
            b.finish_and_clear();
        }
    };
    while !stop.load(Ordering::Relaxed) {
        std::thread::sleep(POLL);
        let (stage, done, total) = p.snapshot();
        if stage != current.0 || total != current.2 || done < current.1 {
            finish(&mut bar);
            since = Instant::now();
            last_line = since;
        }
        current = (stage, done, total);
        if total == 0 || done >= total || since.elapsed() < QUIET {
            if done >= total {
                finish(&mut bar);
            }
            continue;
        }
        if terminal {
            let b = bar.get_or_insert_with(|| {
                let b = ProgressBar::new(total as u64).with_style(
                    ProgressStyle::with_template(
                        "{msg:>12} {bar:40} {pos}/{len} ({per_sec}, {elapsed}, eta {eta})",
                    )
                    .expect("valid template"),
                );
                b.set_message(stage);
                b
            });
            b.set_position(done as u64);
        } else if last_line.elapsed() >= PLAIN_EVERY {
            last_line = Instant::now();
            let s = since.elapsed().as_secs_f64();
            eprintln!(
                "{stage}: {done}/{total} ({:.0}%), {:.0}/s, {s:.0} s",
                100.0 * done as f64 / total as f64,
                done as f64 / s
            );
        }
    }
    finish(&mut bar);
}
