//! `lucent bench interactive`: what a user's action costs from the action to the next image's
//! per-vertex radiance, stage by stage (issue 51 item 5), on the meshes of `bench solver
//! --real` (the embedded bunny and the dragons `scripts/fetch_dragon.sh` fetched), marble at
//! 10 cm and skim milk at 5 cm, one shadowing point light, three bounces, refit mode and
//! the viewer's split view terms (`shading::view_basis`), as the viewer solves.
//!
//! Actions, each repeated [`REPS`] times after one warm-up repetition, from the pose the
//! previous action left:
//!
//! * `light`: the light turns 10° about the vertical through the mesh's centre;
//! * `camera`: the eye turns 10° about the vertical (split view terms), and `camera-per-eye`
//!   the same with the view terms traced per eye (the reference);
//! * `material`: the model scale grows by 5% of its value each time;
//! * `bump`: a bump 0.1 of the extent wide grows on the lit side, to 1% of the extent;
//! * `twist`: 30° of twist over eight frames (the frames of `lucent render --frames 8`).
//!
//! Each row: the median milliseconds of every stage ([`Timings::stages`]; no raster: the
//! bench draws nothing) and of the whole solve, and the last repetition's error against a
//! fresh session solving the same pose, light, material and eye from nothing with the view
//! terms per eye: of `B` per face (`|ΣB - ΣB_fresh| / ΣB_fresh` over the channel sums, faces
//! with light), and of the radiance the mesh pass draws per vertex (`radiance + single` against
//! the fresh one's, vertices seen), median and 95th percentile.
//!
//! Before the actions, the `light-paths` rows (`bench/light_paths.rs`): the view stage with
//! the light paths' shortcut against every path traced, lights in front, at the side and
//! behind. With `LUCENT_BENCH_LIGHT_ONLY` set, those and the `light` action only.
//!
//! `LUCENT_BENCH_MAX_TRIANGLES` (default 60,000: the bunny, the 11K and the 48K dragons, a few
//! minutes on two cores), `LUCENT_BENCH_MIN_TRIANGLES` and `LUCENT_BENCH_MATERIAL` choose, as
//! for `bench solver --real`. `LUCENT_BENCH_ACTIONS` (comma-separated names, `light-paths`
//! among them; default all) picks the rows, `LUCENT_BENCH_REPS` the repetitions (default
//! [`REPS`]). The `camera` row also gives `exp_err_max`: the largest relative change of the
//! drawn radiance per vertex that the split's fast exponentials make, against the C
//! library's (`--ablate view-exp`) from the same eye.

use super::solver_real::{bump, each_case, lights};
use anyhow::Context;
use glam::{Quat, Vec3};
use lucent_core::Rgb;
use lucent_core::bssrdf::Material;
use lucent_core::irradiance::{Light, SceneLight};
use lucent_core::mesh::Mesh;
use lucent_core::mesh::deform::Deformation;
use lucent_core::session::{
    FrameSession, FrameSettings, Method, SolveMode, Solved, Timings, Transport, ViewTerms,
};
use serde::Serialize;
use std::time::Instant;

/// Timed repetitions of each action (after one warm-up), unless `LUCENT_BENCH_REPS` says.
const REPS: usize = 3;

/// The repetitions: `LUCENT_BENCH_REPS`, else [`REPS`].
fn reps() -> usize {
    std::env::var("LUCENT_BENCH_REPS")
        .ok()
        .and_then(|r| r.trim().parse().ok())
        .filter(|r| *r > 0)
        .unwrap_or(REPS)
}

/// Whether `LUCENT_BENCH_ACTIONS` (comma-separated; unset: all) asks for the rows `action`.
fn wants(action: &str) -> bool {
    std::env::var("LUCENT_BENCH_ACTIONS").map_or(true, |a| a.split(',').any(|n| n.trim() == action))
}

