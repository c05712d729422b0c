//! Light that leaves one part of the object and enters another through the air: a bounce of
//! the subsurface radiance between facing surfaces.
//!
//! Mertens et al. (like every dipole method) carry light only *through* the material: what
//! leaves the surface is gone. Where parts face each other (a crevice, the feet under a bunny's
//! body, an ear beside a head) the light one part emits lights the other, and a path tracer
//! shows it: without it the validation bunny's crevices are the darkest blocks of the
//! comparison. lucent adds it as extra irradiance and solves again (the solve is linear in the
//! irradiance): for each face, the rays of [`super::occlusion::cosine_rays`] that hit the front
//! of another face `k` bring its exitant radiance `B_k F_t(η, μ_k) / (c π)` (the exit lobe of
//! [`crate::shading`]), through the receiver's entry term. On meshes with many faces within a
//! diffusion length each face casts fewer of those rays (`strata_for`).
//!
//! The rays are traced once and kept. When the mesh deforms a little they are *refitted*, not
//! traced again: each hit keeps its face and its place on that face (barycentric), and its
//! cosines, distance and weight follow the new positions ([`BounceRays::refit`]); what a ray
//! sees is not asked again until some vertex has moved
//! [`RETRACE_DISPLACEMENT`](crate::mesh::deform::RETRACE_DISPLACEMENT) of the extent since the
//! trace.

use super::occlusion::{ENVIRONMENT_SHADOW_RAYS, stratified_cosine_rays};
use super::{Entering, ShadowCaster};
use crate::Rgb;
use crate::bssrdf::{Profile, fresnel_transmittance};
use crate::mesh::Mesh;
use crate::mesh::deform::TracedPose;
use crate::progress::Progress;
use rayon::prelude::*;

/// The rays of the bounce that hit the front of another face, per face: the geometry of
/// [`bounced_irradiance`], traced once and reused by every bounce and every solve until the
/// mesh moves or the profile asks for another ray count (a moving light, a new material with
/// the same reach). Tracing them is most of a bounce: far more than a gather over stored
/// links.
#[derive(Clone, Debug, Default)]
pub struct BounceRays {
    /// Strata per side the rays were cast with ([`strata_for`]).
    strata: usize,
    /// Face `f`'s hits are `hits[offsets[f]..offsets[f + 1]]`.
    offsets: Vec<u32>,
    /// The hits on the mesh as last traced or refitted.
    hits: Vec<Hit>,
    /// The hits as traced, one per entry of `hits`: what a refit starts from (24 more bytes a
    /// hit: 84 MB for the 871K dragon's 3.5M).
    traced: Vec<TracedHit>,
    /// Face areas when traced (mesh units²).
    traced_area: Vec<f32>,
    /// The pose when traced.
    pose: TracedPose,
}

/// A bounce ray's hit as [`bounced_irradiance`] weighs it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Hit {
    /// The face hit.
    k: u32,
    /// The ray's cosine at the casting face (its entry angle there).
    cos: f32,
    /// The ray's cosine at the face hit (its exit angle there).
    mu_k: f32,
    /// The hit's share of the cosine-weighted estimate against a traced ray's (1 as traced;
    /// a refit scales it by the change of the solid angle and cosine the hit stands for).
    weight: f32,
}

/// A run of faces as traced: their hit counts and hits.
type Run = (Vec<u32>, Vec<(Hit, TracedHit)>);

/// Where a hit was when traced: its place on the face hit and the geometry its weight is
/// relative to.
#[derive(Clone, Copy, Debug, PartialEq)]
struct TracedHit {
    /// Barycentric coordinates of the hit point on face `k` (of its second and third corner).
    uv: [f32; 2],
    /// `cos` and `mu_k` as traced.
    cos: f32,
    mu_k: f32,
    /// Squared distance from the ray's origin to the hit (mesh units²).
    r2: f32,
}

