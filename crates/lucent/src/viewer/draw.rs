//! The 3D view (Mertens §5.4) drawn with `lucent-gpu`'s passes into the window: the mesh pass
//! (per-vertex `B/pi`, exit Fresnel per pixel, highlight) into an HDR target with 4x MSAA, then
//! the tone-map pass (exposure, gamma curve, background) into the colour target, both restricted
//! to the viewport beside the panel. The HDR targets have the size of the whole colour target so
//! that the tone-map pass reads the texel under each pixel. With an environment chosen, the mesh
//! pass also reflects a small copy of the map, Fresnel-weighted (§5.4).

use super::state::EnvChoice;
use lucent_core::Rgb;
use lucent_core::camera::CameraView;
use lucent_core::irradiance::EnvMap;
use lucent_core::mesh::Mesh;
use lucent_core::mesh::texture::{Texture, UvSplit};
use lucent_gpu::mesh_pass::{AlbedoMap, EnvironmentMap, GpuMesh, MeshPass, Shading};
use lucent_gpu::tonemap::{ToneMap, ToneMapPass};
use lucent_gpu::{DEPTH_FORMAT, GpuContext, HDR_FORMAT};

/// Background of the 3D view, display values 0..1 (the Xvfb test compares against it).
pub const BACKGROUND: [f32; 3] = [0.055, 0.06, 0.07];

/// Samples per pixel of the mesh pass.
const MSAA_SAMPLES: u32 = 4;

/// Radiance `B/pi` a new mesh is drawn with before its first solution: a dim grey that shows
/// its shape against the background.
pub const PLACEHOLDER_RADIANCE: Rgb = Rgb::splat(0.03);

/// Viewport rectangle in physical pixels of the colour target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Left edge.
    pub x: f32,
    /// Top edge.
    pub y: f32,
    /// Width (>= 1).
    pub width: f32,
    /// Height (>= 1).
    pub height: f32,
}

/// Everything one draw of the 3D view needs besides the mesh.
#[derive(Clone, Debug)]
pub struct DrawParams {
    /// Camera matrices for the viewport's aspect ratio.
    pub camera: CameraView,
    /// Mesh-pass shading (eta, lights for the highlight).
    pub shading: Shading,
    /// Exposure and tone curve.
    pub tone: ToneMap,
}

/// HDR, resolve and depth targets of one size, with the tone-map bind group reading them.
struct Targets {
    size: (u32, u32),
    msaa: wgpu::TextureView,
    resolved: wgpu::TextureView,
    depth: wgpu::TextureView,
    tone_group: wgpu::BindGroup,
}

/// The view's passes, the mesh on the GPU, and the targets.
pub struct ViewDrawer {
    mesh_pass: MeshPass,
    tone_pass: ToneMapPass,
    mesh: Option<GpuMesh>,
    topology: (usize, usize),
    targets: Option<Targets>,
    srgb_target: bool,
    /// The chosen map, downsampled for the reflection (`None` inside: none or unreadable).
    env_map: Option<(EnvChoice, Option<EnvMap>)>,
    /// The choice and rotation (in map columns) on the GPU now.
    env_uploaded: Option<(EnvChoice, i64)>,
    /// The mesh's colour texture, if it has one.
    texture: Option<Textured>,
}

/// A colour texture as the mesh pass draws it: the radiance times its square root per pixel
/// (the exit half of `lucent_core::mesh::texture`; the worker's session applies the entry half).
struct Textured {
    /// UV of each corner of each triangle of the loaded mesh.
    corner_uvs: Vec<[glam::Vec2; 3]>,
    /// The GPU mesh's vertices: the mesh's split at its UV seams (for the current topology).
    split: Option<UvSplit>,
    /// Kept alive for the mesh pass's bind group.
    _map: AlbedoMap,
}

/// Size of the map copy the reflection samples (mirror reflection of a smooth surface: detail
/// beyond this is lost in the Fresnel weight anyway).
const REFLECTION_SIZE: (usize, usize) = (256, 128);

