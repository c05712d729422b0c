//! How far light crossing a slab spreads sideways: the radial profile of the transmittance of
//! a slab lit by a thin beam, in the multipole diffusion approximation of Donner & Jensen 2005
//! (§3, "Multipole model": the dipole mirrored about both faces of the slab), normalised to
//! integrate to 1. What `solver::transmission` averages the far side's irradiance with; the
//! slab's total transmittance is [`super::slab`]'s exact one, so only the shape is taken from
//! diffusion.
//!
//! For a slab `d` reduced mean free paths thick (lengths here in mean free paths, `σ_t' = 1`),
//! a beam enters at the origin; the real source sits at `z_r = 1` below the lit face and the
//! virtual one `2 z_b` above it (`z_b = 2 A / 3`, the extrapolation distance). Mirroring the
//! pair about the far face's extrapolated boundary `d + z_b` again and again gives sources at
//! `z_{r,i} = 2 i (d + 2 z_b) + z_r` and `z_{v,i} = 2 i (d + 2 z_b) - z_r - 2 z_b`,
//! `i = -n..=n`, and the flux out of the far face at distance `r` from the point under the beam,
//!
//! ```text
//! T(r) ∝ Σ_i (d - z_{r,i}) (1 + σ_tr d_{r,i}) e^{-σ_tr d_{r,i}} / d_{r,i}³
//!          - (d - z_{v,i}) (1 + σ_tr d_{v,i}) e^{-σ_tr d_{v,i}} / d_{v,i}³,
//! d_{·,i} = sqrt(r² + (d - z_{·,i})²),   σ_tr = sqrt(3 (1 - α')).
//! ```
//!
//! Its width is about the thickness where the slab is thin against the diffusion length
//! `1 / σ_tr`, and about `sqrt(d / σ_tr)` (diffusion over the depth) where it is thick. Below one mean free path the
//! real source is put at mid-depth (diffusion has no answer there; the spread is then a fraction
//! of a mean free path, below any mesh's faces), and negative values (the first images of a
//! very thin slab) are taken as 0.

use super::tables::{TableCache, cached_table};
use std::sync::{Arc, OnceLock};

/// Image pairs each side of the real one (`i = -n..=n`); past 6 the sum changes by < 1e-6.
const IMAGES: i32 = 6;
/// Radii of a row (mean free paths): 0 and log-spaced from [`RHO_MIN`] to [`RHO_MAX`].
const RADII: usize = 96;
const RHO_MIN: f64 = 0.01;
const RHO_MAX: f64 = 4000.0;
/// Thicknesses of a table (mean free paths), log-spaced from [`TAU_MIN`] to [`TAU_MAX`]; beyond
/// them the nearest row.
const THICKNESSES: usize = 40;
const TAU_MIN: f64 = 0.02;
const TAU_MAX: f64 = 1000.0;

/// The fractions of the transmitted light within which [`SpreadTable::quantiles`] gives radii.
pub const QUANTILES: [f64; 7] =
    [1.0 / 16.0, 2.5 / 16.0, 4.0 / 16.0, 6.5 / 16.0, 9.0 / 16.0, 12.5 / 16.0, 0.5];

/// The multipole transmittance profile at distance `rho` (mean free paths) through a slab `d`
/// thick, albedo `alpha` (0..1), extrapolation distance `zb` (mean free paths); up to a factor.
pub fn transmitted_profile(rho: f64, d: f64, alpha: f64, zb: f64) -> f64 {
    let s_tr = (3.0 * (1.0 - alpha.clamp(0.0, 1.0))).sqrt();
    let zr = 1.0f64.min(0.5 * d);
    let term = |z: f64| {
        let dz = d - z;
        let dist = (rho * rho + dz * dz).sqrt().max(1e-9);
        dz * (1.0 + s_tr * dist) * (-s_tr * dist).exp() / (dist * dist * dist)
    };
    let period = 2.0 * (d + 2.0 * zb);
    let sum: f64 = (-IMAGES..=IMAGES)
        .map(|i| term(i as f64 * period + zr) - term(i as f64 * period - zr - 2.0 * zb))
        .sum();
    sum.max(0.0)
}

/// One albedo's spread over thickness: per thickness the cumulative share of the transmitted
/// light within each radius, and the radii of [`QUANTILES`].
#[derive(Debug)]
pub struct SpreadTable {
    /// `ln τ` of the rows.
    ln_tau: Vec<f64>,
    /// Per row, the share within each radius of [`radius`] (0..=1, non-decreasing, last 1).
    cdf: Vec<[f64; RADII]>,
    /// Per row, `ln ρ` of each of [`QUANTILES`].
    quantiles: Vec<[f64; QUANTILES.len()]>,
}

/// Radius `j` of a row (mean free paths).
fn radius(j: usize) -> f64 {
    if j == 0 { 0.0 } else { RHO_MIN * (RHO_MAX / RHO_MIN).powf((j - 1) as f64 / (RADII - 2) as f64) }
}

impl SpreadTable {
    /// The table for albedo `alpha` (0..=1) and extrapolation distance `zb` (mean free paths;
    /// a function of the index `eta`, the cache's key), made once per process per pair.
    pub fn cached(alpha: f64, eta: f64, zb: f64) -> Arc<Self> {
        static CACHE: TableCache<SpreadTable> = OnceLock::new();
        cached_table(&CACHE, alpha, eta, || Self::new(alpha, zb))
    }

