//! The view terms split into what the eye changes and what it does not (issue 51 item 3; not in
//! Mertens et al. 2003): a camera move re-evaluates closed forms per face, with no ray.
//!
//! Today's per-eye evaluation ([`super::single_scattering::view_ray_radiance`] and
//! [`super::exit_chord::ExitChord::vertex_factors`]) traces, for every eye, the refracted view
//! ray to where it leaves the body (the chord `T`) and, at four points along it per channel, a
//! ray towards each light and a shadow ray. Two things in it do not depend on the eye:
//!
//! * **The light-side source.** With an isotropic phase function, what a point `p` inside
//!   scatters towards any view ray is `α'/(4π)` times the uncollided flux that reaches it,
//!   `S(p) = Σ_lights F_in e^{-σ_t s'(p)}` (the module docs of `single_scattering`), a scalar
//!   field per channel. Under each face it is taken as `S(p) = A e^{g·(p - x)}` (x the
//!   centroid), fitted per channel through four points of a small tetrahedron below the face,
//!   scaled to the channel's mean free path (one ray to the surface towards each light and one
//!   shadow ray each; channels of similar mean free paths share the points). The view ray's integral is then
//!   in closed form:
//!
//!   ```text
//!   L = α'/(4π) ∫_0^T σ_t e^{-σ_t t} S(x + t ω_t) dt = α'/(4π) σ_t A (1 - e^{-a T}) / a,
//!   a = σ_t - g·ω_t.
//!   ```
//!
//!   On a half-space under a directional light `S` is exactly such an exponential
//!   (`g = σ_t / μ_i' · n`), and the closed form is Hanrahan & Krueger's, exact; near the
//!   terminator and in thin parts it is the field's first-order (log-linear) expansion about
//!   the face (where a shadow's edge crosses the four points, the field is taken as their
//!   mean instead), capped at `e` times the larger of its value at the centroid and the largest
//!   flux the tetrahedron saw (the field may grow past the fit points, never without bound).
//! * **The body's chords.** Per face, the chord along the inward normal and along four
//!   directions tilted by [`TILT`] of the critical angle (traced when the mesh moves), with
//!   the view's chord interpolated between them (piecewise linear in the refracted direction's
//!   tangent components).
//!
//! The environment's half-space term is tabulated per face over the exit cosine (the same 17
//! samples as [`super::single_scattering`]'s kernel), and what the body changes in it
//! (`environment_through_body`) is evaluated once per face for a head-on view and kept for
//! every eye.
//!
//! Per eye then: per face that faces the eye, the refracted direction, the interpolated chord,
//! three exponentials for the chord factor and three for the single scattering; then the
//! area-weighted mean over each vertex's facing faces and the neighbour floor, as the per-eye
//! evaluation does. The per-eye evaluation stays the reference: `lucent render` uses it, and
//! a session with the split terms (the viewer's) still sees every solve (light, pose,
//! material) per eye and makes the eye-independent part only on the first camera move after
//! it, so that light moves and deformations cost what they did and a still camera shows the
//! reference's image; `docs/speed.md` gives the difference on the validation scenes.

mod eye;
mod vertices;

use crate::Rgb;
use crate::irradiance::SceneLight;
use crate::mesh::Mesh;
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;

use super::exit_chord::ExitChord;
use super::single_scattering::{
    ENV_MU_SAMPLES, EnvironmentKernel, ViewRay, ViewRayScene, environment_through_body, light_flux_rgb,
    refract_inward,
};
use eye::{FaceSeen, GeoBlock, LANES, SourceBlock};

/// The tilted chord directions' angle from the inward normal, as a share of the refracted
/// cone's half-angle (the critical angle): view rays lie inside the cone, most of them within
/// three quarters of it.
pub const TILT: f32 = 0.75;

/// Exit cosines of the environment's half-space table (as `single_scattering`'s).
const ENV_MU: usize = ENV_MU_SAMPLES;

