//! The light paths of view-ray single scattering with fewer rays (issue 51, the light move;
//! not in Mertens et al. 2003).
//!
//! Traced in full ([`super`], the reference: `lucent render --ablate
//! light-paths`), each face's view ray has four points per channel, and each point follows
//! the straight path towards each light to the surface (one ray) and asks whether the light
//! reaches it there (one shadow ray): twenty-four rays a face and light, most of a light move's
//! time. Here:
//!
//! * **Channels share their points** where their extinctions are within [`SHARED_RATIO`]
//!   ([`LightPaths::channel_groups`]; marble and skim milk: one group), each channel weighting
//!   the shared points by the ratio of its attenuation measure to the group's: eight rays a
//!   face and light instead of twenty-four.
//! * **A path whose light is negligible takes no shadow ray.** The unshadowed flux
//!   `F_in e^{-σ_t s'}` at the point bounds what the path can bring; where the single
//!   scattering it allows, `α'/(4π η²)` times it, is below [`NEGLIGIBLE`] of the face's drawn
//!   diffuse radiance (the least of its corners, shared among the lights), it is left out:
//!   under a face turned away from the light, where every path crosses a body many mean free
//!   paths thick, that is every path (`e^{-σ_t d}`), and what the face leaves out is below
//!   [`NEGLIGIBLE`] of what it draws (the weights sum to one).
//! * **A face the light falls on, flat at the scale of the paths, takes no ray at all**: the
//!   path from depth `z` under the face's plane meets it after `z / μ_i`, and the half-space's
//!   flux follows in closed form (the same [`refracted_flux`] the traced path ends in). It is
//!   taken where the face and every face sharing a vertex with it (its ring) face the light
//!   and are lit at their centroids (one shadow ray per face and light for the whole mesh),
//!   and where the error it may make stays below [`APPROXIMATE`] of the drawn radiance: the
//!   exits fall on the ring, whose faces stand off the plane by `h` (at most) and tilt from
//!   its normal by `|n_k - n|`, changing the refracted path by `h / μ_t` and
//!   `t |n_k - n| / μ_t` (the mean `σ_t t` under the view ray's weight is below one) and the
//!   entry factor `F_t μ_i / μ_t` by its spread over the ring; the bound is their sum times
//!   the closed form's single scattering. On meshes whose faces are a few mean free paths
//!   across (the 11K and 48K Stanford dragons at 10 cm) the ring's tilt alone exceeds it on
//!   most faces, and their paths are traced.
//!
//! Everything else (faces at the terminator, in thin parts, at shadow edges) is traced as
//! before, with the shared points.

use super::{ViewRayScene, facing, refracted_flux};
use crate::Rgb;
use crate::bssrdf::fresnel_transmittance;
use crate::irradiance::{FaceLit, SceneLight};
use glam::Vec3;
use rayon::prelude::*;
use std::borrow::Cow;
use std::f32::consts::PI;

/// The share of a vertex's drawn radiance a light's single scattering may fall below and be
/// left out, the error allowed for a term not computed (a thousandth, beneath the 1% the
/// solver's oracle allows).
pub const NEGLIGIBLE: f32 = 1e-3;

/// The share of a vertex's drawn radiance a closed form's error may reach where it replaces
/// the traced paths: the solver's default accuracy (its oracle's 1%).
pub const APPROXIMATE: f32 = 1e-2;

/// The largest ratio of extinctions whose channels share their points along a view ray: the
/// four-point Gauss-Legendre rule integrates a half-space's `(1 - u)^a` within 3e-4 up to
/// `a = 8`, and a channel `r` times the group's extinction sees `a <= r (1 + 1/μ_t) - 1`,
/// with `μ_t >= 0.64` the refracted cosine at `η = 1.3`.
pub const SHARED_RATIO: f32 = 3.5;

