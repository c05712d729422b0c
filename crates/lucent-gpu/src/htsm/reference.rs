//! Pass 1, the reference images (Shopf 2007 §4.3, fig. 4.2): the mesh seen from a light into
//! square images with full mip chains, irradiance transmitted through the surface, the lit
//! surface's 3D texture coordinate and its normal; plus a fourth image the thesis does not need,
//! the lit surface's deformation offset (see [`super::geometry`]). One set of images serves every
//! light of a frame in turn: each light's camera pass reads them before the next light's
//! reference pass overwrites them.

use super::pipeline::{
    DepthMode, Uniforms, begin, cleared, depth_attachment, mesh_pipeline, pipeline_layout, shader,
};
use super::{HtsmError, REFERENCE_FORMAT};
use crate::context::DEPTH_FORMAT;
use glam::{Mat4, Vec3};
use lucent_core::irradiance::Light;

/// Number of reference images: irradiance, texture coordinate, normal, deformation offset.
pub const REFERENCE_IMAGES: usize = 4;

/// The light's view and projection for the reference images, and the width of its frustum at
/// the object's centre (mesh units), used to convert the kernel radius to texels.
#[derive(Clone, Copy, Debug)]
pub struct LightFrustum {
    /// World to light clip.
    pub view_proj: Mat4,
    /// Width of the frustum at the bounding sphere's centre, mesh units.
    pub width_at_centre: f32,
}

impl LightFrustum {
    /// Fits the light's frustum to the object's bounding sphere (§4.3: a distant light is
    /// rendered from the minimum distance that captures the object, a point light from its
    /// position; a spot light like a point light, its cone applied per texel). Reads only the
    /// light's [`Light::position`] and [`Light::direction`], so any kind of light fits.
    /// `sphere` is the object's bounding sphere (centre, radius; mesh units).
    pub fn fit(sphere: (Vec3, f32), light: &Light) -> Result<LightFrustum, HtsmError> {
        let (centre, radius) = sphere;
        let up_for = |d: Vec3| {
            if d.dot(Vec3::Y).abs() > 0.99 { Vec3::X } else { Vec3::Y }
        };
        match light.position() {
            None => {
                let d = light.direction().unwrap_or(Vec3::ZERO).normalize_or_zero();
                if d == Vec3::ZERO {
                    return Err(HtsmError::Light("distant light has a zero direction".into()));
                }
                let eye = centre - d * 2.0 * radius;
                let view = Mat4::look_at_rh(eye, centre, up_for(d));
                let proj =
                    Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.5 * radius, 3.5 * radius);
                Ok(LightFrustum { view_proj: proj * view, width_at_centre: 2.0 * radius })
            }
            Some(position) => {
                let to_centre = centre - position;
                let dist = to_centre.length();
                if dist <= radius * 1.001 {
                    return Err(HtsmError::Light(format!(
                        "point light at {position} is inside the object's bounding sphere \
                         (centre {centre}, radius {radius}); HTSM renders the object from the light"
                    )));
                }
                let half = (radius / dist).asin() * 1.02;
                let view = Mat4::look_at_rh(position, centre, up_for(to_centre / dist));
                let near = ((dist - radius) * 0.9).max(dist * 1e-3);
                let proj = Mat4::perspective_rh(2.0 * half, 1.0, near, (dist + radius) * 1.1);
                Ok(LightFrustum { view_proj: proj * view, width_at_centre: 2.0 * dist * half.tan() })
            }
        }
    }
}

/// The reference images with their per-level views, the light-view depth buffer and the
/// pipeline that fills level 0.
pub(super) struct ReferencePass {
    pub size: u32,
    pub levels: u32,
    pub textures: [wgpu::Texture; REFERENCE_IMAGES],
    /// Per level, the single-level views (render attachments / mip sources).
    pub level_views: Vec<[wgpu::TextureView; REFERENCE_IMAGES]>,
    depth_view: wgpu::TextureView,
    pipeline: wgpu::RenderPipeline,
}

impl ReferencePass {
    /// Allocates `size`^2 images with full mip chains and builds the light pipeline.
    pub fn new(device: &wgpu::Device, size: u32, uniforms: &Uniforms) -> ReferencePass {
        let levels = 32 - size.leading_zeros();
        let extent = wgpu::Extent3d { width: size, height: size, depth_or_array_layers: 1 };
        let make = |label: &str| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: extent,
                mip_level_count: levels,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: REFERENCE_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let textures =
            [make("htsm irradiance"), make("htsm texcoord"), make("htsm normal"), make("htsm deformation")];
        let level_views = (0..levels)
            .map(|level| {
                textures.each_ref().map(|t| {
                    t.create_view(&wgpu::TextureViewDescriptor {
                        base_mip_level: level,
                        mip_level_count: Some(1),
                        ..Default::default()
                    })
                })
            })
            .collect();
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("htsm light depth"),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let module = shader(device, "htsm light", include_str!("../shaders/htsm_light.wgsl"));
        let targets: Vec<Option<wgpu::ColorTargetState>> =
            (0..REFERENCE_IMAGES).map(|_| Some(REFERENCE_FORMAT.into())).collect();
        let pipeline = mesh_pipeline(
            device,
            "htsm light pass",
            &module,
            &pipeline_layout(device, "htsm light", &[Some(uniforms.layout())]),
            ("vs_light", "fs_light"),
            DepthMode::NEAREST,
            &targets,
        );
        ReferencePass {
            size,
            levels,
            textures,
            level_views,
            depth_view: depth.create_view(&Default::default()),
            pipeline,
        }
    }

    /// Whole-chain views of the images, for sampling in the camera pass.
    pub fn full_views(&self) -> [wgpu::TextureView; REFERENCE_IMAGES] {
        self.textures.each_ref().map(|t| t.create_view(&Default::default()))
    }

    /// Bytes of one image with its mips (Rgba16Float texels).
    pub fn image_bytes(&self) -> u64 {
        let texels: u64 = (0..self.levels).map(|l| ((self.size >> l).max(1) as u64).pow(2)).sum();
        8 * texels
    }

    /// Records level 0 of the images for light slot `light`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &Uniforms,
        light: usize,
        geometry: &super::geometry::Geometry,
    ) {
        let colour = self.level_views[0].each_ref().map(cleared);
        let mut pass =
            begin(encoder, "htsm light pass", &colour, depth_attachment(&self.depth_view, true, false));
        pass.set_pipeline(&self.pipeline);
        uniforms.bind(&mut pass, light);
        geometry.draw(&mut pass);
    }
}