/// The fit tetrahedron below a face, in units of the depth scale `d` and the face's frame
/// `(t1, t2, n)`: one point on the axis at `0.35 d`, three on a ring of radius `0.9 d` at
/// `1.2 d`, 120° apart (the depths where the view ray's integral has most of its weight).
const AXIS_DEPTH: f32 = 0.35;
const RING_DEPTH: f32 = 1.2;
const RING_RADIUS: f32 = 0.9;

/// What a face keeps for every eye.
#[derive(Clone, Debug, Default)]
struct FaceTerms {
    /// The source's value at the centroid `A` per channel (0: no light reaches under it).
    a: Rgb,
    /// The gradient of `ln S` per channel, per mesh unit.
    g: [Vec3; 3],
    /// The largest of the fit's value at the centroid and the flux the fit points saw, times
    /// `e`: the cap of the closed form.
    cap: Rgb,
    /// What the body changes in the environment's single scattering, head-on.
    env_body: Rgb,
}

/// What depends on the pose alone, per face.
#[derive(Clone, Debug, Default)]
struct FaceFrame {
    centroid: Vec3,
    /// The geometric normal (which faces the eye).
    facing: Vec3,
    /// The mean of the vertices' normals (as the per-eye evaluation's), and a tangent frame.
    n: Vec3,
    t1: Vec3,
    t2: Vec3,
    area: f32,
    /// Chords: along `-n`, then tilted towards `+t1, -t1, +t2, -t2` (mesh units; infinite
    /// where the ray left an open mesh).
    chords: [f32; 5],
}

/// The eye-independent part of the view terms for one pose, lighting and material: see the
/// module docs. Made by [`ViewBasis::new`], evaluated per eye by [`ViewBasis::seen`].
pub struct ViewBasis {
    positions: Vec<Vec3>,
    frames: Vec<FaceFrame>,
    /// Per face, the light and environment terms (empty without single scattering).
    terms: Vec<FaceTerms>,
    /// Each vertex's faces (compressed rows): `vertex_faces[offsets[v]..offsets[v + 1]]`.
    offsets: Vec<u32>,
    vertex_faces: Vec<u32>,
    /// Each vertex's distinct neighbours (compressed rows, as `offsets` and `vertex_faces`).
    neighbours: (Vec<u32>, Vec<u32>),
    /// What an eye reads of `frames` and `terms`, in blocks of `eye::LANES` faces taken in
    /// `order` (`eye::normal_order`; `source` empty without single scattering), and the
    /// positions in `order` of the faces with an infinite chord.
    geo: Vec<GeoBlock>,
    source: Vec<SourceBlock>,
    open: Vec<u32>,
    /// The face at each position of the blocks, each face's position, and `vertex_faces` as
    /// positions.
    order: Vec<u32>,
    position: Vec<u32>,
    slots: Vec<u32>,
    /// Per position, the environment's half-space single scattering at [`ENV_MU`] exit
    /// cosines (empty without an environment).
    env_blocked: Vec<[Rgb; ENV_MU]>,
    /// Buffers kept from eye to eye.
    scratch: Scratch,
    eta: f32,
    sigma_t: [f32; 3],
    albedo: [f32; 3],
    /// `sin` of the tilted chords' angle.
    sin_tilt: f32,
}

