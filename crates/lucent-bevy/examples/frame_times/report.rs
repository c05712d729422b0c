//! What the `frame_times` example records per frame, and its summary: medians and 95th
//! percentiles of the frame time, the solves' times, and the frames a solve waited and lagged.

use std::collections::HashMap;
use std::time::Instant;

/// One frame.
pub struct Record {
    /// The frame's number (its clear colour).
    pub stamp: u32,
    /// When `App::update` began.
    pub begin: Instant,
    /// The body's `SolveStatus` after the frame.
    pub solves: u64,
    pub solving: bool,
    pub done: Option<Instant>,
    pub solve_ms: f32,
}

/// A run of frames with one kind of change and one solve pool.
pub struct Phase {
    pub name: String,
    pub config: String,
    /// The 1-minute load average before and after.
    pub load: (f32, f32),
    pub records: Vec<Record>,
}

/// The 1-minute load average (0 where /proc/loadavg is not there).
pub fn load() -> f32 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse().ok()))
        .unwrap_or(0.0)
}

/// Median and 95th percentile (nearest rank) of `v`; zeros when empty.
fn median_p95(mut v: Vec<f64>) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[((v.len() * 95).div_ceil(100)).saturating_sub(1)])
}

/// What one or more phases of the same kind and pool measured.
#[derive(Default)]
struct Summary {
    /// Frame periods (begin to next begin), ms.
    frames_ms: Vec<f64>,
    in_flight: usize,
    frames: usize,
    /// Times of the solves shown, ms.
    solve_ms: Vec<f64>,
    /// Per solve shown: frames it waited after finishing beyond the one that could take it in.
    waited: Vec<u32>,
    /// Per solve shown: frames from taking it in to the first image showing it (None: no read-
    /// back of those frames, or no change seen within 8 frames).
    lag: Vec<Option<u32>>,
    loads: Vec<f32>,
}

impl Summary {
    fn add(&mut self, phase: &Phase, signatures: &HashMap<u32, f64>) {
        let r = &phase.records;
        self.loads.extend([phase.load.0, phase.load.1]);
        self.frames += r.len();
        self.in_flight += r.iter().filter(|f| f.solving).count();
        self.frames_ms.extend(r.windows(2).map(|w| (w[1].begin - w[0].begin).as_secs_f64() * 1e3));
        for (i, f) in r.iter().enumerate().skip(1) {
            if f.solves == r[i - 1].solves {
                continue;
            }
            self.solve_ms.push(f64::from(f.solve_ms));
            // The frame that was running when the solve finished.
            if let Some(running) = f.done.and_then(|d| r[..=i].iter().rposition(|g| g.begin <= d)) {
                self.waited.push((i.saturating_sub(running + 1)) as u32);
            }
            self.lag.push(lag(f.stamp, signatures));
        }
    }

    fn line(&self, name: &str, config: &str) -> String {
        let (fm, fp) = median_p95(self.frames_ms.clone());
        let (sm, sp) = median_p95(self.solve_ms.clone());
        let waited = self.waited.iter().filter(|&&w| w > 0).count();
        let count = |k: u32| self.lag.iter().filter(|l| **l == Some(k)).count();
        let later = self.lag.iter().filter(|l| matches!(l, Some(k) if *k >= 2)).count();
        let unseen = self.lag.iter().filter(|l| l.is_none()).count();
        let (lo, hi) = self.loads.iter().fold((f32::MAX, 0f32), |(a, b), &l| (a.min(l), b.max(l)));
        format!(
            "| {name} | {config} | {lo:.2}-{hi:.2} | {} | {fm:.2} | {fp:.2} | {:.0}% | {} | {sm:.0} | {sp:.0} | {waited} | {} / {} / {later} / {unseen} |",
            self.frames,
            100.0 * self.in_flight as f64 / self.frames.max(1) as f64,
            self.solve_ms.len(),
            count(0),
            count(1),
        )
    }
}

/// Frames from the frame stamped `taken` (which took a solve in) to the first whose image of the
/// object differs from the frame before it; `None` if a read-back is missing on the way or
/// nothing changed within 8 frames.
fn lag(taken: u32, signatures: &HashMap<u32, f64>) -> Option<u32> {
    let before = *signatures.get(&taken.checked_sub(1)?)?;
    (0..8).find_map(|k| match signatures.get(&(taken + k)) {
        Some(&s) if s != before => Some(Some(k)),
        Some(_) => None,
        None => Some(None),
    })?
}

/// Prints one line per phase kind and pool (the rounds together) as a Markdown table.
pub fn print(phases: &[Phase], signatures: &HashMap<u32, f64>) {
    let mut order: Vec<(String, String)> = Vec::new();
    let mut sums: HashMap<(String, String), Summary> = HashMap::new();
    for p in phases {
        let key = (p.name.clone(), p.config.clone());
        if !order.contains(&key) {
            order.push(key.clone());
        }
        sums.entry(key).or_default().add(p, signatures);
    }
    println!(
        "| change | solve pool | load (1 min) | frames | frame ms median | p95 | solve in flight | solves \
         | solve ms median | p95 | solves that waited a frame | shown after 0 / 1 / 2+ frames / not seen |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for key in &order {
        println!("{}", sums[key].line(&key.0, &key.1));
    }
}
