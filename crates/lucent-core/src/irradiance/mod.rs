//! Irradiance at the leaves (Mertens §5.3): light arriving at each face's midpoint and
//! transmitted through the smooth dielectric boundary, `E = ∫ L_i entry(w_i) cos dω`
//! (Fresnel's `F_t(eta, w_i)`, times the half-space albedo ratio of [`crate::bssrdf::Entry`]).
//!
//! Sources: point, directional and spot lights ([`lights`]), optionally shadowed by ray casting
//! against a refitted BVH of the (deforming) mesh ([`shadow`], over [`crate::mesh::bvh`]), and a distant environment given
//! by nine spherical-harmonic coefficients ([`sh`], [`envmap`]), shadowed by the same BVH
//! ([`occlusion`]; Mertens §5.3 leaves it unshadowed: "shadows cannot be taken into account,
//! unless we assume rigid objects").

pub mod corners;
pub mod envmap;
pub mod interreflection;
pub mod lights;
pub mod occlusion;
pub mod sh;
pub mod shadow;

pub use envmap::{EnvMap, EnvMapError, equirect_direction, equirect_uv};
pub use lights::{Cone, Incident, Light, LightKind, SceneLight, light_irradiance, spot_falloff};
pub use sh::{BandWeights, Sh9};
pub use shadow::{ShadowCaster, Update};

use crate::Rgb;
use crate::bssrdf::Entry;
use crate::mesh::Mesh;
use glam::{Quat, Vec3};
use rayon::prelude::*;

/// Distant environment light as nine SH coefficients of its radiance (Mertens §5.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Environment {
    /// SH coefficients `L_lm` of the radiance in the map's own frame (see [`envmap`] for the
    /// direction convention), per channel, in radiance units.
    pub sh: Sh9,
    /// Rotation of the environment about +Y, in degrees (right-handed; default 0).
    pub rotation_deg: f32,
    /// Multiplier on the radiance (unitless, >= 0; default 1).
    pub intensity: f32,
}

impl Environment {
    /// An environment from a map, projected onto SH (rotation 0, intensity 1).
    pub fn from_map(map: &EnvMap) -> Self {
        Environment { sh: map.project_sh(), rotation_deg: 0.0, intensity: 1.0 }
    }

    /// Takes a world-space direction to the map's frame: `R_y(−rotation)`, since the rotated
    /// environment is `L'(ω) = L(R_y(−α) ω)`.
    #[inline]
    pub fn to_map_frame(&self, d: Vec3) -> Vec3 {
        Quat::from_rotation_y(-self.rotation_deg.to_radians()) * d
    }

    /// Irradiance `∫ L(ω) max(0, n·ω) dω` on a surface with unit normal `n` (world space), by
    /// Ramamoorthi & Hanrahan's formula.
    pub fn irradiance(&self, n: Vec3) -> Rgb {
        self.sh.irradiance(self.to_map_frame(n)) * self.intensity
    }

    /// Transmitted irradiance `∫ L(ω) entry(n·ω) max(0, n·ω) dω` with the material's
    /// [`Entry`] term (Fresnel's transmittance, and for the bounded profiles the half-space
    /// albedo ratio), per channel. Exact for the 9-coefficient radiance: the kernel is zonal
    /// (see [`sh`]). Clamped at zero, where ringing of the truncated expansion could dip below it.
    pub fn transmitted_irradiance(&self, n: Vec3, entry: &Entry) -> Rgb {
        self.transmitted(n, entry).carried
    }

    /// [`Environment::transmitted_irradiance`] in every part of the entry term.
    pub fn transmitted(&self, n: Vec3, entry: &Entry) -> Entering {
        let d = self.to_map_frame(n);
        let part = |bands: &dyn Fn(usize) -> [f32; 3]| {
            let e = Rgb::new(
                self.sh.convolve(d, &BandWeights(bands(0))).x,
                self.sh.convolve(d, &BandWeights(bands(1))).y,
                self.sh.convolve(d, &BandWeights(bands(2))).z,
            );
            (e * self.intensity).max(Rgb::ZERO)
        };
        let carried = part(&|c| entry.band_weights(c));
        Entering {
            carried,
            local: part(&|c| entry.local_band_weights(c)),
            single: part(&|c| entry.single_band_weights(c)),
            carried_cos: carried * (2.0 / 3.0),
            flow: Vec3::ZERO,
        }
    }
}