impl ViewDrawer {
    /// Builds the passes for colour targets of `format`.
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> anyhow::Result<Self> {
        Ok(ViewDrawer {
            mesh_pass: MeshPass::new(ctx, HDR_FORMAT, MSAA_SAMPLES)?,
            tone_pass: ToneMapPass::new(ctx, format)?,
            mesh: None,
            topology: (0, 0),
            targets: None,
            srgb_target: format.is_srgb(),
            env_map: None,
            env_uploaded: None,
            texture: None,
        })
    }

    /// Draws meshes with `texture` (its UVs must fit the mesh given to
    /// [`ViewDrawer::set_geometry`]; a mesh of another topology is drawn untextured).
    pub fn set_texture(&mut self, ctx: &GpuContext, texture: &Texture) -> anyhow::Result<()> {
        let image = &texture.image;
        let map = AlbedoMap::from_rgb(ctx, image.width, image.height, &image.texels)?;
        self.mesh_pass.set_albedo(ctx, &map);
        self.texture = Some(Textured { corner_uvs: texture.corner_uvs.clone(), split: None, _map: map });
        self.mesh = None;
        Ok(())
    }

    /// Whether the last [`ViewDrawer::set_environment`] set a map.
    pub fn reflects(&self) -> bool {
        matches!(self.env_map, Some((_, Some(_)))) && self.env_uploaded.is_some()
    }

    /// Sets the map that the Fresnel-weighted reflection samples: `choice`'s map (the compiled-in
    /// probe, loaded once per choice), rotated by `rotation_deg` about +Y to the nearest map column, as the SH
    /// lighting is. Returns whether a map is set (false for none or an unreadable file).
    pub fn set_environment(&mut self, ctx: &GpuContext, choice: EnvChoice, rotation_deg: f32) -> bool {
        if self.env_map.as_ref().is_none_or(|(c, _)| *c != choice) {
            let loaded = choice.load().map(|r| r.map_err(|e| log::warn!("environment reflection: {e}")));
            let map =
                loaded.and_then(Result::ok).map(|m| m.downsampled(REFLECTION_SIZE.0, REFLECTION_SIZE.1));
            self.env_map = Some((choice, map));
            self.env_uploaded = None;
        }
        let Some((_, Some(map))) = &self.env_map else { return false };
        let columns = (rotation_deg / 360.0 * map.width as f32).round() as i64;
        if self.env_uploaded != Some((choice, columns)) {
            let rotated = map.rotated(rotation_deg);
            let texels: Vec<[f32; 4]> = rotated.texels.iter().map(|t| t.extend(1.0).to_array()).collect();
            match EnvironmentMap::from_rgba_f32(ctx, map.width as u32, map.height as u32, &texels) {
                Ok(gpu) => self.mesh_pass.set_environment(ctx, &gpu),
                Err(e) => {
                    log::warn!("environment reflection: {e}");
                    return false;
                }
            }
            self.env_uploaded = Some((choice, columns));
        }
        true
    }

    /// Uploads `mesh`'s positions and normals: in place when the topology is unchanged
    /// (deformation), else as a new GPU mesh shown in [`PLACEHOLDER_RADIANCE`] until its first
    /// solve arrives (a large mesh's first link can take seconds).
    pub fn set_geometry(&mut self, ctx: &GpuContext, mesh: &Mesh) -> anyhow::Result<()> {
        let normals = mesh.vertex_normals();
        let topology = (mesh.positions.len(), mesh.triangles.len());
        let split = self.texture.as_ref().and_then(|t| t.split.as_ref());
        match &self.mesh {
            Some(gpu) if self.topology == topology => {
                let (p, n) = (UvSplit::through(split, &mesh.positions), UvSplit::through(split, &normals));
                gpu.update_geometry(ctx, &p, &n)?;
            }
            _ => {
                let fits = |t: &&mut Textured| t.corner_uvs.len() == mesh.triangles.len();
                self.mesh = Some(match self.texture.as_mut().filter(fits) {
                    Some(t) => {
                        let s = UvSplit::new(mesh, &t.corner_uvs);
                        let (p, n) = (s.gather(&mesh.positions), s.gather(&normals));
                        let grey = vec![PLACEHOLDER_RADIANCE; p.len()];
                        let gpu = GpuMesh::with_uvs(ctx, &p, &n, &grey, &s.triangles, &s.uvs)?;
                        t.split = Some(s);
                        gpu
                    }
                    None => {
                        if let Some(t) = self.texture.as_mut() {
                            t.split = None;
                        }
                        let grey = vec![PLACEHOLDER_RADIANCE; mesh.positions.len()];
                        GpuMesh::new(ctx, &mesh.positions, &normals, &grey, &mesh.triangles)?
                    }
                });
                self.topology = topology;
            }
        }
        Ok(())
    }

