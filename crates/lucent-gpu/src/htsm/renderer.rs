//! [`HtsmRenderer`]: the resources of one translucent object (mesh, density volume, reference
//! images, pipelines, output targets) and the frame (Shopf 2007 §4.3.5, "putting it all
//! together"): for every light in turn its reference images ([`super::reference`]), their mips
//! ([`super::mips`]) and its camera pass ([`super::camera_pass`]) adding into one HDR target,
//! then the shared tone map ([`crate::tonemap`]) into an image read back to the CPU or into a
//! caller's texture.

use super::camera_pass::CameraPass;
use super::diffusion::{DiffusionKey, DiffusionUniforms};
use super::environment::{environment_lights, write_uniforms};
use super::geometry::Geometry;
use super::medium::extinction_terms;
use super::mips::MipPass;
use super::pipeline::{FrameUniforms, LightUniforms, Uniforms, begin, cleared};
use super::reference::{LightFrustum, REFERENCE_IMAGES, ReferencePass};
use super::{HtsmError, HtsmMemory, HtsmParams, HtsmView, PHASE_TABLE_SIZE, TransportModel};
use crate::context::{DEPTH_FORMAT, GpuContext, HDR_FORMAT, LDR_FORMAT};
use crate::readback::read_texture;
use crate::tonemap::{ToneMap, ToneMapPass};
use glam::Vec3;
use lucent_core::irradiance::{Cone, Light};
use lucent_core::mesh::Mesh;
use lucent_core::volume::DensityVolume;
use std::time::{Duration, Instant};

/// The camera-side targets, re-created when the image size changes.
struct Targets {
    width: u32,
    height: u32,
    hdr: wgpu::Texture,
    hdr_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    ldr: wgpu::Texture,
    ldr_view: wgpu::TextureView,
    /// Tone-map bind groups reading `hdr`, by the tone-map pipeline's target format.
    tone_bind_groups: Vec<(wgpu::TextureFormat, wgpu::BindGroup)>,
}

/// An HTSM renderer for one mesh (deformable, fixed topology) and one density volume.
pub struct HtsmRenderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    geometry: Geometry,
    uniforms: Uniforms,
    reference: ReferencePass,
    mips: MipPass,
    camera: CameraPass,
    /// Tone-map pipelines by target format ([`LDR_FORMAT`] first, callers' formats on demand).
    tonemaps: Vec<(wgpu::TextureFormat, ToneMapPass)>,
    targets: Option<Targets>,
    /// The diffusion model's tables for the last medium and pattern they were made for.
    diffusion: Option<(DiffusionKey, DiffusionUniforms)>,
    /// Whether a frame whose tables are missing makes them ([`HtsmRenderer::set_make_tables`]).
    make_tables: bool,
}

/// One light pass of a frame: the light, and whether it adds the lit side's diffuse and
/// specular terms (the environment's stand-in lights do not; see [`super::environment`]).
struct LightPass {
    light: Light,
    surface: bool,
}

/// The frame's light passes: `view.lights`, then the environment's lights.
fn light_passes(view: &HtsmView) -> Result<Vec<LightPass>, HtsmError> {
    if view.lights.is_empty() && view.environment.is_none() {
        return Err(HtsmError::Light("no light and no environment: nothing lights the object".into()));
    }
    let mut passes: Vec<LightPass> =
        view.lights.iter().map(|&light| LightPass { light, surface: true }).collect();
    if let Some(env) = &view.environment {
        passes.extend(environment_lights(env).into_iter().map(|light| LightPass { light, surface: false }));
    }
    if passes.is_empty() {
        // A black environment alone: one dark pass still records coverage and the surface terms.
        let light = Light::Directional { direction: Vec3::NEG_Y, irradiance: Vec3::ZERO };
        passes.push(LightPass { light, surface: false });
    }
    Ok(passes)
}