/// Transmitted irradiance at a face in the two parts of the [`Entry`] term: what the profile
/// carries away, and what an oblique beam returns at the face itself (per channel, irradiance
/// units; see `bssrdf::entry`); and the exitance of the light scattered once there where the
/// profile does not carry it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Entering {
    /// Irradiance the diffusion profile spreads.
    pub carried: Rgb,
    /// Irradiance returned at the entry face (times the profile's total reflectance).
    pub local: Rgb,
    /// Exitance of the light scattered once that leaves directly at the face (radiant exitance,
    /// per channel; zero where the profile carries single scattering). The eye sees the direct
    /// light's along the view ray (`shading::single_scattering`); a bounce between parts sends
    /// it on.
    pub single: Rgb,
    /// `carried` times the cosine each part of it arrived at (the environment's at 2/3, the
    /// flux-weighted mean cosine of diffuse light): over `carried`, the mean incidence cosine
    /// the slab transmission reads (`solver::transmission`; unitless, 0..=1).
    pub carried_cos: Rgb,
    /// The direction the lights' carried light travels, each light's weighted by what it
    /// carries (summed over the channels; the environment's and bounced light, arriving from
    /// every side, add none): over `carried`'s channel sum, how much of it came as one beam, and
    /// from where (`shading::transmitted_exit`; irradiance units).
    pub flow: Vec3,
}

impl Entering {
    /// Adds light of irradiance `e` (already times its cosine) arriving at cosine `cos`.
    #[inline]
    pub fn add(&mut self, e: Rgb, entry: &Entry, cos: f32) {
        self.add_parts(e, entry, cos);
    }

    /// [`Entering::add`] for light travelling along the unit `travel`, which [`Entering::flow`]
    /// records.
    #[inline]
    pub fn add_beam(&mut self, e: Rgb, entry: &Entry, cos: f32, travel: Vec3) {
        let carried = self.add_parts(e, entry, cos);
        self.flow += travel * carried.element_sum();
    }

    /// Adds every part but the flow; returns what is carried.
    #[inline]
    fn add_parts(&mut self, e: Rgb, entry: &Entry, cos: f32) -> Rgb {
        let carried = e * entry.at(cos);
        self.carried += carried;
        self.local += e * entry.local_at(cos);
        self.single += e * entry.single_at(cos);
        self.carried_cos += carried * cos;
        carried
    }

    /// The mean incidence cosine of `carried`, per channel (1 where nothing is carried).
    #[inline]
    pub fn mean_cos(&self) -> Rgb {
        let c = self.carried;
        Rgb::new(
            if c.x > 0.0 { (self.carried_cos.x / c.x).clamp(0.0, 1.0) } else { 1.0 },
            if c.y > 0.0 { (self.carried_cos.y / c.y).clamp(0.0, 1.0) } else { 1.0 },
            if c.z > 0.0 { (self.carried_cos.z / c.z).clamp(0.0, 1.0) } else { 1.0 },
        )
    }
}

impl std::ops::Sub for Entering {
    type Output = Entering;
    /// Part by part, clamped at zero.
    fn sub(self, o: Entering) -> Entering {
        Entering {
            carried: (self.carried - o.carried).max(Rgb::ZERO),
            local: (self.local - o.local).max(Rgb::ZERO),
            single: (self.single - o.single).max(Rgb::ZERO),
            carried_cos: (self.carried_cos - o.carried_cos).max(Rgb::ZERO),
            flow: self.flow - o.flow,
        }
    }
}

impl std::ops::Mul<f32> for Entering {
    type Output = Entering;
    fn mul(self, k: f32) -> Entering {
        Entering {
            carried: self.carried * k,
            local: self.local * k,
            single: self.single * k,
            carried_cos: self.carried_cos * k,
            flow: self.flow * k,
        }
    }
}

impl std::ops::AddAssign for Entering {
    fn add_assign(&mut self, o: Entering) {
        self.carried += o.carried;
        self.local += o.local;
        self.single += o.single;
        self.carried_cos += o.carried_cos;
        self.flow += o.flow;
    }
}

/// Transmitted irradiance at every face centroid from `lights`, without shadows, through the
/// material's `entry` term ([`crate::bssrdf::Profile::entry`]).
pub fn face_irradiance(mesh: &Mesh, lights: &[Light], entry: &Entry) -> Vec<Rgb> {
    (0..mesh.triangles.len())
        .into_par_iter()
        .map(|f| {
            let p = mesh.face_centroid(f);
            let n = mesh.face_normal(f);
            lights.iter().map(|l| light_irradiance(l, p, n, entry)).sum()
        })
        .collect()
}

