//! The material that shows lucent's solve in Bevy's pipeline: [`LucentMaterial`], a Bevy
//! [`Material`] whose vertex shader reads lucent's per-vertex radiance from a storage buffer and
//! whose fragment shader applies lucent's exit term (Mertens 2003 §5.4, as lucent-gpu's mesh
//! pass: `F_t(η, ω_o) (T(μ_o) B / (c π) + L_single)` plus the Fresnel-weighted highlight).

use crate::lights::MappedLight;
use bevy::asset::{Handle, uuid_handle};
use bevy::math::{UVec4, Vec3, Vec4};
use bevy::pbr::Material;
use bevy::prelude::*;
use bevy::render::render_resource::{AsBindGroup, ShaderType};
use bevy::render::storage::ShaderBuffer;
use bevy::shader::{Shader, ShaderRef};
use lucent_core::bssrdf::ExitLobe;
use lucent_core::session::Solved;

/// The shader of [`LucentMaterial`] (lucent.wgsl with lucent-gpu's shared shader files appended).
pub const LUCENT_SHADER: Handle<Shader> = uuid_handle!("6b1f0a52-3c1e-4e8e-9a55-2f51c0de5301");

/// Lights the highlight uses at most (as lucent's mesh pass).
pub const MAX_LIGHTS: usize = 8;

/// The shader source: lucent.wgsl, then lucent-gpu's `spot_falloff`, `fresnel_dielectric`,
/// `exit_lobe` and `add_highlight` (WGSL has no includes; the same files lucent's own mesh pass
/// prepends, so the two cannot drift apart).
pub fn shader_source() -> String {
    let spot = include_str!("../../lucent-gpu/src/shaders/spot.wgsl");
    let fresnel = include_str!("../../lucent-gpu/src/shaders/fresnel.wgsl");
    let exit = include_str!("../../lucent-gpu/src/shaders/exit.wgsl");
    format!("{}\n{}\n{}\n{}", include_str!("lucent.wgsl"), spot, fresnel, exit)
}

/// One light of the highlight, as the shader reads it.
#[derive(Clone, Copy, Debug, Default, ShaderType)]
pub struct LightUniform {
    /// xyz: world position (w = 1) or the direction the light travels (w = 0).
    pub position: Vec4,
    /// rgb: intensity (cd) or illuminance (lux); w: a spot's soft-edge fraction.
    pub intensity: Vec4,
    /// xyz: a spot's unit axis; w: its cone half-angle in radians (> π: no cone).
    pub spot: Vec4,
}

/// `light` as the highlight of [`LucentMaterial`]'s shader reads it (world units).
pub fn light_uniform(light: &MappedLight) -> LightUniform {
    // A cone wider than π is no cone (lucent-gpu's encoding of point lights).
    const NO_CONE: f32 = 4.0;
    match *light {
        MappedLight::Point { position, cd } => LightUniform {
            position: Vec3::from(position).extend(1.0),
            intensity: Vec3::from(cd).extend(0.0),
            spot: Vec4::new(0.0, 0.0, -1.0, NO_CONE),
        },
        MappedLight::Spot { position, axis, cd, cone, soft_edge } => LightUniform {
            position: Vec3::from(position).extend(1.0),
            intensity: Vec3::from(cd).extend(soft_edge),
            spot: Vec3::from(axis).extend(cone),
        },
        MappedLight::Directional { direction, lux } => LightUniform {
            position: Vec3::from(direction).extend(0.0),
            intensity: Vec3::from(lux).extend(0.0),
            spot: Vec4::new(0.0, 0.0, -1.0, NO_CONE),
        },
    }
}

/// What the fragment shader needs besides the per-vertex radiance.
#[derive(Clone, Copy, Debug, ShaderType)]
pub struct ShadingUniform {
    /// x: relative index of refraction η; y: highlight strength (0 = none); z: Blinn-Phong
    /// exponent; w: unused.
    pub params: Vec4,
    /// x: lights in use; y: 1 to blend single scattering linearly (lucent's ablation only).
    pub counts: UVec4,
    /// The lights of the highlight, world units.
    pub lights: [LightUniform; MAX_LIGHTS],
    /// The exit lobe `T(μ_o)` per channel at `μ_o = k / 32`.
    pub exit_lobe: [Vec4; ExitLobe::COUNT],
}

impl Default for ShadingUniform {
    fn default() -> Self {
        ShadingUniform {
            params: Vec4::new(1.3, 1.0, 64.0, 0.0),
            counts: UVec4::ZERO,
            lights: [LightUniform::default(); MAX_LIGHTS],
            exit_lobe: [Vec4::ONE; ExitLobe::COUNT],
        }
    }
}

impl ShadingUniform {
    /// `eta`, the highlight's `specular` strength and `shininess`, the `lights` (world units) and
    /// the solve's exit lobe and single-scattering blend.
    pub fn new(eta: f32, (specular, shininess): (f32, f32), lights: &[MappedLight], solved: &Solved) -> Self {
        let mut u = ShadingUniform {
            params: Vec4::new(eta, specular, shininess, 0.0),
            counts: UVec4::new(lights.len().min(MAX_LIGHTS) as u32, solved.linear_single as u32, 0, 0),
            ..Default::default()
        };
        for (slot, l) in u.lights.iter_mut().zip(lights) {
            *slot = light_uniform(l);
        }
        for (slot, t) in u.exit_lobe.iter_mut().zip(solved.exit_lobe.samples()) {
            *slot = Vec4::new(t[0], t[1], t[2], 0.0);
        }
        u
    }
}

/// The per-vertex records the vertex shader reads: `[B / (c π), L_single]` as two `vec4`s per
/// vertex of the Bevy mesh (radiance units of lucent: the mapped lights' cd/m² before exposure).
pub fn vertex_records(radiance: &[[f32; 3]], single: &[[f32; 3]]) -> Vec<[f32; 8]> {
    radiance
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let s = single.get(i).copied().unwrap_or([0.0; 3]);
            [r[0], r[1], r[2], 0.0, s[0], s[1], s[2], 0.0]
        })
        .collect()
}

/// A translucent body as Bevy draws it: lucent's solve per vertex, lucent's exit term per pixel.
/// The plugin makes one per [`crate::Translucent`] entity and keeps it current; users do not
/// make it themselves.
#[derive(Asset, TypePath, AsBindGroup, Clone, Debug)]
pub struct LucentMaterial {
    /// Index of refraction, highlight, lights and exit lobe.
    #[uniform(0)]
    pub shading: ShadingUniform,
    /// Per vertex of the Bevy mesh: `B / (c π)` and single-scattered radiance (see
    /// [`vertex_records`]); all zero (black) until the first solve arrives.
    #[storage(1, read_only, visibility(vertex))]
    pub per_vertex: Handle<ShaderBuffer>,
}

/// Bevy's mesh pipeline puts positions at shader location 0 and normals at 1, which is all the
/// vertex shader reads; prepass and shadows use Bevy's own shaders.
impl Material for LucentMaterial {
    fn vertex_shader() -> ShaderRef {
        LUCENT_SHADER.into()
    }

    fn fragment_shader() -> ShaderRef {
        LUCENT_SHADER.into()
    }
}
