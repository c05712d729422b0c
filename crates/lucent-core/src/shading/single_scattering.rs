//! Single scattering along the view ray (not in Mertens et al. 2003; issue "physically right").
//!
//! Light scattered once inside the material reaches the eye along the refracted view ray. A
//! radial profile (PBD's single-scattering term, pbrt-v3's) can only spread it around the point
//! where it entered, as if every surface were a flat half-space seen from above and lit
//! head-on; against a path tracer that gives three-quarters of the single scattering of a
//! marble sphere, and a tenth to a fifth of it past the terminator, where light crosses the body
//! on straight lines to the part the eye sees. Here it is integrated where it happens (Hanrahan
//! & Krueger 1993, with the object's own geometry instead of their slab):
//!
//! ```text
//! L_o(x, ω_o) = F_t(η, μ_o) / η² ∫_0^{t_max} σ_s p e^{-σ_t t} F_in(x_t) e^{-σ_t s'(x_t)} dt
//! ```
//!
//! where `x_t = x + t ω_t` walks the refracted view ray `ω_t` into the body until it leaves it
//! (`t_max`), `s'` is the refracted path from `x_t` back to the surface towards the light (the
//! straight ray's hit distance `s` lengthened as Jensen et al. 2001 do, `s μ_i / μ_i'`), and
//! `F_in = E F_t(η, μ_i) μ_i / μ_i'` is the light's flux per unit area across the refracted beam
//! (zero where something shadows the entry point). The phase function is isotropic and `σ_s` the
//! reduced scattering coefficient, as in the profiles. Substituting `u = 1 - e^{-σ_t t}` makes
//! the view path's attenuation the measure; four-point Gauss-Legendre in `u` per channel
//! (exact to 0.1% on a half-space even for grazing light, where the integrand is `(1 - u)^8`,
//! against 17% for the midpoint rule), each point one ray to the surface and one shadow ray. On a flat half-space this is exactly Hanrahan & Krueger's
//! `α' E F_t F_t μ_i / (4π η² (μ_i' + μ_o'))`.
//!
//! An environment (nine SH coefficients) is first taken as lighting a half-space, in closed
//! form: for a fixed exit cosine the kernel above is zonal in the incident direction, so its
//! band weights (tabulated over `μ_o`) convolve the environment as the irradiance's do. What
//! the real body changes is added by tracing: light from behind the tangent plane (on a part a
//! few mean free paths across, the more the farther a channel reaches: the skim-milk bunny's
//! head is 10% redder in single scattering than its body, in Mitsuba and now in lucent), light
//! through thin parts, and sky hidden by other parts; see [`ENVIRONMENT_BODY_RAYS`].
//!
//! Both are evaluated at the centroids of the faces that face the eye and averaged to the
//! vertices ([`view_ray_radiance`]).
//!
//! The result is a per-vertex radiance *before* the exit Fresnel factor, which the mesh pass
//! applies per pixel to it and to `B / (c π)` alike ([`super`]). The mesh pass blends it across
//! a face geometrically, which follows its exponential fall past the terminator where a linear
//! blend overstates it (about twice the error against Mitsuba on a coarse mesh,
//! `docs/validation.md`); so that a vertex with none (every point on its view ray in shadow)
//! does not blacken its faces, each vertex keeps at least [`NEIGHBOUR_FLOOR`] of its brightest
//! neighbour.

pub mod light_paths;
use crate::Rgb;
use crate::bssrdf::{Profile, fresnel_transmittance, zonal_band_weights};
use crate::irradiance::sh::BandWeights;
use crate::irradiance::{Environment, FaceLit, Incident, SceneLight};
use crate::mesh::Mesh;
use crate::mesh::bvh::Bvh;
use glam::Vec3;
use light_paths::LightPaths;
use rayon::prelude::*;
use std::f32::consts::PI;

/// Where the single-scattering term is computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SingleScattering {
    /// Not at all.
    Off,
    /// In the diffusion profile (PBD's tabulated term, pbrt-v3's), as a function of the
    /// distance between entry and exit only.
    Profile,
    /// Along the refracted view ray through the object's own geometry (this module; default).
    /// Needs the eye position; the `mertens` profile has no single scattering either way.
    #[default]
    ViewRay,
}

