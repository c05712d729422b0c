//! Bevy's frame times with lucent's plugin while no solve runs and while one always runs, and
//! how many frames a finished solve waits before it is on screen (issue 53's targets: the frame
//! rate does not drop while solving; a change shows within the solve's own time).
//!
//! `cargo run --release -p lucent-bevy --example frame_times -- [--frames N] [--rounds R]
//! [--configs all,leave-one,all:10]`
//!
//! The headless test's scene (the embedded bunny in marble at 10 cm, one directional light,
//! 256×192, lavapipe without a GPU), frames as fast as Bevy makes them (no window, no vsync:
//! the frame time is what Bevy's main and render threads need). Per round: `N` frames with
//! nothing changing (no solve), then for each solve-pool configuration (`threads[:nice]`,
//! threads `all`, `leave-one` or a count, see `lucent_bevy::SolveThreads`) `N` frames with the
//! light turning 2° a frame (a light solve always in flight) and `N` frames with the material
//! switching between marble and skim milk as each switch is shown (a material solve always in
//! flight). Rounds interleave the configurations so that the machine's load, which other work
//! changes, weighs on each alike.
//!
//! Latency: the camera's clear colour stamps every frame with its number, and the image is
//! read back every frame; a solve is *shown* in the first frame whose image of the object
//! changed after it. Per solve it reports the frames it waited after finishing before a frame
//! took it in (0: the frame running when it finished, or the next, took it) and the frames from
//! taking it in to showing it (0: the same frame).

use bevy::prelude::*;
use common::{Latest, decode, headless_app, lucent_view, scene};
use lucent_bevy::{LucentPlugin, SolvePool, SolveStatus, SolveThreads, Translucent, TranslucentMaterial};
use std::collections::HashMap;
use std::time::{Duration, Instant};

#[path = "../../tests/common/mod.rs"]
mod common;
mod report;
use report::{Phase, Record};

/// A solve pool to measure: threads and nice increment.
#[derive(Clone, Copy, Debug)]
struct Config {
    threads: SolveThreads,
    nice: u8,
}

impl Config {
    fn parse(s: &str) -> Result<Config, String> {
        let (threads, nice) = s.split_once(':').unwrap_or((s, "0"));
        let threads = match threads {
            "all" => SolveThreads::All,
            "leave-one" => SolveThreads::LeaveOne,
            n => SolveThreads::Count(n.parse().map_err(|_| format!("--configs: bad thread count {n:?}"))?),
        };
        let nice = nice.parse().map_err(|_| format!("--configs: bad nice {nice:?} (0..=19)"))?;
        Ok(Config { threads, nice })
    }

    fn name(&self) -> String {
        let t = match self.threads {
            SolveThreads::All => "all".to_string(),
            SolveThreads::LeaveOne => "leave-one".to_string(),
            SolveThreads::Count(n) => n.to_string(),
        };
        format!("{t} ({} threads), nice {}", self.threads.count(), self.nice)
    }
}

/// The command line.
struct Args {
    frames: usize,
    rounds: usize,
    configs: Vec<Config>,
}

fn args() -> Result<Args, String> {
    let mut a = Args { frames: 200, rounds: 2, configs: vec![] };
    let mut configs = "all,leave-one,all:10".to_string();
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--frames" => a.frames = value()?.parse().map_err(|_| "--frames: a count".to_string())?,
            "--rounds" => a.rounds = value()?.parse().map_err(|_| "--rounds: a count".to_string())?,
            "--configs" => configs = value()?,
            other => return Err(format!("unknown argument {other:?}")),
        }
    }
    a.configs = configs.split(',').map(Config::parse).collect::<Result<_, _>>()?;
    Ok(a)
}

fn main() {
    let args = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("frame_times: {e}");
            std::process::exit(2);
        }
    };
    let mut bench = Bench::new();
    bench.warm_up();
    let mut phases = Vec::new();
    for _ in 0..args.rounds {
        phases.push(bench.run("idle", "-", args.frames, Change::Nothing));
        for config in &args.configs {
            match SolvePool::new(config.threads, config.nice) {
                Ok(pool) => bench.app.insert_resource(pool),
                Err(e) => {
                    eprintln!("frame_times: {e}");
                    std::process::exit(1);
                }
            };
            phases.push(bench.run("light", &config.name(), args.frames, Change::Light));
            phases.push(bench.run("material", &config.name(), args.frames, Change::Material));
        }
    }
    report::print(&phases, &bench.signatures);
}

