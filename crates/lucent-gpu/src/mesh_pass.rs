//! The mesh pass (Mertens 2003 §5.4): a triangle mesh with per-vertex diffuse radiance `B / pi`
//! from the solver, Gouraud interpolated, times the exit Fresnel transmittance
//! `F_t(eta, w_o)` evaluated per pixel (`L = F_t(eta, w_o) B / pi`, eq. 3), and by the exit
//! lobe `T(μ_o)` the half-space gives the profiles other than Mertens'
//! ([`lucent_core::bssrdf::ExitLobe`], a 33-sample table per channel). Single-scattered
//! radiance, where the session computes it per vertex, is added before that factor and
//! interpolated geometrically (the exponential of the blended logarithms): it falls off
//! exponentially past the terminator, by up to a thousand times across one face of a coarse
//! mesh, and a linear blend there overstates it several times. Optional additions in the same
//! pass: a Fresnel-weighted normalised Blinn-Phong highlight for the lights and a Fresnel-weighted
//! reflection of an equirectangular environment map (the paper's "reflection mapping or phong shading").
//!
//! Output is HDR radiance in an [`HDR_FORMAT`](crate::HDR_FORMAT) target with alpha = coverage;
//! [`crate::tonemap`] turns it into an image. Optionally the environment map itself is drawn
//! behind the mesh first ([`Shading::background`], alpha 1, tone mapped with the mesh).
//!
//! Bind groups: 0 = `MeshUniforms` (camera and shading), 1 = environment map and sampler,
//! 2 = albedo map and sampler (a mesh's colour texture: the radiance is multiplied by its
//! square root per pixel, the exit half of `lucent_core::mesh::texture`'s modulation).

use crate::context::{DEPTH_FORMAT, GpuContext, GpuError};
pub use crate::surface_maps::{AlbedoMap, EnvironmentMap};
use crate::surface_maps::{albedo_bind_group, env_bind_group, texture_layout};
use glam::{Vec2, Vec3};
use lucent_core::Rgb;
use lucent_core::bssrdf::ExitLobe;
use lucent_core::camera::CameraView;
use lucent_core::irradiance::{Cone, Light};
use wgpu::util::DeviceExt;

/// Most lights the highlight loop reads (more are ignored, with a log line).
pub const MAX_LIGHTS: usize = 8;

/// A mesh on the GPU: geometry (positions, normals), per-vertex radiance and indices, in
/// separate buffers so the interactive modes can update radiance (every frame) and geometry
/// (deformation) independently.
pub struct GpuMesh {
    geometry: wgpu::Buffer,
    radiance: wgpu::Buffer,
    uvs: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    vertex_count: u32,
    /// Bounding-sphere centre, mesh units (for framing).
    pub center: Vec3,
    /// Bounding-sphere radius, mesh units.
    pub radius: f32,
}

/// Geometry vertex: position and unit normal, mesh units.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GeometryVertex {
    position: [f32; 3],
    normal: [f32; 3],
}

impl GpuMesh {
    /// Uploads a mesh. `positions`, `normals` and `radiance` (per-vertex `B / pi`, HDR, >= 0)
    /// have one entry per vertex; `triangles` index into them.
    pub fn new(
        ctx: &GpuContext,
        positions: &[Vec3],
        normals: &[Vec3],
        radiance: &[Rgb],
        triangles: &[[u32; 3]],
    ) -> Result<GpuMesh, GpuError> {
        Self::with_uvs(ctx, positions, normals, radiance, triangles, &vec![Vec2::ZERO; positions.len()])
    }