impl HtsmRenderer {
    /// Uploads `mesh` at rest (with area-weighted vertex normals; its positions also become the
    /// rest positions that texture the density, see [`HtsmRenderer::set_positions`]) and `volume`
    /// (over the mesh's bounding box, with its full mip chain computed on the CPU), allocates
    /// `reference_size`^2 reference images (texels, 16 up to the adapter's 2D limit) with full
    /// mip chains, and builds the pipelines.
    pub fn new(
        ctx: &GpuContext,
        mesh: &Mesh,
        volume: &DensityVolume,
        reference_size: u32,
    ) -> Result<Self, HtsmError> {
        let device = &ctx.device;
        let geometry = Geometry::new(device, mesh)?;
        let max = device.limits().max_texture_dimension_2d;
        if reference_size < 16 || reference_size > max {
            return Err(HtsmError::Limits(format!(
                "reference image size {reference_size} (must be in 16..={max})"
            )));
        }
        let uniforms = Uniforms::new(device);
        let reference = ReferencePass::new(device, reference_size, &uniforms);
        let mips = MipPass::new(device, &reference);
        let camera = CameraPass::new(ctx, volume, &reference, &uniforms)?;
        let tonemaps = vec![(LDR_FORMAT, ToneMapPass::new(ctx, LDR_FORMAT)?)];
        ctx.check("creating the HTSM renderer")?;
        Ok(HtsmRenderer {
            device: device.clone(),
            queue: ctx.queue.clone(),
            geometry,
            uniforms,
            reference,
            mips,
            camera,
            tonemaps,
            targets: None,
            diffusion: None,
            make_tables: true,
        })
    }

    /// Deforms the mesh: `positions` (mesh units, one per vertex of the mesh given to
    /// [`HtsmRenderer::new`], same triangles) replace the current positions, and the normals
    /// are recomputed from them. The rest positions stay, and with them each surface point's
    /// texture coordinate: the density seen at a point is that of its rest position, so the
    /// volume's features move with the surface. In the camera pass the ray cast marches between
    /// rest texture coordinates while `D_i` is the deformed length (object units of the rest
    /// mesh: stretching the object lengthens paths and absorbs more). Takes effect at the next
    /// frame. Errors ([`HtsmError::Mesh`]) on a wrong count or a non-finite position.
    pub fn set_positions(&mut self, ctx: &GpuContext, positions: &[Vec3]) -> Result<(), HtsmError> {
        self.geometry.set_positions(&ctx.queue, positions)
    }

    /// Side of the (square) reference images at level 0, texels.
    pub fn reference_size(&self) -> u32 {
        self.reference.size
    }

    /// GPU memory of the HTSM data (not counting the camera-side output targets).
    pub fn memory(&self) -> HtsmMemory {
        HtsmMemory {
            reference_images: 3 * self.reference.image_bytes(),
            deformation_image: self.reference.image_bytes(),
            reference_depth: 4 * (self.reference.size as u64).pow(2),
            volume: self.camera.volume_bytes(),
            phase_table: 2 * PHASE_TABLE_SIZE as u64,
        }
    }

    /// The reference images' textures with their mip chains, in the order irradiance, texture
    /// coordinate, normal, deformation offset (all Rgba16Float, alpha = coverage; they hold the
    /// last light of the last frame), e.g. for inspection.
    pub fn reference_textures(&self) -> &[wgpu::Texture; REFERENCE_IMAGES] {
        &self.reference.textures
    }