impl SingleScattering {
    /// Whether the profile carries the term.
    pub fn in_profile(self) -> bool {
        self == SingleScattering::Profile
    }

    /// The name `lucent render --single-scattering` takes.
    pub fn name(self) -> &'static str {
        match self {
            SingleScattering::Off => "off",
            SingleScattering::Profile => "profile",
            SingleScattering::ViewRay => "view",
        }
    }
}

/// A single-scattering mode name that is not one of `view` (or `on`), `profile`, `off`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown single scattering `{0}` (expected view, on, profile or off)")]
pub struct UnknownSingleScattering(pub String);

impl std::str::FromStr for SingleScattering {
    type Err = UnknownSingleScattering;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "view" | "on" | "true" => Ok(SingleScattering::ViewRay),
            "profile" => Ok(SingleScattering::Profile),
            "off" | "false" => Ok(SingleScattering::Off),
            _ => Err(UnknownSingleScattering(s.to_string())),
        }
    }
}

/// Gauss-Legendre nodes on `0..1` and their weights: the points per colour channel along the
/// view ray.
const GAUSS_4: [(f32, f32); 4] = [
    (0.069_431_85, 0.173_927_42),
    (0.330_009_5, 0.326_072_58),
    (0.669_990_5, 0.326_072_58),
    (0.930_568_2, 0.173_927_42),
];

/// The least single scattering a vertex keeps, as a share of its brightest neighbour's (per
/// channel): the steepest fall across one edge the geometric blend reproduces.
pub const NEIGHBOUR_FLOOR: f32 = 1e-3;

/// Exit cosines at which the environment's band weights are tabulated (`μ_o = k / (N - 1)`).
pub(crate) const ENV_MU_SAMPLES: usize = 17;

/// What [`view_ray_radiance`] reads.
pub struct ViewRayScene<'a> {
    /// The posed mesh (mesh units).
    pub mesh: &'a Mesh,
    /// Its unit vertex normals.
    pub normals: &'a [Vec3],
    /// A BVH over `mesh` as posed.
    pub bvh: &'a Bvh,
    /// Ray origins move this far off the surface (mesh units), so a ray does not hit its own face.
    pub offset: f32,
    /// The material's coefficients (`sigma_t`, `alpha_prime`, `eta`) in mesh units.
    pub profile: &'a Profile,
    /// The lights (each says whether it casts shadows).
    pub lights: &'a [SceneLight],
    /// The environment, if any.
    pub environment: Option<&'a Environment>,
    /// Which faces each of `lights` reaches at its centroid, where the irradiance stage found
    /// it with the same rays (`crate::irradiance::face_entering_lit`); `None`: traced here.
    pub lit: Option<&'a FaceLit>,
}

/// Per-vertex single-scattered radiance towards `eye` (mesh units), before the exit Fresnel
/// factor `F_t(η, μ_o)` (see the module docs); radiance units of the lights' irradiance per sr.
///
/// It is integrated along the view ray at the centroid of every face that faces the eye, and
/// each vertex takes the area-weighted mean of its faces': the pixels a vertex colours lie on
/// its faces, and under a convex vertex itself light reaches the ray from more sides than under
/// the faces' interiors (on the 5 cm skim-milk bunny's head, 8-21% more, the most in the
/// channels with short mean free paths).
pub fn view_ray_radiance(scene: &ViewRayScene, eye: Vec3) -> Vec<Rgb> {
    view_ray_radiance_with(scene, eye, None)
}

/// [`view_ray_radiance`] with the light paths whose outcome is certain taken without a ray
/// where `diffuse` (per vertex, the drawn diffuse radiance `B / (c π)` the single scattering is
/// added to) is given ([`light_paths`]); `None`: every path traced.
pub fn view_ray_radiance_with(scene: &ViewRayScene, eye: Vec3, diffuse: Option<&[Rgb]>) -> Vec<Rgb> {
    view_ray_radiance_along(scene, &face_view_rays(scene, eye), diffuse)
}

