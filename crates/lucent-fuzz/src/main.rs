//! `lucent-fuzz`: mutation-fuzz lucent's loaders with an allocation cap and a hang watchdog.
//!
//! ```sh
//! cargo run --release -p lucent-fuzz -- --runs 10000000        # every target, 10M inputs each
//! cargo run --release -p lucent-fuzz -- exr gltf --seconds 60   # two targets, a minute each
//! ```
//!
//! A finding (a panic escaping a loader, an allocation above the cap, an input running past the
//! time limit) writes the input to `--crashes/<target>/` and exits non-zero; copy it into
//! `crates/lucent-fuzz/regressions/<target>/` once fixed, where the tests replay it forever.

use clap::Parser;
use lucent_fuzz::targets::{TARGETS, Target, target};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering::Relaxed};
use std::time::{Duration, Instant};

#[derive(Parser, Debug)]
#[command(about = "Mutation-fuzz lucent's file loaders (stable toolchain, no external tools)")]
struct Args {
    /// Targets to run (default: all): obj, ply-ascii, ply-binary, off, gltf, glb, hdr, exr,
    /// scene, lvol, raw.
    targets: Vec<String>,
    /// Inputs per target (split over the threads).
    #[arg(long, default_value_t = 100_000)]
    runs: u64,
    /// Stop each target after this many seconds, whatever --runs says.
    #[arg(long)]
    seconds: Option<f64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Seed of the mutations; a run is reproducible from its seed and thread count.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The largest single allocation a loader may make, MiB; live memory is capped at this
    /// per thread plus 64 MiB.
    #[arg(long, default_value_t = 256)]
    max_alloc_mib: usize,
    /// An input running longer than this is a hang, milliseconds.
    #[arg(long, default_value_t = 5000)]
    timeout_ms: u64,
    /// Where findings are written.
    #[arg(long, default_value = "target/fuzz-crashes")]
    crashes: PathBuf,
    /// Replay one input file through the target (the first positional argument) under the
    /// allocation cap and watchdog, and print the outcome.
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Write every target's seed inputs under this folder (`<target>/seed-N`) and exit: a
    /// starting corpus for other fuzzers.
    #[arg(long)]
    write_seeds: Option<PathBuf>,
}