#[derive(Serialize)]
struct Row {
    bench: &'static str,
    mesh: String,
    triangles: usize,
    material: &'static str,
    scale_m: f64,
    action: &'static str,
    reps: usize,
    /// Median per-stage milliseconds.
    timings: Timings,
    /// Median wall-clock milliseconds of the whole `solve`.
    wall_ms: f64,
    /// Median CPU milliseconds of the whole `solve`, every thread of the process (steadier
    /// than the wall clock on a loaded machine).
    cpu_ms: f64,
    /// `B` per face against a fresh solve: median and 95th percentile relative difference.
    b_err_median: f64,
    b_err_p95: f64,
    /// The drawn radiance per vertex against a fresh solve with per-eye view terms.
    view_err_median: f64,
    view_err_p95: f64,
    /// `camera` only: the largest relative change of the drawn radiance per vertex, the
    /// split's fast exponentials against the C library's, from the last eye.
    #[serde(skip_serializing_if = "Option::is_none")]
    exp_err_max: Option<f64>,
    /// The load average over the last minute when the row was measured (`/proc/loadavg`).
    load: f64,
    threads: usize,
}

/// The state a fresh session is given to solve the same frame from nothing.
struct State {
    positions: Vec<Vec3>,
    lights: Vec<SceneLight>,
    transport: Transport,
    eye: Vec3,
}

pub fn run(json: bool) -> anyhow::Result<()> {
    if !json {
        println!(
            "{:<12} {:>7} {:<9} {:<15} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8}",
            "mesh",
            "T",
            "material",
            "action",
            "irrad",
            "body",
            "link",
            "solve",
            "bounces",
            "view",
            "wall",
            "cpu",
            "B med",
            "B p95",
            "view med",
            "view p95"
        );
    }
    each_case(json, 60_000, |name, mesh, material, scale_m| {
        for row in measure(name, mesh, material, scale_m, json)? {
            print_row(&row, json)?;
        }
        Ok(())
    })
}

fn print_row(r: &Row, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(r)?);
        return Ok(());
    }
    let t = &r.timings;
    println!(
        "{:<12} {:>7} {:<9} {:<15} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>9.1} {:>9.1} {:>7.3}% {:>7.3}% {:>7.3}% {:>7.3}%",
        r.mesh,
        r.triangles,
        r.material,
        r.action,
        t.irradiance_ms,
        t.body_ms,
        t.link_ms,
        t.solve_ms(),
        t.bounces_ms,
        t.single_scattering_ms,
        r.wall_ms,
        r.cpu_ms,
        100.0 * r.b_err_median,
        100.0 * r.b_err_p95,
        100.0 * r.view_err_median,
        100.0 * r.view_err_p95
    );
    Ok(())
}

/// A session as the viewer makes it, solved once (its first image).
fn session(
    mesh: &Mesh,
    transport: Transport,
    lights: Vec<SceneLight>,
    eye: Vec3,
    terms: ViewTerms,
) -> FrameSession {
    let settings = FrameSettings {
        method: Method::Hierarchical,
        mode: SolveMode::Refit,
        oracle: None,
        environment_shadows: false,
        bounces: 3,
        ablate: Default::default(),
    };
    let mut s = FrameSession::new(mesh.clone(), None, transport, settings);
    s.set_lights(lights);
    s.set_eye(Some(eye));
    s.set_view_terms(terms);
    s
}

