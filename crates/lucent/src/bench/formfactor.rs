//! `lucent bench formfactor`: the semi-analytic form factor (Mertens et al. 2003, §4) on the
//! set-up of the paper's figure 3, against converged Monte Carlo and a deterministic adaptive
//! cubature, with its cost, and the point-sampling alternatives for comparison.
//!
//! Figure 3: skim milk (units in mm), a triangle with a 10 mm base and 5 mm height in the
//! receiver's plane, its tip at `(d, 0)` pointing at the receiver `x_o = 0`, its base parallel
//! to the y axis at `x = d + 5`, for tip distances `d = 0, 1, ..., 10` mm.

use anyhow::Context;
use glam::DVec3;
use lucent_core::bssrdf::{Material, Profile};
use lucent_core::formfactor::montecarlo::{adaptive_cubature, monte_carlo, sample_estimate};
use lucent_core::formfactor::{FormFactorOptions, form_factor, form_factor_counted, point_sample};
use rayon::prelude::*;
use serde::Serialize;
use std::hint::black_box;
use std::time::Instant;

/// Samples of the Monte Carlo reference per distance.
const MC_SAMPLES: usize = 4_000_000;
/// Random seeds over which the 12-sample estimate's error is averaged (RMS).
const SEEDS_12: u64 = 2000;

/// One tip distance of figure 3.
#[derive(Serialize)]
struct Row {
    /// Distance of the triangle's tip from the receiver, mm.
    distance_mm: f64,
    /// Semi-analytic `F(A, x_o)` per channel (unitless).
    form_factor: [f64; 3],
    /// Stratified Monte Carlo estimate and its standard error.
    mc: [f64; 3],
    mc_stderr: [f64; 3],
    /// `|F - MC| / MC` per channel.
    rel_error: [f64; 3],
    /// Deterministic adaptive cubature (relative tolerance 1e-10) and `|F - cubature| / cubature`.
    cubature: [f64; 3],
    rel_error_vs_cubature: [f64; 3],
    /// Edge segments integrated (over the 6 dipole sources and 3 edges).
    segments: usize,
    /// One-sample (centroid) estimate and its relative error against the cubature.
    point_sample: [f64; 3],
    point_sample_rel_error: [f64; 3],
    /// RMS relative error of a 12-sample uniform estimate (Jensen & Buhler 2002), over seeds.
    samples12_rms_rel_error: [f64; 3],
}

#[derive(Serialize)]
struct Report {
    bench: &'static str,
    setup: &'static str,
    /// What `rel_error` and `max_rel_error_vs_mc` are measured against.
    reference: String,
    /// Largest `rel_error` over distances and channels.
    max_rel_error_vs_mc: f64,
    /// Largest `rel_error_vs_cubature` over distances and channels.
    max_rel_error_vs_cubature: f64,
    /// Largest 12-sample RMS relative error and one-sample relative error, for comparison.
    max_rel_error_12_samples: f64,
    max_rel_error_point_sample: f64,
    /// Median wall time of one `form_factor` call over the 11 triangles, ns.
    ns_per_form_factor: f64,
    /// Median wall time of one `point_sample` call, ns.
    ns_per_point_sample: f64,
    /// Mean edge segments per `form_factor` call.
    mean_segments: f64,
    options: Options,
    rows: Vec<Row>,
}

#[derive(Serialize)]
struct Options {
    max_segment_ratio: f64,
    max_segment_sigma: f64,
    gauss_legendre_points: u32,
}

fn triangle(d: f64) -> [DVec3; 3] {
    [DVec3::new(d, 0.0, 0.0), DVec3::new(d + 5.0, -5.0, 0.0), DVec3::new(d + 5.0, 5.0, 0.0)]
}

fn rel(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| (a[c] - b[c]).abs() / b[c].abs())
}

fn max3(rows: &[Row], f: impl Fn(&Row) -> [f64; 3]) -> f64 {
    rows.iter().flat_map(f).fold(0.0, f64::max)
}

