//! A backlit sphere's transmittance with a dielectric boundary, by forward random walk: what
//! [`super::sphere_walk`] measures at `η = 1`, for the presets' `η = 1.3` (issue 50).
//!
//! The reciprocal walk needs the transport kernel's symmetry at a point, which a curved
//! refracting boundary breaks into a lens (the beam refracted into a sphere converges: the
//! light reaching a point inside is not `e^{-d}` along one straight line). So this walk goes
//! forward and lets the boundary be what it is: photons from the beam's cross-section (irradiance
//! 1 over the disk of radius `R`), Fresnel-weighted and refracted in, isotropic scattering of
//! albedo `ρ`, and at every boundary hit the Fresnel-transmitted part of the weight leaves while
//! the reflected part walks on (total internal reflection included). What leaves after two or
//! more collisions through the band about each exit angle is scored, with the direction it
//! leaves in outside, so `T(θ)`, [`Exits::normal`] and [`Exits::tilt`] are the same quantities
//! as the reciprocal walk's, refracted out. At `η = 1` both walks measure the same thing, which
//! checks this one (unit test).
//!
//! Few photons reach the far side of a large sphere, so the walk splits them as they move away
//! from the light ([`super::sphere_walk::Slices`], as the reciprocal walk does toward it).

use super::fresnel::fresnel_dielectric;
use super::sphere_walk::{Exits, Photon, Slices, to_boundary};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use std::f64::consts::PI;

/// No path is followed further.
const MAX_STEPS: usize = 1 << 20;
/// Half the width of the band scored about each exit angle (degrees; the last band stops short
/// of the terminator). `T(θ)` bends little across it: its curvature over ±2.5° moves a band's
/// mean by well under the walk's error (at 5 mean free paths, bands of 5° meet the reciprocal
/// walk's points within 1% from 70 to 90°).
const HALF_BAND: f64 = 2.5;

/// The band scored about the antipode (degrees): wider, since its area goes as the square of
/// its width, and `T` is flat there (`T(15°)` is within 2-4% of `T(0)`, so over `0..10°` the
/// band's mean is within 0.5% of `T(0)`).
const POLE_BAND: f64 = 10.0;

/// The bands scored about `thetas` (radians): `(cos lo, cos hi)` per angle. Bands may overlap;
/// a photon leaving where two do scores in both.
fn bands(thetas: &[f64]) -> Vec<(f64, f64)> {
    let h = HALF_BAND.to_radians();
    thetas
        .iter()
        .map(|&t| {
            let (lo, hi) = if t < h { (0.0, POLE_BAND.to_radians()) } else { (t - h, t + h) };
            (lo.cos(), hi.min(0.5 * PI - 0.01).cos())
        })
        .collect()
}

/// The refraction of the unit `dir` through a boundary whose unit normal `n` faces against it,
/// from index `1` into `1 / ratio` (`ratio` = the index it leaves over the one it enters); `None`
/// on total internal reflection.
fn refract(dir: DVec3, n: DVec3, ratio: f64) -> Option<DVec3> {
    let cos_i = -dir.dot(n);
    let sin2_t = ratio * ratio * (1.0 - cos_i * cos_i);
    (sin2_t < 1.0).then(|| (ratio * dir + (ratio * cos_i - (1.0 - sin2_t).sqrt()) * n).normalize())
}

