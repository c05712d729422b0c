//! Multiple scattering through a sphere lit from one side, by random walk: what a curved part
//! lit from behind transmits (issue 50; the sphere's counterpart of [`super::slab`]).
//!
//! A sphere `R` mean free paths in radius (isotropic scattering, albedo `ρ`, an index-matched
//! boundary, `η = 1`) is lit by a collimated beam of irradiance 1 over the hemisphere facing
//! it. `T(θ)` is the multiple-scattering exit flux density (unscattered light and direct single
//! scattering are the view ray's, as in [`super::walk`]) at the angle `θ` from the antipode of
//! the lit pole, per unit incident irradiance. A slab of the sphere's diameter transmits several
//! times more at its far face (at `R = 5`, albedo 0.999: 0.024 at the antipode against 0.13),
//! because light that spreads sideways leaves through the sphere's sides: that is why the
//! tangent slab overshot backlit spheres by 70-105% (docs/transmission.md).
//!
//! It is walked by reciprocity (Case & Zweifel 1967, ch. 2; for `η = 1` the transport kernel is
//! symmetric under exchanging source and detector with their directions reversed): the flux
//! density leaving at a point `x` under a beam from direction `ω_L` equals `π` times the flux per
//! steradian leaving the sphere toward `ω_L` when a Lambertian source of unit power sits at `x`.
//! Photons start at `x` with cosine-weighted inward directions; every collision `n >= 2` with
//! weight `w` scores `w e^{-d} / 4`, `d` the distance to the boundary along `ω_L` (the chance to
//! leave uncollided that way, `e^{-d} / 4π` per steradian, times `π`). Every photon scores, so
//! the estimate needs no detector area, and one walk gives every `θ` at once.
//! `validation/sphere_transmission.py` walks the same quantity forward (photons from the beam,
//! scored where they leave), independently.

use super::tables::{TableCache, cached_table};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::{Arc, OnceLock};

/// Photons below this weight play Russian roulette (survivors double).
const ROULETTE: f64 = 0.05;
/// No path is followed further (reached only at albedo 1 in very large spheres).
const MAX_STEPS: usize = 1 << 20;
/// Most slices of the importance splitting ([`walk`]).
const LEVELS: i32 = 6;
/// Radii of a [`SphereTable`], log-spaced.
const TABLE_STEPS: usize = 24;
/// Smallest radius of a [`SphereTable`] (mean free paths); below it `T` is taken in proportion
/// to `R³` (the first two collisions' chance in a small sphere).
const TABLE_MIN_R: f64 = 0.25;
/// Largest radius walked (mean free paths); beyond it `T` falls as the slab's slowest mode
/// over the diameter, scaled to meet the last walked point.
pub const WALK_R: f64 = 48.0;
/// Photons per radius of a [`SphereTable`] up to 4 mean free paths, in proportion to the
/// radius beyond (up to [`TABLE_MAX_PATHS`]): standard errors of 1-2% up to 4, about 8% at 22
/// (marble's red at 2 cm), before the smoothing of [`SphereTable::new`].
const TABLE_PATHS: usize = 4_096;
/// Most photons per radius of a [`SphereTable`].
const TABLE_MAX_PATHS: usize = 16_384;

/// `T(θ)` of a sphere of `radius` mean free paths and albedo `rho` (0..=1) at each angle of
/// `thetas` (radians from the antipode of the lit pole, 0..π/2), per unit incident irradiance,
/// from `paths` photons seeded by `seed` (the same arguments give the same values anywhere),
/// and the standard error of each.
pub fn transmitted(radius: f64, rho: f64, thetas: &[f64], paths: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    // The point x is the pole (0, 0, R); the light lies toward -z rotated by θ about y.
    let toward: Vec<DVec3> = thetas.iter().map(|&t| DVec3::new(-t.sin(), 0.0, -t.cos())).collect();
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let (mut sum, mut sq) = (vec![0.0; thetas.len()], vec![0.0; thetas.len()]);
    let mut score = vec![0.0; thetas.len()];
    for k in 0..paths {
        // Lambertian inward direction (stratified cosine).
        let mu = ((k as f64 + rng.random::<f64>()) / paths as f64).sqrt();
        let phi = 2.0 * PI * rng.random::<f64>();
        let s = (1.0 - mu * mu).max(0.0).sqrt();
        let dir = DVec3::new(s * phi.cos(), s * phi.sin(), -mu);
        score.iter_mut().for_each(|v| *v = 0.0);
        walk(radius, rho, dir, &toward, &mut score, &mut rng);
        for i in 0..thetas.len() {
            sum[i] += score[i];
            sq[i] += score[i] * score[i];
        }
    }
    let n = paths as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / n).collect();
    let se = sq.iter().zip(&mean).map(|(q, m)| ((q / n - m * m).max(0.0) / n).sqrt()).collect();
    (mean, se)
}