    fn new(alpha: f64, zb: f64) -> Self {
        let (mut ln_tau, mut cdf, mut quantiles) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..THICKNESSES {
            let tau = TAU_MIN * (TAU_MAX / TAU_MIN).powf(k as f64 / (THICKNESSES - 1) as f64);
            // ∫ T 2πr dr by the trapezoid rule in r² (exact for a flat profile near 0).
            let t: Vec<f64> = (0..RADII).map(|j| transmitted_profile(radius(j), tau, alpha, zb)).collect();
            let mut row = [0.0; RADII];
            for j in 1..RADII {
                let (a, b) = (radius(j - 1), radius(j));
                row[j] = row[j - 1] + 0.5 * (t[j - 1] + t[j]) * (b * b - a * a);
            }
            let total = row[RADII - 1];
            if total > 0.0 {
                row.iter_mut().for_each(|v| *v /= total);
            } else {
                row.iter_mut().skip(1).for_each(|v| *v = 1.0);
            }
            let q = QUANTILES.map(|p| {
                let j = row.partition_point(|&v| v < p).clamp(1, RADII - 1);
                let (c0, c1) = (row[j - 1], row[j]);
                let f = if c1 > c0 { (p - c0) / (c1 - c0) } else { 0.0 };
                let (r0, r1) = (radius(j - 1).max(RHO_MIN * 0.1), radius(j));
                (r0.ln() + (r1.ln() - r0.ln()) * f).max((RHO_MIN * 0.1).ln())
            });
            ln_tau.push(tau.ln());
            cdf.push(row);
            quantiles.push(q);
        }
        SpreadTable { ln_tau, cdf, quantiles }
    }

    /// The rows around optical thickness `tau` and the weight of the second (linear in `ln τ`).
    fn rows(&self, tau: f64) -> (usize, f64) {
        let x = (tau.max(TAU_MIN).ln() - self.ln_tau[0]) / (self.ln_tau[1] - self.ln_tau[0]);
        let x = x.clamp(0.0, (THICKNESSES - 1) as f64);
        let k = (x as usize).min(THICKNESSES - 2);
        (k, x - k as f64)
    }

    /// The radii (mean free paths) within which [`QUANTILES`] of the light a slab `tau` mean
    /// free paths thick transmits leaves the far face.
    pub fn quantiles(&self, tau: f64) -> [f64; QUANTILES.len()] {
        let (k, f) = self.rows(tau);
        std::array::from_fn(|q| (self.quantiles[k][q] * (1.0 - f) + self.quantiles[k + 1][q] * f).exp())
    }

    /// The share (0..=1) of the light a slab `tau` mean free paths thick transmits that leaves
    /// the far face within `rho` mean free paths of the point under the beam.
    pub fn within(&self, tau: f64, rho: f64) -> f64 {
        if rho <= 0.0 {
            return 0.0;
        }
        let (k, f) = self.rows(tau);
        let at = |row: &[f64; RADII]| {
            if rho <= radius(1) {
                return row[1] * (rho / radius(1)).powi(2);
            }
            if rho >= RHO_MAX {
                return 1.0;
            }
            let x = 1.0 + (rho / RHO_MIN).ln() / (RHO_MAX / RHO_MIN).ln() * (RADII - 2) as f64;
            let j = (x as usize).min(RADII - 2);
            let g = x - j as f64;
            row[j] + (row[j + 1] - row[j]) * g
        };
        at(&self.cdf[k]) * (1.0 - f) + at(&self.cdf[k + 1]) * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slab's spread: about the thickness where it is thin against the diffusion length,
    /// about the diffusion length where it is thick; every row's share reaches 1.
    #[test]
    fn the_spread_grows_with_thickness_up_to_the_diffusion_length() {
        let zb = 2.0 / 3.0;
        let t = SpreadTable::new(0.999, zb);
        let median = |tau: f64| t.quantiles(tau)[6];
        // Thin: within a few thicknesses.
        assert!(median(2.0) > 0.5 && median(2.0) < 4.0, "{}", median(2.0));
        // Growing with thickness; through a slab many diffusion lengths thick (1/σ_tr = 18 mfp)
        // as diffusion over the depth, about sqrt(d / σ_tr) (135 mfp at 1000).
        assert!(median(10.0) > median(2.0) && median(100.0) > median(10.0));
        assert!(median(1000.0) > 70.0 && median(1000.0) < 270.0, "{}", median(1000.0));
        for tau in [0.05, 1.0, 30.0, 500.0] {
            assert!((t.within(tau, RHO_MAX) - 1.0).abs() < 1e-12);
            let q = t.quantiles(tau);
            assert!((t.within(tau, q[6]) - 0.5).abs() < 0.02, "tau {tau}: {}", t.within(tau, q[6]));
        }
    }

    /// Against a direct integral of the profile: the share within the median radius.
    #[test]
    fn the_table_matches_a_fine_integral() {
        let (alpha, zb, tau) = (0.99, 2.0 / 3.0, 8.0);
        let t = SpreadTable::new(alpha, zb);
        let integral = |r_max: f64| {
            let n = 200_000;
            (0..n)
                .map(|i| {
                    let r = (i as f64 + 0.5) / n as f64 * r_max;
                    transmitted_profile(r, tau, alpha, zb) * r * r_max / n as f64
                })
                .sum::<f64>()
        };
        let share = integral(5.0) / integral(RHO_MAX.min(400.0));
        assert!((t.within(tau, 5.0) - share).abs() < 0.01, "{} vs {share}", t.within(tau, 5.0));
    }
}