/// `T(θ)` and its exit moments for a sphere `radius` mean free paths in radius, albedo `rho`
/// (0..=1), relative index `eta` (1..=3), at each angle of `thetas` (radians from the antipode
/// of the lit pole, 0..π/2), per unit incident irradiance outside, from `paths` photons seeded
/// by `seed`.
pub fn forward_exits(radius: f64, rho: f64, eta: f64, thetas: &[f64], paths: usize, seed: u64) -> Exits {
    // The light travels along +z: the lit pole is (0, 0, -R), the antipode (0, 0, R).
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let bands = bands(thetas);
    let slices = Slices::new(radius, DVec3::Z);
    let n = thetas.len();
    let (mut sum, mut sq) = (vec![0.0; n], vec![0.0; n]);
    let (mut along, mut normal) = (vec![0.0; n], vec![0.0; n]);
    let mut score = vec![0.0; n];
    let mut moments = vec![(0.0, 0.0); n];
    for k in 0..paths {
        // A point of the beam's cross-section (stratified in the area), refracted in.
        let r = radius * ((k as f64 + rng.random::<f64>()) / paths as f64).sqrt();
        let phi = 2.0 * PI * rng.random::<f64>();
        let p = DVec3::new(r * phi.cos(), r * phi.sin(), -(radius * radius - r * r).max(0.0).sqrt());
        let m = p / radius;
        let weight = 1.0 - fresnel_dielectric(-m.z, eta);
        let Some(dir) = refract(DVec3::Z, m, 1.0 / eta) else { continue };
        score.iter_mut().for_each(|v| *v = 0.0);
        moments.iter_mut().for_each(|v| *v = (0.0, 0.0));
        walk(radius, rho, eta, p, dir, weight, &slices, &bands, &mut score, &mut moments, &mut rng);
        for i in 0..n {
            sum[i] += score[i];
            sq[i] += score[i] * score[i];
            along[i] += moments[i].0;
            normal[i] += moments[i].1;
        }
    }
    // Flux density: a photon carries π R² / paths of the beam's power; a band's area is
    // 2 π R² (cos lo - cos hi).
    let per = |i: usize| 1.0 / (2.0 * (bands[i].0 - bands[i].1));
    let np = paths as f64;
    let t: Vec<f64> = (0..n).map(|i| sum[i] / np * per(i)).collect();
    let se = (0..n).map(|i| ((sq[i] / np - (sum[i] / np).powi(2)).max(0.0) / np).sqrt() * per(i)).collect();
    let tilt =
        (0..n).map(|i| if sum[i] > 0.0 && thetas[i] > 0.0 { along[i] / sum[i] } else { 0.0 }).collect();
    let normal = (0..n).map(|i| if sum[i] > 0.0 { normal[i] / sum[i] } else { 2.0 / 3.0 }).collect();
    Exits { t, se, tilt, normal }
}