impl ViewBasis {
    /// The eye-independent terms of `scene` (its BVH current for the pose); `single`: whether
    /// view-ray single scattering is wanted (else only the chords). `previous`, when it was
    /// made for the same positions, gives its frames and chords (no ray traced again).
    pub fn new(scene: &ViewRayScene, single: bool, previous: Option<ViewBasis>) -> Self {
        let d = scene.profile;
        let eta = d.eta as f32;
        let sin_tilt = (TILT * (1.0 / eta).min(1.0).asin()).sin();
        let reuse = previous.filter(|p| p.sin_tilt == sin_tilt && p.positions == scene.mesh.positions);
        let (positions, frames, offsets, vertex_faces, neighbours, scratch) = match reuse {
            Some(p) => (p.positions, p.frames, p.offsets, p.vertex_faces, p.neighbours, p.scratch),
            None => {
                let (offsets, vertex_faces) = scene.mesh.vertex_faces();
                let neighbours = vertices::neighbours(scene.mesh, &offsets, &vertex_faces);
                let frames = face_frames(scene, sin_tilt);
                (scene.mesh.positions.clone(), frames, offsets, vertex_faces, neighbours, Scratch::default())
            }
        };
        let sigma_t = d.sigma_t.map(|s| s as f32);
        let mut basis = ViewBasis {
            positions,
            frames,
            terms: Vec::new(),
            offsets,
            vertex_faces,
            neighbours,
            geo: Vec::new(),
            source: Vec::new(),
            open: Vec::new(),
            order: Vec::new(),
            position: Vec::new(),
            slots: Vec::new(),
            env_blocked: Vec::new(),
            scratch,
            eta,
            sigma_t,
            albedo: d.alpha_prime.map(|a| a as f32),
            sin_tilt,
        };
        if single {
            basis.terms = scene.bvh.map_faces(|f| basis.face_terms(scene, f));
        }
        basis.order = eye::normal_order(&basis.frames);
        (basis.geo, basis.source, basis.open) = eye::blocks(&basis.frames, &basis.terms, &basis.order);
        basis.position = vec![0u32; basis.order.len()];
        for (p, &f) in basis.order.iter().enumerate() {
            basis.position[f as usize] = p as u32;
        }
        basis.slots = basis.vertex_faces.iter().map(|&f| basis.position[f as usize]).collect();
        if let Some(env) = scene.environment.filter(|_| single) {
            let kernel = EnvironmentKernel::new(d);
            basis.env_blocked = basis
                .order
                .par_iter()
                .map(|&f| {
                    let n = basis.frames[f as usize].n;
                    std::array::from_fn(|k| kernel.radiance_at(env, n, k) * env.intensity)
                })
                .collect();
        }
        basis
    }

    /// The light source fit and the environment's body term under face `f`.
    fn face_terms(&self, scene: &ViewRayScene, f: usize) -> FaceTerms {
        let fr = &self.frames[f];
        if fr.n == Vec3::ZERO {
            return FaceTerms::default();
        }
        let mut terms = FaceTerms::default();
        if !scene.lights.is_empty() {
            (terms.a, terms.g, terms.cap) = self.fit_source(scene, scene.lights, fr);
        }
        if let Some(env) = scene.environment {
            let ray = ViewRay {
                site: f,
                origin: fr.centroid,
                normal: fr.n,
                w_t: -fr.n,
                mu_o: 1.0,
                exit: fr.chords[0],
            };
            terms.env_body = environment_through_body(scene, env, &ray);
        }
        terms
    }

    /// `(A, g, cap)` of the lights' source under the face of frame `fr` (module docs), each
    /// channel fitted on a tetrahedron scaled to its own mean free path (channels within a
    /// factor [`SHARED_SCALE`] of each other share one), inside half the body's thickness under
    /// the face.
    fn fit_source(
        &self,
        scene: &ViewRayScene,
        lights: &[SceneLight],
        fr: &FaceFrame,
    ) -> (Rgb, [Vec3; 3], Rgb) {
        let mut stencils: Vec<(f32, [Vec3; 4], [Rgb; 4])> = Vec::with_capacity(3);
        let (mut a, mut g, mut cap) = (Rgb::ZERO, [Vec3::ZERO; 3], Rgb::ZERO);
        for c in 0..3 {
            let depth = (1.0 / self.sigma_t[c]).min(0.5 * fr.chords[0]);
            let k = match stencils.iter().position(|(d, ..)| (depth / d).max(d / depth) < SHARED_SCALE) {
                Some(k) => k,
                None => {
                    let offsets = tetrahedron(fr, depth);
                    let flux = offsets.map(|o| {
                        let p = fr.centroid + o;
                        lights
                            .iter()
                            .map(|l| light_flux_rgb(scene, l, p, self.eta, self.sigma_t))
                            .sum::<Rgb>()
                    });
                    stencils.push((depth, offsets, flux));
                    stencils.len() - 1
                }
            };
            let (depth, offsets, flux) = &stencils[k];
            (a[c], g[c], cap[c]) = fit_channel(fr, *depth, offsets, &flux.map(|v| v[c]));
        }
        (a, g, cap)
    }