/// Every action's row for one mesh and material.
fn measure(
    name: &str,
    rest: &Mesh,
    material: &'static str,
    scale_m: f64,
    json: bool,
) -> anyhow::Result<Vec<Row>> {
    let transport = Transport::new(Material::by_name(material).context("material preset")?, scale_m);
    let (mut lights, light_at) = lights(rest);
    let (lo, hi) = rest.bounds();
    let centre = 0.5 * (lo + hi);
    let mut eye = centre + Vec3::new(0.0, 0.3, 2.5) * rest.extent();
    let mut state = State {
        positions: rest.positions.clone(),
        lights: lights.clone(),
        transport: transport.clone(),
        eye,
    };
    let mut s = session(rest, transport.clone(), lights.clone(), eye, ViewTerms::Split);
    s.solve();
    if wants("light-paths") {
        for r in super::light_paths::rows(name, material, &mut s, eye)? {
            super::light_paths::print(&r, json)?;
        }
    }
    let turn = |p: Vec3| centre + Quat::from_rotation_y(10f32.to_radians()) * (p - centre);
    let mut rows = Vec::new();
    let mut row =
        |action: &'static str, s: &mut FrameSession, state: &State, times: Vec<(Timings, (f64, f64))>| {
            let (b, view) = errors(rest, s, state);
            let mut wall: Vec<f64> = times.iter().map(|(_, w)| w.0).collect();
            wall.sort_by(f64::total_cmp);
            let mut cpu: Vec<f64> = times.iter().map(|(_, w)| w.1).collect();
            cpu.sort_by(f64::total_cmp);
            let t: Vec<Timings> = times.iter().map(|(t, _)| *t).collect();
            rows.push(Row {
                bench: "interactive",
                mesh: name.to_string(),
                triangles: rest.triangles.len(),
                material,
                scale_m,
                action,
                reps: times.len(),
                timings: Timings::median(&t),
                wall_ms: wall[wall.len() / 2],
                cpu_ms: cpu[cpu.len() / 2],
                b_err_median: b.0,
                b_err_p95: b.1,
                view_err_median: view.0,
                view_err_p95: view.1,
                exp_err_max: (action == "camera").then(|| exp_change(s)),
                load: load_average(),
                threads: rayon::current_num_threads(),
            });
        };
    // The light.
    if wants("light") {
        let times = repeat(&mut s, |s| {
            lights = lights.iter().map(|l| turn_light(l, &turn)).collect();
            s.set_lights(lights.clone());
        });
        state.lights = lights.clone();
        row("light", &mut s, &state, times);
    }
    if std::env::var_os("LUCENT_BENCH_LIGHT_ONLY").is_some() {
        return Ok(rows);
    }
    // The camera, split and per eye.
    for (action, terms) in [("camera", ViewTerms::Split), ("camera-per-eye", ViewTerms::PerEye)] {
        if !wants(action) {
            continue;
        }
        s.set_view_terms(terms);
        let times = repeat(&mut s, |s| {
            eye = turn(eye);
            s.set_eye(Some(eye));
        });
        state.eye = eye;
        row(action, &mut s, &state, times);
    }
    s.set_view_terms(ViewTerms::Split);
    if wants("material") || wants("bump") || wants("twist") {
        changes(&mut s, &mut state, (rest, light_at, scale_m), &mut row);
    }
    Ok(rows)
}