/// [`view_ray_radiance_with`] along the faces' view rays `rays` ([`face_view_rays`]), which
/// the lights do not change.
pub(crate) fn view_ray_radiance_along(
    scene: &ViewRayScene,
    rays: &[Option<ViewRay>],
    diffuse: Option<&[Rgb]>,
) -> Vec<Rgb> {
    let paths = diffuse.map(|d| LightPaths::new(scene, d));
    let faces = radiance_along(scene, rays, paths.as_ref());
    let mut radiance = scene.mesh.face_to_vertex_over(&faces, |f| rays[f].is_some());
    floor_at_neighbours(scene.mesh, &mut radiance);
    radiance
}

/// Single-scattered radiance along each face's view ray (`Rgb::ZERO` where there is none),
/// before the exit Fresnel factor. Without `paths`, every channel has its own four points
/// and every light path is traced; with them, channels share points
/// ([`LightPaths::channel_groups`]) and the paths go through [`LightPaths::fluxes`].
fn radiance_along(scene: &ViewRayScene, rays: &[Option<ViewRay>], paths: Option<&LightPaths>) -> Vec<Rgb> {
    let d = scene.profile;
    let eta = d.eta as f32;
    let env = scene.environment.map(|e| (e, EnvironmentKernel::new(d)));
    let sigma_t = d.sigma_t.map(|s| s as f32);
    let albedo = d.alpha_prime.map(|a| a as f32);
    let groups = match paths {
        Some(_) => LightPaths::channel_groups(sigma_t),
        None => (0..3).map(|c| (sigma_t[c], vec![c])).collect(),
    };
    // Faces in the tree's leaf order: neighbours' shadow rays walk the same nodes.
    debug_assert_eq!(rays.len(), scene.mesh.triangles.len(), "one view ray a face");
    scene.bvh.map_faces(|f| {
        let Some(ray) = &rays[f] else { return Rgb::ZERO };
        let mut l = Rgb::ZERO;
        if !scene.lights.is_empty() {
            for (sigma, channels) in &groups {
                let u_max = 1.0 - (-sigma * ray.exit).exp();
                let t = GAUSS_4.map(|(node, _)| -(-u_max * node).ln_1p() / sigma);
                let points = t.map(|t| ray.origin + ray.w_t * t);
                let flux: Vec<[Rgb; 4]> = (0..scene.lights.len())
                    .map(|i| match paths {
                        Some(paths) => paths.fluxes(scene, f, i, &points),
                        None => points.map(|p| light_flux_rgb(scene, &scene.lights[i], p, eta, sigma_t)),
                    })
                    .collect();
                for &c in channels {
                    // The channel's own attenuation beyond the group's, and its measure's ratio.
                    let ratio = sigma_t[c] / sigma;
                    let mut sum = 0.0;
                    for (k, (_, weight)) in GAUSS_4.iter().enumerate() {
                        let extra = ratio * (-(sigma_t[c] - sigma) * t[k]).exp();
                        for light in &flux {
                            sum += weight * (extra * light[k][c]);
                        }
                    }
                    l[c] = albedo[c] / (4.0 * PI) * sum * u_max;
                }
            }
        }
        if let Some((e, kernel)) = &env {
            l += kernel.radiance(e, ray.normal, ray.mu_o);
            l += environment_through_body(scene, e, ray);
        }
        (l / (eta * eta)).max(Rgb::ZERO)
    })
}

/// Where the eye looks into the body at one point of the surface.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ViewRay {
    /// The vertex or face it stands for (seeds the environment's jitter).
    pub site: usize,
    /// Where it enters the body (mesh units).
    pub origin: Vec3,
    /// The unit normal there.
    pub normal: Vec3,
    /// The refracted view direction into the material (unit).
    pub w_t: Vec3,
    /// The exit cosine outside, `n·w_o` (1e-3..=1).
    pub mu_o: f32,
    /// How far the refracted view ray runs inside the body before it leaves it (mesh units;
    /// infinite where it leaves an open mesh).
    pub exit: f32,
}

