//! `lucent bench solver`: the hierarchical solve (Mertens et al. 2003, §3.2, §5.5).
//!
//! * default: table 3 of the paper: a marble butterfly-subdivision model (an octahedron,
//!   stretched, subdivided 4..7 times: 2048, 8192, 32768, 131072 triangles; the paper's 2016,
//!   8160, 32736, 131736) scaled at 2.5 cm under a point light: links, links per triangle,
//!   on-the-fly, incremental (after a small bump) and render times (medians), and the relative
//!   RMSE of per-vertex `B` against the exact O(N²) solve where that is affordable; with the
//!   default oracle or the one `--oracle` names.
//! * `--sweep`: oracle thresholds against error and link count (both oracle modes).
//! * `--table5`: table 5 of the paper: full on-the-fly evaluation with the semi-analytic form
//!   factor for near links against uniform point sampling of the near faces, marble at
//!   0.05 .. 0.8 m.
//!
//! `LUCENT_BENCH_MAX_TRIANGLES` caps table 3's sizes (default: all four).

use anyhow::Context;
use glam::Vec3;
use lucent_core::bssrdf::{Material, Profile};
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::hierarchy::subdivision::{butterfly, octahedron};
use lucent_core::irradiance::{Light, face_irradiance};
use lucent_core::mesh::Mesh;
use lucent_core::solver::exact::rel_rmse;
use lucent_core::solver::oracle::OracleMode;
use lucent_core::solver::{HierarchicalSolver, Oracle, exact};
use serde::Serialize;
use std::time::Instant;

/// Largest mesh for which the exact O(N²) reference is computed (4M form factors).
const EXACT_MAX_TRIANGLES: usize = 2048;

/// Render-mode frames timed per row: a frame takes milliseconds, and a median of seven
/// moved by 10% from run to run of the command at 131K triangles.
const RENDER_RUNS: usize = 21;

#[derive(Serialize)]
struct Table3Row {
    bench: &'static str,
    /// Triangles of the finest mesh.
    triangles: usize,
    /// Stored links after `link()`.
    links: usize,
    links_per_triangle: f64,
    /// Median wall-clock times, ms.
    on_the_fly_ms: f64,
    incremental_ms: f64,
    render_ms: f64,
    /// Time of the initial `link()`, ms.
    link_ms: f64,
    /// Relative RMSE of per-vertex B against the exact solve (null when not computed).
    rel_rmse_vs_exact: Option<f64>,
    /// Rayon worker threads.
    threads: usize,
    /// Oracle used.
    oracle: String,
}

#[derive(Serialize)]
struct SweepRow {
    bench: &'static str,
    mesh: String,
    triangles: usize,
    material: String,
    scale_m: f64,
    oracle: String,
    links: usize,
    links_per_triangle: f64,
    on_the_fly_ms: f64,
    rel_rmse_vs_exact: f64,
}

pub fn run(json: bool, sweep: bool, table5: bool, oracle: Option<Oracle>) -> anyhow::Result<()> {
    if oracle.is_some() && (sweep || table5) {
        anyhow::bail!("--oracle applies to table 3 only: --sweep and --table5 choose their own oracles");
    }
    if sweep {
        return run_sweep(json);
    }
    if table5 {
        return run_table5(json);
    }
    run_table3(json, oracle.unwrap_or_default())
}

fn oracle_name(o: &Oracle) -> String {
    match o.mode {
        OracleMode::SolidAngle => format!("solid-angle eps1={} eps2={}", o.eps1, o.eps2),
        OracleMode::Transport => {
            format!(
                "transport eps1={} eps2={} eps_abs={} eps_share={} irradiance_contrast={} linear_receivers={}",
                o.eps1, o.eps2, o.eps_abs, o.eps_share, o.irradiance_contrast, o.linear_receivers
            )
        }
    }
}

