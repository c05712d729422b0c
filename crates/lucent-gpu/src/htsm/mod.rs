//! Heterogeneous Translucent Shadow Maps (Shopf 2007, "Interactive Rendering of Heterogeneous
//! Translucent Objects", chapter 4).
//!
//! A translucent object is a mesh plus a [`DensityVolume`] over its rest bounding box (§4.2).
//! Each frame runs, for every light in turn (files in brackets):
//!
//! 1. **Reference images** (§4.3, fig. 4.2; [`reference`](mod@reference)): the mesh seen from the light into
//!    images of the irradiance transmitted through the surface (Schlick's Fresnel) times the
//!    light colour, the 3D texture coordinate of the lit surface (its rest position in the
//!    volume's `[0,1]^3` box), its normal, and (not in the thesis) its deformation offset.
//!    Alpha holds coverage. A perspective view for a point or spot light, an orthographic view
//!    fitted to the bounding sphere for a distant one ([`LightFrustum`]).
//! 2. **Mips** (§4.3.1; [`mips`]): a full chain for each image by 2x2 averaging; texture
//!    coordinates and offsets are normalised by coverage when sampled, so they average covered
//!    texels only.
//! 3. **Camera pass** (§4.3.1-§4.3.5, table 4.1; [`camera_pass`]): for each visible point,
//!    `n` = 1, 5, 9 or 13 samples of the reference images in the hierarchical pattern of
//!    fig. 4.3 (the centre at level 0, then rings of 4 at doubling radius, one mip level coarser
//!    per ring); for each, a `K`-step ray cast through the density texture from the point to
//!    the sample's lit surface gives the absorption `alpha_i` (`sigma_at = sigma_a + density`,
//!    eq. 4.1), the ray length is `D_i`, and a Henyey-Greenstein table gives the phase
//!    `f(theta_i)`. [`TransportModel`] turns these into transmitted light; Lambert and
//!    Blinn-Phong shading are added on the lit side. The first light's pass writes an HDR
//!    target, each further light's pass adds to it (additive blending, same depth).
//!
//! then **tone mapping** with lucent's shared pass ([`crate::tonemap`]) into an 8-bit image read
//! back to the CPU ([`HtsmRenderer::render`]) or into a caller's texture, e.g. a window's
//! surface ([`HtsmRenderer::encode_into`]). [`renderer`] holds the resources and the frame;
//! [`pipeline`] and [`geometry`] the plumbing they share.
//!
//! # Lights and environment
//!
//! [`HtsmView::lights`] takes any number of point, spot and distant lights; a spot's cone
//! (with its soft edge, as `lucent_core::irradiance::spot_falloff`) scales the irradiance of its
//! reference image and of its surface terms. A spherical-harmonic [`Environment`], which the
//! thesis cannot render (§5.4), is approximated by eight distant lights that match its radiance
//! to SH band 1 for the subsurface transport, and by its full nine-coefficient irradiance for the
//! lit side's diffuse term ([`environment`] says exactly what is approximated).
//!
//! # Deformation
//!
//! [`HtsmRenderer::set_positions`] moves the vertices; the rest positions stay as a vertex
//! attribute, so every surface point keeps its rest texture coordinate and the density volume
//! follows the mesh. The ray cast marches from the visible point's to the lit sample's texture
//! coordinate (rest space) while `D_i` is the deformed length of that ray ([`geometry`]).
//!
//! # Units
//!
//! *Object units*: mesh units divided by the rest mesh's largest bounding-box side, so a
//! transport distance of 0.5 is half the object's size whatever its scale. Ray lengths `D_i`,
//! the transport distance `T_d`, the kernel radius and the density scale (per object unit) use
//! them.
//!
//! # Limits (Shopf §5.4)
//!
//! The space between a lit and a visible surface is assumed to be inside the object (convexity):
//! concave objects absorb light in the gaps. Transport is forward only (no back-scattering).
//! Each light costs one reference pass, one mip chain and one camera pass.

pub mod camera_pass;
pub mod diffusion;
pub mod environment;
pub mod geometry;
pub mod medium;
pub mod mips;
pub mod pipeline;
pub mod reference;
pub mod renderer;

use crate::tonemap::ToneMap;
use glam::Vec3;
use lucent_core::camera::CameraView;
use lucent_core::irradiance::{Environment, Light};
use lucent_core::mesh::Mesh;
use lucent_core::volume::DensityVolume;

pub use environment::{ENVIRONMENT_LIGHTS, environment_lights};
pub use medium::{HtsmCoefficients, HtsmMedium};
pub use reference::{LightFrustum, REFERENCE_IMAGES};
pub use renderer::HtsmRenderer;