/// Median over `rounds` of the mean time per call of `f` over all `tris`, in ns.
fn median_ns(tris: &[[DVec3; 3]], rounds: usize, mut f: impl FnMut(&[DVec3; 3]) -> [f64; 3]) -> f64 {
    // Enough repetitions per round for ~5 ms rounds.
    let start = Instant::now();
    for t in tris {
        black_box(f(black_box(t)));
    }
    let once = start.elapsed().as_secs_f64().max(1e-7);
    let reps = ((5e-3 / once).ceil() as usize).max(1);
    let mut times: Vec<f64> = (0..rounds)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..reps {
                for t in tris {
                    black_box(f(black_box(t)));
                }
            }
            start.elapsed().as_secs_f64() * 1e9 / (reps * tris.len()) as f64
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

pub fn run(json: bool) -> anyhow::Result<()> {
    let material = Material::by_name("skimmilk").context("bench formfactor: material")?;
    let profile = Profile::new(&material, 1.0);
    let opts = FormFactorOptions::default();
    let (x_o, n_o) = (DVec3::ZERO, DVec3::Z);
    let distances: Vec<f64> = (0..=10).map(f64::from).collect();

    let rows: Vec<Row> = distances
        .par_iter()
        .map(|&d| {
            let tri = triangle(d);
            let (f, segments) = form_factor_counted(&tri, x_o, n_o, &profile, &opts);
            let mc = monte_carlo(&tri, x_o, n_o, &profile, MC_SAMPLES, 1000 + d as u64);
            let cubature = adaptive_cubature(&tri, x_o, n_o, &profile, 1e-10);
            let ps = point_sample(&tri, x_o, n_o, &profile);
            let mut sq = [0.0; 3];
            for seed in 0..SEEDS_12 {
                let e = rel(sample_estimate(&tri, x_o, n_o, &profile, 12, seed), cubature);
                for c in 0..3 {
                    sq[c] += e[c] * e[c];
                }
            }
            Row {
                distance_mm: d,
                form_factor: f,
                mc: mc.mean,
                mc_stderr: mc.std_error,
                rel_error: rel(f, mc.mean),
                cubature,
                rel_error_vs_cubature: rel(f, cubature),
                segments,
                point_sample: ps,
                point_sample_rel_error: rel(ps, cubature),
                samples12_rms_rel_error: sq.map(|s| (s / SEEDS_12 as f64).sqrt()),
            }
        })
        .collect();

    let tris: Vec<[DVec3; 3]> = distances.iter().map(|&d| triangle(d)).collect();
    let ns_ff = median_ns(&tris, 21, |t| form_factor(t, x_o, n_o, &profile, &opts));
    let ns_ps = median_ns(&tris, 21, |t| point_sample(t, x_o, n_o, &profile));

    let report = Report {
        bench: "formfactor",
        setup: "Mertens 2003 fig. 3: skim milk (mm), triangle base 10 mm, height 5 mm, tip at (d,0), \
                base at x = d + 5, receiver at the origin in the triangle's plane",
        reference: format!(
            "stratified Monte Carlo, {MC_SAMPLES} samples per distance (16 replicates); \
             also deterministic adaptive degree-5 cubature (rel. tol. 1e-10)"
        ),
        max_rel_error_vs_mc: max3(&rows, |r| r.rel_error),
        max_rel_error_vs_cubature: max3(&rows, |r| r.rel_error_vs_cubature),
        max_rel_error_12_samples: max3(&rows, |r| r.samples12_rms_rel_error),
        max_rel_error_point_sample: max3(&rows, |r| r.point_sample_rel_error),
        ns_per_form_factor: ns_ff,
        ns_per_point_sample: ns_ps,
        mean_segments: rows.iter().map(|r| r.segments as f64).sum::<f64>() / rows.len() as f64,
        options: Options {
            max_segment_ratio: opts.max_segment_ratio,
            max_segment_sigma: opts.max_segment_sigma,
            gauss_legendre_points: 3,
        },
        rows,
    };

    if json {
        println!("{}", serde_json::to_string(&report).context("bench formfactor: JSON")?);
    } else {
        print_table(&report);
    }
    Ok(())
}

/// The report as a table with a summary, for a reader.
fn print_table(report: &Report) {
    println!("Form factor, Mertens 2003 fig. 3 set-up ({})", report.setup);
    println!("reference: {}", report.reference);
    println!(
        "{:>5} {:>12} {:>12} {:>12} {:>9} {:>9} {:>9} {:>5} {:>9} {:>9}",
        "d mm", "F red", "F green", "F blue", "err MC", "err cub", "MC se", "segs", "err 1pt", "err 12pt"
    );
    for r in &report.rows {
        let worst = |v: [f64; 3]| v.into_iter().fold(0.0, f64::max);
        let se = (0..3).map(|c| r.mc_stderr[c] / r.mc[c]).fold(0.0, f64::max);
        println!(
            "{:>5.1} {:>12.6e} {:>12.6e} {:>12.6e} {:>9.2e} {:>9.2e} {:>9.2e} {:>5} {:>9.2e} {:>9.2e}",
            r.distance_mm,
            r.form_factor[0],
            r.form_factor[1],
            r.form_factor[2],
            worst(r.rel_error),
            worst(r.rel_error_vs_cubature),
            se,
            r.segments,
            worst(r.point_sample_rel_error),
            worst(r.samples12_rms_rel_error),
        );
    }
    println!("(errors: worst channel, relative; MC se: relative standard error; 12pt: RMS over seeds)");
    println!("max relative error vs Monte Carlo:  {:.3e}", report.max_rel_error_vs_mc);
    println!("max relative error vs cubature:     {:.3e}", report.max_rel_error_vs_cubature);
    println!("max relative error, 12 samples:     {:.3e}", report.max_rel_error_12_samples);
    println!("max relative error, 1 point sample: {:.3e}", report.max_rel_error_point_sample);
    println!(
        "form_factor: {:.0} ns/call (median, {:.1} segments/call); point_sample: {:.1} ns/call",
        report.ns_per_form_factor, report.mean_segments, report.ns_per_point_sample
    );
}