    /// Uploads a mesh like [`GpuMesh::new`] with a texture coordinate per vertex (for the
    /// albedo map, [`MeshPass::set_albedo`]).
    pub fn with_uvs(
        ctx: &GpuContext,
        positions: &[Vec3],
        normals: &[Vec3],
        radiance: &[Rgb],
        triangles: &[[u32; 3]],
        uvs: &[Vec2],
    ) -> Result<GpuMesh, GpuError> {
        let n = positions.len();
        if normals.len() != n || radiance.len() != n || uvs.len() != n {
            return Err(GpuError::InvalidInput(format!(
                "mesh upload: {} positions, {} normals, {} radiance values, {} uvs (must be equal)",
                n,
                normals.len(),
                radiance.len(),
                uvs.len()
            )));
        }
        if let Some(t) = triangles.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
            return Err(GpuError::InvalidInput(format!(
                "mesh upload: triangle {t:?} indexes past the {n} vertices"
            )));
        }
        if triangles.is_empty() {
            return Err(GpuError::InvalidInput("mesh upload: no triangles".into()));
        }
        let geometry: Vec<GeometryVertex> = positions
            .iter()
            .zip(normals)
            .map(|(p, nrm)| GeometryVertex { position: p.to_array(), normal: nrm.to_array() })
            .collect();
        let usage = wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST;
        let geometry = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lucent mesh geometry"),
            contents: bytemuck::cast_slice(&geometry),
            usage,
        });
        let radiance = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lucent mesh radiance"),
            contents: bytemuck::cast_slice(&interleave(radiance, &[])),
            usage,
        });
        let uvs = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lucent mesh uvs"),
            contents: bytemuck::cast_slice(uvs),
            usage,
        });
        let indices = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lucent mesh indices"),
            contents: bytemuck::cast_slice(triangles),
            usage: wgpu::BufferUsages::INDEX,
        });
        let (center, radius) = lucent_core::camera::bounding_sphere(positions);
        Ok(GpuMesh {
            geometry,
            radiance,
            uvs,
            indices,
            index_count: (triangles.len() * 3) as u32,
            vertex_count: n as u32,
            center,
            radius,
        })
    }

    /// Replaces the per-vertex radiance, e.g. after a new solve: the diffuse part (`B / pi`)
    /// and the single-scattered part (empty for none), both before the exit Fresnel factor.
    pub fn update_radiance(
        &self,
        ctx: &GpuContext,
        radiance: &[Rgb],
        single: &[Rgb],
    ) -> Result<(), GpuError> {
        let n = self.vertex_count as usize;
        if radiance.len() != n || !(single.is_empty() || single.len() == n) {
            return Err(GpuError::InvalidInput(format!(
                "radiance update: {} diffuse and {} single-scattering values for {n} vertices",
                radiance.len(),
                single.len(),
            )));
        }
        ctx.queue.write_buffer(&self.radiance, 0, bytemuck::cast_slice(&interleave(radiance, single)));
        Ok(())
    }

    /// Replaces positions and normals (deformation; same vertex count and connectivity).
    /// The bounding sphere is not recomputed.
    pub fn update_geometry(
        &self,
        ctx: &GpuContext,
        positions: &[Vec3],
        normals: &[Vec3],
    ) -> Result<(), GpuError> {
        if positions.len() != self.vertex_count as usize || normals.len() != positions.len() {
            return Err(GpuError::InvalidInput(format!(
                "geometry update: {} positions and {} normals for {} vertices",
                positions.len(),
                normals.len(),
                self.vertex_count
            )));
        }
        let geometry: Vec<GeometryVertex> = positions
            .iter()
            .zip(normals)
            .map(|(p, n)| GeometryVertex { position: p.to_array(), normal: n.to_array() })
            .collect();
        ctx.queue.write_buffer(&self.geometry, 0, bytemuck::cast_slice(&geometry));
        Ok(())
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> u32 {
        self.index_count / 3
    }
}

/// Per vertex: the diffuse radiance, then the single-scattered (zero where `single` is empty).
fn interleave(radiance: &[Rgb], single: &[Rgb]) -> Vec<[f32; 6]> {
    let single = |v: usize| single.get(v).copied().unwrap_or(Rgb::ZERO);
    radiance
        .iter()
        .enumerate()
        .map(|(v, d)| {
            let s = single(v);
            [d.x, d.y, d.z, s.x, s.y, s.z]
        })
        .collect()
}