/// What changes every frame of a phase.
#[derive(Clone, Copy, PartialEq)]
enum Change {
    Nothing,
    Light,
    Material,
}

/// The app, its read-back, and what was recorded.
struct Bench {
    app: App,
    latest: Latest,
    /// Frames run so far (the stamp of the next).
    frame: u32,
    /// The object's image per frame stamp (sum of its radiance), from the read-backs.
    signatures: HashMap<u32, f64>,
    /// The light's angle about the vertical, radians.
    angle: f32,
}

impl Bench {
    fn new() -> Bench {
        let mut app = headless_app(LucentPlugin::default());
        let latest = scene(&mut app, &lucent_view());
        Bench { app, latest, frame: 0, signatures: HashMap::new(), angle: 0.0 }
    }

    /// Runs frames until the first solve is shown and the pipelines have compiled (the object
    /// is in a read-back), then 30 more.
    fn warm_up(&mut self) {
        let started = Instant::now();
        while !(self.status().solves >= 1 && self.signatures.values().any(|&s| s > 0.0)) {
            assert!(started.elapsed() < Duration::from_secs(300), "no solved frame within 300 s");
            self.step();
        }
        for _ in 0..30 {
            self.step();
        }
    }

    fn status(&mut self) -> SolveStatus {
        let world = self.app.world_mut();
        world.query::<&SolveStatus>().single(world).cloned().unwrap_or_default()
    }

    /// One frame, stamped; returns its record.
    fn step(&mut self) -> Record {
        let stamp = self.frame;
        {
            let world = self.app.world_mut();
            let mut camera = world.query::<&mut Camera>().single_mut(world).expect("one camera");
            camera.clear_color = ClearColorConfig::Custom(Color::linear_rgba(
                (stamp % 1024) as f32,
                (stamp / 1024) as f32,
                0.0,
                0.0,
            ));
        }
        let begin = Instant::now();
        self.app.update();
        self.frame += 1;
        if let Some(bytes) = self.latest.lock().unwrap().take() {
            let pixels = decode(&bytes);
            // The top-left corner is background: it holds the stamp.
            let corner = pixels[0];
            let at = corner[0] as u32 + 1024 * corner[1] as u32;
            let sum: f64 =
                pixels.iter().filter(|p| p[3] > 0.999).map(|p| f64::from(p[0] + p[1] + p[2])).sum();
            self.signatures.insert(at, sum);
        }
        let s = self.status();
        Record { stamp, begin, solves: s.solves, solving: s.solving, done: s.last_done, solve_ms: s.last_ms }
    }

    /// `frames` frames with `change` each frame.
    fn run(&mut self, name: &str, config: &str, frames: usize, change: Change) -> Phase {
        let load = report::load();
        let mut records = Vec::with_capacity(frames);
        // The material phase switches in its first frame, then whenever the switch is shown.
        let mut shown = u64::MAX;
        for _ in 0..frames {
            match change {
                Change::Nothing => {}
                Change::Light => {
                    self.angle += 2f32.to_radians();
                    self.set_light();
                }
                Change::Material => {
                    let solves = self.status().solves;
                    if solves != shown {
                        shown = solves;
                        self.switch_material();
                    }
                }
            }
            records.push(self.step());
        }
        // Let the last solve finish so that the next phase starts idle.
        while self.status().solving {
            self.step();
        }
        Phase { name: name.into(), config: config.into(), load: (load, report::load()), records }
    }

    fn set_light(&mut self) {
        let direction = Quat::from_rotation_y(self.angle) * Vec3::from(common::LIGHT);
        let world = self.app.world_mut();
        let mut light = world.query_filtered::<&mut Transform, With<DirectionalLight>>();
        if let Ok(mut t) = light.single_mut(world) {
            *t = Transform::default().looking_to(direction, Vec3::Y);
        }
    }

    fn switch_material(&mut self) {
        let world = self.app.world_mut();
        let mut body = world.query::<&mut Translucent>().single_mut(world).expect("one body");
        let next =
            if body.material == TranslucentMaterial::Preset("marble".into()) { "skimmilk" } else { "marble" };
        body.material = TranslucentMaterial::Preset(next.into());
    }
}