impl ViewRay {
    /// The view ray from `eye` into the surface point `origin` of unit normal `n`, traced to
    /// where it leaves the body. A point turned slightly away still colours the pixels of its
    /// front-facing triangles: the view direction is mirrored to the front.
    fn trace(scene: &ViewRayScene, eye: Vec3, site: usize, origin: Vec3, n: Vec3) -> ViewRay {
        let mut w_o = (eye - origin).normalize_or_zero();
        let mut mu_o = n.dot(w_o);
        if mu_o < 0.0 {
            w_o -= 2.0 * mu_o * n;
            mu_o = -mu_o;
        }
        let mu_o = mu_o.clamp(1e-3, 1.0);
        let w_t = refract_inward(w_o, n, mu_o, scene.profile.eta as f32);
        // Only this ray starts on the surface (and skips its own faces); the points along it
        // are inside.
        let exit =
            scene.bvh.closest_hit(origin, w_t, scene.offset, f32::INFINITY).map_or(f32::INFINITY, |h| h.0);
        ViewRay { site, origin, normal: n, w_t, mu_o, exit }
    }
}

/// The view ray at every vertex of `scene.mesh` seen from `eye`; `None` where no face the
/// vertex belongs to faces the eye, or it has no normal (`exit_chord` reads them).
pub(crate) fn view_rays(scene: &ViewRayScene, eye: Vec3) -> Vec<Option<ViewRay>> {
    let seen = front_facing_vertices(scene.mesh, eye);
    (0..scene.mesh.positions.len())
        .into_par_iter()
        .map(|v| {
            let n = scene.normals[v];
            (n != Vec3::ZERO && seen[v]).then(|| ViewRay::trace(scene, eye, v, scene.mesh.positions[v], n))
        })
        .collect()
}

/// The view ray at the centroid of every face that faces `eye`, with the mean of its
/// vertices' normals there; `None` for the rest.
pub(crate) fn face_view_rays(scene: &ViewRayScene, eye: Vec3) -> Vec<Option<ViewRay>> {
    let mesh = scene.mesh;
    (0..mesh.triangles.len())
        .into_par_iter()
        .map(|f| {
            let centroid = mesh.face_centroid(f);
            if mesh.face_normal(f).dot(eye - centroid) <= 0.0 {
                return None;
            }
            let n = mesh.triangles[f]
                .iter()
                .map(|&v| scene.normals[v as usize])
                .sum::<Vec3>()
                .normalize_or_zero();
            (n != Vec3::ZERO).then(|| ViewRay::trace(scene, eye, f, centroid, n))
        })
        .collect()
}

/// Raises each vertex to [`NEIGHBOUR_FLOOR`] times the brightest vertex it shares a face with.
fn floor_at_neighbours(mesh: &Mesh, radiance: &mut [Rgb]) {
    let mut floor = vec![Rgb::ZERO; radiance.len()];
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|v| v as usize);
        floor[a] = floor[a].max(radiance[b].max(radiance[c]));
        floor[b] = floor[b].max(radiance[a].max(radiance[c]));
        floor[c] = floor[c].max(radiance[a].max(radiance[b]));
    }
    radiance.iter_mut().zip(floor).for_each(|(r, f)| *r = r.max(f * NEIGHBOUR_FLOOR));
}

/// Whether each vertex belongs to a triangle that faces `eye` (its plane has the eye on the
/// side of its normal). Only those colour a pixel of a closed mesh, which hides its back faces
/// behind its front ones, so the rest (about half) cast no rays.
fn front_facing_vertices(mesh: &Mesh, eye: Vec3) -> Vec<bool> {
    let mut seen = vec![false; mesh.positions.len()];
    for (f, tri) in mesh.triangles.iter().enumerate() {
        let p = mesh.positions[tri[0] as usize];
        if mesh.face_normal(f).dot(eye - p) > 0.0 {
            for &v in tri {
                seen[v as usize] = true;
            }
        }
    }
    seen
}

