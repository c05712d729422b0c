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

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use std::f64::consts::PI;

/// Photons below this weight (times their slice's share) play Russian roulette (survivors
/// double).
const ROULETTE: f64 = 0.05;
/// No path is followed further (reached only at albedo 1 in very large spheres).
const MAX_STEPS: usize = 1 << 20;
/// Most slices of the importance splitting ([`walk`]).
const LEVELS: i32 = 6;
/// Largest radius walked for [`super::sphere_table`] (mean free paths); beyond it `T` falls as
/// the slab's slowest mode over the diameter, scaled to meet the last walked point.
pub const WALK_R: f64 = 48.0;
/// `T(θ)` of a sphere of `radius` mean free paths and albedo `rho` (0..=1) at each angle of
/// `thetas` (radians from the antipode of the lit pole, 0..π/2), per unit incident irradiance,
/// from `paths` photons seeded by `seed` (the same arguments give the same values anywhere),
/// and the standard error of each.
pub fn transmitted(radius: f64, rho: f64, thetas: &[f64], paths: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let m = walk_exits(radius, rho, thetas, paths, seed);
    (m.t, m.se)
}

/// What [`walk_exits`] measures at each exit angle.
#[derive(Clone, Debug, PartialEq)]
pub struct Exits {
    /// `T(θ)` per unit incident irradiance (unitless).
    pub t: Vec<f64>,
    /// Its standard error.
    pub se: Vec<f64>,
    /// The flux-weighted mean of `ω_o · t` over the light leaving there, `t` the unit tangent
    /// pointing away from the lit pole (unitless, -1..=1; 0 for a Lambertian exit, and at
    /// `θ = 0` by symmetry): how far the light that crossed the body leaves tilted on, in the
    /// direction it was flowing (`shading::transmitted_exit`).
    pub tilt: Vec<f64>,
    /// The flux-weighted mean of `ω_o · n`, the exit's cosine with the normal (unitless,
    /// 0..=1; 2/3 for a Lambertian exit, about 0.71 for light diffusing out of a deep
    /// half-space, Milne's problem).
    pub normal: Vec<f64>,
}

/// [`transmitted`] with the exit's first moment along the tangent ([`Exits::tilt`]): by
/// reciprocity a photon started along `-ω_o` scores the light leaving along `ω_o`, so the
/// scores weighted by `ω_o · t` give the moment from the same walk (the same `T` as
/// [`transmitted`] for the same arguments).
pub fn walk_exits(radius: f64, rho: f64, thetas: &[f64], paths: usize, seed: u64) -> Exits {
    // The point x is the pole (0, 0, R); the light lies toward -z rotated by θ about y, so the
    // lit pole is toward -x from x and the tangent away from it is +x.
    let toward: Vec<DVec3> = thetas.iter().map(|&t| DVec3::new(-t.sin(), 0.0, -t.cos())).collect();
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let (mut sum, mut sq) = (vec![0.0; thetas.len()], vec![0.0; thetas.len()]);
    let mut along = vec![0.0; thetas.len()];
    let mut normal = vec![0.0; thetas.len()];
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
            // The light leaves along -dir.
            along[i] += score[i] * -dir.x;
            normal[i] += score[i] * mu;
        }
    }
    let n = paths as f64;
    let t: Vec<f64> = sum.iter().map(|s| s / n).collect();
    let se = sq.iter().zip(&t).map(|(q, m)| ((q / n - m * m).max(0.0) / n).sqrt()).collect();
    let tilt = along
        .iter()
        .zip(&sum)
        .zip(thetas)
        .map(|((a, s), &th)| if *s > 0.0 && th > 0.0 { a / s } else { 0.0 })
        .collect();
    let normal = normal.iter().zip(&sum).map(|(a, s)| if *s > 0.0 { a / s } else { 2.0 / 3.0 }).collect();
    Exits { t, se, tilt, normal }
}

/// Distance from `pos` (inside or on a sphere of `radius` about the origin) to its boundary
/// along the unit `dir`.
pub(crate) fn to_boundary(pos: DVec3, dir: DVec3, radius: f64) -> f64 {
    let b = pos.dot(dir);
    -b + (b * b - (pos.dot(pos) - radius * radius)).max(0.0).sqrt()
}

