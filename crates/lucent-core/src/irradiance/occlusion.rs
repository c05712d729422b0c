//! Shadowed environment light: the part of the SH environment the mesh hides from each face.
//!
//! Mertens §5.3 leaves the environment unshadowed ("shadows cannot be taken into account, unless
//! we assume rigid objects"). With a BVH that is refitted as the mesh deforms
//! ([`super::shadow`]), lucent ray casts it: a face in a crevice, under a chin or between two
//! touching parts sees less sky, and the path tracer agrees. The unshadowed transmitted
//! irradiance is exact for the nine-coefficient radiance ([`super::Environment`]); from it we
//! subtract a Monte Carlo estimate of what is *blocked*,
//! `(π/N) Σ_k (1 - V_k) L(ω_k) entry(μ_k)` over `N` cosine-weighted, stratified directions. A face
//! that sees the whole hemisphere so gets the exact value with no noise at all; only the
//! occluded part is estimated. The jitter is a hash of the face and the stratum, so the result is
//! the same every run.

use super::{Entering, Environment, Incident, ShadowCaster};
use crate::Rgb;
use crate::bssrdf::Entry;
use glam::Vec3;

/// Rays per face for the environment's shadows (an 8 × 8 stratification of the cosine-weighted
/// hemisphere).
pub const ENVIRONMENT_SHADOW_RAYS: usize = 64;
const STRATA: usize = 8;

/// The transmitted environment irradiance the mesh blocks at point `p` with unit normal `n`
/// (face `face`, which seeds the jitter): subtract it from
/// [`Environment::transmitted`], in both parts of the entry term. Per channel, >= 0.
pub fn blocked_environment(
    env: &Environment,
    entry: &Entry,
    caster: &ShadowCaster,
    p: Vec3,
    n: Vec3,
    face: usize,
) -> Entering {
    let mut blocked = Entering::default();
    for (dir, cos) in cosine_rays(n, face) {
        let ray = Incident { to_light: dir, distance: f32::INFINITY, irradiance: Rgb::ZERO };
        if !caster.visible(p, n, &ray) {
            let radiance = env.sh.radiance(env.to_map_frame(dir)).max(Rgb::ZERO) * env.intensity;
            blocked.add(radiance, entry, cos);
        }
    }
    blocked * (std::f32::consts::PI / ENVIRONMENT_SHADOW_RAYS as f32)
}

/// [`ENVIRONMENT_SHADOW_RAYS`] cosine-weighted directions about the unit normal `n`, stratified
/// 8 × 8 and jittered by a hash of `face` (the same every run): `(direction, cosine to n)`.
/// With `N` of them, `(π/N) Σ f(ω_k)` estimates `∫ f(ω) cos dω` over the hemisphere.
pub fn cosine_rays(n: Vec3, face: usize) -> impl Iterator<Item = (Vec3, f32)> {
    stratified_cosine_rays(n, face, STRATA)
}

/// [`cosine_rays`] on a `strata` × `strata` grid (`strata²` rays).
pub fn stratified_cosine_rays(n: Vec3, face: usize, strata: usize) -> impl Iterator<Item = (Vec3, f32)> {
    let (t, b) = n.any_orthonormal_pair();
    (0..strata * strata).map(move |k| {
        let (i, j) = (k % strata, k / strata);
        let (ju, jv) = jitter(face as u32, k as u32);
        let u = (i as f32 + ju) / strata as f32;
        let v = (j as f32 + jv) / strata as f32;
        // Malley's method: a uniform disk sample lifted to the hemisphere is cosine-weighted.
        let (r, phi) = (u.sqrt(), std::f32::consts::TAU * v);
        let cos = (1.0 - u).max(0.0).sqrt();
        (t * (r * phi.cos()) + b * (r * phi.sin()) + n * cos, cos)
    })
}

/// Two numbers in `[0, 1)` from a face and a stratum (a 32-bit integer hash, PCG's output
/// permutation on a combined seed).
pub(crate) fn jitter(face: u32, k: u32) -> (f32, f32) {
    let hash = |x: u32| {
        let s = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        let w = ((s >> ((s >> 28) + 4)) ^ s).wrapping_mul(277_803_737);
        (w >> 22) ^ w
    };
    let a = hash(face.wrapping_mul(0x9E37_79B9) ^ k);
    let b = hash(a ^ 0x68E3_1DA4);
    (a as f32 / 4_294_967_296.0, b as f32 / 4_294_967_296.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::irradiance::Sh9;
    use crate::mesh::generate;

    /// A constant sky of radiance 1 and Fresnel-free entry: the blocked part is the occluded
    /// fraction of the cosine-weighted hemisphere times π.
    fn constant_sky() -> Environment {
        let mut coeffs = [[0.0f32; 3]; 9];
        // L00 of a constant radiance 1: Y00 = 0.282095, so L00 = 4π · 0.282095 = 1 / 0.282095.
        coeffs[0] = [1.0 / 0.282_095; 3];
        Environment { sh: Sh9::from_array(coeffs), rotation_deg: 0.0, intensity: 1.0 }
    }

    #[test]
    fn a_convex_mesh_blocks_nothing_and_a_floor_blocks_half() {
        let env = constant_sky();
        let entry = Entry::fresnel(1.0);
        let sphere = generate::icosphere(3);
        let caster = ShadowCaster::new(&sphere);
        for f in (0..sphere.triangles.len()).step_by(37) {
            let b =
                blocked_environment(&env, &entry, &caster, sphere.face_centroid(f), sphere.face_normal(f), f);
            assert_eq!(b, Entering::default(), "face {f}");
        }
        // A point just outside the sphere, facing along the surface (normal tangent to it):
        // the sphere fills close to half of its hemisphere.
        let p = Vec3::new(0.0, 1.001, 0.0);
        let b = blocked_environment(&env, &entry, &caster, p, Vec3::X, 0);
        let open = env.transmitted_irradiance(Vec3::X, &entry);
        assert!((open.x - std::f32::consts::PI).abs() < 5e-3, "{open}");
        let fraction = b.carried.x / open.x;
        assert!(fraction > 0.35 && fraction < 0.5, "{fraction}");
    }
}