/// Distance from `pos` (inside or on a sphere of `radius` about the origin) to its boundary
/// along the unit `dir`.
fn to_boundary(pos: DVec3, dir: DVec3, radius: f64) -> f64 {
    let b = pos.dot(dir);
    -b + (b * b - (pos.dot(pos) - radius * radius)).max(0.0).sqrt()
}

/// One photon from the pole along `dir`: adds each collision's score toward each of `toward`.
///
/// Few photons from the antipode reach the lit side, where they score; so the sphere is cut
/// into at most [`LEVELS`] slices across the first direction of `toward`, each at least three
/// mean free paths thick, and a photon entering a slice nearer the light is split in two per
/// slice crossed (each half the weight), one moving away plays roulette (survives with half
/// the chance per slice, twice the weight): splitting by importance, which leaves the expected
/// score unchanged.
fn walk(radius: f64, rho: f64, dir: DVec3, toward: &[DVec3], score: &mut [f64], rng: &mut Pcg64Mcg) {
    let axis = toward[0];
    let levels = ((2.0 * radius / 3.0) as i32).clamp(1, LEVELS);
    let level_of =
        |p: DVec3| (((p.dot(axis) + radius) / (2.0 * radius) * levels as f64) as i32).clamp(0, levels - 1);
    // Photons to follow: position, direction, weight, scatterings, slice.
    let start = DVec3::new(0.0, 0.0, radius);
    let mut stack = vec![(start, dir, 1.0, 0u32, level_of(start))];
    while let Some((mut pos, mut dir, mut weight, mut n, mut level)) = stack.pop() {
        for _ in 0..MAX_STEPS {
            let step = -(1.0 - rng.random::<f64>()).ln();
            if step >= to_boundary(pos, dir, radius) {
                break;
            }
            pos += dir * step;
            weight *= rho;
            n += 1;
            if n >= 2 {
                for (s, u) in score.iter_mut().zip(toward) {
                    *s += weight * (-to_boundary(pos, *u, radius)).exp() / 4.0;
                }
            }
            let z = 1.0 - 2.0 * rng.random::<f64>();
            let a = 2.0 * PI * rng.random::<f64>();
            let r = (1.0 - z * z).max(0.0).sqrt();
            dir = DVec3::new(r * a.cos(), r * a.sin(), z);
            let now = level_of(pos);
            if now > level {
                let copies = 1u32 << (now - level);
                weight /= copies as f64;
                for _ in 1..copies {
                    let z = 1.0 - 2.0 * rng.random::<f64>();
                    let a = 2.0 * PI * rng.random::<f64>();
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    stack.push((pos, DVec3::new(r * a.cos(), r * a.sin(), z), weight, n, now));
                }
            } else if now < level {
                let keep = 1.0 / (1u32 << (level - now)) as f64;
                if rng.random::<f64>() >= keep {
                    break;
                }
                weight /= keep;
            }
            level = now;
            // Roulette against the slice's own weight (splitting halves it by design).
            if weight * ((1u32 << level) as f64) < ROULETTE {
                if rng.random::<f64>() < 0.5 {
                    break;
                }
                weight *= 2.0;
            }
        }
    }
}

/// Cosines of the exit angle `θ` from the antipode at which a [`SphereTable`] holds `T(θ)`:
/// head-on to near the terminator, where `T` rises fastest.
pub const EXIT_COS: [f64; 8] = [1.0, 0.9, 0.75, 0.6, 0.45, 0.3, 0.15, 0.05];