    fn ensure_targets(&mut self, width: u32, height: u32) -> Result<(), HtsmError> {
        if let Some(t) = &self.targets
            && t.width == width
            && t.height == height
        {
            return Ok(());
        }
        let max = self.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(HtsmError::Limits(format!(
                "image size {width}x{height} (each side must be in 1..={max})"
            )));
        }
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        let make = |label: &str, format: wgpu::TextureFormat, usage: wgpu::TextureUsages| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        use wgpu::TextureUsages as U;
        let hdr = make("htsm hdr", HDR_FORMAT, U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC);
        let depth = make("htsm depth", DEPTH_FORMAT, U::RENDER_ATTACHMENT);
        let ldr = make("htsm ldr", LDR_FORMAT, U::RENDER_ATTACHMENT | U::COPY_SRC);
        self.targets = Some(Targets {
            width,
            height,
            hdr_view: hdr.create_view(&Default::default()),
            hdr,
            depth_view: depth.create_view(&Default::default()),
            ldr_view: ldr.create_view(&Default::default()),
            ldr,
            tone_bind_groups: Vec::new(),
        });
        Ok(())
    }

    /// The uniforms of one light pass; checks the light.
    fn light_uniforms(
        &self,
        pass: &LightPass,
        environment_surface: bool,
        params: &HtsmParams,
    ) -> Result<LightUniforms, HtsmError> {
        let frustum = LightFrustum::fit(self.geometry.sphere, &pass.light)?;
        let light = &pass.light;
        // Homogeneous: a positional light's position (w = 1), a distant one's unit direction of
        // travel (w = 0).
        let position = match light.position() {
            Some(p) => p.extend(1.0),
            None => light.direction().unwrap_or(Vec3::ZERO).normalize_or_zero().extend(0.0),
        };
        // Cone: unit axis (xyz) and half-angle (w), zero for none; its soft edge in `colour.w`.
        let (spot, soft_edge) = match light.cone() {
            None => ([0.0; 4], 0.0),
            Some(Cone { axis, half_angle, soft_edge }) => {
                let unit = axis.normalize_or_zero();
                if unit == Vec3::ZERO || !(half_angle > 0.0 && half_angle <= std::f32::consts::PI) {
                    return Err(HtsmError::Light(format!(
                        "spot light with axis {axis} and cone half-angle {half_angle} rad \
                         (needs a non-zero axis and an angle in (0, pi])"
                    )));
                }
                (unit.extend(half_angle).to_array(), soft_edge)
            }
        };
        let colour = light.power().extend(soft_edge);
        // Ring-1 radius: object units -> level-0 texels at the object's centre.
        let kernel_texels = params.kernel_radius * self.geometry.extent() / frustum.width_at_centre
            * self.reference.size as f32;
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        Ok(LightUniforms {
            view_proj: frustum.view_proj.to_cols_array_2d(),
            position: position.to_array(),
            colour: colour.to_array(),
            spot,
            flags: [kernel_texels, flag(pass.surface), flag(environment_surface), 0.0],
        })
    }

    /// Whether a frame makes the diffusion model's tables when the medium, index or pattern
    /// changed (`true`, the default: every image has its own medium's tables), or renders with
    /// the last tables it has (`false`; tables are made only when it has none). `false` is for
    /// an interactive caller that makes them on another thread ([`DiffusionUniforms::new`], up
    /// to seconds for a new medium) and hands them over with
    /// [`HtsmRenderer::set_diffusion_tables`], so that a frame never waits for them.
    pub fn set_make_tables(&mut self, make: bool) {
        self.make_tables = make;
    }

    /// Hands over the diffusion model's tables made elsewhere for `key`
    /// ([`DiffusionKey::of`]): frames of that medium use them instead of making their own.
    pub fn set_diffusion_tables(&mut self, key: DiffusionKey, tables: DiffusionUniforms) {
        if self.diffusion.as_ref().is_none_or(|(k, _)| *k != key) {
            self.diffusion = Some((key, tables));
        }
    }

    /// The diffusion model's tables for `params` (made when the medium, index or pattern
    /// changed, unless [`HtsmRenderer::set_make_tables`] said not to; zeros for the other
    /// models).
    fn diffusion_uniforms(&mut self, params: &HtsmParams) -> DiffusionUniforms {
        let Some(key) = DiffusionKey::of(params) else {
            return bytemuck::Zeroable::zeroed();
        };
        match &self.diffusion {
            Some((k, u)) if *k == key || !self.make_tables => *u,
            _ => {
                let u = DiffusionUniforms::new(&key);
                self.diffusion = Some((key, u));
                u
            }
        }
    }

    /// The uniforms shared by every pass of the frame.
    fn frame_uniforms(
        &self,
        view: &HtsmView,
        params: &HtsmParams,
        diffusion: DiffusionUniforms,
    ) -> FrameUniforms {
        let extent = self.geometry.extent();
        let (sigma_a, sigma_s, sigma_d) = extinction_terms(params);
        let mut u = FrameUniforms {
            view_proj: view.camera.view_proj.to_cols_array_2d(),
            box_min: self.geometry.box_min.extend(0.0).to_array(),
            box_size: self.geometry.box_size.extend(1.0 / extent).to_array(),
            eye: view.camera.eye.extend(1.0).to_array(),
            transport: params.transport_colour.extend(params.transport_distance).to_array(),
            sigma: sigma_a.extend(0.0).to_array(),
            scatter: sigma_s.extend(0.0).to_array(),
            density_absorption: sigma_d.extend(0.0).to_array(),
            material: [
                params.f0(),
                params.shadow_bias,
                (self.camera.density_levels - 1) as f32,
                if self.geometry.deformed { 1.0 } else { 0.0 },
            ],
            shading: [params.diffuse, params.specular, params.shininess, 0.0],
            counts: [
                params.samples as f32,
                params.steps as f32,
                match params.model {
                    TransportModel::Thesis => 0.0,
                    TransportModel::BeerLambert => 1.0,
                    TransportModel::Diffusion => 2.0,
                },
                *self.camera.density_dims.iter().max().expect("three sides") as f32,
            ],
            env_frame: [0.0; 4],
            env_irradiance: [[0.0; 4]; 9],
            env_radiance: [[0.0; 4]; 9],
            diffusion,
        };
        write_uniforms(view.environment.as_ref(), params.f0(), &mut u);
        u
    }

    /// Records every light's reference images, mips and camera pass into the HDR target (after
    /// queueing the uniforms and the phase table). Nothing is recorded on error.
    fn encode_frame(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<(), HtsmError> {
        self.ensure_targets(view.width, view.height)?;
        params.validate()?;
        let passes = light_passes(view)?;
        let lights = passes
            .iter()
            .enumerate()
            .map(|(i, p)| self.light_uniforms(p, i == 0 && view.environment.is_some(), params))
            .collect::<Result<Vec<_>, _>>()?;
        let diffusion = self.diffusion_uniforms(params);
        let frame = self.frame_uniforms(view, params, diffusion);
        self.uniforms.write(&self.device, &self.queue, &frame, &lights);
        self.camera.set_phase(&self.queue, params.phase_g);
        let t = self.targets.as_ref().expect("just ensured");
        for light in 0..lights.len() {
            self.reference.encode(encoder, &self.uniforms, light, &self.geometry);
            self.mips.encode(encoder, &self.reference);
            let order = (light == 0, light + 1 == lights.len());
            self.camera.encode(
                encoder,
                &t.hdr_view,
                &t.depth_view,
                order,
                &self.uniforms,
                light,
                &self.geometry,
            );
        }
        Ok(())
    }

    /// Records the tone map of the HDR target into `target` (format `format`, the HDR target's
    /// size), making the pipeline and bind group for `format` on first use.
    fn encode_tone_map(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
        tone: &ToneMap,
    ) -> Result<(), HtsmError> {
        self.ensure_tonemap(ctx, format)?;
        let pass = &self.tonemaps.iter().find(|(f, _)| *f == format).expect("just made").1;
        pass.prepare(ctx, tone)?;
        let t = self.targets.as_mut().expect("the frame made the targets");
        if !t.tone_bind_groups.iter().any(|(f, _)| *f == format) {
            t.tone_bind_groups.push((format, pass.bind(ctx, &t.hdr_view)));
        }
        let bind_group = &t.tone_bind_groups.iter().find(|(f, _)| *f == format).expect("just made").1;
        let mut render = begin(encoder, "htsm tonemap pass", &[cleared(target)], None);
        pass.draw(&mut render, bind_group);
        Ok(())
    }

    /// Builds the tone-map pipeline for target `format` unless there is one.
    fn ensure_tonemap(&mut self, ctx: &GpuContext, format: wgpu::TextureFormat) -> Result<(), HtsmError> {
        if !self.tonemaps.iter().any(|(f, _)| *f == format) {
            self.tonemaps.push((format, ToneMapPass::new(ctx, format)?));
        }
        Ok(())
    }

    fn encoder(&self) -> wgpu::CommandEncoder {
        self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("htsm frame") })
    }

    /// Records a whole frame into the caller's `encoder`, tone mapped into `target`: for
    /// drawing HTSM straight into a window's surface texture without a read-back.
    ///
    /// * `target`: a view of a texture exactly `view.width` x `view.height` (level 0), usable
    ///   as a render attachment, e.g. the surface texture's view. Every pixel is written: the
    ///   object tone mapped, the background colour of `params.tone` elsewhere.
    /// * `target_format`: the view's format (any renderable colour format; for an sRGB format
    ///   the shader pre-compensates, so the displayed values equal those of
    ///   [`HtsmRenderer::render`]). The first frame for each format builds its pipeline.
    ///
    /// Uniforms and the phase table go through `queue.write_*`, which lands at the *next*
    /// `queue.submit`: submit `encoder` before recording another HTSM frame with this renderer
    /// (one frame per submission). GPU validation errors are not returned here; they show in
    /// [`GpuContext::check`] after the submission. Errors: the same parameter, light and size
    /// errors as [`HtsmRenderer::render`], and [`HtsmError::Param`] when `target`'s texture is not
    /// `view.width` x `view.height` or not a render attachment; nothing is recorded then.
    pub fn encode_into(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        target_format: wgpu::TextureFormat,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<(), HtsmError> {
        let texture = target.texture();
        if (texture.width(), texture.height()) != (view.width, view.height) {
            return Err(HtsmError::Param(format!(
                "target texture is {}x{}, the view {}x{}",
                texture.width(),
                texture.height(),
                view.width,
                view.height
            )));
        }
        if !texture.usage().contains(wgpu::TextureUsages::RENDER_ATTACHMENT) {
            return Err(HtsmError::Param("target texture is not a render attachment".into()));
        }
        // Everything that can fail after recording has started is checked first.
        params.tone.validate()?;
        self.ensure_tonemap(ctx, target_format)?;
        self.encode_frame(encoder, view, params)?;
        self.encode_tone_map(ctx, encoder, target, target_format, &params.tone)
    }

    /// Renders one frame and reads it back: an sRGB-encoded RGBA8 image, `view.width` x
    /// `view.height`, rows top to bottom.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<image::RgbaImage, HtsmError> {
        let mut encoder = self.encoder();
        self.encode_frame(&mut encoder, view, params)?;
        let ldr_view = self.targets.as_ref().expect("encoded").ldr_view.clone();
        self.encode_tone_map(ctx, &mut encoder, &ldr_view, LDR_FORMAT, &params.tone)?;
        self.queue.submit([encoder.finish()]);
        ctx.check("rendering HTSM")?;
        let t = self.targets.as_ref().expect("encoded");
        Ok(read_texture(ctx, &t.ldr, 0)?.to_rgba_image()?)
    }

    /// Renders one frame and reads back the HDR radiance before tone mapping: RGBA `f32`,
    /// radiance summed over the lights, alpha = coverage (1 on the object, 0 elsewhere,
    /// radiance 0 there), rows top first.
    pub fn render_hdr(
        &mut self,
        ctx: &GpuContext,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<Vec<[f32; 4]>, HtsmError> {
        let mut encoder = self.encoder();
        self.encode_frame(&mut encoder, view, params)?;
        self.queue.submit([encoder.finish()]);
        ctx.check("rendering HTSM")?;
        let t = self.targets.as_ref().expect("encoded");
        Ok(read_texture(ctx, &t.hdr, 0)?.to_rgba_f32()?)
    }

    /// Renders one frame (every pass including the tone map, no read-back) and blocks until
    /// the queue has finished it (`device.poll(wait)`): the wall time from encoding to
    /// completion, for benchmarks.
    pub fn render_timed(
        &mut self,
        ctx: &GpuContext,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<Duration, HtsmError> {
        let start = Instant::now();
        let mut encoder = self.encoder();
        self.encode_frame(&mut encoder, view, params)?;
        let ldr_view = self.targets.as_ref().expect("encoded").ldr_view.clone();
        self.encode_tone_map(ctx, &mut encoder, &ldr_view, LDR_FORMAT, &params.tone)?;
        let index = self.queue.submit([encoder.finish()]);
        self.device
            .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
            .map_err(|e| HtsmError::Readback(e.to_string()))?;
        let elapsed = start.elapsed();
        ctx.check("rendering HTSM")?;
        Ok(elapsed)
    }
}