fn write_seeds(dir: &std::path::Path) -> std::io::Result<()> {
    for t in TARGETS {
        std::fs::create_dir_all(dir.join(t.name))?;
        for (k, seed) in (t.seeds)().iter().enumerate() {
            std::fs::write(dir.join(t.name).join(format!("seed-{k}")), seed)?;
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// The allocation cap

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static CAP_SINGLE: AtomicUsize = AtomicUsize::new(usize::MAX);
static CAP_LIVE: AtomicUsize = AtomicUsize::new(usize::MAX);

thread_local! {
    /// Set while a finding is being reported, so the report's own allocations pass.
    static REPORTING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// This thread's watchdog slot, if it is a worker.
    static SLOT: std::cell::Cell<Option<usize>> = const { std::cell::Cell::new(None) };
}

struct Capped;

impl Capped {
    fn admit(size: usize) {
        let live = LIVE.load(Relaxed);
        if (size > CAP_SINGLE.load(Relaxed) || live.saturating_add(size) > CAP_LIVE.load(Relaxed))
            && !REPORTING.with(|r| r.replace(true))
        {
            let trace = std::backtrace::Backtrace::force_capture();
            report_current(
                &format!("allocation of {size} bytes with {live} live exceeds the cap, at\n{trace}"),
                4,
            );
        }
    }
    fn added(size: usize) {
        let live = LIVE.fetch_add(size, Relaxed) + size;
        PEAK.fetch_max(live, Relaxed);
    }
}

unsafe impl GlobalAlloc for Capped {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        Self::admit(layout.size());
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            Self::added(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        Self::admit(layout.size());
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            Self::added(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() {
            Self::admit(new_size - layout.size());
        }
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_sub(layout.size(), Relaxed);
            Self::added(new_size);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Capped = Capped;

// ---------------------------------------------------------------------------------------------
// Watchdog slots: what each worker is running, and since when

struct Slot {
    /// Nanoseconds since `EPOCH` when the current input started; 0 when idle.
    started: AtomicU64,
    input: Mutex<Vec<u8>>,
}

const MAX_THREADS: usize = 64;
static SLOTS: [Slot; MAX_THREADS] =
    [const { Slot { started: AtomicU64::new(0), input: Mutex::new(Vec::new()) } }; MAX_THREADS];
static TARGET: Mutex<&str> = Mutex::new("");
static CRASH_DIR: Mutex<Option<PathBuf>> = Mutex::new(None);
static EPOCH: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();

fn now_ns() -> u64 {
    EPOCH.get_or_init(Instant::now).elapsed().as_nanos() as u64 + 1
}

/// Writes `input` under the crash folder and returns its path.
fn save(input: &[u8], target: &str, kind: &str) -> Option<PathBuf> {
    let dir = CRASH_DIR.try_lock().ok()?.clone()?.join(target);
    std::fs::create_dir_all(&dir).ok()?;
    let hash =
        input.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    let path = dir.join(format!("{kind}-{hash:016x}"));
    std::fs::write(&path, input).ok()?;
    Some(path)
}

/// Reports the calling worker's current input as a finding and exits with `code`.
fn report_current(what: &str, code: i32) -> ! {
    let target = TARGET.try_lock().map(|t| *t).unwrap_or("unknown");
    let input = SLOT.with(|s| s.get()).and_then(|k| SLOTS[k].input.try_lock().ok().map(|i| i.clone()));
    let saved = input.and_then(|i| save(&i, target, "oom"));
    eprintln!("lucent-fuzz: FINDING in {target}: {what}; input: {saved:?}");
    std::process::exit(code);
}

fn watchdog(timeout: Duration) {
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_millis(100));
            for slot in &SLOTS {
                let started = slot.started.load(Relaxed);
                if started != 0 && now_ns().saturating_sub(started) > timeout.as_nanos() as u64 {
                    let target = *TARGET.lock().unwrap_or_else(|e| e.into_inner());
                    let input = slot.input.lock().unwrap_or_else(|e| e.into_inner()).clone();
                    let saved = save(&input, target, "hang");
                    eprintln!(
                        "lucent-fuzz: FINDING in {target}: an input ran past {timeout:?}; input: {saved:?}"
                    );
                    std::process::exit(3);
                }
            }
        }
    });
}

// ---------------------------------------------------------------------------------------------

fn run_target(t: &'static Target, args: &Args, threads: usize) -> Result<lucent_fuzz::Stats, String> {
    *TARGET.lock().unwrap_or_else(|e| e.into_inner()) = t.name;
    let deadline = args.seconds.map(|s| Instant::now() + Duration::from_secs_f64(s));
    let per_thread = args.runs.div_ceil(threads as u64);
    let results: Vec<_> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|k| {
                let seed =
                    args.seed.wrapping_mul(0x9e37_79b9).wrapping_add(k as u64 * 7919 + t.name.len() as u64);
                std::thread::Builder::new()
                    .stack_size(64 << 20)
                    .spawn_scoped(scope, move || {
                        SLOT.with(|s| s.set(Some(k)));
                        let mut total = lucent_fuzz::Stats::default();
                        // Batches, so that --seconds is honoured.
                        let mut left = per_thread;
                        while left > 0 && deadline.is_none_or(|d| Instant::now() < d) {
                            let batch = left.min(20_000);
                            let stats = lucent_fuzz::fuzz(t, batch, seed.wrapping_add(left), |input| {
                                let mut slot = SLOTS[k].input.lock().unwrap_or_else(|e| e.into_inner());
                                slot.clear();
                                slot.extend_from_slice(input);
                                SLOTS[k].started.store(now_ns(), Relaxed);
                            });
                            SLOTS[k].started.store(0, Relaxed);
                            let stats = stats?;
                            total.executions += stats.executions;
                            total.accepted += stats.accepted;
                            total.outcomes = total.outcomes.max(stats.outcomes);
                            left -= batch;
                        }
                        Ok::<_, lucent_fuzz::Crash>(total)
                    })
                    .expect("spawn a worker")
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("worker thread")).collect()
    });
    let mut total = lucent_fuzz::Stats::default();
    for r in results {
        match r {
            Ok(s) => {
                total.executions += s.executions;
                total.accepted += s.accepted;
                total.outcomes = total.outcomes.max(s.outcomes);
            }
            Err(crash) => {
                let saved = save(&crash.input, t.name, "panic");
                return Err(format!("a panic escaped the loader: {}; input: {saved:?}", crash.message));
            }
        }
    }
    Ok(total)
}

