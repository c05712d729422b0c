//! The four HTSM passes (module [`super`]) and the GPU resources they share.

use super::{
    DENSITY_FORMAT, HtsmError, HtsmMemory, HtsmParams, HtsmView, LightFrustum, PHASE_TABLE_SIZE,
    REFERENCE_FORMAT, TransportModel, check_volume, phase_table,
};
use crate::camera::bounding_sphere;
use crate::context::{DEPTH_FORMAT, GpuContext, HDR_FORMAT, LDR_FORMAT};
use crate::readback::read_texture;
use crate::tonemap::ToneMapPass;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use lucent_core::irradiance::Light;
use lucent_core::mesh::Mesh;
use lucent_core::volume::DensityVolume;
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

const PHASE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

/// Uniforms shared by every pass; mirrors `Globals` in `htsm_common.wgsl` field for field.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    light_view_proj: [[f32; 4]; 4],
    box_min: [f32; 4],
    box_size: [f32; 4],
    eye: [f32; 4],
    light: [f32; 4],
    light_colour: [f32; 4],
    transport: [f32; 4],
    sigma: [f32; 4],
    kernel: [f32; 4],
    shading: [f32; 4],
    counts: [f32; 4],
}

/// Vertex layout: position then normal, both `f32x3`, mesh units.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
}

/// The camera-side targets, re-created when the image size changes.
struct Targets {
    width: u32,
    height: u32,
    hdr: wgpu::Texture,
    hdr_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    ldr: wgpu::Texture,
    ldr_view: wgpu::TextureView,
    tonemap_bind_group: wgpu::BindGroup,
}

/// An HTSM renderer for one mesh and one density volume: pipelines, mesh buffers, the density
/// texture with its mips, the reference images with theirs, and the output targets.
pub struct HtsmRenderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    light_pipeline: wgpu::RenderPipeline,
    mip_pipeline: wgpu::RenderPipeline,
    camera_pipeline: wgpu::RenderPipeline,
    tonemap: ToneMapPass,
    globals: wgpu::Buffer,
    globals_bind_group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    /// The mesh's bounding box (mesh units) and bounding sphere, for frusta and texture coords.
    box_min: Vec3,
    box_size: Vec3,
    sphere: (Vec3, f32),
    reference_size: u32,
    reference_levels: u32,
    reference_textures: [wgpu::Texture; 3],
    /// Per level, the three single-level views (render attachments / mip sources).
    reference_level_views: Vec<[wgpu::TextureView; 3]>,
    /// `mip_bind_groups[k]` reads level `k` to write level `k + 1`.
    mip_bind_groups: Vec<wgpu::BindGroup>,
    reference_depth_view: wgpu::TextureView,
    density_dims: [u32; 3],
    density_levels: u32,
    phase: wgpu::Texture,
    phase_g: Option<f32>,
    scene_bind_group: wgpu::BindGroup,
    targets: Option<Targets>,
}

fn shader(device: &wgpu::Device, label: &str, body: &str) -> wgpu::ShaderModule {
    let source = format!("{}\n{}", include_str!("../shaders/htsm_common.wgsl"), body);
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

fn texture_entry(
    binding: u32,
    dim: wgpu::TextureViewDimension,
    filterable: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable },
            view_dimension: dim,
            multisampled: false,
        },
        count: None,
    }
}

fn sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn linear_sampler(device: &wgpu::Device, label: &str) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(label),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        address_mode_w: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    })
}

fn fullscreen_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    fragment_entry: &str,
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_fullscreen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment_entry),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn mesh_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entries: (&str, &str),
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(entries.0),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attributes,
            })],
        },
        // No culling: the nearest surface wins the depth test, so open or inconsistently wound
        // meshes still render.
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entries.1),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn validate_mesh(mesh: &Mesh) -> Result<(), HtsmError> {
    if mesh.triangles.is_empty() {
        return Err(HtsmError::Mesh("it has no triangles".into()));
    }
    let n = mesh.positions.len() as u32;
    if mesh.triangles.iter().flatten().any(|&i| i >= n) {
        return Err(HtsmError::Mesh("a triangle indexes a missing vertex".into()));
    }
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        return Err(HtsmError::Mesh("a vertex position is not finite".into()));
    }
    if mesh.extent().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(HtsmError::Mesh("its bounding box is a point".into()));
    }
    Ok(())
}