/// Shading parameters of the mesh pass.
#[derive(Clone, Debug, PartialEq)]
pub struct Shading {
    /// Relative index of refraction of the material (unitless, 1..3); the Fresnel terms use it.
    pub eta: f32,
    /// Lights for the highlight, in mesh units (the same ones that gave the irradiance). At
    /// most [`MAX_LIGHTS`] are used.
    pub lights: Vec<Light>,
    /// Scale of the Fresnel-weighted Blinn-Phong highlight; 0 disables it. Default 1 (the
    /// physically weighted lobe).
    pub specular: f32,
    /// Blinn-Phong exponent (> 0). Default 64.
    pub shininess: f32,
    /// Scale of the Fresnel-weighted environment reflection; 0 (default) disables it. Has an
    /// effect only after [`MeshPass::set_environment`].
    pub environment: f32,
    /// Scale of the environment map drawn behind the mesh (radiance multiplier, >= 0); 0
    /// (default) draws none, and the tone map's flat background shows.
    pub background: f32,
    /// How the diffuse radiance leaves over exit angles (unitless factor `T(μ_o)` per channel,
    /// which keeps the exitance); default flat, the paper's. A solve gives the profile's
    /// (`lucent_core::session::Solved::exit_lobe`).
    pub exit_lobe: ExitLobe,
    /// Blend single scattering linearly across a face instead of geometrically: only for the
    /// validation's ablation (`lucent render --ablate single-blend`). Default false.
    pub linear_single: bool,
}

impl Default for Shading {
    fn default() -> Self {
        Shading {
            eta: 1.3,
            lights: Vec::new(),
            specular: 1.0,
            shininess: 64.0,
            environment: 0.0,
            background: 0.0,
            exit_lobe: ExitLobe::flat(),
            linear_single: false,
        }
    }
}

/// mesh.wgsl after the functions it shares (WGSL has no includes).
const MESH_WGSL: &str = concat!(
    include_str!("shaders/spot.wgsl"),
    include_str!("shaders/fresnel.wgsl"),
    include_str!("shaders/exit.wgsl"),
    include_str!("shaders/mesh.wgsl")
);

/// GPU layout of `Uniforms` in `mesh.wgsl` (std140-compatible by construction: only vec4s).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MeshUniforms {
    view_proj: [[f32; 4]; 4],
    // Clip to world, for the background's view rays.
    inv_view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    params: [f32; 4],
    counts: [u32; 4],
    // x: environment background scale (0 = none).
    background: [f32; 4],
    lights: [LightUniform; MAX_LIGHTS],
    // rgb: the exit lobe T at μ_o = k / (COUNT - 1).
    exit_lobe: [[f32; 4]; ExitLobe::COUNT],
}

// mesh.wgsl sizes its table by hand.
const _: () = assert!(ExitLobe::COUNT == 33, "mesh.wgsl's EXIT_SAMPLES must match ExitLobe::COUNT");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LightUniform {
    position: [f32; 4],
    intensity: [f32; 4],
    /// Spot lights: unit axis (xyz) and cone half-angle in radians (w); `w > pi` for none.
    /// `intensity.w` holds the soft-edge fraction.
    spot: [f32; 4],
}

/// No cone: the half-angle the shader reads for point and directional lights.
const NO_CONE: f32 = 4.0;

/// One light as `mesh.wgsl` reads it, from the light's shape (its position or direction, power
/// and cone; see [`lucent_core::irradiance::Cone`]), whatever its kind.
fn light_uniform(light: &Light) -> LightUniform {
    // A positional light's position (w = 1), a distant one's direction of travel (w = 0).
    let position = match light.position() {
        Some(p) => p.extend(1.0),
        None => light.direction().unwrap_or(Vec3::ZERO).extend(0.0),
    };
    match light.cone() {
        // The same cone and smoothstep edge as the subsurface irradiance
        // (`lucent_core::irradiance::spot_falloff`).
        Some(Cone { axis, half_angle, soft_edge }) => LightUniform {
            position: position.to_array(),
            intensity: light.power().extend(soft_edge.clamp(0.0, 1.0)).to_array(),
            spot: axis.normalize_or_zero().extend(half_angle).to_array(),
        },
        None => LightUniform {
            position: position.to_array(),
            intensity: light.power().extend(0.0).to_array(),
            spot: [0.0, 0.0, 0.0, NO_CONE],
        },
    }
}

