//! `lucent bench interactive`'s `light-paths` rows: the view stage of a light move with the
//! view ray's light paths taken without a ray where certain (`shading::single_scattering::light_paths`, the
//! default) against every path traced (`--ablate light-paths`), for a light in front of the
//! model (beside the eye), at its side and behind it.
//!
//! Per light: the session solves once, then the view stage alone is evaluated [`REPS`] times
//! each way, alternated (shortcut, traced, shortcut, ...), so that both see the same load;
//! the row gives both medians (wall clock and CPU time) and the shortcut's difference from the traced result in what
//! the mesh pass draws per vertex (`radiance + single`, channel sums; vertices with light),
//! median, 99th percentile and largest, and in the single scattering alone.

use super::cpu_time::process_cpu_ms;
use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::irradiance::{Light, SceneLight};
use lucent_core::session::{FrameSession, Solved, ViewTerms};
use serde::Serialize;

/// Timed evaluations each way, alternated.
const REPS: usize = 3;

#[derive(Serialize)]
pub(super) struct Row {
    bench: &'static str,
    mesh: String,
    triangles: usize,
    material: &'static str,
    /// `front`, `side` or `back` of the model as the eye sees it.
    light: &'static str,
    reps: usize,
    /// Median view-stage milliseconds with the shortcut (the default) and every path traced.
    view_ms: f64,
    view_ms_traced: f64,
    /// The same in CPU milliseconds of every thread of the process (the whole solve call,
    /// which is the view stage alone here): steadier than the wall clock on a loaded machine.
    view_cpu_ms: f64,
    view_cpu_ms_traced: f64,
    /// What the mesh pass draws per vertex, shortcut against traced: median, 99th percentile
    /// and largest relative difference.
    drawn_err: [f64; 3],
    /// The single scattering alone, where the traced one is above 1e-3 of the drawn radiance.
    single_err: [f64; 3],
}

/// The three rows of one mesh and material; `s` solved as the viewer solves, seen from `eye`
/// (mesh units). Leaves `s` with its lights and settings as they were, solved again.
pub(super) fn rows(
    name: &str,
    material: &'static str,
    s: &mut FrameSession,
    eye: Vec3,
) -> anyhow::Result<Vec<Row>> {
    let (lights, settings) = (s.lights().to_vec(), *s.settings());
    // Per eye, so that an evaluation of the view stage alone is the per-eye one a solve sees.
    s.set_view_terms(ViewTerms::PerEye);
    let (lo, hi) = s.mesh().bounds();
    let (centre, ext) = (0.5 * (lo + hi), s.mesh().extent());
    let ahead = (eye - centre).normalize_or_zero();
    let side = ahead.cross(Vec3::Y).normalize_or_zero();
    let intensity = Vec3::splat(ext * ext * 4.0);
    let mut rows = Vec::new();
    for (light, dir) in [("front", ahead + 0.5 * side), ("side", side), ("back", -ahead - 0.5 * side)] {
        let position = centre + (dir.normalize_or_zero() + Vec3::Y * 0.6) * 2.5 * ext;
        s.set_lights(vec![SceneLight::from(Light::Point { position, intensity })]);
        let (mut fast, mut traced) = (Vec::new(), Vec::new());
        let (mut got, mut want) = (None, None);
        for rep in 0..2 * REPS {
            let all = rep % 2 == 1;
            let mut set = settings;
            set.ablate.light_paths = all;
            s.set_settings(set);
            if rep == 0 {
                // The light's own stages once, before the view stage is timed alone.
                s.solve();
                set.ablate.light_paths = true;
                s.set_settings(set);
                s.solve();
                set.ablate.light_paths = false;
                s.set_settings(set);
            }
            let cpu = process_cpu_ms();
            let solved = s.solve();
            let ms = (solved.timings.single_scattering_ms, process_cpu_ms() - cpu);
            if all {
                traced.push(ms);
                want.get_or_insert_with(|| drawn(solved));
            } else {
                fast.push(ms);
                got.get_or_insert_with(|| drawn(solved));
            }
        }
        let (got, want) = (got.unwrap_or_default(), want.unwrap_or_default());
        let drawn_err = spread(got.iter().zip(&want).map(|(g, w)| (g.0, w.0)));
        let single_err =
            spread(got.iter().zip(&want).filter(|(_, w)| w.1 > 1e-3 * w.0).map(|(g, w)| (g.1, w.1)));
        rows.push(Row {
            bench: "light-paths",
            mesh: name.to_string(),
            triangles: s.mesh().triangles.len(),
            material,
            light,
            reps: REPS,
            view_ms: median(fast.iter().map(|t| t.0).collect()),
            view_ms_traced: median(traced.iter().map(|t| t.0).collect()),
            view_cpu_ms: median(fast.iter().map(|t| t.1).collect()),
            view_cpu_ms_traced: median(traced.iter().map(|t| t.1).collect()),
            drawn_err,
            single_err,
        });
    }
    s.set_settings(settings);
    s.set_lights(lights);
    s.set_view_terms(ViewTerms::Split);
    s.solve();
    Ok(rows)
}

/// Per vertex: `(drawn, single)` channel sums.
fn drawn(x: &Solved) -> Vec<(f64, f64)> {
    let sum = |v: Rgb| (v.x + v.y + v.z) as f64;
    let single = |i: usize| x.vertex_single.get(i).copied().unwrap_or(Rgb::ZERO);
    x.vertex_radiance.iter().enumerate().map(|(i, r)| (sum(*r + single(i)), sum(single(i)))).collect()
}

/// Median, 99th percentile and largest of `|a - b| / b` over the pairs `(a, b)` with `b > 0`.
fn spread(pairs: impl Iterator<Item = (f64, f64)>) -> [f64; 3] {
    let mut e: Vec<f64> = pairs.filter(|(_, b)| *b > 1e-12).map(|(a, b)| (a - b).abs() / b).collect();
    if e.is_empty() {
        return [0.0; 3];
    }
    e.sort_by(f64::total_cmp);
    let at = |q: f64| e[((e.len() - 1) as f64 * q).round() as usize];
    [at(0.5), at(0.99), e[e.len() - 1]]
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// One row as a table line or JSON.
pub(super) fn print(r: &Row, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string(r)?);
        return Ok(());
    }
    println!(
        "{:<12} {:>7} {:<9} light-paths {:<5} view {:>8.1} ms (traced {:>8.1}), CPU {:>8.1} ms (traced {:>8.1}) drawn {:.3}% / {:.3}% / {:.3}% single {:.3}% / {:.3}% / {:.3}%",
        r.mesh,
        r.triangles,
        r.material,
        r.light,
        r.view_ms,
        r.view_ms_traced,
        r.view_cpu_ms,
        r.view_cpu_ms_traced,
        100.0 * r.drawn_err[0],
        100.0 * r.drawn_err[1],
        100.0 * r.drawn_err[2],
        100.0 * r.single_err[0],
        100.0 * r.single_err[1],
        100.0 * r.single_err[2]
    );
    Ok(())
}