impl BounceRays {
    /// Traces the bounce rays of every face of `mesh` (`caster` built on it) at the ray count
    /// the profile `profile` asks for, counting faces done on `progress` (stage "bounce
    /// rays").
    pub fn trace(mesh: &Mesh, caster: &ShadowCaster, profile: &Profile, progress: Option<&Progress>) -> Self {
        let eps = caster.offset();
        let strata = strata_for(mesh, profile);
        let faces = mesh.triangles.len();
        if let Some(p) = progress {
            p.start("bounce rays", faces);
        }
        // Faces in runs of `RUN`, in the BVH's leaf order (neighbours' rays walk the same
        // nodes): one progress count and one hit buffer per run, not per face.
        const RUN: usize = 256;
        let order = caster.bvh().leaf_order();
        let runs: Vec<Run> = order
            .par_chunks(RUN)
            .map(|run| {
                let (mut counts, mut hits) = (Vec::with_capacity(run.len()), Vec::new());
                for &f in run {
                    let f = f as usize;
                    let n = mesh.face_normal(f);
                    let origin = mesh.face_centroid(f) + n * eps;
                    let before = hits.len();
                    hits.extend(stratified_cosine_rays(n, f, strata).filter_map(|(dir, cos)| {
                        let (t, k) = caster.bvh().closest_hit(origin, dir, 0.0, f32::INFINITY)?;
                        let mu_k = -mesh.face_normal(k as usize).dot(dir);
                        let uv = mesh.barycentric(k as usize, origin + dir * t);
                        let traced = TracedHit { uv, cos, mu_k, r2: t * t };
                        (mu_k > 0.0).then_some((Hit { k, cos, mu_k, weight: 1.0 }, traced))
                    }));
                    counts.push((hits.len() - before) as u32);
                }
                if let Some(p) = progress {
                    p.add(run.len());
                }
                (counts, hits)
            })
            .collect();
        // Back to face order: offsets from each face's count, then each run's hits moved to
        // their faces' places.
        let mut count = vec![0u32; faces];
        for (&f, &c) in order.iter().zip(runs.iter().flat_map(|(counts, _)| counts)) {
            count[f as usize] = c;
        }
        let mut offsets = Vec::with_capacity(faces + 1);
        offsets.push(0u32);
        for c in count {
            let end = offsets.last().expect("starts at 0").checked_add(c);
            offsets.push(end.expect("fewer than 2^32 bounce hits"));
        }
        let total = *offsets.last().expect("starts at 0") as usize;
        let none = (
            Hit { k: 0, cos: 0.0, mu_k: 0.0, weight: 0.0 },
            TracedHit { uv: [0.0; 2], cos: 0.0, mu_k: 0.0, r2: 0.0 },
        );
        let mut placed = vec![none; total];
        for (faces_of_run, (counts, run_hits)) in order.chunks(RUN).zip(&runs) {
            let mut at = 0;
            for (&f, &c) in faces_of_run.iter().zip(counts) {
                let (start, c) = (offsets[f as usize] as usize, c as usize);
                placed[start..start + c].copy_from_slice(&run_hits[at..at + c]);
                at += c;
            }
        }
        let (hits, traced) = placed.into_iter().unzip();
        BounceRays {
            strata,
            offsets,
            hits,
            traced,
            traced_area: (0..faces).map(|f| mesh.face_area(f)).collect(),
            pose: TracedPose::of(mesh),
        }
    }

    /// Whether these rays serve `mesh` under `dipole`, as they are or refitted ([`Self::refit`]):
    /// the same faces, the ray count the profile asks for, and the pose traced still holds
    /// ([`TracedPose::holds`]).
    pub fn fits(&self, mesh: &Mesh, profile: &Profile) -> bool {
        self.offsets.len() == mesh.triangles.len() + 1
            && self.strata == strata_for(mesh, profile)
            && self.pose.holds(mesh)
    }

