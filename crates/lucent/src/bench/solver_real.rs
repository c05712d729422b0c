//! `lucent bench solver --real`: the hierarchical solve on real scanned meshes, where users
//! live, beside table 3's smooth generated blobs: the embedded Stanford bunny (3,674
//! triangles) and the Stanford dragon at each resolution `scripts/fetch_dragon.sh` fetched into
//! `target/meshes/` (11K, 48K, 203K, 871K triangles; missing ones are skipped with a note),
//! marble at 10 cm and skim milk at 5 cm, under a shadowing point light, with the profile's
//! default oracle ([`Oracle::for_profile`]) and the face-cluster hierarchy, as
//! `lucent render` solves them.
//!
//! Each row: links, links per triangle, on-the-fly, render (gather over the stored links) and
//! incremental (a bump of 1% of the extent on the lit side, on and off, updated incrementally
//! and rendered) times, medians of 3 runs (1 run above 100K triangles for on-the-fly), the
//! process's peak resident set, and the error at 1,000 faces drawn with a fixed seed against
//! their exact `B` ([`exact::solve_receivers`]: every face gathered with the exact solver's form
//! factor and energy bound): median and max of `|ΣB_h - ΣB_x| / ΣB_x` over the channel sums.
//!
//! Peak RSS is `VmHWM` from `/proc/self/status`. Before each row the high-water mark is reset
//! (`5` written to `/proc/self/clear_refs`, Linux 4.0+); where that is refused it stays a
//! process-wide mark, and the row says so (`rss_reset: false`).
//!
//! `LUCENT_BENCH_MAX_TRIANGLES` and `LUCENT_BENCH_MIN_TRIANGLES` skip larger and smaller meshes,
//! `LUCENT_BENCH_MATERIAL` (`marble` or `skimmilk`) the other material;
//! `LUCENT_BENCH_EXACT_SAMPLES` changes the 1,000 sampled faces; `LUCENT_BENCH_NO_ON_THE_FLY`
//! skips the on-the-fly solve (reported as NaN, `null` in JSON).

use crate::progress::Watch;
use anyhow::Context;
use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::Material;
use lucent_core::clock::ms_since;
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::hierarchy::face_cluster;
use lucent_core::irradiance::{Light, SceneLight, ShadowCaster, face_irradiance_shadowed};
use lucent_core::mesh::{Mesh, embedded, load_mesh};
use lucent_core::session::Transport;
use lucent_core::solver::oracle::OracleMode;
use lucent_core::solver::{HierarchicalSolver, Oracle, exact};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Serialize)]
struct RealRow {
    bench: &'static str,
    mesh: String,
    triangles: usize,
    material: &'static str,
    scale_m: f64,
    links: usize,
    links_per_triangle: f64,
    /// Face-cluster hierarchy build, ms (once per mesh, not part of a frame).
    hierarchy_ms: f64,
    /// Median wall-clock times, ms.
    on_the_fly_ms: f64,
    link_ms: f64,
    render_ms: f64,
    incremental_ms: f64,
    /// Peak resident set, MiB (`VmHWM`), after this row.
    peak_rss_mib: f64,
    /// Whether the peak was reset before the row (else it is process-wide).
    rss_reset: bool,
    /// Faces whose exact `B` was computed, and the relative error of the hierarchical `B`
    /// (render mode, channel sum) there.
    sampled_faces: usize,
    median_rel_err: f64,
    max_rel_err: f64,
    /// Median of the *signed* relative error (hierarchical over exact, minus 1): the
    /// one-point estimates of a convex profile fall short, so a bias shows here.
    median_signed_err: f64,
    exact_ms: f64,
    /// The link's evaluations by kind (the stored links' coefficients): semi-analytic form
    /// factors, seven-point cubatures, polar-rule faces, one-point estimates.
    form_factors: usize,
    cubatures: usize,
    polar_faces: usize,
    point_samples: usize,
    threads: usize,
    oracle: String,
}