    /// `(chord factor, single)` per vertex seen from `eye` (mesh units), as the per-eye
    /// evaluation gives them: the factor by which `B / (c π)` is multiplied (`None` without
    /// `chord`, the exit lobe's weights and each vertex's mean chord factor `N`), and the
    /// single-scattered radiance before the exit Fresnel factor (empty unless the basis was
    /// made with it). [`ViewBasis::draw`] without the diffuse radiance, into fresh buffers.
    pub fn seen(
        &self,
        mesh: &Mesh,
        eye: Vec3,
        chord: Option<(&ExitChord, &[Rgb])>,
    ) -> (Option<Vec<Rgb>>, Vec<Rgb>) {
        debug_assert_eq!(mesh.positions.len(), self.offsets.len() - 1, "the basis's mesh");
        let (mut factors, mut single) = (Vec::new(), Vec::new());
        let terms = DrawTerms { diffuse: None, chord_means: chord.map(|(_, n)| n), exact_exp: false };
        self.evaluate(eye, terms, &mut Scratch::default(), (&mut factors, &mut single));
        (chord.map(|_| factors), single)
    }

    /// What the mesh pass draws per vertex seen from `eye` (mesh units): `radiance`, the
    /// diffuse radiance times the chord factor (see [`DrawTerms`]), and `single`, the
    /// single-scattered radiance before the exit Fresnel factor (emptied unless the basis was
    /// made with it). The buffers are overwritten, their memory reused, as are the basis's
    /// own: a camera move allocates nothing once the sizes are reached.
    pub fn draw(
        &mut self,
        mesh: &Mesh,
        eye: Vec3,
        terms: DrawTerms,
        radiance: &mut Vec<Rgb>,
        single: &mut Vec<Rgb>,
    ) {
        debug_assert_eq!(mesh.positions.len(), self.offsets.len() - 1, "the basis's mesh");
        let mut scratch = std::mem::take(&mut self.scratch);
        self.evaluate(eye, terms, &mut scratch, (radiance, single));
        self.scratch = scratch;
    }

    /// [`ViewBasis::draw`] with the buffers `scratch`.
    fn evaluate(
        &self,
        eye: Vec3,
        terms: DrawTerms,
        scratch: &mut Scratch,
        (radiance, single): (&mut Vec<Rgb>, &mut Vec<Rgb>),
    ) {
        let with_single = !self.terms.is_empty();
        let with_chord = terms.chord_means.is_some();
        let per_face = &mut scratch.per_face;
        per_face.resize(self.geo.len(), [FaceSeen::default(); LANES]);
        if terms.exact_exp {
            per_face.as_flattened_mut()[..self.frames.len()].par_iter_mut().zip(&self.order).for_each(
                |(out, &f)| {
                    *out = self.face_seen_weighted(f as usize, eye, with_chord, with_single);
                },
            );
        } else {
            self.faces_seen_fast(eye, with_chord, per_face);
            let flat = per_face.as_flattened_mut();
            for &p in &self.open {
                let f = self.order[p as usize] as usize;
                flat[p as usize] = self.face_seen_weighted(f, eye, with_chord, with_single);
            }
        }
        let vertices = self.offsets.len() - 1;
        radiance.resize(vertices, Rgb::ZERO);
        scratch.unfloored.resize(vertices, glam::Vec4::ZERO);
        let means = vertices::Means { diffuse: terms.diffuse, chord_means: terms.chord_means };
        let rows = (self.offsets.as_slice(), self.slots.as_slice());
        vertices::means(per_face.as_flattened(), rows, means, radiance, &mut scratch.unfloored);
        if with_single {
            single.resize(vertices, Rgb::ZERO);
            let rows = (self.neighbours.0.as_slice(), self.neighbours.1.as_slice());
            vertices::floor_at_neighbours(&scratch.unfloored, rows, single);
        } else {
            single.clear();
        }
    }