/// The reference images' texel format: HDR irradiance and texture coordinates need more than
/// 8 bits, and Rgba32Float is neither filterable nor renderable everywhere (lavapipe, GL).
pub const REFERENCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The density texture's format: 8 bits per voxel is the thesis's 64^3 budget and is filterable
/// on every backend, including its 3D mips.
pub const DENSITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// Entries in the Henyey-Greenstein table (indexed by `cos(theta) * 0.5 + 0.5`).
pub const PHASE_TABLE_SIZE: u32 = 256;

/// Errors of the HTSM renderer.
#[derive(Debug, thiserror::Error)]
pub enum HtsmError {
    /// A parameter outside its documented range.
    #[error("invalid HTSM parameter: {0}")]
    Param(String),
    /// The mesh cannot be rendered (empty, or a flat bounding box).
    #[error("mesh unusable for HTSM: {0}")]
    Mesh(String),
    /// The lights cannot be handled: none and no environment, a point or spot light inside the
    /// object's bounding sphere, a zero direction or a spot cone outside `(0, pi]`.
    #[error("light unusable for HTSM: {0}")]
    Light(String),
    /// A size beyond the adapter's limits.
    #[error("{0} exceeds the adapter's limits")]
    Limits(String),
    /// Reading the image back from the GPU failed.
    #[error("reading the image back from the GPU failed: {0}")]
    Readback(String),
    /// wgpu reported an error (validation, out of memory, no adapter).
    #[error(transparent)]
    Gpu(#[from] crate::context::GpuError),
}

/// How the transmitted light is computed from `D_i`, `alpha_i` and `f(theta_i)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TransportModel {
    /// Shopf's table 4.1:
    /// `L = T_c (1/n) sum_i E_i max(0, (2 T_d - (D_i + alpha_i)) / T_d) f(theta_i)`.
    /// The printed equation has neither the sample irradiance `E_i` nor the clamp; both are
    /// needed (the shader says why).
    Thesis,
    /// Physically based: `L = (1/n) sum_i E_i exp(-sigma D_i - alpha_i) f(theta_i)`, the
    /// exponent being the optical depth along the ray: with a [`HtsmParams::medium`], the
    /// integral of the diffusion transport coefficient ([`medium`]); without, `sigma =
    /// -ln(T_c) / T_d` per channel (glTF `KHR_materials_volume`'s definition of attenuation
    /// colour and distance) and `alpha_i` the density times `density_scale`.
    #[default]
    BeerLambert,
    /// The diffusion quadrature ([`diffusion`], issue 55): each sample weighs the medium's
    /// diffusion kernel along its ray integrated over the annulus it stands for, times the
    /// half-space's albedo where the light reaches the visible point and the exact slab
    /// transmittance where it crosses the body (the slab as thick as the ray's extent along the
    /// light; that light leaves by diffusion's exit lobe). Needs [`HtsmParams::medium`]; the
    /// phase weight is not used.
    Diffusion,
}

/// Material and sampling parameters of an HTSM render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HtsmParams {
    /// Sample rays per pixel `n`: 1, 5, 9 or 13 (fig. 4.3). Default 9.
    pub samples: u32,
    /// Ray-cast steps per sample ray `K`, at least 1. Default 16.
    pub steps: u32,
    /// Transport colour `T_c`, each channel in `(0, 1]`: the colour light takes after `T_d`
    /// through the base material (§4.3.3). Default (0.9, 0.6, 0.3), a wax-like orange.
    pub transport_colour: Vec3,
    /// Transport distance `T_d`, object units, > 0. Default 0.5 (half the object's size).
    pub transport_distance: f32,
    /// Henyey-Greenstein asymmetry `g` in `(-1, 1)`: > 0 forward scattering. Default 0.3.
    pub phase_g: f32,
    /// Extra absorption of density 1, per object unit: the density term of `sigma_at`
    /// (eq. 4.1) is `density_scale * density`. Default 20. Unused when [`HtsmParams::medium`]
    /// is set.
    pub density_scale: f32,
    /// The medium in physical coefficients ([`medium`]), or `None` (the default): the
    /// attenuation then comes from `transport_colour`, `transport_distance` and
    /// `density_scale` as [`medium`]'s last section says. Set it with [`HtsmMedium::apply`],
    /// which also derives `transport_colour` and `transport_distance` from it.
    pub medium: Option<HtsmCoefficients>,
    /// Transport model. Default [`TransportModel::BeerLambert`]: it keeps the thesis's inputs
    /// but ties colour to path length (thin parts pale, thick parts saturated, the correlation
    /// §4.1.1 asks for); [`TransportModel::Thesis`] tints everything with `T_c` alike.
    pub model: TransportModel,
    /// Radius of the first sampling ring, object units (rings 2 and 3 are 2x and 4x). Default
    /// 0.04.
    pub kernel_radius: f32,
    /// Relative index of refraction for Schlick's Fresnel. Default 1.3.
    pub eta: f32,
    /// Weight of the Lambertian surface term on the lit side (times `T_c`). Default 0.3.
    pub diffuse: f32,
    /// Weight of the Blinn-Phong specular term. Default 1.
    pub specular: f32,
    /// Blinn-Phong exponent. Default 60.
    pub shininess: f32,
    /// Shadow-test tolerance: a point is lit when the reference image's surface is within this
    /// distance of it, object units. Default 0.02.
    pub shadow_bias: f32,
    /// Exposure, tone curve and background of the final image (the shared tone-map pass).
    pub tone: ToneMap,
}

