//! The form factor's smooth-integrand short cut: where `R_d` varies slowly over the emitter
//! polygon (all six dipole sources far from it compared to its size, and the polygon small
//! against the diffusion length `1/σ_tr`), Radon's seven-point rule on its fan triangles.
//!
//! Not in Mertens et al. 2003, and needed: the edge integrals of §4 cancel to the small
//! area term when the sources' foot points lie far outside a small polygon, so their
//! quadrature error is amplified by about `(distance / size)²`. With the default segment
//! ratio the semi-analytic result then errs by up to 4% (measured against the same integral
//! with 25× finer segments), while the rule errs by less than 1e-4 (test
//! `smooth_far_triangle_matches_converged_form_factor`). It is also 20 to 50 times cheaper.

use crate::bssrdf::Profile;
use glam::DVec3;

/// Radon's rule (exact for polynomials of degree 5): per orbit, the barycentric coordinates
/// `(1 - 2a, a, a)` as `a` and the weight of each of its points (weights sum to 1).
/// `a = (6 ∓ √15) / 21`, `w = (155 ∓ √15) / 1200`; the centroid has weight 9/40.
pub const RADON7_CENTROID_WEIGHT: f64 = 0.225;
pub const RADON7_ORBITS: [(f64, f64); 2] = [
    (0.101_286_507_323_456_34, 0.125_939_180_544_827_15),
    (0.470_142_064_105_115_1, 0.132_394_152_788_506_2),
];

/// Largest `k ρ` at which the rule replaces the edge integrals, with `ρ` the polygon's
/// radius about its vertex average and `k = σ_tr + 3/s` for the nearest source at distance
/// `s` from that centre (`R_d`'s relative rate of change there). Below it the rule errs by
/// under 1e-4 relative; at 1.5 by ~1e-3, at 2 by ~6e-3.
pub const MAX_K_RHO: f64 = 1.5;

/// Radon's seven points on triangle `(a, b, c)` with their weights (summing to 1).
pub fn radon7(a: DVec3, b: DVec3, c: DVec3) -> [(DVec3, f64); 7] {
    let mut out = [((a + b + c) / 3.0, RADON7_CENTROID_WEIGHT); 7];
    for (o, &(t, w)) in RADON7_ORBITS.iter().enumerate() {
        for (k, (u, v, x)) in [(a, b, c), (b, c, a), (c, a, b)].into_iter().enumerate() {
            out[1 + 3 * o + k] = ((1.0 - 2.0 * t) * u + t * (v + x), w);
        }
    }
    out
}

/// `k ρ` of a polygon with centre `centre` and radius `radius` for the dipole at `x_o`
/// (normal `n_o`): the largest over channels of `(σ_tr + 3/s) ρ`, `s` the distance from the
/// centre to where the profile peaks ([`Profile::peak_distance`]).
pub fn k_rho(profile: &Profile, x_o: DVec3, n_o: DVec3, centre: DVec3, radius: f64) -> f64 {
    let s = profile.peak_distance(x_o, n_o, centre);
    (0..3).map(|c| (profile.sigma_tr[c] + 3.0 / s[c]) * radius).fold(0.0, f64::max)
}

/// `∫_P R_d` over polygon `polygon` (planar, any winding, convex or not) by the rule on the
/// fan triangles from its first vertex, each weighted by its area signed along `normal` (the
/// polygon's unit normal), so concave polygons come out right.
pub fn polygon_integral(
    polygon: &[DVec3],
    normal: DVec3,
    x_o: DVec3,
    n_o: DVec3,
    profile: &Profile,
) -> [f64; 3] {
    let p0 = polygon[0];
    let mut sum = [0.0f64; 3];
    for i in 1..polygon.len() - 1 {
        let (p1, p2) = (polygon[i], polygon[i + 1]);
        let area = 0.5 * (p1 - p0).cross(p2 - p0).dot(normal);
        for (p, w) in radon7(p0, p1, p2) {
            let rd = profile.rd(x_o, n_o, p);
            for c in 0..3 {
                sum[c] += w * area * rd[c];
            }
        }
    }
    sum.map(|v| v.max(0.0))
}