    /// Moves every hit with the deformed `mesh` (the one traced, vertices moved): each ray
    /// still ends on the face it hit, at the same barycentric place, and is cast from the
    /// casting face's centroid. Its cosines follow the new directions, and its weight the
    /// change of what it stands for in the cosine-weighted estimate, `cos dω` with
    /// `dω = A_k μ_k / r²` (the hit face's area at that place): a hit whose faces turned away
    /// from each other weighs 0. Visibility is not asked again (see
    /// [`RETRACE_DISPLACEMENT`](crate::mesh::deform::RETRACE_DISPLACEMENT)).
    /// Refitting the mesh as traced restores the traced hits.
    ///
    /// # Panics
    /// If `mesh` has another number of faces than the one traced.
    pub fn refit(&mut self, mesh: &Mesh, caster: &ShadowCaster) {
        assert_eq!(self.offsets.len(), mesh.triangles.len() + 1, "refit on the mesh traced");
        let faces = mesh.triangles.len();
        let eps = caster.offset();
        let area_ratio: Vec<f32> = (0..faces)
            .into_par_iter()
            .map(|f| {
                let a0 = self.traced_area[f];
                if a0 > 0.0 { mesh.face_area(f) / a0 } else { 0.0 }
            })
            .collect();
        let (offsets, traced) = (&self.offsets, &self.traced);
        let mut runs: Vec<&mut [Hit]> = Vec::with_capacity(faces);
        let mut rest = self.hits.as_mut_slice();
        for w in offsets.windows(2) {
            let (face, tail) = rest.split_at_mut((w[1] - w[0]) as usize);
            runs.push(face);
            rest = tail;
        }
        runs.into_par_iter().enumerate().for_each(|(f, face_hits)| {
            let n = mesh.face_normal(f);
            let origin = mesh.face_centroid(f) + n * eps;
            let start = offsets[f] as usize;
            for (hit, at) in face_hits.iter_mut().zip(&traced[start..]) {
                let k = hit.k as usize;
                let to = mesh.point_at(k, at.uv) - origin;
                let r2 = to.length_squared();
                let dir = to * r2.sqrt().recip();
                let (cos, mu_k) = (n.dot(dir), -mesh.face_normal(k).dot(dir));
                let weight = if cos > 0.0 && mu_k > 0.0 && r2 > 0.0 {
                    (cos / at.cos) * (mu_k / at.mu_k) * area_ratio[k] * (at.r2 / r2)
                } else {
                    0.0
                };
                *hit = if weight.is_finite() && weight > 0.0 {
                    Hit { k: hit.k, cos, mu_k, weight }
                } else {
                    Hit { k: hit.k, cos: at.cos, mu_k: at.mu_k, weight: 0.0 }
                };
            }
        });
    }
}

/// Transmitted irradiance per face from the light the other faces emit, given their exitant
/// radiosity `face_b` (per face, the solve's `B`) under the profile `dipole` (its exit term and
/// entry term, in both its parts), along the traced `rays`. Zero where a face sees no other
/// face's front.
pub fn bounced_irradiance(rays: &BounceRays, face_b: &[Rgb], profile: &Profile) -> Vec<Entering> {
    bounced_irradiance_with(rays, &hit_weights(rays, profile), face_b, profile)
}

/// Each stored hit's weight in [`bounced_irradiance`] under `profile`: its own weight times
/// the exit term and the Fresnel transmittance at its exit cosine, fixed while the rays and
/// the profile stay (so that a light move gathers without them).
pub fn hit_weights(rays: &BounceRays, profile: &Profile) -> Vec<f32> {
    let exit = (profile.exit_normalization() / std::f64::consts::PI) as f32;
    let eta = profile.eta;
    rays.hits.par_iter().map(|h| h.weight * exit * fresnel_transmittance(h.mu_k as f64, eta) as f32).collect()
}

/// [`bounced_irradiance`] with the hits' weights `weights` ([`hit_weights`]) given.
pub fn bounced_irradiance_with(
    rays: &BounceRays,
    weights: &[f32],
    face_b: &[Rgb],
    profile: &Profile,
) -> Vec<Entering> {
    assert_eq!(face_b.len() + 1, rays.offsets.len());
    assert_eq!(weights.len(), rays.hits.len());
    let weight = std::f32::consts::PI / (rays.strata * rays.strata) as f32;
    rays.offsets
        .par_windows(2)
        .map(|w| {
            let mut e = Entering::default();
            let range = w[0] as usize..w[1] as usize;
            for (h, hit_weight) in rays.hits[range.clone()].iter().zip(&weights[range]) {
                e.add(face_b[h.k as usize] * *hit_weight, &profile.entry, h.cos);
            }
            e * weight
        })
        .collect()
}