    /// Uploads per-vertex radiance: `B/pi` and single scattering (empty for none); a result
    /// for another topology (a mesh replaced while it was solved) is skipped.
    pub fn set_radiance(&mut self, ctx: &GpuContext, radiance: &[Rgb], single: &[Rgb]) -> anyhow::Result<()> {
        if let Some(gpu) = &self.mesh
            && radiance.len() == self.topology.0
        {
            let split = self.texture.as_ref().and_then(|t| t.split.as_ref());
            gpu.update_radiance(ctx, &UvSplit::through(split, radiance), &UvSplit::through(split, single))?;
        }
        Ok(())
    }

    /// Records the mesh pass and the tone-map pass into `target` (of `size` pixels), inside
    /// `viewport`; the rest of the target is cleared to [`BACKGROUND`].
    pub fn draw(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        size: (u32, u32),
        viewport: Viewport,
        params: &DrawParams,
    ) -> anyhow::Result<()> {
        self.ensure_targets(ctx, size);
        let t = self.targets.as_ref().expect("just made");
        self.mesh_pass.prepare(ctx, &params.camera, &params.shading);
        {
            let mut pass = MeshPass::begin(encoder, "viewer mesh", &t.msaa, &t.resolved, &t.depth);
            if let Some(mesh) = &self.mesh {
                set_viewport(&mut pass, viewport);
                self.mesh_pass.draw(&mut pass, mesh);
            }
        }
        self.tone_pass.prepare(ctx, &params.tone)?;
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("viewer tone map"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear_colour(self.srgb_target)),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        set_viewport(&mut pass, viewport);
        self.tone_pass.draw(&mut pass, &t.tone_group);
        Ok(())
    }

    fn ensure_targets(&mut self, ctx: &GpuContext, size: (u32, u32)) {
        if self.targets.as_ref().is_some_and(|t| t.size == size) {
            return;
        }
        let make = |label, format, samples, usage| {
            ctx.device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let msaa = make("viewer hdr msaa", HDR_FORMAT, MSAA_SAMPLES, attach);
        let resolved = make("viewer hdr", HDR_FORMAT, 1, attach | wgpu::TextureUsages::TEXTURE_BINDING);
        let depth = make("viewer depth", DEPTH_FORMAT, MSAA_SAMPLES, attach);
        let tone_group = self.tone_pass.bind(ctx, &resolved);
        self.targets = Some(Targets { size, msaa, resolved, depth, tone_group });
    }
}

/// The tone curve the viewer uses: the paper's gamma curve over [`BACKGROUND`].
pub fn tone_map(exposure: f32) -> ToneMap {
    ToneMap { exposure, background: BACKGROUND, ..Default::default() }
}

fn set_viewport(pass: &mut wgpu::RenderPass<'_>, v: Viewport) {
    pass.set_viewport(v.x, v.y, v.width.max(1.0), v.height.max(1.0), 0.0, 1.0);
}

/// [`BACKGROUND`] as a clear value (linearised for an sRGB target, which re-encodes it).
fn clear_colour(srgb: bool) -> wgpu::Color {
    let c = BACKGROUND.map(|v| if srgb { (v as f64).powf(2.2) } else { v as f64 });
    wgpu::Color { r: c[0], g: c[1], b: c[2], a: 1.0 }
}