/// One photon entering at `p` along `dir` with `weight`: adds to `score` what leaves through
/// each band after two or more collisions, and to `moments` that weight times its exit's tilt
/// and normal cosine.
#[allow(clippy::too_many_arguments)]
fn walk(
    radius: f64,
    rho: f64,
    eta: f64,
    p: DVec3,
    dir: DVec3,
    weight: f64,
    slices: &Slices,
    bands: &[(f64, f64)],
    score: &mut [f64],
    moments: &mut [(f64, f64)],
    rng: &mut Pcg64Mcg,
) {
    let mut stack: Vec<Photon> = vec![(p, dir, weight, 0, slices.level_of(p))];
    while let Some((mut pos, mut dir, mut weight, mut n, mut level)) = stack.pop() {
        for _ in 0..MAX_STEPS {
            let step = -(1.0 - rng.random::<f64>()).ln();
            let d = to_boundary(pos, dir, radius);
            if step >= d {
                pos += dir * d;
                let m = pos / radius;
                let cos = dir.dot(m).clamp(0.0, 1.0);
                let reflect = fresnel_dielectric(cos, 1.0 / eta);
                if n >= 2 && reflect < 1.0 {
                    let cos_theta = m.z;
                    let w = weight * (1.0 - reflect);
                    let out = refract(dir, -m, eta).unwrap_or(m);
                    // The tangent toward the antipode, the way the light was flowing.
                    let t = (DVec3::Z - cos_theta * m).normalize_or_zero();
                    for (b, _) in
                        bands.iter().enumerate().filter(|(_, (hi, lo))| cos_theta <= *hi && cos_theta > *lo)
                    {
                        score[b] += w;
                        moments[b].0 += w * out.dot(t);
                        moments[b].1 += w * out.dot(m);
                    }
                }
                weight *= reflect;
                if weight <= 0.0 {
                    break;
                }
                dir = (dir - 2.0 * dir.dot(m) * m).normalize();
                pos = m * radius * (1.0 - 1e-12);
            } else {
                pos += dir * step;
                weight *= rho;
                n += 1;
                match slices.scatter(pos, n, &mut level, &mut weight, &mut stack, rng) {
                    Some(d) => dir = d,
                    None => break,
                }
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
    use crate::bssrdf::sphere_walk::walk_exits;

    /// At `η = 1` the forward walk measures what the reciprocal one does: `T`, the normal cosine
    /// and the tilt, within three combined standard errors (plus 2% for the band's width).
    #[test]
    fn at_index_one_the_forward_walk_meets_the_reciprocal_one() {
        let thetas: Vec<f64> = [0.0f64, 45.0, 78.0].iter().map(|d| d.to_radians()).collect();
        for (r, rho) in [(2.0, 0.999), (6.0, 0.99)] {
            let f = forward_exits(r, rho, 1.0, &thetas, 200_000, 3);
            let b = walk_exits(r, rho, &thetas, 40_000, 4);
            for i in 0..thetas.len() {
                let tol = 3.0 * (f.se[i].powi(2) + b.se[i].powi(2)).sqrt() + 0.02 * b.t[i];
                assert!((f.t[i] - b.t[i]).abs() < tol, "R {r} rho {rho} angle {i}: {} vs {}", f.t[i], b.t[i]);
                assert!(
                    (f.normal[i] - b.normal[i]).abs() < 0.03,
                    "normal {i}: {} vs {}",
                    f.normal[i],
                    b.normal[i]
                );
                assert!((f.tilt[i] - b.tilt[i]).abs() < 0.03, "tilt {i}: {} vs {}", f.tilt[i], b.tilt[i]);
            }
        }
    }

    /// At the presets' index the walk meets the independent forward walk of
    /// `validation/sphere_transmission.py --radius R --albedo 0.999 0.95 --eta 1.3 --photons
    /// 1000000 --seed 5 --edges 0 10 42.5 47.5 84.5 89.43` (numpy, analog Fresnel) in the bands
    /// about 0, 45 and 87 degrees, within three combined standard errors.
    #[test]
    fn at_index_1_3_the_walk_meets_the_numpy_walk() {
        let thetas: Vec<f64> = [0.0f64, 45.0, 87.0].iter().map(|d| d.to_radians()).collect();
        let cases = [
            (2.0, 0.999, [(0.12848, 0.00205), (0.13857, 0.00105), (0.16541, 0.00096)]),
            (2.0, 0.95, [(0.09426, 0.00153), (0.10182, 0.00079), (0.12408, 0.00074)]),
            (5.0, 0.999, [(0.05291, 0.0013), (0.06902, 0.00074), (0.15577, 0.00093)]),
            (5.0, 0.95, [(0.01829, 0.00053), (0.0276, 0.00034), (0.08367, 0.00055)]),
            (12.0, 0.999, [(0.01513, 0.00066), (0.02316, 0.00041), (0.08977, 0.0007)]),
        ];
        for (r, rho, want) in cases {
            let f = forward_exits(r, rho, 1.3, &thetas, 60_000, 21);
            for (i, (t, se)) in want.into_iter().enumerate() {
                let tol = 3.0 * (f.se[i].powi(2) + se * se).sqrt();
                assert!(
                    (f.t[i] - t).abs() < tol,
                    "R {r} rho {rho} angle {i}: {} +- {} vs {t} +- {se}",
                    f.t[i],
                    f.se[i]
                );
            }
        }
    }
}