impl HtsmRenderer {
    /// Uploads `mesh` (with area-weighted vertex normals) and `volume` (with its full mip
    /// chain, every level computed on the CPU), allocates `reference_size`^2 reference images
    /// with full mip chains, and builds the pipelines.
    pub fn new(
        ctx: &GpuContext,
        mesh: &Mesh,
        volume: &DensityVolume,
        reference_size: u32,
    ) -> Result<Self, HtsmError> {
        validate_mesh(mesh)?;
        let (device, queue) = (&ctx.device, &ctx.queue);
        let limits = device.limits();
        check_volume(volume, &limits)?;
        if reference_size < 16 || reference_size > limits.max_texture_dimension_2d {
            return Err(HtsmError::Limits(format!(
                "reference image size {reference_size} (must be in 16..={})",
                limits.max_texture_dimension_2d
            )));
        }

        // Mesh buffers.
        let normals = mesh.vertex_normals();
        let vertices: Vec<Vertex> = mesh
            .positions
            .iter()
            .zip(&normals)
            .map(|(p, n)| Vertex { position: p.to_array(), normal: n.to_array() })
            .collect();
        let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("htsm vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("htsm indices"),
            contents: bytemuck::cast_slice(&mesh.triangles),
            usage: wgpu::BufferUsages::INDEX,
        });
        let (box_min, box_max) = mesh.bounds();