impl Default for HtsmParams {
    fn default() -> Self {
        HtsmParams {
            samples: 9,
            steps: 16,
            transport_colour: Vec3::new(0.9, 0.6, 0.3),
            transport_distance: 0.5,
            phase_g: 0.3,
            density_scale: 20.0,
            medium: None,
            model: TransportModel::BeerLambert,
            kernel_radius: 0.04,
            eta: 1.3,
            diffuse: 0.3,
            specular: 1.0,
            shininess: 60.0,
            shadow_bias: 0.02,
            tone: ToneMap::default(),
        }
    }
}

impl HtsmParams {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<(), HtsmError> {
        let bad = |m: String| Err(HtsmError::Param(m));
        if ![1, 5, 9, 13].contains(&self.samples) {
            return bad(format!("samples {} is not 1, 5, 9 or 13", self.samples));
        }
        if self.steps == 0 || self.steps > 1024 {
            return bad(format!("steps {} is not in 1..=1024", self.steps));
        }
        let c = self.transport_colour;
        if !(c.cmpgt(Vec3::ZERO).all() && c.cmple(Vec3::ONE).all()) {
            return bad(format!("transport colour {c} must have every channel in (0, 1]"));
        }
        if !(self.transport_distance.is_finite() && self.transport_distance > 0.0) {
            return bad(format!("transport distance {} must be > 0", self.transport_distance));
        }
        if !(self.phase_g > -1.0 && self.phase_g < 1.0) {
            return bad(format!("phase g {} must be in (-1, 1)", self.phase_g));
        }
        for (name, v) in [
            ("density scale", self.density_scale),
            ("kernel radius", self.kernel_radius),
            ("diffuse", self.diffuse),
            ("specular", self.specular),
            ("shininess", self.shininess),
            ("shadow bias", self.shadow_bias),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} {v} must be finite and >= 0"));
            }
        }
        if let Some(m) = self.medium {
            for v in [m.sigma_a, m.sigma_s_prime, m.density_sigma_a] {
                if !(v.is_finite() && v.cmpge(Vec3::ZERO).all()) {
                    return bad(format!("medium coefficient {v} per object unit must be finite and >= 0"));
                }
            }
        }
        if self.model == TransportModel::Diffusion && self.medium.is_none() {
            return bad("the diffusion model needs the medium's coefficients (HtsmParams::medium; \
                        the former transport colour and distance inputs have none)"
                .into());
        }
        if !(self.eta.is_finite() && self.eta >= 1.0) {
            return bad(format!("eta {} must be >= 1", self.eta));
        }
        Ok(())
    }

    /// Per-channel Beer-Lambert attenuation `sigma = -ln(T_c) / T_d`, per object unit.
    pub fn sigma(&self) -> Vec3 {
        -self.transport_colour.map(f32::ln) / self.transport_distance
    }

    /// Schlick's `F0 = ((eta - 1) / (eta + 1))^2`.
    pub fn f0(&self) -> f32 {
        ((self.eta - 1.0) / (self.eta + 1.0)).powi(2)
    }
}

/// Henyey-Greenstein phase function times `4 pi`, so that isotropic scattering weighs 1:
/// `4 pi p(cos) = (1 - g^2) / (1 + g^2 - 2 g cos)^(3/2)`. `cos` is the cosine between the
/// sample ray and `-N` (§4.3.4).
pub fn henyey_greenstein(g: f32, cos: f32) -> f32 {
    (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos).max(1e-6).powf(1.5)
}