/// What [`LightPaths::fluxes`] reads besides the scene: per light, which faces it reaches;
/// each vertex's faces; per face, the single scattering a light may leave out.
pub(crate) struct LightPaths<'a> {
    /// Per light, per face: whether it faces the light and the light reaches its centroid.
    lit: Cow<'a, FaceLit>,
    /// Each vertex's faces (compressed rows): `vertex_faces[offsets[v]..offsets[v + 1]]`.
    offsets: Vec<u32>,
    vertex_faces: Vec<u32>,
    /// Per face, per channel: the least drawn diffuse radiance of its corners, divided among
    /// the lights.
    diffuse: Vec<Rgb>,
}

impl<'a> LightPaths<'a> {
    /// The shadow tests at the vertices of `scene` and the rows above, for the drawn diffuse
    /// radiance `diffuse` per vertex (`B / (c π)`, before the exit Fresnel factor, which the
    /// single scattering shares).
    pub(crate) fn new(scene: &ViewRayScene<'a>, diffuse: &[Rgb]) -> Self {
        let mesh = scene.mesh;
        let lit = match scene.lit.filter(|l| l.fits(scene.lights.len(), mesh.triangles.len())) {
            Some(lit) => Cow::Borrowed(lit),
            None => {
                let n = scene.lights.len();
                let lit = (0..mesh.triangles.len() * n)
                    .into_par_iter()
                    .map(|k| face_lit(scene, &scene.lights[k % n], k / n))
                    .collect();
                Cow::Owned(FaceLit::new(n, lit))
            }
        };
        let (offsets, vertex_faces) = mesh.vertex_faces();
        let share = 1.0 / scene.lights.len().max(1) as f32;
        let diffuse = if diffuse.len() == mesh.positions.len() {
            mesh.triangles
                .par_iter()
                .map(|t| t.iter().map(|&v| diffuse[v as usize]).fold(Rgb::INFINITY, Rgb::min) * share)
                .collect()
        } else {
            vec![Rgb::ZERO; mesh.triangles.len()]
        };
        LightPaths { lit, offsets, vertex_faces, diffuse }
    }

    /// The channels that share their points along a view ray, as `(the group's extinction,
    /// its channels)`: channels in increasing extinction, each joining the group of the
    /// farthest-reaching channel while its extinction is within [`SHARED_RATIO`] of it. The
    /// points are the four Gauss-Legendre nodes of the group's attenuation `u = 1 - e^{-σ t}`;
    /// a channel of extinction `r σ` weights them by `r e^{-(r - 1) σ t}`, the ratio of its
    /// measure to the group's.
    pub(crate) fn channel_groups(sigma_t: [f32; 3]) -> Vec<(f32, Vec<usize>)> {
        let mut order = [0, 1, 2];
        order.sort_by(|&a, &b| sigma_t[a].total_cmp(&sigma_t[b]));
        let mut groups: Vec<(f32, Vec<usize>)> = Vec::with_capacity(3);
        for c in order {
            match groups.last_mut() {
                Some((sigma, channels)) if sigma_t[c] <= SHARED_RATIO * *sigma => channels.push(c),
                _ => groups.push((sigma_t[c], vec![c])),
            }
        }
        groups
    }

    /// Light `i`'s flux `F_in e^{-σ_t s'}` (every channel) at the `points` along face `f`'s
    /// view ray (module docs).
    pub(crate) fn fluxes(&self, scene: &ViewRayScene, f: usize, i: usize, points: &[Vec3; 4]) -> [Rgb; 4] {
        if let Some(h) = self.half_space(scene, f, i, points) {
            return h;
        }
        let light = &scene.lights[i];
        let d = scene.profile;
        let (eta, sigma_t) = (d.eta as f32, d.sigma_t.map(|s| s as f32));
        // Flux whose single scattering stays below this is left out without its shadow ray.
        let albedo = Rgb::from_array(d.alpha_prime.map(|a| a as f32));
        let negligible =
            self.diffuse[f] * NEGLIGIBLE * (4.0 * PI * eta * eta) / albedo.max(Rgb::splat(1e-12));
        points.map(|p| {
            let Some(inc) = light.light.incident(p) else { return Rgb::ZERO };
            let Some((s, face)) = scene.bvh.closest_hit(p, inc.to_light, 0.0, inc.distance) else {
                return Rgb::ZERO;
            };
            let n_h = facing(scene.mesh.face_normal(face as usize), inc.to_light);
            let flux = refracted_flux(&inc, s, n_h, eta, sigma_t);
            if flux.cmple(negligible).all() {
                return Rgb::ZERO;
            }
            if light.shadows {
                let entry = p + inc.to_light * s + n_h * scene.offset;
                if scene.bvh.occluded(entry, inc.to_light, 0.0, inc.distance - s - scene.offset) {
                    return Rgb::ZERO;
                }
            }
            flux
        })
    }