/// The mesh pipeline and its uniforms. Draws into a render pass whose colour target has the
/// format and sample count given to [`MeshPass::new`] and whose depth target is
/// [`DEPTH_FORMAT`].
pub struct MeshPass {
    pipeline: wgpu::RenderPipeline,
    background_pipeline: wgpu::RenderPipeline,
    // Set by `prepare` (which takes `&self`), read by `draw`.
    draw_background: std::cell::Cell<bool>,
    uniforms: wgpu::Buffer,
    uniform_group: wgpu::BindGroup,
    env_layout: wgpu::BindGroupLayout,
    env_group: wgpu::BindGroup,
    sampler: wgpu::Sampler,
    albedo_layout: wgpu::BindGroupLayout,
    albedo_group: wgpu::BindGroup,
    albedo_sampler: wgpu::Sampler,
}

/// The layout of the mesh pass's uniform buffer ([`MeshUniforms`]), read by both stages.
fn uniform_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("lucent mesh uniforms"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<MeshUniforms>() as u64),
            },
            count: None,
        }],
    })
}

/// A bilinear sampler that repeats in u and addresses v with `v_mode`.
fn linear_sampler(device: &wgpu::Device, label: &str, v_mode: wgpu::AddressMode) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(label),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: v_mode,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    })
}