    /// Every block of faces seen from `eye` by the vectorised closed forms (`eye.rs`), in
    /// parallel tasks of [`BLOCKS_PER_TASK`] blocks; the faces with an infinite chord are left.
    fn faces_seen_fast(&self, eye: Vec3, chord: bool, per_face: &mut [[FaceSeen; LANES]]) {
        let k = eye::EyeConsts {
            eye,
            eta: self.eta,
            sin_tilt: self.sin_tilt,
            sigma_t: self.sigma_t,
            albedo_4pi: self.albedo.map(|a| a / (4.0 * PI)),
            chord,
        };
        let isa = crate::simd::Isa::best();
        per_face.par_chunks_mut(BLOCKS_PER_TASK).enumerate().for_each(|(task, out)| {
            let blocks = task * BLOCKS_PER_TASK..task * BLOCKS_PER_TASK + out.len();
            let source = self.source.get(blocks.clone()).unwrap_or(&[]);
            let faces = blocks.start * LANES..(blocks.end * LANES).min(self.env_blocked.len());
            let env = self.env_blocked.get(faces).unwrap_or(&[]);
            eye::faces_seen(isa, &k, &self.geo[blocks], source, env, out);
        });
    }

    /// [`ViewBasis::face_seen`] as the vertex means take it: `(weight, kept, single)` with
    /// the last two times the weight.
    fn face_seen_weighted(&self, f: usize, eye: Vec3, chord: bool, single: bool) -> FaceSeen {
        let (a, k, s) = self.face_seen(f, &self.frames[f], eye, chord, single);
        let (k, s) = (k * a, s * a);
        FaceSeen([glam::Vec4::new(a, k.x, k.y, k.z), glam::Vec4::new(s.x, s.y, s.z, 0.0)])
    }

    /// One face seen from `eye`: `(weight, kept, single)`; weight 0 where it does not face it.
    /// The reference of `eye.rs`'s blocks (the C library's exponentials), and what they leave
    /// to it: the faces with an infinite chord.
    fn face_seen(&self, f: usize, fr: &FaceFrame, eye: Vec3, chord: bool, single: bool) -> (f32, Rgb, Rgb) {
        let to_eye = eye - fr.centroid;
        if fr.facing.dot(to_eye) <= 0.0 || fr.n == Vec3::ZERO {
            return (0.0, Rgb::ZERO, Rgb::ZERO);
        }
        let mut w_o = to_eye.normalize_or_zero();
        let mut mu_o = fr.n.dot(w_o);
        if mu_o < 0.0 {
            w_o -= 2.0 * mu_o * fr.n;
            mu_o = -mu_o;
        }
        let mu_o = mu_o.clamp(1e-3, 1.0);
        let w_t = refract_inward(w_o, fr.n, mu_o, self.eta);
        let t = self.chord(fr, w_t);
        let kept = if chord { Rgb::from_array(self.sigma_t.map(|s| -(-s * t).exp_m1())) } else { Rgb::ZERO };
        let l = if single { self.single(f, w_t, t, mu_o) } else { Rgb::ZERO };
        (fr.area, kept, l)
    }

    /// The chord along the refracted view direction `w_t`, interpolated between the face's five:
    /// linearly in the direction's tangent components `(u, v)` (in units of the tilt's sine)
    /// inside the diamond `|u| + |v| <= 1` of the samples, and at its edge beyond, so that it
    /// stays between the samples (a linear extrapolation from a long normal chord and short
    /// tilted ones, near a thin rim, went below zero).
    fn chord(&self, fr: &FaceFrame, w_t: Vec3) -> f32 {
        let (u, v) = (w_t.dot(fr.t1) / self.sin_tilt, w_t.dot(fr.t2) / self.sin_tilt);
        let reach = (u.abs() + v.abs()).max(1.0);
        let (u, v) = (u / reach, v / reach);
        let c = &fr.chords;
        let cu = if u >= 0.0 { c[1] } else { c[2] };
        let cv = if v >= 0.0 { c[3] } else { c[4] };
        let weights = [1.0 - u.abs() - v.abs(), u.abs(), v.abs()];
        if [c[0], cu, cv].iter().zip(weights).any(|(t, w)| t.is_infinite() && w > 0.0) {
            // Beside a ray that left an open mesh: the heaviest sample's.
            let k = (0..3).max_by(|&a, &b| weights[a].total_cmp(&weights[b])).unwrap_or(0);
            return [c[0], cu, cv][k];
        }
        c[0] * weights[0] + cu * weights[1] + cv * weights[2]
    }