/// The meshes: the embedded bunny, then each dragon resolution found.
pub(super) fn meshes(json: bool) -> Vec<(String, PathBuf)> {
    let dirs =
        [PathBuf::from("target/meshes"), Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/meshes")];
    let mut out = vec![("bunny".to_string(), PathBuf::new())];
    for name in ["dragon_11k", "dragon_48k", "dragon_203k", "dragon_871k"] {
        match dirs.iter().map(|d| d.join(format!("{name}.ply"))).find(|p| p.is_file()) {
            Some(p) => out.push((name.to_string(), p)),
            None if json => {
                println!(
                    "{}",
                    serde_json::json!({"bench": "solver_real", "mesh": name, "skipped": "not found in target/meshes/: run scripts/fetch_dragon.sh"})
                )
            }
            None => println!("{name}: skipped, not in target/meshes/ (run scripts/fetch_dragon.sh)"),
        }
    }
    out
}

pub fn run(json: bool, oracle: Option<Oracle>) -> anyhow::Result<()> {
    let samples = env_usize("LUCENT_BENCH_EXACT_SAMPLES", 1000);
    if !json {
        println!(
            "{:<12} {:>7} {:<9} {:>10} {:>6} {:>11} {:>10} {:>9} {:>12} {:>9} {:>9} {:>9}",
            "mesh",
            "T",
            "material",
            "links",
            "L/T",
            "on-the-fly",
            "link",
            "render",
            "incremental",
            "peak RSS",
            "med err",
            "max err"
        );
    }
    let watch = Watch::new();
    each_case(json, usize::MAX, |name, mesh, material, scale_m| {
        let row = measure(name, mesh, material, scale_m, samples, &watch, oracle)?;
        if json {
            println!("{}", serde_json::to_string(&row)?);
        } else {
            println!(
                "{:<12} {:>7} {:<9} {:>10} {:>6.1} {:>9.1}ms {:>8.1}ms {:>7.1}ms {:>10.1}ms {:>6.0}MiB{} {:>8.3}% {:>8.3}%",
                row.mesh,
                row.triangles,
                row.material,
                row.links,
                row.links_per_triangle,
                row.on_the_fly_ms,
                row.link_ms,
                row.render_ms,
                row.incremental_ms,
                row.peak_rss_mib,
                if row.rss_reset { " " } else { "*" },
                100.0 * row.median_rel_err,
                100.0 * row.max_rel_err
            );
        }
        Ok(())
    })
}

/// A `usize` from the environment variable `key`, else `default`.
pub(super) fn env_usize(key: &str, default: usize) -> usize {
    std::env::var(key).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Runs `each` on every case of the real-mesh benches as (mesh name, mesh, material, scale in
/// metres): the meshes of [`meshes`] with `LUCENT_BENCH_MIN_TRIANGLES` (default 0) to
/// `LUCENT_BENCH_MAX_TRIANGLES` (default `max_default`) triangles, each in marble at 10 cm and
/// skim milk at 5 cm, or only the material `LUCENT_BENCH_MATERIAL` names.
pub(super) fn each_case(
    json: bool,
    max_default: usize,
    mut each: impl FnMut(&str, &Mesh, &'static str, f64) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let max_t = env_usize("LUCENT_BENCH_MAX_TRIANGLES", max_default);
    let min_t = env_usize("LUCENT_BENCH_MIN_TRIANGLES", 0);
    let only = std::env::var("LUCENT_BENCH_MATERIAL").ok();
    for (name, path) in meshes(json) {
        let mesh = if path.as_os_str().is_empty() {
            embedded::bunny()
        } else {
            load_mesh(&path).with_context(|| format!("loading {}", path.display()))?
        };
        if mesh.triangles.len() > max_t || mesh.triangles.len() < min_t {
            continue;
        }
        for (material, scale_m) in [("marble", 0.1), ("skimmilk", 0.05)] {
            if only.as_deref().is_none_or(|m| m == material) {
                each(&name, &mesh, material, scale_m)?;
            }
        }
    }
    Ok(())
}

/// With `LUCENT_BENCH_CENSUS` set: where the links come from (the oracle's decisions by cause,
/// links by kind, level, separation and emitter size), per mesh, marble at 10 cm.
pub fn census(json: bool, oracle: Option<Oracle>) -> anyhow::Result<()> {
    let max_t = env_usize("LUCENT_BENCH_MAX_TRIANGLES", usize::MAX);
    for (name, path) in meshes(json) {
        let mesh = if path.as_os_str().is_empty() { embedded::bunny() } else { load_mesh(&path)? };
        if mesh.triangles.len() > max_t {
            continue;
        }
        let transport = Transport::new(Material::by_name("marble").context("material preset")?, 0.1);
        let profile = transport.profile_at(mesh.extent());
        let oracle = oracle.unwrap_or_else(|| Oracle::for_profile(profile.kind));
        let solver = HierarchicalSolver::new(mesh.clone(), face_cluster::build(&mesh), profile, oracle);
        let c = solver.census();
        let t = mesh.triangles.len() as f64;
        if json {
            println!(
                "{}",
                serde_json::json!({"bench": "solver_census", "mesh": name, "triangles": t,
                    "links_per_triangle": c.total as f64 / t, "decisions": c.decisions, "links": c.links,
                    "near_causes": c.near_causes, "separation_log2": c.separation,
                    "emitter_size_log2": c.emitter_size, "receiver_level": c.receiver_level,
                    "per_face_p50_p90_p99_max": c.per_face, "slivers": c.slivers,
                    "sliver_mean": c.sliver_mean, "other_mean": c.other_mean})
            );
        } else {
            println!("{name}: {} triangles, {} links ({:.1}/triangle)", t, c.total, c.total as f64 / t);
            println!("{c:#?}");
        }
    }
    Ok(())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A point light above, in front and to the side of `mesh`, casting shadows.
pub(super) fn lights(mesh: &Mesh) -> (Vec<SceneLight>, Vec3) {
    let (lo, hi) = mesh.bounds();
    let c = 0.5 * (lo + hi);
    let ext = mesh.extent();
    let position = c + Vec3::new(1.0, 1.5, 0.8) * ext;
    let light = Light::Point { position, intensity: Vec3::splat(ext * ext * 4.0) };
    (vec![SceneLight::from(light)], position)
}

/// The mesh with a smooth bump of height `h` along the direction to `toward`, on the vertices
/// within `radius` of the vertex nearest `toward`.
pub(super) fn bump(mesh: &Mesh, toward: Vec3, radius: f32, h: f32) -> Vec<Vec3> {
    let p = &mesh.positions;
    let at = *p
        .iter()
        .min_by(|a, b| a.distance_squared(toward).total_cmp(&b.distance_squared(toward)))
        .expect("vertices");
    let dir = (toward - at).normalize_or_zero();
    p.iter()
        .map(|&q| {
            let d2 = (q - at).length_squared() / (radius * radius);
            if d2 < 1.0 { q + dir * h * (1.0 - d2) * (1.0 - d2) } else { q }
        })
        .collect()
}

/// `n` distinct faces of `count`, drawn with a fixed seed (splitmix64), sorted.
pub(super) fn sample_faces(count: usize, n: usize) -> Vec<usize> {
    if n >= count {
        return (0..count).collect();
    }
    let mut state = 0x05ee_d1ce_u64;
    let mut next = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let mut picked = std::collections::BTreeSet::new();
    while picked.len() < n {
        picked.insert((next() % count as u64) as usize);
    }
    picked.into_iter().collect()
}

/// Resets the peak RSS; whether the kernel allowed it.
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// `VmHWM` in MiB (0 where unreadable).
fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(0.0, |kib| kib / 1024.0)
}

fn measure(
    name: &str,
    mesh: &Mesh,
    material: &'static str,
    scale_m: f64,
    samples: usize,
    watch: &Watch,
    oracle: Option<Oracle>,
) -> anyhow::Result<RealRow> {
    let rss_reset = reset_peak_rss();
    let big = mesh.triangles.len() > 100_000;
    let transport = Transport::new(Material::by_name(material).context("material preset")?, scale_m);
    let profile = transport.profile_at(mesh.extent());
    let oracle = oracle.unwrap_or_else(|| Oracle::for_profile(profile.kind));
    let (lights, light_at) = lights(mesh);
    let caster = ShadowCaster::new(mesh);
    let e = face_irradiance_shadowed(mesh, &lights, None, &profile.entry, Some(&caster));

    let t = Instant::now();
    let h = face_cluster::build(mesh);
    let hierarchy_ms = ms_since(t);
    let mut solver = HierarchicalSolver::new(mesh.clone(), h, profile.clone(), oracle);
    solver.progress = Some(watch.progress());

    let otf_runs = if std::env::var_os("LUCENT_BENCH_NO_ON_THE_FLY").is_some() {
        0
    } else if big {
        1
    } else {
        3
    };
    let on_the_fly_ms = if otf_runs == 0 {
        f64::NAN
    } else {
        median((0..otf_runs).map(|_| solver.solve_on_the_fly(&e).stats.total_ms).collect())
    };
    let link_stats = solver.link();
    let link_ms = link_stats.total_ms;
    let render_ms = median((0..3).map(|_| solver.solve_render(&e).stats.total_ms).collect());
    let face_b = solver.solve_render(&e).face_b;

    let incremental_ms = incremental_ms(&mut solver, mesh, light_at, &e);
    let links = solver.links().map_or(0, |l| l.len());
    drop(solver);

    let faces = sample_faces(mesh.triangles.len(), samples);
    let t = Instant::now();
    let opts = FormFactorOptions::default();
    let want = exact::solve_receivers(mesh, &profile, &e, &opts, &faces, Some(&watch.progress()));
    let exact_ms = ms_since(t);
    let (median_rel_err, max_rel_err, median_signed_err) = sampled_errors(&faces, &want, &face_b);
    Ok(RealRow {
        bench: "solver_real",
        mesh: name.to_string(),
        triangles: mesh.triangles.len(),
        material,
        scale_m,
        links,
        links_per_triangle: links as f64 / mesh.triangles.len() as f64,
        hierarchy_ms,
        on_the_fly_ms,
        link_ms,
        render_ms,
        incremental_ms,
        peak_rss_mib: peak_rss_mib(),
        rss_reset,
        sampled_faces: faces.len(),
        median_rel_err,
        max_rel_err,
        median_signed_err,
        exact_ms,
        form_factors: link_stats.form_factors,
        cubatures: link_stats.cubatures,
        polar_faces: link_stats.polar_faces,
        point_samples: link_stats.point_samples,
        threads: rayon::current_num_threads(),
        oracle: oracle_label(&oracle),
    })
}

/// Median time of an incremental update and render solve: a bump of 1% of the extent on the
/// lit side, on and off; one untimed update first (the steady state of an animation reuses the
/// last update's buffers).
fn incremental_ms(solver: &mut HierarchicalSolver, mesh: &Mesh, light_at: Vec3, e: &[Rgb]) -> f64 {
    let rest = mesh.positions.clone();
    let ext = mesh.extent();
    let bumped = bump(mesh, light_at, 0.05 * ext, 0.01 * ext);
    solver.update_incremental(&bumped, None);
    let mut on = true;
    median(
        (0..3)
            .map(|_| {
                on = !on;
                let t = Instant::now();
                solver.update_incremental(if on { &bumped } else { &rest }, None);
                solver.solve_render(e);
                ms_since(t)
            })
            .collect(),
    )
}

/// Median and largest relative error, and the median signed one, of `face_b` against the
/// exact `want` over the sampled `faces` (channels summed; unlit faces skipped; NaN for none).
fn sampled_errors(faces: &[usize], want: &[Rgb], face_b: &[Rgb]) -> (f64, f64, f64) {
    let sum = |b: Rgb| (b[0] + b[1] + b[2]) as f64;
    let signed: Vec<f64> = faces
        .iter()
        .zip(want)
        .filter(|(_, w)| sum(**w) > 0.0)
        .map(|(&f, &w)| (sum(face_b[f]) - sum(w)) / sum(w))
        .collect();
    let errs: Vec<f64> = signed.iter().map(|e| e.abs()).collect();
    if errs.is_empty() {
        (f64::NAN, f64::NAN, f64::NAN)
    } else {
        (median(errs.clone()), errs.iter().copied().fold(0.0, f64::max), median(signed))
    }
}

/// The oracle as `--oracle` takes it (`transport:EPS1,EPS2,EPS_ABS,EPS_SHARE,CONTRAST`).
fn oracle_label(oracle: &Oracle) -> String {
    format!(
        "{}:{},{},{},{},{}",
        match (oracle.mode, oracle.linear_receivers, oracle.curved_receivers) {
            (OracleMode::Transport, false, _) => "transport-constant",
            (OracleMode::Transport, true, false) => "transport-linear",
            (OracleMode::Transport, true, true) => "transport",
            (OracleMode::SolidAngle, ..) => "solid-angle",
        },
        oracle.eps1,
        oracle.eps2,
        oracle.eps_abs,
        oracle.eps_share,
        oracle.irradiance_contrast
    )
    .to_lowercase()
}