/// Faces within a diffusion length below which every face casts all 64 rays.
const FACES_PER_DISC: f64 = 64.0;

/// Rays per face for the bounce, as strata per side (8: 64 rays, down to 2: 4 rays). The
/// bounced light reaches a receiver through the profile, which averages it over the faces
/// within a diffusion length `1/σ_tr` (the shortest channel's); where that disc holds more
/// than [`FACES_PER_DISC`] faces, their rays together sample it, so each face casts 64 times
/// that over their number (at least 4). The bunny in marble at 10 cm holds about 60 faces a
/// disc (all 64 rays), the 203K Stanford dragon hundreds: fewer rays there moved the image by
/// 0.24% at the median pixel, 2.1% at the 99th percentile (low-frequency blotches, not
/// speckle: the profile smooths them).
fn strata_for(mesh: &Mesh, profile: &Profile) -> usize {
    let sigma_tr = profile.sigma_tr.into_iter().fold(0.0f64, f64::max);
    let faces = mesh.triangles.len().max(1);
    let area: f64 = (0..faces).map(|f| mesh.face_area(f) as f64).sum::<f64>() / faces as f64;
    let usable = sigma_tr.is_finite() && sigma_tr > 0.0 && area.is_finite() && area > 0.0;
    if !usable {
        return 8;
    }
    let per_disc = std::f64::consts::PI / (sigma_tr * sigma_tr) / area;
    let rays = (ENVIRONMENT_SHADOW_RAYS as f64 * FACES_PER_DISC / per_disc)
        .clamp(4.0, ENVIRONMENT_SHADOW_RAYS as f64);
    (rays.sqrt().round() as usize).clamp(2, 8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::{Material, ProfileKind};
    use crate::mesh::generate;
    use glam::Vec3;

    /// Coarse meshes cast every ray; a mesh with thousands of faces within a diffusion length
    /// casts the fewest.
    #[test]
    fn dense_meshes_cast_fewer_bounce_rays() {
        let marble = Material::by_name("marble").unwrap();
        let at = |mesh: &Mesh, metres: f64| {
            let d = Profile::at_model_scale(&marble, mesh.extent() as f64, metres, ProfileKind::Pbd, true);
            strata_for(mesh, &d)
        };
        let bunny = crate::mesh::embedded::bunny();
        assert_eq!(at(&bunny, 0.1), 8, "the bunny at 10 cm");
        let fine = generate::icosphere(7);
        let dense = at(&fine, 0.1);
        assert!((2..=3).contains(&dense), "327,680 faces on a 10 cm sphere: {dense} strata");
        assert_eq!(at(&fine, 100.0), 8, "the same at 100 m: faces wider than a diffusion length");
    }

    /// Two `size`-wide square plates of `n × n` quads, one at y = 0 facing up and one at
    /// y = `gap` facing down.
    fn facing_plates(n: u32, size: f32, gap: f32) -> Mesh {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (y, up) in [(0.0, true), (gap, false)] {
            let base = positions.len() as u32;
            for j in 0..=n {
                for i in 0..=n {
                    let (x, z) = (size * (i as f32 / n as f32 - 0.5), size * (j as f32 / n as f32 - 0.5));
                    positions.push(Vec3::new(x, y, z));
                }
            }
            for j in 0..n {
                for i in 0..n {
                    let a = base + j * (n + 1) + i;
                    let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
                    // Counter-clockwise seen from +y is (a, c, b): normal +y.
                    if up {
                        triangles.extend([[a, c, b], [b, c, d]]);
                    } else {
                        triangles.extend([[a, b, c], [b, d, c]]);
                    }
                }
            }
        }
        Mesh::new(positions, triangles)
    }

    /// A refit follows a move as a new trace does: plates brought closer catch more of each
    /// other's light (the solid angles grow), and a refit on the mesh as traced restores the
    /// traced hits.
    #[test]
    fn refitted_rays_follow_a_move_as_a_new_trace_does() {
        let m1 = Material::custom("m", [1.0; 3], [0.01; 3], 1.0).unwrap();
        let d1 = Profile::of_kind(&m1, 1.0, ProfileKind::Pbd, true);
        let plates = facing_plates(12, 4.0, 1.0);
        let total = |rays: &BounceRays| -> f32 {
            let b = vec![Rgb::ONE; plates.triangles.len()];
            bounced_irradiance(rays, &b, &d1).iter().map(|e| e.carried.x + e.local.x).sum()
        };
        let mut rays = BounceRays::trace(&plates, &ShadowCaster::new(&plates), &d1, None);
        let traced_hits = rays.hits.clone();
        let before = total(&rays);
        let closer = facing_plates(12, 4.0, 0.9);
        rays.refit(&closer, &ShadowCaster::new(&closer));
        let refitted = total(&rays);
        let retraced = total(&BounceRays::trace(&closer, &ShadowCaster::new(&closer), &d1, None));
        eprintln!("before {before} refitted {refitted} retraced {retraced}");
        assert!(retraced > 1.03 * before, "closer plates catch more: {before} -> {retraced}");
        assert!((refitted / retraced - 1.0).abs() < 0.01, "refitted {refitted} against traced {retraced}");

        rays.refit(&plates, &ShadowCaster::new(&plates));
        for (h, t) in rays.hits.iter().zip(&traced_hits) {
            assert_eq!(h.k, t.k);
            assert!(
                (h.weight - 1.0).abs() < 1e-4
                    && (h.cos - t.cos).abs() < 1e-4
                    && (h.mu_k - t.mu_k).abs() < 1e-4
            );
        }
    }

    #[test]
    fn a_convex_mesh_lights_nothing_and_facing_plates_light_each_other() {
        let m = Material::by_name("marble").unwrap();
        let sphere = generate::icosphere(3);
        let d = Profile::of_kind(&m, 10.0, crate::bssrdf::ProfileKind::Pbd, true);
        let b = vec![Rgb::ONE; sphere.triangles.len()];
        let rays = BounceRays::trace(&sphere, &ShadowCaster::new(&sphere), &d, None);
        let e = bounced_irradiance(&rays, &b, &d);
        assert!(e.iter().all(|v| *v == Entering::default()));

        // Two large parallel plates facing each other at a small gap, B = 1 on both, eta = 1:
        // the exit lobe integrates to 1, so each plate's centre receives the whole hemisphere's
        // radiance 1/π through its entry term: the entry term's cosine-weighted mean (its
        // zonal band weight A_0 over π; above 1, as oblique light returns more).
        let m1 = Material::custom("m", [1.0; 3], [0.01; 3], 1.0).unwrap();
        let d1 = Profile::of_kind(&m1, 1.0, crate::bssrdf::ProfileKind::Pbd, true);
        let plates = facing_plates(16, 20.0, 0.2);
        let b = vec![Rgb::ONE; plates.triangles.len()];
        let rays = BounceRays::trace(&plates, &ShadowCaster::new(&plates), &d1, None);
        assert!(rays.fits(&plates, &d1));
        let e = bounced_irradiance(&rays, &b, &d1);
        assert!(plates.face_normal(0).y > 0.9 && plates.face_normal(plates.triangles.len() - 1).y < -0.9);
        let centre = (0..plates.triangles.len())
            .min_by(|&a, &c| plates.face_centroid(a).length().total_cmp(&plates.face_centroid(c).length()))
            .unwrap();
        let want = (d1.entry.band_weights(0)[0] + d1.entry.local_band_weights(0)[0]) / std::f32::consts::PI;
        let got = e[centre].carried.x + e[centre].local.x;
        assert!(want > 1.0 && (got / want - 1.0).abs() < 0.03, "{got} vs {want}");
    }
}