/// The refracted direction into the material for a view direction `w_o` (unit, towards the eye)
/// at a surface with unit outward normal `n`, `μ_o = n·w_o > 0`.
pub(crate) fn refract_inward(w_o: Vec3, n: Vec3, mu_o: f32, eta: f32) -> Vec3 {
    let cos_t = (1.0 - (1.0 - mu_o * mu_o) / (eta * eta)).max(0.0).sqrt();
    (-w_o / eta + (mu_o / eta - cos_t) * n).normalize_or_zero()
}

/// `F_in e^{-σ_t s'}` at the point `p` inside the body, per channel (extinctions `sigma_t`,
/// mesh units): the light of `light` refracted in where the straight ray from `p` towards it
/// leaves the surface, attenuated along the refracted path back to `p`. One ray to the
/// surface and one shadow ray.
pub(crate) fn light_flux_rgb(
    scene: &ViewRayScene,
    light: &SceneLight,
    p: Vec3,
    eta: f32,
    sigma_t: [f32; 3],
) -> Rgb {
    let Some(inc) = light.light.incident(p) else { return Rgb::ZERO };
    let Some((s, face)) = scene.bvh.closest_hit(p, inc.to_light, 0.0, inc.distance) else {
        // `p` lies outside the body (an open mesh): no material on the way.
        return Rgb::ZERO;
    };
    let n_h = facing(scene.mesh.face_normal(face as usize), inc.to_light);
    if light.shadows {
        let entry = p + inc.to_light * s + n_h * scene.offset;
        if scene.bvh.occluded(entry, inc.to_light, 0.0, inc.distance - s - scene.offset) {
            return Rgb::ZERO;
        }
    }
    refracted_flux(&inc, s, n_h, eta, sigma_t)
}

/// The unit normal `n` turned to face `w`.
pub(crate) fn facing(n: Vec3, w: Vec3) -> Vec3 {
    if n.dot(w) < 0.0 { -n } else { n }
}

/// `F_in e^{-σ_t s'}` per channel at a point inside the body whose straight path towards the
/// light `inc` meets the surface, unshadowed, after `s` (mesh units) where its unit normal
/// (facing the light) is `n_h`: the refracted flux, attenuated along the refracted path
/// `s' = s μ_i / μ_t` (module docs).
pub(crate) fn refracted_flux(inc: &Incident, s: f32, n_h: Vec3, eta: f32, sigma_t: [f32; 3]) -> Rgb {
    let mu_i = n_h.dot(inc.to_light).clamp(1e-4, 1.0);
    let mu_t = (1.0 - (1.0 - mu_i * mu_i) / (eta * eta)).max(1e-4).sqrt();
    let f_t = fresnel_transmittance(mu_i as f64, eta as f64) as f32;
    let s_refracted = s * mu_i / mu_t;
    Rgb::from_array(std::array::from_fn(|c| {
        inc.irradiance[c] * f_t * mu_i / mu_t * (-sigma_t[c] * s_refracted).exp()
    }))
}

/// Directions per view ray for the environment's single scattering through the body (a 4 × 4
/// stratification of the sphere about the normal, jittered per face). 32 and 128 gave the
/// skim-milk bunny's single scattering under the sky within 0.3% of 16.
pub const ENVIRONMENT_BODY_RAYS: usize = 16;
const BODY_STRATA: (usize, usize) = (4, 4);

