//! Offscreen rendering of a mesh with per-vertex radiance to an image: the path of
//! `lucent render` and of the golden-image tests (Mertens 2003 §5.4).
//!
//! mesh pass (4x MSAA, [`HDR_FORMAT`]) ─► resolve ─► tone-map pass ([`LDR_FORMAT`]) ─► read-back.

use crate::context::{DEPTH_FORMAT, GpuContext, GpuError, HDR_FORMAT, LDR_FORMAT};
use crate::mesh_pass::{GpuMesh, MeshPass, Shading};
use crate::readback::read_texture;
use crate::tonemap::{ToneMap, ToneMapPass};
use lucent_core::camera::{CameraView, OrbitCamera};

/// Samples per pixel of the mesh pass (4 is guaranteed for the formats used).
pub const MSAA_SAMPLES: u32 = 4;

/// Everything that decides one image besides the mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width, pixels (1..=the device's max_texture_dimension_2d).
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Camera placement around the mesh's bounding sphere.
    pub camera: OrbitCamera,
    /// Fresnel, highlight and environment parameters.
    pub shading: Shading,
    /// Exposure and display curve.
    pub tone: ToneMap,
}

/// The render targets and passes for one image size. Reuse it for several frames.
pub struct OffscreenRenderer {
    width: u32,
    height: u32,
    msaa: wgpu::TextureView,
    depth: wgpu::TextureView,
    hdr: wgpu::Texture,
    hdr_view: wgpu::TextureView,
    ldr: wgpu::Texture,
    ldr_view: wgpu::TextureView,
    mesh_pass: MeshPass,
    tone_pass: ToneMapPass,
    tone_group: wgpu::BindGroup,
}

impl OffscreenRenderer {
    /// Creates targets of `width` x `height` and the pipelines.
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Result<Self, GpuError> {
        ctx.check_size(width, height)?;
        let device = &ctx.device;
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        let target = |label, format, samples, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let msaa =
            target("lucent hdr msaa", HDR_FORMAT, MSAA_SAMPLES, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let depth =
            target("lucent depth", DEPTH_FORMAT, MSAA_SAMPLES, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let hdr = target(
            "lucent hdr",
            HDR_FORMAT,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let ldr = target(
            "lucent ldr",
            LDR_FORMAT,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Device {
                during: format!("allocating {width}x{height} render targets"),
                message: e.to_string(),
            });
        }
        let mesh_pass = MeshPass::new(ctx, HDR_FORMAT, MSAA_SAMPLES)?;
        let tone_pass = ToneMapPass::new(ctx, LDR_FORMAT)?;
        let hdr_view = hdr.create_view(&Default::default());
        let tone_group = tone_pass.bind(ctx, &hdr_view);
        Ok(OffscreenRenderer {
            width,
            height,
            msaa: msaa.create_view(&Default::default()),
            depth: depth.create_view(&Default::default()),
            hdr,
            hdr_view,
            ldr_view: ldr.create_view(&Default::default()),
            ldr,
            mesh_pass,
            tone_pass,
            tone_group,
        })
    }

    /// Width and height of the targets, pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The mesh pass, e.g. to set an environment map.
    pub fn mesh_pass_mut(&mut self) -> &mut MeshPass {
        &mut self.mesh_pass
    }

    /// The camera `settings.camera` gives for `mesh` at this renderer's aspect ratio.
    pub fn camera_view(&self, mesh: &GpuMesh, camera: &OrbitCamera) -> CameraView {
        camera.frame(mesh.center, mesh.radius, self.width as f32 / self.height as f32)
    }

    /// Renders `mesh` seen by `camera` into the HDR and LDR targets and waits for the GPU.
    pub fn render(
        &self,
        ctx: &GpuContext,
        mesh: &GpuMesh,
        camera: &CameraView,
        shading: &Shading,
        tone: &ToneMap,
    ) -> Result<(), GpuError> {
        self.mesh_pass.prepare(ctx, camera, shading);
        self.tone_pass.prepare(ctx, tone)?;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lucent offscreen") });
        {
            let mut pass =
                MeshPass::begin(&mut encoder, "lucent mesh", &self.msaa, &self.hdr_view, &self.depth);
            self.mesh_pass.draw(&mut pass, mesh);
        }
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("lucent tone map"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.ldr_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.tone_pass.draw(&mut pass, &self.tone_group);
        }
        ctx.queue.submit([encoder.finish()]);
        ctx.wait("rendering")
    }

    /// The tone-mapped image of the last [`OffscreenRenderer::render`].
    pub fn read_image(&self, ctx: &GpuContext) -> Result<image::RgbaImage, GpuError> {
        read_texture(ctx, &self.ldr, 0)?.to_rgba_image()
    }

    /// The HDR radiance of the last render (alpha = coverage), rows top first.
    pub fn read_hdr(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>, GpuError> {
        read_texture(ctx, &self.hdr, 0)?.to_rgba_f32()
    }
}

/// Renders `mesh` once with `settings` and returns the tone-mapped image.
pub fn render_image(
    ctx: &GpuContext,
    mesh: &GpuMesh,
    settings: &RenderSettings,
) -> Result<image::RgbaImage, GpuError> {
    let r = OffscreenRenderer::new(ctx, settings.width, settings.height)?;
    let camera = r.camera_view(mesh, &settings.camera);
    r.render(ctx, mesh, &camera, &settings.shading, &settings.tone)?;
    r.read_image(ctx)
}