    /// Light `i`'s flux at `points` under face `f` as under the half-space of the face's
    /// plane, where the face and its ring face the light, the light reaches their centroids,
    /// and the half-space's error is within [`APPROXIMATE`] of the drawn radiance (module
    /// docs); else `None`.
    fn half_space(&self, scene: &ViewRayScene, f: usize, i: usize, points: &[Vec3; 4]) -> Option<[Rgb; 4]> {
        let mesh = scene.mesh;
        let light = &scene.lights[i];
        if !self.lit.get(i, f) {
            return None;
        }
        let (n, centroid) = (mesh.face_normal(f), mesh.face_centroid(f));
        let to_light = light.light.incident(centroid)?.to_light;
        let eta = scene.profile.eta as f32;
        let entering = |mu: f32| {
            let mu = mu.clamp(1e-4, 1.0);
            let mu_t = (1.0 - (1.0 - mu * mu) / (eta * eta)).max(1e-4).sqrt();
            (fresnel_transmittance(mu as f64, eta as f64) as f32 * mu / mu_t, mu_t)
        };
        let (f_n, mu_t) = entering(n.dot(to_light));
        // Over the ring: the entry factor's relative spread, the heights above the face's
        // plane and the normals' tilt from it.
        let (mut spread, mut height, mut tilt) = (0.0f32, 0.0f32, 0.0f32);
        for &v in &mesh.triangles[f] {
            let v = v as usize;
            for &k in &self.vertex_faces[self.offsets[v] as usize..self.offsets[v + 1] as usize] {
                let k = k as usize;
                if !self.lit.get(i, k) {
                    return None;
                }
                let n_k = mesh.face_normal(k);
                spread = spread.max((entering(n_k.dot(to_light)).0 / f_n - 1.0).abs());
                height = height.max(n.dot(mesh.face_centroid(k) - centroid).abs());
                tilt = tilt.max(n_k.distance(n));
            }
        }
        let sigma_t = scene.profile.sigma_t.map(|s| s as f32);
        let fluxes = points.map(|p| {
            let Some(inc) = light.light.incident(p) else { return Rgb::ZERO };
            let mu = n.dot(inc.to_light);
            if mu <= 0.0 {
                return Rgb::ZERO;
            }
            let depth = n.dot(centroid - p).max(0.0);
            refracted_flux(&inc, depth / mu, n, eta, sigma_t)
        });
        // The single scattering the closed form gives, per channel, and its error's bound.
        let albedo = Rgb::from_array(scene.profile.alpha_prime.map(|a| a as f32));
        let single = albedo / (4.0 * PI * eta * eta) * fluxes.iter().copied().sum::<Rgb>() * 0.25;
        let relative = Rgb::from_array(sigma_t.map(|s| spread + (s * height + tilt) / mu_t));
        let error = single * relative;
        error.cmple((self.diffuse[f] + single) * APPROXIMATE).all().then_some(fluxes)
    }
}

/// Whether face `f` faces `light` and the light reaches its centroid: its shadow ray starts
/// the scene's offset above the surface, as the irradiance's does.
fn face_lit(scene: &ViewRayScene, light: &SceneLight, f: usize) -> bool {
    let (n, centroid) = (scene.mesh.face_normal(f), scene.mesh.face_centroid(f));
    let Some(inc) = light.light.incident(centroid) else { return false };
    if n.dot(inc.to_light) <= 0.0 {
        return false;
    }
    let origin = centroid + n * scene.offset;
    !light.shadows || !scene.bvh.occluded(origin, inc.to_light, 0.0, inc.distance - scene.offset)
}