/// What the body changes in the environment's single scattering at one view ray, against the
/// half-space [`EnvironmentKernel`] gives in closed form (add the two): the light that reaches
/// the view ray through the real body (from behind the tangent plane, through a thin part,
/// shadowed by another part) minus the half-space's, both estimated with the same
/// [`ENVIRONMENT_BODY_RAYS`] directions inside the material, so that where the body is a
/// half-space the two cancel and the closed form stands; less the half-space's light beyond
/// where the view ray leaves.
///
/// Inside, light travels straight from where it refracted in: a direction `w'` from a point on
/// the view ray meets the surface at distance `s` and cosine `μ'`, and brings `η² F_t L(ω)
/// e^{-σ_t s}` from the direction `ω` it refracted from (none past the critical angle: light
/// reflected inside is multiple scattering's). The four points along the view ray are shared
/// by the channels (Gauss-Legendre in the attenuation of the channel that reaches farthest,
/// the others weighted by their extra attenuation), so each direction costs four rays to the
/// surface and one shadow ray.
pub(crate) fn environment_through_body(scene: &ViewRayScene, env: &Environment, ray: &ViewRay) -> Rgb {
    let n = ray.normal;
    let d = scene.profile;
    let eta = d.eta as f32;
    let sigma_t = d.sigma_t.map(|s| s as f32);
    let albedo = d.alpha_prime.map(|a| a as f32);
    let sigma_far = sigma_t[0].min(sigma_t[1]).min(sigma_t[2]);
    let origin = ray.origin;
    // The light inside along `w'` (unit) where it meets a surface of unit normal `n_h` facing
    // it: `(η² F_t L(ω), ω)`, or `None` past the critical angle.
    let entering = |w: Vec3, n_h: Vec3| {
        let mu_in = n_h.dot(w);
        let sin2_out = eta * eta * (1.0 - mu_in * mu_in);
        if mu_in <= 0.0 || sin2_out >= 1.0 {
            return None;
        }
        let mu_out = (1.0 - sin2_out).sqrt();
        let out = (w * eta + n_h * (mu_out - eta * mu_in)).normalize_or_zero();
        let l = env.sh.radiance(env.to_map_frame(out)).max(Rgb::ZERO) * env.intensity;
        Some((l * (eta * eta * fresnel_transmittance(mu_out as f64, d.eta) as f32), out))
    };
    // The exit cosine inside, which sets the half-space's depth along the view ray.
    let mu_o_t = (-n.dot(ray.w_t)).clamp(1e-3, 1.0);
    let u_max = 1.0 - (-sigma_far * ray.exit).exp();
    // Each point: its depth along the view ray, its weight per channel (the node's, times the
    // channel's attenuation beyond the farthest-reaching channel's), and where it is.
    let points = GAUSS_4.map(|(node, weight)| {
        let t = -(-u_max * node).ln_1p() / sigma_far;
        let extra = Rgb::from_array(sigma_t.map(|sigma| (-(sigma - sigma_far) * t).exp()));
        (t, extra * (weight * u_max), origin + ray.w_t * t)
    });
    let attenuated = |l: Rgb, s: f32| l * Rgb::from_array(sigma_t.map(|sigma| (-sigma * s).exp()));
    let (t_axis, b_axis) = n.any_orthonormal_pair();
    let (rows, cols) = BODY_STRATA;
    let mut sum = Rgb::ZERO;
    for k in 0..ENVIRONMENT_BODY_RAYS {
        let (ju, jv) = crate::irradiance::occlusion::jitter(ray.site as u32, k as u32);
        let z = 1.0 - 2.0 * ((k / cols) as f32 + ju) / rows as f32;
        let phi = std::f32::consts::TAU * ((k % cols) as f32 + jv) / cols as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let w = t_axis * (r * phi.cos()) + b_axis * (r * phi.sin()) + n * z;
        // The half-space's surface, the tangent plane at the view ray's origin.
        let half_space = entering(w, n);
        let mut visible = None;
        for &(t, weight, p) in &points {
            let hs = half_space.map_or(Rgb::ZERO, |(l, _)| attenuated(l, t * mu_o_t / z));
            let real = match scene.bvh.closest_hit(p, w, 0.0, f32::INFINITY) {
                // Outside the body (an open mesh): keep the half-space's.
                None => hs,
                Some((s, face)) => {
                    let mut n_h = scene.mesh.face_normal(face as usize);
                    if n_h.dot(w) < 0.0 {
                        n_h = -n_h;
                    }
                    match entering(w, n_h) {
                        Some((l, out)) => {
                            let open = *visible.get_or_insert_with(|| {
                                let entry = p + w * s + n_h * scene.offset;
                                !scene.bvh.occluded(entry, out, 0.0, f32::INFINITY)
                            });
                            if open { attenuated(l, s) } else { Rgb::ZERO }
                        }
                        None => Rgb::ZERO,
                    }
                }
            };
            sum += (real - hs) * weight;
        }
        // The half-space's light along the view ray beyond where it leaves the body.
        if let Some((l, _)) = half_space.filter(|_| ray.exit.is_finite()) {
            let k = 1.0 + mu_o_t / z;
            let tail =
                Rgb::from_array(sigma_t.map(|sigma| (-sigma * ray.exit * k).exp() * sigma_far / (sigma * k)));
            sum -= l * tail;
        }
    }
    let solid = 4.0 * PI / ENVIRONMENT_BODY_RAYS as f32;
    Rgb::from_array(std::array::from_fn(|c| albedo[c] * sigma_t[c] / sigma_far / (4.0 * PI) * solid * sum[c]))
}

