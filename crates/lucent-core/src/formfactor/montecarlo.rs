//! Reference integrators for the form factor `F(A, x_o) = ∫_A R_d(x_i, x_o) dx_i` (Mertens et
//! al. 2003, eq. 7, with the dipole at the receiver as in §4), to check the semi-analytic
//! [`form_factor`](super::form_factor) against:
//!
//! * [`monte_carlo`]: stratified area sampling with a seeded PCG generator, in independent
//!   replicates so that the standard error is honest (the Monte Carlo curves of Mertens fig. 3).
//! * [`sample_estimate`]: plain uniform area sampling with `n` samples (e.g. the 12 samples of
//!   Jensen & Buhler 2002 that Mertens fig. 3 shows to be inaccurate).
//! * [`adaptive_cubature`]: deterministic, adaptive degree-5 triangle cubature, converging fast
//!   even where `R_d` is sharply peaked.
//!
//! Polygons are split into a fan from vertex 0 whose triangles are weighted by their *signed*
//! area along the polygon's normal, which is exact for any simple planar polygon.

use crate::bssrdf::Profile;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Number of independent stratified replicates behind [`monte_carlo`]'s standard error.
const REPLICATES: usize = 16;

/// A Monte Carlo estimate of the form factor, per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonteCarloEstimate {
    /// Estimated `F(A, x_o)` (unitless).
    pub mean: [f64; 3],
    /// Standard error of `mean` (one standard deviation of the estimator, unitless).
    pub std_error: [f64; 3],
    /// Number of `R_d` evaluations actually made (≥ the number asked for, after rounding the
    /// strata up).
    pub samples: usize,
}

/// Fan triangles of a planar polygon with their signed areas (mesh units²), relative to the
/// polygon's own normal, so that the signed areas add up to the polygon's area.
fn fan(polygon: &[DVec3]) -> Vec<([DVec3; 3], f64)> {
    let n = polygon.len();
    if n < 3 {
        return Vec::new();
    }
    let p0 = polygon[0];
    let mut area_vec = DVec3::ZERO;
    for i in 1..n - 1 {
        area_vec += (polygon[i] - p0).cross(polygon[i + 1] - p0);
    }
    let normal = area_vec.normalize_or_zero();
    if normal == DVec3::ZERO {
        return Vec::new();
    }
    (1..n - 1)
        .map(|i| {
            let (a, b) = (polygon[i], polygon[i + 1]);
            ([p0, a, b], 0.5 * (a - p0).cross(b - p0).dot(normal))
        })
        .filter(|(_, area)| *area != 0.0)
        .collect()
}

/// Maps the unit square to a uniformly distributed point of triangle `tri`.
#[inline]
fn square_to_triangle(tri: &[DVec3; 3], u: f64, v: f64) -> DVec3 {
    let su = u.sqrt();
    let b1 = su * (1.0 - v);
    let b2 = su * v;
    tri[0] + b1 * (tri[1] - tri[0]) + b2 * (tri[2] - tri[0])
}

#[inline]
fn add(acc: &mut [f64; 3], v: [f64; 3], w: f64) {
    for c in 0..3 {
        acc[c] += w * v[c];
    }
}

/// Stratified Monte Carlo estimate of `F(A, x_o)` with about `samples` evaluations of `R_d`
/// (at least `REPLICATES` × 1 per fan triangle), seeded by `seed` (same seed, same result).
///
/// The samples are split into 16 independent replicates; each replicate jitters one sample per
/// cell of a `m × m` grid over every fan triangle (`m²` in proportion to the triangle's area).
/// The standard error is that of the mean of the replicate estimates.
pub fn monte_carlo(
    polygon: &[DVec3],
    x_o: DVec3,
    n_o: DVec3,
    profile: &Profile,
    samples: usize,
    seed: u64,
) -> MonteCarloEstimate {
    let tris = fan(polygon);
    let total_area: f64 = tris.iter().map(|(_, a)| a.abs()).sum();
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let per_replicate = (samples / REPLICATES).max(1) as f64;
    let mut estimates = [[0.0; 3]; REPLICATES];
    let mut used = 0;
    if total_area > 0.0 {
        for est in estimates.iter_mut() {
            for (tri, area) in &tris {
                let m = ((per_replicate * area.abs() / total_area).sqrt().round() as usize).max(1);
                let inv = 1.0 / m as f64;
                let w = area / (m * m) as f64;
                for i in 0..m {
                    for j in 0..m {
                        let u = (i as f64 + rng.random::<f64>()) * inv;
                        let v = (j as f64 + rng.random::<f64>()) * inv;
                        let x = square_to_triangle(tri, u, v);
                        add(est, profile.rd(x_o, n_o, x), w);
                    }
                }
                used += m * m;
            }
        }
    }
    let r = REPLICATES as f64;
    let mean: [f64; 3] = std::array::from_fn(|c| estimates.iter().map(|e| e[c]).sum::<f64>() / r);
    let std_error = std::array::from_fn(|c| {
        let var = estimates.iter().map(|e| (e[c] - mean[c]).powi(2)).sum::<f64>() / (r - 1.0);
        (var / r).sqrt()
    });
    MonteCarloEstimate { mean, std_error, samples: used }
}