fn main() {
    let args = Args::parse();
    if let Some(dir) = &args.write_seeds {
        if let Err(e) = write_seeds(dir) {
            eprintln!("lucent-fuzz: cannot write seeds to {}: {e}", dir.display());
            std::process::exit(1);
        }
        return;
    }
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .clamp(1, MAX_THREADS);
    let chosen: Vec<&'static Target> = if args.targets.is_empty() {
        TARGETS.iter().collect()
    } else {
        let mut v = Vec::new();
        for name in &args.targets {
            match target(name) {
                Some(t) => v.push(t),
                None => {
                    let known: Vec<_> = TARGETS.iter().map(|t| t.name).collect();
                    eprintln!("lucent-fuzz: unknown target '{name}' (known: {})", known.join(", "));
                    std::process::exit(2);
                }
            }
        }
        v
    };
    *CRASH_DIR.lock().unwrap_or_else(|e| e.into_inner()) = Some(args.crashes.clone());
    let cap = args.max_alloc_mib << 20;
    CAP_SINGLE.store(cap, Relaxed);
    CAP_LIVE.store(cap * threads + (64 << 20) + LIVE.load(Relaxed), Relaxed);
    watchdog(Duration::from_millis(args.timeout_ms));
    if let Some(file) = &args.replay {
        let input = std::fs::read(file).unwrap_or_else(|e| {
            eprintln!("lucent-fuzz: cannot read {}: {e}", file.display());
            std::process::exit(2);
        });
        let t = chosen[0];
        *TARGET.lock().unwrap_or_else(|e| e.into_inner()) = t.name;
        match lucent_fuzz::run_one(t, &input) {
            Ok(outcome) => println!("{}: {outcome:?}", t.name),
            Err(crash) => {
                eprintln!(
                    "lucent-fuzz: FINDING in {}: a panic escaped the loader: {}",
                    t.name, crash.message
                );
                std::process::exit(1);
            }
        }
        return;
    }

    println!(
        "{:<11} {:>12} {:>10} {:>9} {:>9} {:>12}",
        "target", "executions", "exec/s", "accepted", "outcomes", "peak MiB"
    );
    for t in chosen {
        PEAK.store(LIVE.load(Relaxed), Relaxed);
        let start = Instant::now();
        match run_target(t, &args, threads) {
            Ok(s) => {
                let secs = start.elapsed().as_secs_f64();
                println!(
                    "{:<11} {:>12} {:>10.0} {:>9} {:>9} {:>12.1}",
                    t.name,
                    s.executions,
                    s.executions as f64 / secs,
                    s.accepted,
                    s.outcomes,
                    PEAK.load(Relaxed) as f64 / (1 << 20) as f64
                );
            }
            Err(e) => {
                eprintln!("lucent-fuzz: FINDING in {}: {e}", t.name);
                std::process::exit(1);
            }
        }
    }
}