/// Transmitted irradiance at every face centroid from `lights` (shadowed where
/// `SceneLight::shadows` is set and a `caster` is given; call [`ShadowCaster::update`] after
/// the mesh moved) plus the `environment` (shadowed when a `caster` is given:
/// [`occlusion::blocked_environment`]), through the material's `entry` term.
pub fn face_irradiance_shadowed(
    mesh: &Mesh,
    lights: &[SceneLight],
    environment: Option<&Environment>,
    entry: &Entry,
    caster: Option<&ShadowCaster>,
) -> Vec<Rgb> {
    face_entering(mesh, lights, environment, entry, caster).into_iter().map(|e| e.carried).collect()
}

/// [`face_irradiance_shadowed`] in both parts of the entry term (what the profile carries, and
/// what returns at the face).
pub fn face_entering(
    mesh: &Mesh,
    lights: &[SceneLight],
    environment: Option<&Environment>,
    entry: &Entry,
    caster: Option<&ShadowCaster>,
) -> Vec<Entering> {
    face_entering_lit(mesh, lights, environment, entry, caster).0
}

/// [`face_entering`], and which faces each light reached ([`FaceLit`]).
pub fn face_entering_lit(
    mesh: &Mesh,
    lights: &[SceneLight],
    environment: Option<&Environment>,
    entry: &Entry,
    caster: Option<&ShadowCaster>,
) -> (Vec<Entering>, FaceLit) {
    let faces = mesh.triangles.len();
    let mut lit = vec![false; faces * lights.len()];
    let entering = if lights.is_empty() {
        (0..faces)
            .into_par_iter()
            .map(|f| face_entering_at(mesh, f, lights, environment, entry, caster, &mut []))
            .collect()
    } else {
        lit.par_chunks_mut(lights.len())
            .enumerate()
            .map(|(f, lit)| face_entering_at(mesh, f, lights, environment, entry, caster, lit))
            .collect()
    };
    (entering, FaceLit { lights: lights.len(), lit })
}

/// Face `f`'s transmitted irradiance (centroid), with `lit[i]` set where light `i` reached it.
fn face_entering_at(
    mesh: &Mesh,
    f: usize,
    lights: &[SceneLight],
    environment: Option<&Environment>,
    entry: &Entry,
    caster: Option<&ShadowCaster>,
    lit: &mut [bool],
) -> Entering {
    let p = mesh.face_centroid(f);
    let n = mesh.face_normal(f);
    let mut e = environment.map_or(Entering::default(), |env| {
        let open = env.transmitted(n, entry);
        match caster {
            Some(c) => open - occlusion::blocked_environment(env, entry, c, p, n, f),
            None => open,
        }
    });
    add_lights(&mut e, p, n, lights, entry, caster, lit);
    e
}

/// Per light and face, whether the face faces the light and the light reaches its centroid
/// (through the shadow test where the light casts shadows and a caster was given): what
/// [`face_entering_lit`] found, for the later stages that ask the same of the same rays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FaceLit {
    /// The number of lights.
    lights: usize,
    /// Face by face, a flag per light: `lit[f * lights + i]`.
    lit: Vec<bool>,
}

impl FaceLit {
    /// `lit[f * lights + i]`: whether light `i` reaches face `f`.
    pub(crate) fn new(lights: usize, lit: Vec<bool>) -> Self {
        FaceLit { lights, lit }
    }

    /// Whether light `i` reaches face `f` (`false` for a light or face it was not made for).
    pub fn get(&self, i: usize, f: usize) -> bool {
        i < self.lights && self.lit.get(f * self.lights + i).copied().unwrap_or(false)
    }

    /// Whether it was made for `lights` lights over `faces` faces.
    pub fn fits(&self, lights: usize, faces: usize) -> bool {
        self.lights == lights && self.lit.len() == lights * faces
    }
}

/// Adds to `e` the light of `lights` at point `p` of a surface with unit normal `n`, through
/// the `entry` term, each light shadowed where it says so and a `caster` is given; sets
/// `lit[i]` where light `i` arrives (`lit` may be shorter than `lights`: those are not told).
pub(crate) fn add_lights(
    e: &mut Entering,
    p: Vec3,
    n: Vec3,
    lights: &[SceneLight],
    entry: &Entry,
    caster: Option<&ShadowCaster>,
    lit: &mut [bool],
) {
    for (i, sl) in lights.iter().enumerate() {
        let Some(inc) = sl.light.incident(p) else {
            continue;
        };
        let cos = n.dot(inc.to_light);
        if cos <= 0.0 {
            continue;
        }
        if sl.shadows && caster.is_some_and(|c| !c.visible(p, n, &inc)) {
            continue;
        }
        if let Some(l) = lit.get_mut(i) {
            *l = true;
        }
        e.add_beam(inc.irradiance * cos, entry, cos, -inc.to_light);
    }
}