/// Plain (unstratified) uniform area sampling with exactly `n` samples (≥ 1), seeded by `seed`:
/// the estimator a point-sample method with `n` samples per element would use.
pub fn sample_estimate(
    polygon: &[DVec3],
    x_o: DVec3,
    n_o: DVec3,
    profile: &Profile,
    n: usize,
    seed: u64,
) -> [f64; 3] {
    let tris = fan(polygon);
    let total_area: f64 = tris.iter().map(|(_, a)| a.abs()).sum();
    let mut acc = [0.0; 3];
    if total_area <= 0.0 || n == 0 {
        return acc;
    }
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    for _ in 0..n {
        // Pick a fan triangle in proportion to |area|, weight by its sign.
        let mut pick = rng.random::<f64>() * total_area;
        let mut chosen = &tris[tris.len() - 1];
        for t in &tris {
            if pick < t.1.abs() {
                chosen = t;
                break;
            }
            pick -= t.1.abs();
        }
        let x = square_to_triangle(&chosen.0, rng.random(), rng.random());
        add(&mut acc, profile.rd(x_o, n_o, x), chosen.1.signum());
    }
    acc.map(|v| v * total_area / n as f64)
}

/// Radon's 7-point degree-5 rule on a triangle: barycentric points and weights (sum 1).
const RADON: [([f64; 3], f64); 7] = {
    // a = (6 - √15)/21, b = (6 + √15)/21; weights (155 ∓ √15)/1200.
    const A: f64 = 0.101_286_507_323_456_34;
    const B: f64 = 0.470_142_064_105_115_1;
    const WA: f64 = 0.125_939_180_544_827_15;
    const WB: f64 = 0.132_394_152_788_506_2;
    [
        ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
        ([A, A, 1.0 - 2.0 * A], WA),
        ([A, 1.0 - 2.0 * A, A], WA),
        ([1.0 - 2.0 * A, A, A], WA),
        ([B, B, 1.0 - 2.0 * B], WB),
        ([B, 1.0 - 2.0 * B, B], WB),
        ([1.0 - 2.0 * B, B, B], WB),
    ]
};

/// Degree-5 cubature of `R_d` over one triangle of signed area `area`.
fn radon(tri: &[DVec3; 3], area: f64, x_o: DVec3, n_o: DVec3, profile: &Profile) -> [f64; 3] {
    let mut acc = [0.0; 3];
    for (b, w) in RADON {
        let x = b[0] * tri[0] + b[1] * tri[1] + b[2] * tri[2];
        add(&mut acc, profile.rd(x_o, n_o, x), w * area);
    }
    acc
}

/// Deterministic adaptive cubature of `F(A, x_o)`: every fan triangle is split 1 → 4 (edge
/// midpoints) until the degree-5 rule on a triangle agrees with the sum over its four children
/// to within its share (by area) of `rel_tol` times the integral (estimated on the way), per
/// channel, or until 18 levels deep. `rel_tol` around 1e-8 converges to ~1e-9 relative for
/// any receiver that is not (nearly) inside the polygon's plane.
pub fn adaptive_cubature(
    polygon: &[DVec3],
    x_o: DVec3,
    n_o: DVec3,
    profile: &Profile,
    rel_tol: f64,
) -> [f64; 3] {
    let tris = fan(polygon);
    let total_area: f64 = tris.iter().map(|(_, a)| a.abs()).sum();
    if total_area <= 0.0 {
        return [0.0; 3];
    }
    // A first estimate of the integral's size sets the absolute tolerance; a few levels of
    // uniform refinement make it robust to a peak that the coarse rule misses.
    let mut coarse = [0.0f64; 3];
    let mut stack: Vec<([DVec3; 3], f64, u32)> = tris.iter().map(|(t, a)| (*t, *a, 0)).collect();
    let mut level = Vec::new();
    for _ in 0..3 {
        level.clear();
        for (t, a, d) in stack.drain(..) {
            level.extend(split(&t, a, d));
        }
        std::mem::swap(&mut stack, &mut level);
    }
    for (t, a, _) in &stack {
        add(&mut coarse, radon(t, *a, x_o, n_o, profile), 1.0);
    }
    let tol: [f64; 3] = std::array::from_fn(|c| rel_tol * coarse[c].abs().max(f64::MIN_POSITIVE));
    let mut result = [0.0; 3];
    while let Some((t, a, d)) = stack.pop() {
        let parent = radon(&t, a, x_o, n_o, profile);
        let kids = split(&t, a, d);
        let mut sum = [0.0; 3];
        for (kt, ka, _) in &kids {
            add(&mut sum, radon(kt, *ka, x_o, n_o, profile), 1.0);
        }
        let share = a.abs() / total_area;
        let converged = (0..3).all(|c| (sum[c] - parent[c]).abs() <= tol[c] * share);
        if converged || d >= 18 {
            add(&mut result, sum, 1.0);
        } else {
            stack.extend(kids);
        }
    }
    result
}

/// Splits a triangle into four at its edge midpoints.
fn split(t: &[DVec3; 3], area: f64, depth: u32) -> [([DVec3; 3], f64, u32); 4] {
    let m01 = 0.5 * (t[0] + t[1]);
    let m12 = 0.5 * (t[1] + t[2]);
    let m20 = 0.5 * (t[2] + t[0]);
    let a = 0.25 * area;
    let d = depth + 1;
    [([t[0], m01, m20], a, d), ([m01, t[1], m12], a, d), ([m20, m12, t[2]], a, d), ([m01, m12, m20], a, d)]
}