    /// Single-scattered radiance of face `f` along `w_t` with chord `t` (before the exit
    /// Fresnel factor).
    fn single(&self, f: usize, w_t: Vec3, t: f32, mu_o: f32) -> Rgb {
        let terms = &self.terms[f];
        let mut l = Rgb::ZERO;
        for c in 0..3 {
            if terms.a[c] <= 0.0 {
                continue;
            }
            let s = self.sigma_t[c];
            // Growth along the ray is kept below twice the extinction (a backlit slab's is
            // `σ_t / μ_i'`, at most about 1.6 `σ_t`).
            let a = s - terms.g[c].dot(w_t).min(2.0 * s);
            let a = if t.is_finite() { a } else { a.max(0.1 * s) };
            let x = a * t;
            let integral = if x.abs() < 1e-4 { t * (1.0 - 0.5 * x) } else { -(-x).exp_m1() / a };
            let kept = if t.is_finite() { -(-s * t).exp_m1() } else { 1.0 };
            let value = (s * terms.a[c] * integral).min(terms.cap[c] * kept);
            l[c] = self.albedo[c] / (4.0 * PI) * value;
        }
        if let Some(table) = self.env_blocked.get(self.position[f] as usize) {
            let x = mu_o * (ENV_MU - 1) as f32;
            let k = (x as usize).min(ENV_MU - 2);
            let w = x - k as f32;
            l += (table[k] * (1.0 - w) + table[k + 1] * w).max(Rgb::ZERO) + terms.env_body;
        }
        (l / (self.eta * self.eta)).max(Rgb::ZERO)
    }
}

/// Blocks of faces per parallel task of a camera move (2,048 faces: a task costs about 20 µs
/// to hand to the other core, its faces about 100 µs).
const BLOCKS_PER_TASK: usize = 128;

/// The buffers a camera move writes besides its outputs, kept in the basis.
#[derive(Default)]
struct Scratch {
    /// Per face, what the vertex means take (`eye::FaceSeen`), in blocks.
    per_face: Vec<[FaceSeen; LANES]>,
    /// Per vertex, the single scattering before the neighbour floor (fourth lane 0).
    unfloored: Vec<glam::Vec4>,
}

/// What [`ViewBasis::draw`] needs besides the basis and the eye.
#[derive(Clone, Copy, Debug, Default)]
pub struct DrawTerms<'a> {
    /// The diffuse radiance `B / (c π)` per vertex, multiplied by the chord factor (`None`:
    /// the chord factor itself is written, 1 without `chord_means`).
    pub diffuse: Option<&'a [Rgb]>,
    /// Each vertex's mean chord factor `N` (`ExitChord`'s, area-weighted over its faces);
    /// `None`: no chord factor.
    pub chord_means: Option<&'a [Rgb]>,
    /// The C library's exponentials, as before the camera move was vectorised: the reference
    /// the fast ones (`fastexp::exp_m1_with`, within 6e-7 relative) are measured against
    /// (`Ablations::view_exp`).
    pub exact_exp: bool,
}

/// Every face's frame and chords (five rays per face).
fn face_frames(scene: &ViewRayScene, sin_tilt: f32) -> Vec<FaceFrame> {
    let mesh = scene.mesh;
    let cos_tilt = (1.0 - sin_tilt * sin_tilt).sqrt();
    scene.bvh.map_faces(|f| {
        let n =
            mesh.triangles[f].iter().map(|&v| scene.normals[v as usize]).sum::<Vec3>().normalize_or_zero();
        let centroid = mesh.face_centroid(f);
        let (t1, t2) = if n == Vec3::ZERO { (Vec3::ZERO, Vec3::ZERO) } else { n.any_orthonormal_pair() };
        let dirs = [
            -n,
            -n * cos_tilt + t1 * sin_tilt,
            -n * cos_tilt - t1 * sin_tilt,
            -n * cos_tilt + t2 * sin_tilt,
            -n * cos_tilt - t2 * sin_tilt,
        ];
        let chords = dirs.map(|d| {
            if n == Vec3::ZERO {
                return 0.0;
            }
            scene.bvh.closest_hit(centroid, d, scene.offset, f32::INFINITY).map_or(f32::INFINITY, |h| h.0)
        });
        FaceFrame { centroid, facing: mesh.face_normal(f), n, t1, t2, area: mesh.face_area(f), chords }
    })
}