/// A uniformly random unit direction.
pub(crate) fn isotropic(rng: &mut Pcg64Mcg) -> DVec3 {
    let z = 1.0 - 2.0 * rng.random::<f64>();
    let a = 2.0 * PI * rng.random::<f64>();
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * a.cos(), r * a.sin(), z)
}

/// Importance splitting across a sphere: it is cut into at most [`LEVELS`] slices across
/// `axis`, each at least three mean free paths thick, numbered up along `axis` (toward where the
/// walk scores); a photon entering a slice further up is split in two per slice crossed (each
/// half the weight), one moving down plays roulette (survives with half the chance per slice,
/// twice the weight). The expected score is unchanged.
pub(crate) struct Slices {
    axis: DVec3,
    radius: f64,
    levels: i32,
}

impl Slices {
    pub(crate) fn new(radius: f64, axis: DVec3) -> Self {
        Slices { axis, radius, levels: ((2.0 * radius / 3.0) as i32).clamp(1, LEVELS) }
    }

    /// The slice holding `p`.
    pub(crate) fn level_of(&self, p: DVec3) -> i32 {
        (((p.dot(self.axis) + self.radius) / (2.0 * self.radius) * self.levels as f64) as i32)
            .clamp(0, self.levels - 1)
    }

    /// A photon of `weight` that was in slice `level` collided at `pos`: moves it to the slice
    /// there and returns how many copies it becomes (itself included; each of `weight`, now
    /// divided among them), or `None` where roulette ended it.
    pub(crate) fn split(
        &self,
        pos: DVec3,
        level: &mut i32,
        weight: &mut f64,
        rng: &mut Pcg64Mcg,
    ) -> Option<u32> {
        let now = self.level_of(pos);
        let mut copies = 1;
        if now > *level {
            copies = 1u32 << (now - *level);
            *weight /= copies as f64;
        } else if now < *level {
            let keep = 1.0 / (1u32 << (*level - now)) as f64;
            if rng.random::<f64>() >= keep {
                return None;
            }
            *weight /= keep;
        }
        *level = now;
        Some(copies)
    }

    /// After a collision at `pos` of a photon with `n` scatterings: its new (isotropic)
    /// direction, the photon split or played at roulette by slice ([`Slices::split`]), its
    /// copies pushed on `stack`; `None` where roulette ended it.
    pub(crate) fn scatter(
        &self,
        pos: DVec3,
        n: u32,
        level: &mut i32,
        weight: &mut f64,
        stack: &mut Vec<Photon>,
        rng: &mut Pcg64Mcg,
    ) -> Option<DVec3> {
        let dir = isotropic(rng);
        let copies = self.split(pos, level, weight, rng)?;
        for _ in 1..copies {
            stack.push((pos, isotropic(rng), *weight, n, *level));
        }
        Some(dir)
    }

    /// Russian roulette against the weight in the slice's own terms (splitting lowers it by
    /// design): whether the photon goes on (twice the weight where it won).
    pub(crate) fn survives(&self, level: i32, weight: &mut f64, rng: &mut Pcg64Mcg) -> bool {
        if *weight * (1u32 << level) as f64 >= ROULETTE {
            return true;
        }
        *weight *= 2.0;
        rng.random::<f64>() >= 0.5
    }
}

/// A photon to follow: position, direction, weight, scatterings, slice.
pub(crate) type Photon = (DVec3, DVec3, f64, u32, i32);

/// One photon from the pole along `dir`: adds each collision's score toward each of `toward`.
///
/// Few photons from the antipode reach the lit side, where they score; so they are split as
/// they move toward the light ([`Slices`] across the first direction of `toward`).
fn walk(radius: f64, rho: f64, dir: DVec3, toward: &[DVec3], score: &mut [f64], rng: &mut Pcg64Mcg) {
    let slices = Slices::new(radius, toward[0]);
    let start = DVec3::new(0.0, 0.0, radius);
    let mut stack: Vec<Photon> = vec![(start, dir, 1.0, 0, slices.level_of(start))];
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
            match slices.scatter(pos, n, &mut level, &mut weight, &mut stack, rng) {
                Some(d) => dir = d,
                None => break,
            }
            if !slices.survives(level, &mut weight, rng) {
                break;
            }
        }
    }
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
