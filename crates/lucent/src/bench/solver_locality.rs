//! `lucent bench solver --locality`: the cost of a solve on the embedded bunny over optical
//! density and size, against the default material's (skim milk at 5 cm, `lucent render`'s
//! defaults). Materials `sigma_s' = sigma_a = sigma` (albedo 1/2) for sigma in 1e-4..1e3
//! mm^-1, at model scales 1 mm..10 m (scales over `lucent render --scale`'s 100 m are left
//! out). Each row: links, evaluations and on-the-fly time (median of 3) and their ratios to the
//! default's, how many faces took the local limit (`B = R_d E`, transport far below a face),
//! and the error at sampled faces against their exact `B` (`LUCENT_BENCH_EXACT_SAMPLES`,
//! default 200). Link and evaluation counts are deterministic; times depend on the load.

use anyhow::Context;
use glam::Vec3;
use lucent_core::bssrdf::Material;
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::hierarchy::{Hierarchy, face_cluster};
use lucent_core::irradiance::{Light, SceneLight, ShadowCaster, face_irradiance_shadowed};
use lucent_core::mesh::{Mesh, embedded};
use lucent_core::session::Transport;
use lucent_core::solver::{HierarchicalSolver, Oracle, SolveStats, exact};
use serde::Serialize;

#[derive(Serialize)]
struct LocalityRow {
    bench: &'static str,
    /// `sigma_s' = sigma_a`, mm^-1.
    sigma_mm: f64,
    /// Model scale (largest bounding-box side), m.
    scale_m: f64,
    links: usize,
    /// Form factors, cubatures and one-point estimates of the solve.
    evaluations: usize,
    on_the_fly_ms: f64,
    /// Links, evaluations and time over the default material's.
    links_ratio: f64,
    evaluations_ratio: f64,
    time_ratio: f64,
    /// Faces whose `B` is the local limit `R_d E`.
    local_faces: usize,
    triangles: usize,
    sampled_faces: usize,
    median_rel_err: f64,
    max_rel_err: f64,
}

struct Case {
    stats: SolveStats,
    ms: f64,
    errs: (f64, f64),
}

pub fn run(json: bool) -> anyhow::Result<()> {
    let samples: usize =
        std::env::var("LUCENT_BENCH_EXACT_SAMPLES").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let mesh = embedded::bunny();
    let h = face_cluster::build(&mesh);
    let faces = super::solver_real::sample_faces(mesh.triangles.len(), samples);
    let default = measure(&mesh, &h, Material::by_name("skimmilk")?, 0.05, &faces)?;
    let evals = |s: &SolveStats| s.form_factors + s.cubatures + s.polar_faces + s.point_samples;
    if !json {
        println!(
            "default (skimmilk at 0.05 m): {} links, {} evaluations, {:.1} ms",
            default.stats.links,
            evals(&default.stats),
            default.ms
        );
        println!(
            "{:>9} {:>8} {:>9} {:>7} {:>7} {:>7} {:>7} {:>9} {:>9}",
            "sigma/mm", "scale m", "links", "xlinks", "xevals", "xtime", "local", "med err", "max err"
        );
    }
    let mut worst = 0.0f64;
    for sigma in [1e-4, 1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3] {
        for scale in [1e-3, 1e-2, 1e-1, 1.0, 10.0] {
            let m = Material::custom("locality", [sigma; 3], [sigma; 3], 1.3)?;
            let c = measure(&mesh, &h, m, scale, &faces)?;
            let row = LocalityRow {
                bench: "solver_locality",
                sigma_mm: sigma,
                scale_m: scale,
                links: c.stats.links,
                evaluations: evals(&c.stats),
                on_the_fly_ms: c.ms,
                links_ratio: c.stats.links as f64 / default.stats.links as f64,
                evaluations_ratio: evals(&c.stats) as f64 / evals(&default.stats) as f64,
                time_ratio: c.ms / default.ms,
                local_faces: c.stats.local_faces,
                triangles: mesh.triangles.len(),
                sampled_faces: faces.len(),
                median_rel_err: c.errs.0,
                max_rel_err: c.errs.1,
            };
            worst = worst.max(row.evaluations_ratio.max(row.links_ratio));
            if json {
                println!("{}", serde_json::to_string(&row)?);
            } else {
                println!(
                    "{:>9.0e} {:>8} {:>9} {:>7.2} {:>7.2} {:>7.2} {:>7} {:>8.3}% {:>8.3}%",
                    sigma,
                    scale,
                    row.links,
                    row.links_ratio,
                    row.evaluations_ratio,
                    row.time_ratio,
                    row.local_faces,
                    100.0 * row.median_rel_err,
                    100.0 * row.max_rel_err
                );
            }
        }
    }
    if !json {
        println!("largest links or evaluations ratio to the default: {worst:.2}");
    }
    Ok(())
}

fn measure(
    mesh: &Mesh,
    h: &Hierarchy,
    material: Material,
    scale_m: f64,
    faces: &[usize],
) -> anyhow::Result<Case> {
    let profile = Transport::new(material, scale_m).profile_at(mesh.extent());
    let (lo, hi) = mesh.bounds();
    let ext = mesh.extent();
    let light = Light::Point {
        position: 0.5 * (lo + hi) + Vec3::new(1.0, 1.5, 0.8) * ext,
        intensity: Vec3::splat(ext * ext * 4.0),
    };
    let caster = ShadowCaster::new(mesh);
    let e = face_irradiance_shadowed(mesh, &[SceneLight::from(light)], None, &profile.entry, Some(&caster));
    let solver =
        HierarchicalSolver::new(mesh.clone(), h.clone(), profile.clone(), Oracle::for_profile(profile.kind));
    let mut runs: Vec<(f64, SolveStats)> = (0..3)
        .map(|_| {
            let s = solver.solve_on_the_fly(&e).stats;
            (s.total_ms, s)
        })
        .collect();
    runs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (ms, stats) = runs[1];
    let b = solver.solve_on_the_fly(&e).face_b;
    let want = exact::solve_receivers(mesh, &profile, &e, &FormFactorOptions::default(), faces, None);
    let sum = |v: lucent_core::Rgb| (v[0] + v[1] + v[2]) as f64;
    let mut errs: Vec<f64> = faces
        .iter()
        .zip(&want)
        .filter(|(_, w)| sum(**w) > 1e-30)
        .map(|(&f, &w)| (sum(b[f]) - sum(w)).abs() / sum(w))
        .collect();
    errs.sort_by(f64::total_cmp);
    let errs =
        if errs.is_empty() { (0.0, 0.0) } else { (errs[errs.len() / 2], *errs.last().context("errors")?) };
    Ok(Case { stats, ms, errs })
}