/// Channels whose mean free paths are within this factor of each other share one fit
/// tetrahedron.
const SHARED_SCALE: f32 = 1.5;

/// The fit tetrahedron's points below the face of frame `fr` at depth scale `depth`, relative
/// to its centroid: one on the axis, three on a ring.
fn tetrahedron(fr: &FaceFrame, depth: f32) -> [Vec3; 4] {
    let ring = |k: usize| {
        let phi = k as f32 * std::f32::consts::TAU / 3.0;
        (fr.t1 * phi.cos() + fr.t2 * phi.sin()) * (RING_RADIUS * depth) - fr.n * (RING_DEPTH * depth)
    };
    [-fr.n * (AXIS_DEPTH * depth), ring(0), ring(1), ring(2)]
}

/// One channel's `(A, g, cap)` from its flux at the [`tetrahedron`] points `offsets` (depth
/// scale `depth`): `ln S` linear through the four, or their mean where a shadow's edge crosses
/// them.
fn fit_channel(fr: &FaceFrame, depth: f32, offsets: &[Vec3; 4], flux: &[f32; 4]) -> (f32, Vec3, f32) {
    let max = flux.iter().fold(0.0f32, |m, v| m.max(*v));
    if max <= 0.0 {
        return (0.0, Vec3::ZERO, 0.0);
    }
    if flux.iter().any(|v| *v <= 0.0) {
        // A shadow's edge (or the body's) crosses the tetrahedron: no exponential fits a
        // step; the mean of the points, even along the ray.
        let mean = flux.iter().sum::<f32>() / 4.0;
        return (mean, Vec3::ZERO, max * std::f32::consts::E);
    }
    let ln = flux.map(f32::ln);
    let b = [ln[1] - ln[0], ln[2] - ln[0], ln[3] - ln[0]];
    // The tetrahedron's system in closed form (the ring is symmetric).
    let (cos, sin) = ([1.0, -0.5, -0.5], [0.0, 0.866_025_4, -0.866_025_4]);
    let gu = (0..3).map(|k| b[k] * cos[k]).sum::<f32>() / (1.5 * RING_RADIUS * depth);
    let gv = (0..3).map(|k| b[k] * sin[k]).sum::<f32>() / (1.5 * RING_RADIUS * depth);
    let gw = -(b[0] + b[1] + b[2]) / (3.0 * (RING_DEPTH - AXIS_DEPTH) * depth);
    let g = fr.t1 * gu + fr.t2 * gv + fr.n * gw;
    let a = (ln[0] - g.dot(offsets[0])).exp();
    // The field's largest value along a view ray: at the surface where it falls inward, else
    // past the fit points, where growth is capped at `e` times the largest seen.
    (a, g, a.max(max) * std::f32::consts::E)
}

/// How the view terms are evaluated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ViewTerms {
    /// Traced for every eye (`single_scattering::view_ray_radiance`, `ExitChord::vertex_factors`):
    /// the reference. Default.
    #[default]
    PerEye,
    /// Split into the eye-independent [`ViewBasis`], made when the pose, light or material
    /// changes, and closed forms per eye (this module).
    Split,
}

impl ViewTerms {
    /// Both, in the order the CLI lists them.
    pub const ALL: [ViewTerms; 2] = [ViewTerms::PerEye, ViewTerms::Split];

    /// The name `lucent render --view-terms` takes.
    pub fn name(self) -> &'static str {
        match self {
            ViewTerms::PerEye => "per-eye",
            ViewTerms::Split => "split",
        }
    }
}

impl std::str::FromStr for ViewTerms {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_ascii_lowercase();
        ViewTerms::ALL
            .into_iter()
            .find(|v| v.name() == t)
            .ok_or_else(|| format!("unknown view terms {s:?}; expected per-eye or split"))
    }
}