/// A sphere's multiple-scattering transmittance `T(θ)` over radius for one albedo (`η = 1`),
/// at the exit angles [`EXIT_COS`]: what [`crate::solver::sphere_term`] reads for curved parts.
#[derive(Debug)]
pub struct SphereTable {
    /// Radii (mean free paths), log-spaced from [`TABLE_MIN_R`] to [`WALK_R`].
    radius: Vec<f64>,
    /// `T(θ)` at each radius and each of [`EXIT_COS`] (unitless, per unit incident irradiance).
    at: Vec<[f64; EXIT_COS.len()]>,
    /// The slab's slowest mode's decay rate per mean free path ([`super::slab::asymptotic_decay`]).
    kappa: f64,
}

impl SphereTable {
    /// The table for albedo `rho` (0..=1), made once per process for each (a few hundred
    /// milliseconds on two cores for albedos near 1).
    pub fn cached(rho: f64) -> Arc<Self> {
        static CACHE: TableCache<SphereTable> = OnceLock::new();
        cached_table(&CACHE, rho, 1.0, || Self::new(rho))
    }

    fn new(rho: f64) -> Self {
        let rho = rho.clamp(0.0, 1.0);
        let radius: Vec<f64> = (0..TABLE_STEPS)
            .map(|k| TABLE_MIN_R * (WALK_R / TABLE_MIN_R).powf(k as f64 / (TABLE_STEPS - 1) as f64))
            .collect();
        let thetas = EXIT_COS.map(f64::acos);
        let walked: Vec<Vec<f64>> = radius
            .par_iter()
            .enumerate()
            .map(|(k, &r)| {
                let paths = ((TABLE_PATHS as f64 * (r / 4.0).max(1.0)) as usize).min(TABLE_MAX_PATHS);
                transmitted(r, rho, &thetas, paths, 0x5eed + k as u64).0
            })
            .collect();
        // Beyond 4 mean free paths each radius's noise is independent of its neighbours':
        // the mean of three neighbours in ln T (the table's steps are 26% in R, over which
        // ln T bends by a few thousandths) takes it down by √3.
        let smooth = |k: usize, j: usize| {
            let near = |i: usize| walked[i][j];
            if radius[k] <= 4.0 || k == 0 || k + 1 == walked.len() || (k - 1..=k + 1).any(|i| near(i) <= 0.0)
            {
                return near(k);
            }
            ((near(k - 1).ln() + near(k).ln() + near(k + 1).ln()) / 3.0).exp()
        };
        let at = (0..walked.len()).map(|k| std::array::from_fn(|j| smooth(k, j))).collect();
        SphereTable { radius, at, kappa: super::slab::asymptotic_decay(rho) }
    }

    /// `T(0)` of a sphere `radius` mean free paths in radius (see [`SphereTable::at_cos`]).
    pub fn at(&self, radius: f64) -> f64 {
        self.at_cos(radius, 1.0)
    }

    /// `T(θ)` of a sphere `radius` mean free paths in radius at `cos θ = mu`: linear in `ln R`
    /// between the table's radii, as `R³` below them, and beyond them falling as the slab's
    /// slowest mode over the diameter (module docs); linear in `mu` between [`EXIT_COS`],
    /// clamped to their range.
    pub fn at_cos(&self, radius: f64, mu: f64) -> f64 {
        let n = self.radius.len();
        if radius.is_nan() || radius <= 0.0 {
            return 0.0;
        }
        let column = |k: usize| cos_interpolate(&self.at[k], mu);
        if radius <= self.radius[0] {
            return column(0) * (radius / self.radius[0]).powi(3);
        }
        if radius >= self.radius[n - 1] {
            let mode = |r: f64| (-self.kappa * 2.0 * r).exp();
            return column(n - 1) * mode(radius) / mode(self.radius[n - 1]);
        }
        let k = self.radius.partition_point(|&v| v <= radius) - 1;
        let f = (radius / self.radius[k]).ln() / (self.radius[k + 1] / self.radius[k]).ln();
        column(k) + (column(k + 1) - column(k)) * f
    }
}