/// Median of `runs` timings of `f`, ms.
fn median_ms(runs: usize, mut f: impl FnMut() -> f64) -> f64 {
    let mut t: Vec<f64> = (0..runs).map(|_| f()).collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// A point light above, in front and to the side of a mesh with extent `ext`.
fn light_for(mesh: &Mesh) -> Vec<Light> {
    let (lo, hi) = mesh.bounds();
    let c = 0.5 * (lo + hi);
    let ext = mesh.extent();
    vec![Light::Point {
        position: c + Vec3::new(1.0, 1.5, 0.8) * ext,
        intensity: Vec3::splat(ext * ext * 4.0),
    }]
}

/// A bump of height `h` (mesh units) along +z on vertices within `radius` of `at`.
fn bump(positions: &[Vec3], at: Vec3, radius: f32, h: f32) -> Vec<Vec3> {
    positions
        .iter()
        .map(|&p| {
            let d2 = (p - at).length_squared() / (radius * radius);
            if d2 < 1.0 { p + Vec3::Z * h * (1.0 - d2) * (1.0 - d2) } else { p }
        })
        .collect()
}

fn run_table3(json: bool, oracle: Oracle) -> anyhow::Result<()> {
    let max_t: usize =
        std::env::var("LUCENT_BENCH_MAX_TRIANGLES").ok().and_then(|v| v.parse().ok()).unwrap_or(usize::MAX);
    let marble = Material::by_name("marble").context("marble preset")?;
    let base = octahedron(Vec3::new(1.0, 1.25, 0.9));
    if !json {
        println!(
            "{:>8} {:>10} {:>6} {:>12} {:>12} {:>10} {:>10}  (marble, 2.5 cm, {})",
            "T",
            "links",
            "L/T",
            "on-the-fly",
            "incremental",
            "render",
            "rel RMSE",
            oracle_name(&oracle)
        );
    }
    for levels in 4..=7u32 {
        if 8 * 4usize.pow(levels) > max_t {
            break;
        }
        let sub = butterfly(&base, levels).context("subdividing the octahedron")?;
        let mesh = sub.mesh;
        let profile = Profile::for_model_scale(&marble, mesh.extent() as f64, 0.025);
        let e = face_irradiance(&mesh, &light_for(&mesh), &profile.entry);
        let mut solver = HierarchicalSolver::new(mesh.clone(), sub.hierarchy, profile.clone(), oracle);
        let runs = if mesh.triangles.len() > 40_000 { 3 } else { 5 };
        let otf = median_ms(runs, || solver.solve_on_the_fly(&e).stats.total_ms);
        let link_ms = solver.link().total_ms;
        let render = median_ms(RENDER_RUNS, || solver.solve_render(&e).stats.total_ms);
        // Incremental: alternate a small bump (2% of the extent, on the +z pole) on and off.
        let rest = mesh.positions.clone();
        let bumped = bump(&rest, Vec3::new(0.0, 0.0, 0.9), 0.25, 0.02);
        // One untimed update first: the steady state of an animation, in which the buffers
        // of the previous update are reused, is what a frame costs.
        solver.update_incremental(&bumped, None);
        let mut on = true;
        // An update is cheap, and its time varies more than a full link's.
        let incremental = median_ms(2 * runs + 1, || {
            on = !on;
            let t = Instant::now();
            solver.update_incremental(if on { &bumped } else { &rest }, None);
            solver.solve_render(&e);
            t.elapsed().as_secs_f64() * 1e3
        });
        if on {
            solver.update_incremental(&rest, None);
        }
        let rel = (mesh.triangles.len() <= EXACT_MAX_TRIANGLES).then(|| {
            let want = exact::solve(&mesh, &profile, &e, &FormFactorOptions::default());
            let got = solver.solve_render(&e).face_b;
            rel_rmse(&mesh.face_to_vertex(&want), &mesh.face_to_vertex(&got))
        });
        let links = solver.links().map_or(0, |l| l.len());
        let row = Table3Row {
            bench: "solver_table3",
            triangles: mesh.triangles.len(),
            links,
            links_per_triangle: links as f64 / mesh.triangles.len() as f64,
            on_the_fly_ms: otf,
            incremental_ms: incremental,
            render_ms: render,
            link_ms,
            rel_rmse_vs_exact: rel,
            threads: rayon::current_num_threads(),
            oracle: oracle_name(&oracle),
        };
        if json {
            println!("{}", serde_json::to_string(&row)?);
        } else {
            println!(
                "{:>8} {:>10} {:>6.1} {:>10.1}ms {:>10.1}ms {:>8.1}ms {:>10}",
                row.triangles,
                row.links,
                row.links_per_triangle,
                row.on_the_fly_ms,
                row.incremental_ms,
                row.render_ms,
                rel.map_or("-".into(), |r| format!("{:.3}%", 100.0 * r))
            );
        }
    }
    Ok(())
}

fn run_sweep(json: bool) -> anyhow::Result<()> {
    let base = octahedron(Vec3::new(1.0, 1.25, 0.9));
    let sub = butterfly(&base, 4).context("subdividing the octahedron")?;
    let mesh = sub.mesh;
    let h = sub.hierarchy;
    let name = "octahedron-butterfly-4".to_string();
    for (mat, scale) in [("marble", 0.025), ("skimmilk", 0.1)] {
        let material = Material::by_name(mat).context("preset")?;
        let profile = Profile::for_model_scale(&material, mesh.extent() as f64, scale);
        let e = face_irradiance(&mesh, &light_for(&mesh), &profile.entry);
        let want = mesh.face_to_vertex(&exact::solve(&mesh, &profile, &e, &FormFactorOptions::default()));
        let mut oracles = Vec::new();
        for (e1, e2) in [(0.005, 0.01), (0.02, 0.05), (0.05, 0.1), (0.1, 0.3)] {
            oracles.push(Oracle {
                mode: OracleMode::SolidAngle,
                eps1: e1,
                eps2: e2,
                eps_near_cluster: 0.0,
                ..Oracle::default()
            });
        }
        for (eps, abs) in [(0.01, 1e-5), (0.03, 1e-5), (0.1, 1e-4), (0.3, 1e-3)] {
            oracles.push(Oracle {
                mode: OracleMode::Transport,
                eps1: eps,
                eps2: eps,
                eps_abs: abs,
                ..Oracle::default()
            });
        }
        oracles.push(Oracle::default());
        for o in oracles {
            let solver = HierarchicalSolver::new(mesh.clone(), h.clone(), profile.clone(), o);
            let mut links = 0;
            let mut b = Vec::new();
            let ms = median_ms(3, || {
                let s = solver.solve_on_the_fly(&e);
                links = s.stats.links;
                b = s.face_b;
                s.stats.total_ms
            });
            let row = SweepRow {
                bench: "solver_sweep",
                mesh: name.clone(),
                triangles: mesh.triangles.len(),
                material: mat.into(),
                scale_m: scale,
                oracle: oracle_name(&o),
                links,
                links_per_triangle: links as f64 / mesh.triangles.len() as f64,
                on_the_fly_ms: ms,
                rel_rmse_vs_exact: rel_rmse(&want, &mesh.face_to_vertex(&b)),
            };
            if json {
                println!("{}", serde_json::to_string(&row)?);
            } else {
                println!(
                    "{:>9} {:>6} {:<48} {:>9} links {:>7.1}/T {:>9.1} ms  {:.3}%",
                    row.material,
                    row.scale_m,
                    row.oracle,
                    row.links,
                    row.links_per_triangle,
                    row.on_the_fly_ms,
                    100.0 * row.rel_rmse_vs_exact
                );
            }
        }
    }
    Ok(())
}

#[derive(Serialize)]
struct Table5Row {
    bench: &'static str,
    triangles: usize,
    scale_m: f64,
    /// Median on-the-fly time with the semi-analytic form factor for near links, ms.
    form_factor_ms: f64,
    /// The same with uniform point sampling of near links, ms.
    point_sampling_ms: f64,
    /// Relative RMSE of each against the exact solve.
    form_factor_rel_rmse: f64,
    point_sampling_rel_rmse: f64,
    threads: usize,
}

/// Mertens table 5: marble, the 2048-triangle butterfly model, scales 0.05 .. 0.8 m.
fn run_table5(json: bool) -> anyhow::Result<()> {
    let base = octahedron(Vec3::new(1.0, 1.25, 0.9));
    let sub = butterfly(&base, 4).context("subdividing the octahedron")?;
    let mesh = sub.mesh;
    let marble = Material::by_name("marble").context("marble preset")?;
    for scale in [0.05, 0.1, 0.2, 0.4, 0.8] {
        let profile = Profile::for_model_scale(&marble, mesh.extent() as f64, scale);
        let e = face_irradiance(&mesh, &light_for(&mesh), &profile.entry);
        let want = mesh.face_to_vertex(&exact::solve(&mesh, &profile, &e, &FormFactorOptions::default()));
        let mut solver =
            HierarchicalSolver::new(mesh.clone(), sub.hierarchy.clone(), profile, Oracle::default());
        let mut run = |ps: bool| {
            solver.near_point_sampling = ps;
            let mut b = Vec::new();
            let ms = median_ms(3, || {
                let s = solver.solve_on_the_fly(&e);
                b = s.face_b;
                s.stats.total_ms
            });
            (ms, rel_rmse(&want, &mesh.face_to_vertex(&b)))
        };
        let (ff_ms, ff_err) = run(false);
        let (ps_ms, ps_err) = run(true);
        let row = Table5Row {
            bench: "solver_table5",
            triangles: mesh.triangles.len(),
            scale_m: scale,
            form_factor_ms: ff_ms,
            point_sampling_ms: ps_ms,
            form_factor_rel_rmse: ff_err,
            point_sampling_rel_rmse: ps_err,
            threads: rayon::current_num_threads(),
        };
        if json {
            println!("{}", serde_json::to_string(&row)?);
        } else {
            println!(
                "scale {:>5} m: form factor {:>8.1} ms ({:.3}%)   point sampling {:>8.1} ms ({:.3}%)",
                scale,
                ff_ms,
                100.0 * ff_err,
                ps_ms,
                100.0 * ps_err
            );
        }
    }
    Ok(())
}