/// Band weights of the half-space single-scattering kernel for the environment, per channel,
/// over the exit cosine.
pub(crate) struct EnvironmentKernel {
    /// `[μ_o sample][channel]` band weights (sr).
    weights: Vec<[BandWeights; 3]>,
}

impl EnvironmentKernel {
    pub(crate) fn new(d: &Profile) -> Self {
        let eta = d.eta;
        let refracted = |mu: f64| (1.0 - (1.0 - mu * mu) / (eta * eta)).max(1e-6).sqrt();
        let weights = (0..ENV_MU_SAMPLES)
            .map(|k| {
                let mu_o_t = refracted((k as f64 / (ENV_MU_SAMPLES - 1) as f64).max(1e-3));
                std::array::from_fn(|c| {
                    let a = d.alpha_prime[c] / (4.0 * std::f64::consts::PI);
                    BandWeights(zonal_band_weights(|mu| {
                        if mu <= 0.0 {
                            return 0.0;
                        }
                        a * fresnel_transmittance(mu, eta) * mu / (refracted(mu) + mu_o_t)
                    }))
                })
            })
            .collect();
        EnvironmentKernel { weights }
    }

    /// Single-scattered radiance before the exit Fresnel factor and `1/η²`, at unit normal `n`
    /// seen at exit cosine `mu_o`.
    fn radiance(&self, env: &Environment, n: Vec3, mu_o: f32) -> Rgb {
        let x = mu_o * (ENV_MU_SAMPLES - 1) as f32;
        let k = (x as usize).min(ENV_MU_SAMPLES - 2);
        let f = x - k as f32;
        let at = |k: usize| self.radiance_at(env, n, k);
        ((at(k) * (1.0 - f) + at(k + 1) * f) * env.intensity).max(Rgb::ZERO)
    }

    /// [`Self::radiance`] at the `k`-th tabulated exit cosine `k / (ENV_MU_SAMPLES - 1)`, before
    /// the environment's intensity and the clamp at 0.
    pub(crate) fn radiance_at(&self, env: &Environment, n: Vec3, k: usize) -> Rgb {
        let d = env.to_map_frame(n);
        let w = &self.weights[k];
        Rgb::new(env.sh.convolve(d, &w[0]).x, env.sh.convolve(d, &w[1]).y, env.sh.convolve(d, &w[2]).z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertex with no single scattering keeps the floor share of its brightest neighbour, per
    /// channel; brighter vertices keep their own.
    #[test]
    fn dark_vertices_keep_a_share_of_their_brightest_neighbour() {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE, Vec3::Z * 5.0];
        let mesh = Mesh::new(positions, vec![[0, 1, 2], [1, 3, 2]]);
        let mut radiance =
            vec![Rgb::new(2.0, 0.0, 1.0), Rgb::ZERO, Rgb::new(1.0, 4.0, 0.0), Rgb::splat(1e-6), Rgb::ZERO];
        floor_at_neighbours(&mesh, &mut radiance);
        let f = NEIGHBOUR_FLOOR;
        assert_eq!(radiance[0], Rgb::new(2.0, 4.0 * f, 1.0));
        assert_eq!(radiance[1], Rgb::new(2.0 * f, 4.0 * f, 1.0 * f));
        assert_eq!(radiance[2], Rgb::new(1.0, 4.0, 1.0 * f));
        assert_eq!(radiance[3], Rgb::new(1.0 * f, 4.0 * f, 1e-6));
        // On no face: nothing to follow.
        assert_eq!(radiance[4], Rgb::ZERO);
    }
}