/// `values` (one per [`EXIT_COS`]) at cosine `mu`, linear between them, clamped to their range.
pub fn cos_interpolate<T>(values: &[T; EXIT_COS.len()], mu: f64) -> T
where
    T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>,
{
    let mu = if mu.is_nan() { 1.0 } else { mu.clamp(EXIT_COS[EXIT_COS.len() - 1], 1.0) };
    // EXIT_COS falls: the first node at or below mu.
    let j = EXIT_COS.iter().position(|&c| c <= mu).unwrap_or(EXIT_COS.len() - 1).max(1);
    let (hi, lo) = (EXIT_COS[j - 1], EXIT_COS[j]);
    let f = ((mu - lo) / (hi - lo)).clamp(0.0, 1.0);
    values[j] * (1.0 - f) + values[j - 1] * f
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The area-weighted mean of `T(θ)` over the band `lo..hi` degrees from the antipode
    /// (8-point Gauss-Legendre in `θ` with weight `sin θ`), and its standard error (the
    /// nodes share photons, so their errors are summed as if fully correlated).
    fn band(radius: f64, rho: f64, lo: f64, hi: f64, paths: usize) -> (f64, f64) {
        let nodes = crate::bssrdf::halfspace::gauss_legendre(8, lo.to_radians(), hi.to_radians());
        let thetas: Vec<f64> = nodes.iter().map(|n| n.0).collect();
        let (t, se) = transmitted(radius, rho, &thetas, paths, 11);
        let norm: f64 = nodes.iter().map(|(th, w)| w * th.sin()).sum();
        let mean = nodes.iter().zip(&t).map(|((th, w), t)| w * th.sin() * t).sum::<f64>() / norm;
        let err = nodes.iter().zip(&se).map(|((th, w), s)| w * th.sin() * s).sum::<f64>() / norm;
        (mean, err)
    }

    /// The reciprocal walk against the forward one of `validation/sphere_transmission.py
    /// --radius R --albedo A --photons 1000000 --seed S --edges 0 20 45 70 90` (S = 3 for R = 2
    /// and 5, 4 for R = 12), two bands each, within three combined standard errors.
    #[test]
    fn the_reciprocal_walk_meets_the_forward_walk() {
        let cases = [
            (2.0, 0.999, 0.0, 20.0, 0.06210, 0.00071),
            (2.0, 0.9, 45.0, 70.0, 0.05729, 0.00022),
            (5.0, 0.999, 0.0, 20.0, 0.02781, 0.00047),
            (5.0, 0.999, 45.0, 70.0, 0.05288, 0.00026),
            (5.0, 0.9, 0.0, 20.0, 0.00516, 0.00012),
            (12.0, 0.999, 0.0, 20.0, 0.00940, 0.00026),
            (12.0, 0.999, 70.0, 90.0, 0.04925, 0.00026),
        ];
        for (r, rho, lo, hi, want, want_se) in cases {
            let (got, se) = band(r, rho, lo, hi, 20_000);
            let tol = 3.0 * (se * se + want_se * want_se).sqrt();
            assert!(
                (got - want).abs() < tol,
                "R {r} rho {rho} {lo}-{hi}: {got} +- {se} vs {want} +- {want_se}"
            );
        }
    }

    /// The table (smoothed, fewer photons) against a longer independent walk of the same
    /// estimator at radii between its own, within 3 standard errors plus the smoothing's bias.
    #[test]
    fn the_table_meets_a_long_walk() {
        for (rho, r) in [(0.999, 1.3), (0.999, 7.7), (0.99, 3.1), (0.9995, 20.0)] {
            let table = SphereTable::cached(rho);
            let (t, se) = transmitted(r, rho, &[0.0], 40_000, 99);
            let got = table.at(r);
            assert!(
                (got - t[0]).abs() < 3.0 * se[0] * 2.0 + 0.02 * t[0],
                "rho {rho} R {r}: {got} vs {} +- {}",
                t[0],
                se[0]
            );
        }
    }

    /// A sphere transmits far less at its antipode than a slab of its diameter: light that
    /// spreads sideways leaves through its sides (the tangent slab's overshoot).
    #[test]
    fn a_sphere_transmits_less_than_the_slab_of_its_diameter() {
        for (r, rho) in [(2.0, 0.999), (5.0, 0.999), (5.0, 0.95)] {
            let sphere = transmitted(r, rho, &[0.0], 20_000, 5).0[0];
            let slab = crate::bssrdf::slab::multiple_return_exact(2.0 * r, rho, 1.0).transmitted;
            assert!(sphere < 0.6 * slab, "R {r} rho {rho}: sphere {sphere}, slab {slab}");
        }
    }
}