        // Density volume: R8Unorm 3D texture, every mip level computed on the CPU and uploaded.
        let chain = volume.mip_chain();
        let density = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("htsm density"),
            size: wgpu::Extent3d {
                width: volume.dims[0],
                height: volume.dims[1],
                depth_or_array_layers: volume.dims[2],
            },
            mip_level_count: chain.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: DENSITY_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (level, v) in chain.iter().enumerate() {
            queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &density,
                    mip_level: level as u32,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                &v.to_unorm8(),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(v.dims[0]),
                    rows_per_image: Some(v.dims[1]),
                },
                wgpu::Extent3d { width: v.dims[0], height: v.dims[1], depth_or_array_layers: v.dims[2] },
            );
        }

        // Reference images (fig. 4.2) with full mip chains.
        let reference_levels = 32 - reference_size.leading_zeros();
        let make_reference = |label: &str| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: reference_size,
                    height: reference_size,
                    depth_or_array_layers: 1,
                },
                mip_level_count: reference_levels,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: REFERENCE_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let reference_textures = [
            make_reference("htsm irradiance"),
            make_reference("htsm texcoord"),
            make_reference("htsm normal"),
        ];
        let reference_level_views: Vec<[wgpu::TextureView; 3]> = (0..reference_levels)
            .map(|level| {
                reference_textures.each_ref().map(|t| {
                    t.create_view(&wgpu::TextureViewDescriptor {
                        base_mip_level: level,
                        mip_level_count: Some(1),
                        ..Default::default()
                    })
                })
            })
            .collect();
        let reference_depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("htsm light depth"),
            size: wgpu::Extent3d { width: reference_size, height: reference_size, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });

        let phase = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("htsm phase table"),
            size: wgpu::Extent3d { width: PHASE_TABLE_SIZE, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: PHASE_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });

        // Layouts.
        let globals_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("htsm globals"),
            entries: &[uniform_entry(0)],
        });
        let d2 = wgpu::TextureViewDimension::D2;
        let scene_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("htsm scene"),
            entries: &[
                texture_entry(0, d2, true),
                texture_entry(1, d2, true),
                texture_entry(2, d2, true),
                sampler_entry(3),
                texture_entry(4, wgpu::TextureViewDimension::D3, true),
                sampler_entry(5),
                texture_entry(6, d2, true),
            ],
        });
        let mip_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("htsm mip source"),
            entries: &[texture_entry(0, d2, false), texture_entry(1, d2, false), texture_entry(2, d2, false)],
        });

        // Pipelines.
        let light_module = shader(device, "htsm light", include_str!("../shaders/htsm_light.wgsl"));
        let render_module = shader(device, "htsm render", include_str!("../shaders/htsm_render.wgsl"));
        let mip_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("htsm mip"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../shaders/htsm_mip.wgsl").into()),
        });
        let layout = |label: &str, groups: &[Option<&wgpu::BindGroupLayout>]| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: groups,
                immediate_size: 0,
            })
        };
        let reference_targets: Vec<Option<wgpu::ColorTargetState>> =
            (0..3).map(|_| Some(REFERENCE_FORMAT.into())).collect();
        let light_pipeline = mesh_pipeline(
            device,
            "htsm light pass",
            &light_module,
            &layout("htsm light", &[Some(&globals_layout)]),
            ("vs_light", "fs_light"),
            &reference_targets,
        );
        let camera_pipeline = mesh_pipeline(
            device,
            "htsm camera pass",
            &render_module,
            &layout("htsm camera", &[Some(&globals_layout), Some(&scene_layout)]),
            ("vs_camera", "fs_camera"),
            &[Some(HDR_FORMAT.into())],
        );
        let mip_pipeline = fullscreen_pipeline(
            device,
            "htsm mip pass",
            &mip_module,
            &layout("htsm mip", &[Some(&mip_layout)]),
            "fs_mip",
            &reference_targets,
        );
        let tonemap = ToneMapPass::new(ctx, LDR_FORMAT)?;

        // Bind groups.
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("htsm globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let globals_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("htsm globals"),
            layout: &globals_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: globals.as_entire_binding() }],
        });
        let mip_bind_groups = (0..reference_levels.saturating_sub(1) as usize)
            .map(|level| {
                let views = &reference_level_views[level];
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("htsm mip source"),
                    layout: &mip_layout,
                    entries: &[0, 1, 2].map(|i| wgpu::BindGroupEntry {
                        binding: i,
                        resource: wgpu::BindingResource::TextureView(&views[i as usize]),
                    }),
                })
            })
            .collect();
        let full_views = reference_textures.each_ref().map(|t| t.create_view(&Default::default()));
        let density_view = density.create_view(&Default::default());
        let phase_view = phase.create_view(&Default::default());
        let ref_sampler = linear_sampler(device, "htsm reference sampler");
        let density_sampler = linear_sampler(device, "htsm density sampler");
        let scene_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("htsm scene"),
            layout: &scene_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&full_views[0]),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&full_views[1]),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&full_views[2]),
                },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::Sampler(&ref_sampler) },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(&density_view),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::Sampler(&density_sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: wgpu::BindingResource::TextureView(&phase_view),
                },
            ],
        });

        ctx.check("creating the HTSM renderer")?;
        Ok(HtsmRenderer {
            device: device.clone(),
            queue: queue.clone(),
            light_pipeline,
            mip_pipeline,
            camera_pipeline,
            tonemap,
            globals,
            globals_bind_group,
            vertices: vertex_buffer,
            indices: index_buffer,
            index_count: (mesh.triangles.len() * 3) as u32,
            box_min,
            box_size: box_max - box_min,
            sphere: bounding_sphere(&mesh.positions),
            reference_size,
            reference_levels,
            reference_textures,
            reference_level_views,
            mip_bind_groups,
            reference_depth_view: reference_depth.create_view(&Default::default()),
            density_dims: volume.dims,
            density_levels: chain.len() as u32,
            phase,
            phase_g: None,
            scene_bind_group,
            targets: None,
        })
    }

    /// Side of the (square) reference images at level 0, texels.
    pub fn reference_size(&self) -> u32 {
        self.reference_size
    }

    /// GPU memory of the HTSM data (not counting the camera-side output targets).
    pub fn memory(&self) -> HtsmMemory {
        let texel = 8u64; // Rgba16Float
        let reference_level_texels: u64 =
            (0..self.reference_levels).map(|l| ((self.reference_size >> l).max(1) as u64).pow(2)).sum();
        let volume: u64 = (0..self.density_levels)
            .map(|l| self.density_dims.iter().map(|&d| (d >> l).max(1) as u64).product::<u64>())
            .sum();
        HtsmMemory {
            reference_images: 3 * texel * reference_level_texels,
            reference_depth: 4 * (self.reference_size as u64).pow(2),
            volume,
            phase_table: 2 * PHASE_TABLE_SIZE as u64,
        }
    }

    fn ensure_targets(&mut self, ctx: &GpuContext, width: u32, height: u32) -> Result<(), HtsmError> {
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
        let hdr = make(
            "htsm hdr",
            HDR_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let depth = make("htsm depth", DEPTH_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let ldr = make(
            "htsm ldr",
            LDR_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let hdr_view = hdr.create_view(&Default::default());
        let tonemap_bind_group = self.tonemap.bind(ctx, &hdr_view);
        self.targets = Some(Targets {
            width,
            height,
            hdr,
            hdr_view,
            depth_view: depth.create_view(&Default::default()),
            ldr_view: ldr.create_view(&Default::default()),
            ldr,
            tonemap_bind_group,
        });
        Ok(())
    }

    /// Writes the uniforms and the phase table for this frame.
    fn upload(&mut self, ctx: &GpuContext, view: &HtsmView, params: &HtsmParams) -> Result<(), HtsmError> {
        params.validate()?;
        let frustum = LightFrustum::fit(self.sphere, &view.light)?;
        let extent = self.box_size.max_element();
        let (light, light_colour) = match view.light {
            // A spot renders like a point light from its position (cone not applied in HTSM).
            Light::Point { position, intensity } | Light::Spot { position, intensity, .. } => {
                (position.extend(1.0), intensity)
            }
            Light::Directional { direction, irradiance } => {
                (direction.normalize_or_zero().extend(0.0), irradiance)
            }
        };
        // Ring-1 radius: object units -> level-0 texels at the object's centre.
        let kernel_texels =
            params.kernel_radius * extent / frustum.width_at_centre * self.reference_size as f32;
        let sigma = params.sigma();
        let globals = Globals {
            view_proj: view.camera.view_proj.to_cols_array_2d(),
            light_view_proj: frustum.view_proj.to_cols_array_2d(),
            box_min: self.box_min.extend(0.0).to_array(),
            box_size: self.box_size.extend(1.0 / extent).to_array(),
            eye: view.camera.eye.extend(1.0).to_array(),
            light: light.to_array(),
            light_colour: light_colour.extend(0.0).to_array(),
            transport: params.transport_colour.extend(params.transport_distance).to_array(),
            sigma: sigma.extend(params.density_scale).to_array(),
            kernel: [kernel_texels, params.f0(), params.shadow_bias, (self.density_levels - 1) as f32],
            shading: [params.diffuse, params.specular, params.shininess, 0.0],
            counts: [
                params.samples as f32,
                params.steps as f32,
                match params.model {
                    TransportModel::Thesis => 0.0,
                    TransportModel::BeerLambert => 1.0,
                },
                *self.density_dims.iter().max().expect("three sides") as f32,
            ],
        };
        self.queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&globals));
        self.tonemap.prepare(ctx, &params.tone)?;
        if self.phase_g != Some(params.phase_g) {
            let halves: Vec<u16> =
                phase_table(params.phase_g).iter().map(|&v| half::f16::from_f32(v).to_bits()).collect();
            self.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.phase,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(&halves),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(2 * PHASE_TABLE_SIZE),
                    rows_per_image: Some(1),
                },
                wgpu::Extent3d { width: PHASE_TABLE_SIZE, height: 1, depth_or_array_layers: 1 },
            );
            self.phase_g = Some(params.phase_g);
        }
        Ok(())
    }

    /// Records the four passes of one frame.
    fn encode(
        &mut self,
        ctx: &GpuContext,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<wgpu::CommandEncoder, HtsmError> {
        self.ensure_targets(ctx, view.width, view.height)?;
        self.upload(ctx, view, params)?;
        let targets = self.targets.as_ref().expect("just ensured");
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("htsm frame") });
        let clear = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };

        // 1. Reference images from the light.
        {
            let level0 = &self.reference_level_views[0];
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("htsm light pass"),
                color_attachments: &[clear(&level0[0]), clear(&level0[1]), clear(&level0[2])],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.reference_depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.light_pipeline);
            pass.set_bind_group(0, &self.globals_bind_group, &[]);
            pass.set_vertex_buffer(0, self.vertices.slice(..));
            pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.index_count, 0, 0..1);
        }

        // 2. Mip chains, one level at a time.
        for (level, bind_group) in self.mip_bind_groups.iter().enumerate() {
            let dst = &self.reference_level_views[level + 1];
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("htsm mip pass"),
                color_attachments: &[clear(&dst[0]), clear(&dst[1]), clear(&dst[2])],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.mip_pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.draw(0..3, 0..1);
        }

        // 3. Camera pass into the HDR target.
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("htsm camera pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &targets.hdr_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        // Alpha 0 is "no object": the tone-map pass puts the background there.
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.camera_pipeline);
            pass.set_bind_group(0, &self.globals_bind_group, &[]);
            pass.set_bind_group(1, &self.scene_bind_group, &[]);
            pass.set_vertex_buffer(0, self.vertices.slice(..));
            pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.index_count, 0, 0..1);
        }

        // 4. Tone mapping to 8 bits.
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("htsm tonemap pass"),
                color_attachments: &[clear(&targets.ldr_view)],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.tonemap.draw(&mut pass, &targets.tonemap_bind_group);
        }
        Ok(encoder)
    }

    /// Renders one frame and reads it back: an sRGB-encoded RGBA8 image, `view.width` x
    /// `view.height`, rows top to bottom.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<image::RgbaImage, HtsmError> {
        let encoder = self.encode(ctx, view, params)?;
        self.queue.submit([encoder.finish()]);
        ctx.check("rendering HTSM")?;
        let t = self.targets.as_ref().expect("encode ensures targets");
        Ok(read_texture(ctx, &t.ldr, 0)?.to_rgba_image()?)
    }

    /// Renders one frame and reads back the HDR radiance before tone mapping: RGBA `f32`,
    /// alpha = coverage (1 on the object, 0 elsewhere, radiance 0 there), rows top first.
    pub fn render_hdr(
        &mut self,
        ctx: &GpuContext,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<Vec<[f32; 4]>, HtsmError> {
        let encoder = self.encode(ctx, view, params)?;
        self.queue.submit([encoder.finish()]);
        ctx.check("rendering HTSM")?;
        let t = self.targets.as_ref().expect("encode ensures targets");
        Ok(read_texture(ctx, &t.hdr, 0)?.to_rgba_f32()?)
    }

    /// Renders one frame without read-back and blocks until the queue has finished it
    /// (`device.poll(wait)`): the wall time from encoding to completion, for benchmarks.
    pub fn render_timed(
        &mut self,
        ctx: &GpuContext,
        view: &HtsmView,
        params: &HtsmParams,
    ) -> Result<Duration, HtsmError> {
        let start = Instant::now();
        let encoder = self.encode(ctx, view, params)?;
        let index = self.queue.submit([encoder.finish()]);
        self.device
            .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
            .map_err(|e| HtsmError::Readback(e.to_string()))?;
        let elapsed = start.elapsed();
        ctx.check("rendering HTSM")?;
        Ok(elapsed)
    }

    /// The three reference images' level-0 texture handles (irradiance, texture coordinate,
    /// normal), e.g. for inspection.
    pub fn reference_textures(&self) -> &[wgpu::Texture; 3] {
        &self.reference_textures
    }
}
