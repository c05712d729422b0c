//! The [`Translucent`] component: what a translucent body is made of and how lucent solves it.

use bevy::prelude::*;
use lucent_core::bssrdf::{Material, ProfileKind};
use lucent_core::session::{FrameSettings, SolveMode, Transport};

/// Bounces of subsurface light between facing parts of a body by default (lucent's CLI, scenes
/// and viewer default for the `pbd` and `dipole` profiles, `ranges::DEFAULT_BOUNCES`).
pub const DEFAULT_BOUNCES: u32 = 3;

/// What a translucent body is made of.
#[derive(Clone, Debug, PartialEq)]
pub enum TranslucentMaterial {
    /// One of lucent's measured presets by name, case-insensitive: apple, chicken1, chicken2,
    /// cream, ketchup, marble, potato, skimmilk, skin1, skin2, wholemilk, wax (Jensen et al.
    /// 2001's table, ARCHITECTURE.md).
    Preset(String),
    /// A material by colour and distance, as artists give it (Blender's Principled BSDF):
    /// `albedo` is the linear RGB colour a flat, thick slab of it shows under uniform light
    /// (each 0.001..=0.999), `scatter_distance_mm` the reduced mean free path per channel in
    /// millimetres (each 0.0001..=1000), `eta` the relative index of refraction (1..=3; 1.3 is
    /// the presets'). See `lucent_core::bssrdf::Material::from_albedo_mfp`.
    Colour {
        /// Slab albedo per linear channel, 0.001..=0.999.
        albedo: [f32; 3],
        /// Reduced mean free path per channel, mm, 0.0001..=1000.
        scatter_distance_mm: [f32; 3],
        /// Relative index of refraction, 1..=3.
        eta: f32,
    },
}

impl Default for TranslucentMaterial {
    /// Marble.
    fn default() -> Self {
        TranslucentMaterial::Preset("marble".into())
    }
}

impl TranslucentMaterial {
    /// lucent's scattering coefficients, or a one-line error naming the bad value.
    pub fn resolve(&self) -> Result<Material, String> {
        match self {
            TranslucentMaterial::Preset(name) => Material::by_name(name).map_err(|e| e.to_string()),
            TranslucentMaterial::Colour { albedo, scatter_distance_mm, eta } => {
                let f = |v: [f32; 3]| v.map(f64::from);
                Material::from_albedo_mfp("colour", f(*albedo), f(*scatter_distance_mm), f64::from(*eta))
                    .map_err(|e| e.to_string())
            }
        }
    }
}

/// A body lucent solves: put it on an entity with a [`Mesh3d`] (a triangle list with normals).
/// The plugin replaces the entity's `MeshMaterial3d<StandardMaterial>`, if any, by a
/// [`crate::LucentMaterial`] that shows lucent's subsurface radiance with lucent's exit term.
///
/// Lengths: Bevy's world unit is taken as one metre. The body's mesh is solved in its own local
/// coordinates (lucent's "mesh units"); `scale_m` says how large it is.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Translucent {
    /// The scattering material. Default: marble.
    pub material: TranslucentMaterial,
    /// Model scale: the largest side of the mesh's bounding box in metres (> 0), which fixes how
    /// far light travels inside relative to the body. `None` (default): measured in the world,
    /// the mesh's largest local side times the entity's largest global scale, taken when the body
    /// is first solved.
    pub scale_m: Option<f32>,
    /// The diffusion profile: `Pbd` (photon beam diffusion, default), `Dipole` or `Mertens`.
    pub profile: ProfileKind,
    /// Bounces of subsurface light between facing parts of the body through the air, 0..=4.
    /// Default [`DEFAULT_BOUNCES`] (3).
    pub bounces: u32,
    /// Strength of the Fresnel-weighted Blinn-Phong highlight, 0 (none)..; default 1 (the
    /// physically weighted lobe, as `lucent render`).
    pub specular: f32,
    /// Blinn-Phong exponent of the highlight (> 0); default 64.
    pub shininess: f32,
}

impl Default for Translucent {
    fn default() -> Self {
        Translucent {
            material: TranslucentMaterial::default(),
            scale_m: None,
            profile: ProfileKind::default(),
            bounces: DEFAULT_BOUNCES,
            specular: 1.0,
            shininess: 64.0,
        }
    }
}

impl Translucent {
    /// A body of the preset `name` (see [`TranslucentMaterial::Preset`]).
    pub fn preset(name: &str) -> Self {
        Translucent { material: TranslucentMaterial::Preset(name.into()), ..default() }
    }

    /// With the model scale `scale_m` metres.
    pub fn with_scale(self, scale_m: f32) -> Self {
        Translucent { scale_m: Some(scale_m), ..self }
    }

    /// lucent's transport for this body at `scale_m` metres, or a one-line error.
    pub fn transport(&self, scale_m: f32) -> Result<Transport, String> {
        if !(scale_m.is_finite() && scale_m > 0.0) {
            return Err(format!("Translucent scale_m {scale_m} must be a positive number of metres"));
        }
        let mut t = Transport::new(self.material.resolve()?, f64::from(scale_m));
        t.profile = self.profile;
        Ok(t)
    }

    /// The session's settings: the hierarchical method in refit mode (links kept while lights
    /// move, and kept with their coefficients re-evaluated after a deformation: lucent's
    /// animation default) with the body's bounces.
    pub fn settings(&self) -> FrameSettings {
        FrameSettings { mode: SolveMode::Refit, bounces: self.bounces.min(4), ..Default::default() }
    }
}