/// The phase table uploaded to the GPU: entry `i` is [`henyey_greenstein`] at
/// `cos = 2 (i + 0.5) / PHASE_TABLE_SIZE - 1` (texel centres of a linear-filtered texture).
pub fn phase_table(g: f32) -> Vec<f32> {
    (0..PHASE_TABLE_SIZE)
        .map(|i| {
            let cos = 2.0 * (i as f32 + 0.5) / PHASE_TABLE_SIZE as f32 - 1.0;
            henyey_greenstein(g, cos)
        })
        .collect()
}

/// Where the camera is, what lights the object, and the image size.
#[derive(Clone, Debug, PartialEq)]
pub struct HtsmView {
    /// The camera (e.g. [`lucent_core::camera::OrbitCamera::frame`]), mesh units.
    pub camera: CameraView,
    /// Point, spot and distant lights (positions in mesh units, outside the object's bounding
    /// sphere), each rendered through its own reference images and added up. May be empty
    /// when there is an environment; with neither, rendering fails with [`HtsmError::Light`].
    pub lights: Vec<Light>,
    /// A distant SH environment, or `None`. See [`environment`] for how HTSM renders it.
    pub environment: Option<Environment>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// GPU memory held by an [`HtsmRenderer`], bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HtsmMemory {
    /// The thesis's three reference images (irradiance, texture coordinate, normal) with their
    /// mip chains, shared by all lights.
    pub reference_images: u64,
    /// The fourth reference image with its mip chain, the deformation offset (not in the thesis:
    /// it serves [`HtsmRenderer::set_positions`]).
    pub deformation_image: u64,
    /// The light-view depth buffer used to render them.
    pub reference_depth: u64,
    /// The density volume with its mip chain.
    pub volume: u64,
    /// The phase table.
    pub phase_table: u64,
}

impl HtsmMemory {
    /// What the thesis counts (§5.2, "~3 MB"): its three reference images plus the density
    /// volume (not the deformation image).
    pub fn thesis_bytes(&self) -> u64 {
        self.reference_images + self.volume
    }
}

/// Dimensions of a density grid over `mesh`'s bounding box whose largest side has `largest`
/// voxels and whose other sides follow the box's proportions (at least 4 voxels), so that
/// voxels are close to cubes.
pub fn volume_dims_for(mesh: &Mesh, largest: u32) -> [u32; 3] {
    let (lo, hi) = mesh.bounds();
    let size = hi - lo;
    let extent = size.max_element().max(f32::MIN_POSITIVE);
    [size.x, size.y, size.z]
        .map(|s| ((s / extent * largest as f32).round() as u32).clamp(4.min(largest), largest))
}

/// Checks that `volume` is usable with a mesh (dimensions within the 3D texture limits).
pub(crate) fn check_volume(volume: &DensityVolume, limits: &wgpu::Limits) -> Result<(), HtsmError> {
    let max = limits.max_texture_dimension_3d;
    if volume.dims.iter().any(|&d| d > max) {
        return Err(HtsmError::Limits(format!(
            "density volume {:?} (3D texture side limit {max})",
            volume.dims
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phase_table_is_normalised_to_isotropic() {
        // Integral over the sphere of p = 1: with the 4 pi factor, the mean over cos in [-1, 1]
        // of the table (uniform in cos is uniform in solid angle) must be 1.
        for g in [-0.5f32, 0.0, 0.3, 0.8] {
            let t = phase_table(g);
            let mean = t.iter().map(|&v| v as f64).sum::<f64>() / t.len() as f64;
            assert!((mean - 1.0).abs() < 0.01, "g {g}: mean {mean}");
        }
        assert_eq!(henyey_greenstein(0.0, 0.3), 1.0);
    }

    #[test]
    fn beer_lambert_sigma_reproduces_the_transport_colour_at_the_transport_distance() {
        let p = HtsmParams::default();
        let t = (-p.sigma() * p.transport_distance).exp();
        assert!((t - p.transport_colour).abs().max_element() < 1e-6);
    }

    #[test]
    fn params_are_validated() {
        assert!(HtsmParams::default().validate().is_ok());
        for bad in [
            HtsmParams { samples: 4, ..Default::default() },
            HtsmParams { steps: 0, ..Default::default() },
            HtsmParams { transport_colour: Vec3::new(0.0, 0.5, 0.5), ..Default::default() },
            HtsmParams { transport_distance: 0.0, ..Default::default() },
            HtsmParams { phase_g: 1.0, ..Default::default() },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }
}