impl MeshPass {
    /// Builds the pipeline for colour targets of `color_format` with `sample_count` samples
    /// (1 or 4).
    pub fn new(
        ctx: &GpuContext,
        color_format: wgpu::TextureFormat,
        sample_count: u32,
    ) -> Result<MeshPass, GpuError> {
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lucent mesh.wgsl"),
            source: wgpu::ShaderSource::Wgsl(MESH_WGSL.into()),
        });
        let uniform_layout = uniform_layout(device);
        let env_layout = texture_layout(device, "lucent mesh environment");
        let albedo_layout = texture_layout(device, "lucent mesh albedo");
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lucent mesh"),
            bind_group_layouts: &[Some(&uniform_layout), Some(&env_layout), Some(&albedo_layout)],
            immediate_size: 0,
        });
        let buffers = [
            Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<GeometryVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
            }),
            Some(wgpu::VertexBufferLayout {
                array_stride: 24,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![2 => Float32x3, 4 => Float32x3],
            }),
            Some(wgpu::VertexBufferLayout {
                array_stride: 8,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![3 => Float32x2],
            }),
        ];
        let target = PassTarget { color_format, sample_count };
        let mesh = Stage { label: "lucent mesh", vertex: "vs_main", fragment: "fs_main", depth_write: true };
        let pipeline = create_pipeline(device, &layout, &module, mesh, &buffers, target);
        // A full-screen triangle behind everything: no depth written, so the mesh draws over it.
        let background = Stage {
            label: "lucent environment background",
            vertex: "vs_background",
            fragment: "fs_background",
            depth_write: false,
        };
        let background_pipeline = create_pipeline(device, &layout, &module, background, &[], target);
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lucent mesh uniforms"),
            size: std::mem::size_of::<MeshUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let uniform_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lucent mesh uniforms"),
            layout: &uniform_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() }],
        });
        // Longitude wraps around; latitude stops at the poles.
        let sampler = linear_sampler(device, "lucent environment", wgpu::AddressMode::ClampToEdge);
        let black = EnvironmentMap::from_rgba_f32(ctx, 1, 1, &[[0.0; 4]])?;
        let env_group = env_bind_group(device, &env_layout, &black, &sampler);
        let albedo_sampler = linear_sampler(device, "lucent albedo", wgpu::AddressMode::Repeat);
        let white = AlbedoMap::from_rgb(ctx, 1, 1, &[Vec3::ONE])?;
        let albedo_group = albedo_bind_group(device, &albedo_layout, &white, &albedo_sampler);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Device {
                during: "creating the mesh pipeline".into(),
                message: e.to_string(),
            });
        }
        Ok(MeshPass {
            pipeline,
            background_pipeline,
            draw_background: std::cell::Cell::new(false),
            uniforms,
            uniform_group,
            env_layout,
            env_group,
            sampler,
            albedo_layout,
            albedo_group,
            albedo_sampler,
        })
    }

    /// Sets the albedo map (a mesh's colour texture) the mesh is drawn with; without one, a 1x1
    /// white map leaves the radiance unchanged.
    pub fn set_albedo(&mut self, ctx: &GpuContext, map: &AlbedoMap) {
        self.albedo_group = albedo_bind_group(&ctx.device, &self.albedo_layout, map, &self.albedo_sampler);
    }

    /// Sets the environment map the reflection samples (see [`Shading::environment`]).
    pub fn set_environment(&mut self, ctx: &GpuContext, env: &EnvironmentMap) {
        self.env_group = env_bind_group(&ctx.device, &self.env_layout, env, &self.sampler);
    }

    /// Writes the camera and shading uniforms for the next [`MeshPass::draw`].
    pub fn prepare(&self, ctx: &GpuContext, camera: &CameraView, shading: &Shading) {
        if shading.lights.len() > MAX_LIGHTS {
            log::warn!("{} lights given; the highlight uses the first {MAX_LIGHTS}", shading.lights.len());
        }
        let mut lights =
            [LightUniform { position: [0.0; 4], intensity: [0.0; 4], spot: [0.0; 4] }; MAX_LIGHTS];
        for (dst, l) in lights.iter_mut().zip(&shading.lights) {
            *dst = light_uniform(l);
        }
        let u = MeshUniforms {
            view_proj: camera.view_proj.to_cols_array_2d(),
            inv_view_proj: camera.view_proj.inverse().to_cols_array_2d(),
            eye: camera.eye.extend(1.0).to_array(),
            params: [
                shading.eta,
                shading.specular.max(0.0),
                shading.shininess.max(1e-3),
                shading.environment.max(0.0),
            ],
            counts: [shading.lights.len().min(MAX_LIGHTS) as u32, shading.linear_single as u32, 0, 0],
            background: [shading.background.max(0.0), 0.0, 0.0, 0.0],
            lights,
            exit_lobe: shading.exit_lobe.samples().map(|[r, g, b]| [r, g, b, 0.0]),
        };
        ctx.queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        self.draw_background.set(shading.background > 0.0);
    }

    /// The mesh pass's render pass: into `msaa` resolved to `resolved`, cleared to transparent
    /// (alpha 0 marks the background for tone mapping), `depth` cleared; only the resolve kept.
    pub fn begin<'e>(
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        msaa: &wgpu::TextureView,
        resolved: &wgpu::TextureView,
        depth: &wgpu::TextureView,
    ) -> wgpu::RenderPass<'e> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: msaa,
                depth_slice: None,
                resolve_target: Some(resolved),
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Discard,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        })
    }

    /// Records the draw of `mesh` into `pass` (after the environment background, when the
    /// last [`MeshPass::prepare`] asked for one).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, mesh: &GpuMesh) {
        pass.set_bind_group(0, &self.uniform_group, &[]);
        pass.set_bind_group(1, &self.env_group, &[]);
        pass.set_bind_group(2, &self.albedo_group, &[]);
        if self.draw_background.get() {
            pass.set_pipeline(&self.background_pipeline);
            pass.draw(0..3, 0..1);
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_vertex_buffer(0, mesh.geometry.slice(..));
        pass.set_vertex_buffer(1, mesh.radiance.slice(..));
        pass.set_vertex_buffer(2, mesh.uvs.slice(..));
        pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..mesh.index_count, 0, 0..1);
    }
}

/// The colour target a mesh-pass pipeline draws into.
#[derive(Clone, Copy)]
struct PassTarget {
    color_format: wgpu::TextureFormat,
    sample_count: u32,
}

/// One of the mesh pass's two pipelines: the mesh (depth written and tested) or the background
/// behind it (neither).
#[derive(Clone, Copy)]
struct Stage {
    label: &'static str,
    vertex: &'static str,
    fragment: &'static str,
    depth_write: bool,
}

fn create_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    stage: Stage,
    buffers: &[Option<wgpu::VertexBufferLayout>],
    target: PassTarget,
) -> wgpu::RenderPipeline {
    let compare = if stage.depth_write { wgpu::CompareFunction::Less } else { wgpu::CompareFunction::Always };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(stage.label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(stage.vertex),
            compilation_options: Default::default(),
            buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            front_face: wgpu::FrontFace::Ccw,
            // Open meshes show their inside; the shader flips the normal there.
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(stage.depth_write),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState { count: target.sample_count, ..Default::default() },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(stage.fragment),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: target.color_format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}