/// The material, bump and twist rows (after the light and camera ones) of `s` as `measure`
/// made it, `row` taking each action's times.
fn changes(
    s: &mut FrameSession,
    state: &mut State,
    (rest, light_at, scale_m): (&Mesh, Vec3, f64),
    row: &mut impl FnMut(&'static str, &mut FrameSession, &State, Vec<(Timings, (f64, f64))>),
) {
    // The material: the scale grows by 5% each time.
    let (transport, mut step) = (s.transport().clone(), 0);
    let times = repeat(s, |s| {
        step += 1;
        s.set_transport(Transport { scale_m: scale_m * (1.0 + 0.05 * step as f64), ..transport.clone() });
    });
    state.transport = s.transport().clone();
    row("material", s, state, times);
    // A local bump growing on the lit side, then a global twist, frame by frame.
    let (mut step, top) = (0, 0.01 * rest.extent());
    let times = repeat(s, |s| {
        step += 1;
        let h = top * step as f32 / (reps() + 1) as f32;
        s.set_positions(&bump(rest, light_at, 0.1 * rest.extent(), h));
    });
    state.positions = s.mesh().positions.clone();
    row("bump", s, state, times);
    let (twist, mut frame, mut out) = (Deformation::Twist { degrees: 30.0 }, 0, Vec::new());
    let times = repeat(s, |s| {
        frame += 1;
        twist.apply(rest, frame as f32 / 8.0, &mut out);
        s.set_positions(&out);
    });
    state.positions = s.mesh().positions.clone();
    row("twist", s, state, times);
}

/// `light` turned by `turn` (positions about the centre, directions about the vertical).
fn turn_light(l: &SceneLight, turn: &impl Fn(Vec3) -> Vec3) -> SceneLight {
    let light = match l.light {
        Light::Point { position, intensity } => Light::Point { position: turn(position), intensity },
        other => other,
    };
    SceneLight { light, ..*l }
}

/// One warm-up and [`reps`] timed repetitions of `act` then a solve: `(stages, (wall ms, CPU
/// ms))`.
fn repeat(s: &mut FrameSession, mut act: impl FnMut(&mut FrameSession)) -> Vec<(Timings, (f64, f64))> {
    act(s);
    s.solve();
    (0..reps())
        .map(|_| {
            act(s);
            let (t, cpu) = (Instant::now(), super::cpu_time::process_cpu_ms());
            let timings = s.solve().timings;
            (timings, (lucent_core::clock::ms_since(t), super::cpu_time::process_cpu_ms() - cpu))
        })
        .collect()
}

/// `((median, p95) of B's error, (median, p95) of the drawn radiance's)` of `s`'s last solve
/// against a fresh session's solve of `state` with per-eye view terms.
fn errors(rest: &Mesh, s: &mut FrameSession, state: &State) -> ((f64, f64), (f64, f64)) {
    let mut mesh = rest.clone();
    mesh.positions.clone_from(&state.positions);
    let mut fresh =
        session(&mesh, state.transport.clone(), state.lights.clone(), state.eye, ViewTerms::PerEye);
    let want = fresh.solve().clone();
    let got = s.solve().clone();
    let sum = |v: &Rgb| (v.x + v.y + v.z) as f64;
    let b = relative(got.face_b.iter().map(sum), want.face_b.iter().map(sum));
    let drawn = |x: &Solved| -> Vec<f64> {
        let single = |i: usize| x.vertex_single.get(i).copied().unwrap_or(Rgb::ZERO);
        x.vertex_radiance.iter().enumerate().map(|(i, r)| sum(&(*r + single(i)))).collect()
    };
    let view = relative(drawn(&got).into_iter(), drawn(&want).into_iter());
    (b, view)
}

/// The largest relative change of the drawn radiance per vertex (channel sums, vertices with
/// any) of `s`'s last image when the split takes the C library's exponentials instead of the
/// fast ones (`--ablate view-exp`, a view-only setting: the same eye seen again); `s` is left
/// as it was.
fn exp_change(s: &mut FrameSession) -> f64 {
    let drawn = |x: &Solved| -> Vec<f64> {
        let single = |i: usize| x.vertex_single.get(i).copied().unwrap_or(Rgb::ZERO);
        x.vertex_radiance
            .iter()
            .enumerate()
            .map(|(i, r)| (r.x + r.y + r.z + single(i).element_sum()) as f64)
            .collect()
    };
    let fast = drawn(s.solve());
    let settings = *s.settings();
    let mut exact = settings;
    exact.ablate.view_exp = true;
    s.set_settings(exact);
    let libm = drawn(s.solve());
    s.set_settings(settings);
    s.solve();
    fast.iter().zip(&libm).filter(|(_, b)| **b > 0.0).map(|(a, b)| (a - b).abs() / b).fold(0.0, f64::max)
}

/// The load average over the last minute (`/proc/loadavg`; 0 where there is none).
fn load_average() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next()?.parse().ok())
        .unwrap_or(0.0)
}

/// Median and 95th percentile of `|a - b| / b` where `b > 0`.
fn relative(a: impl Iterator<Item = f64>, b: impl Iterator<Item = f64>) -> (f64, f64) {
    let mut e: Vec<f64> = a.zip(b).filter(|(_, b)| *b > 1e-12).map(|(a, b)| (a - b).abs() / b).collect();
    if e.is_empty() {
        return (0.0, 0.0);
    }
    e.sort_by(f64::total_cmp);
    let at = |q: f64| e[((e.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.95))
}
