//! Plumbing shared by the HTSM passes (no thesis section of its own): shader assembly, bind-group
//! layout entries, samplers, the two pipeline shapes (a mesh draw, a full-screen triangle) and
//! the uniforms, one block per frame plus one slot per light pass selected by a dynamic offset,
//! so that every light of a frame can be recorded into one command encoder.

use super::diffusion::DiffusionUniforms;
use bytemuck::{Pod, Zeroable};

/// Uniforms of a whole frame; mirrors `Frame` in `htsm_common.wgsl` field for field.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct FrameUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub box_min: [f32; 4],
    pub box_size: [f32; 4],
    pub eye: [f32; 4],
    pub transport: [f32; 4],
    pub sigma: [f32; 4],
    pub scatter: [f32; 4],
    pub density_absorption: [f32; 4],
    pub material: [f32; 4],
    pub shading: [f32; 4],
    pub counts: [f32; 4],
    pub env_frame: [f32; 4],
    pub env_irradiance: [[f32; 4]; 9],
    pub env_radiance: [[f32; 4]; 9],
    pub diffusion: DiffusionUniforms,
}

/// Uniforms of one light's passes; mirrors `LightPass` in `htsm_common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct LightUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub position: [f32; 4],
    pub colour: [f32; 4],
    pub spot: [f32; 4],
    pub flags: [f32; 4],
}

/// Mesh vertex: deformed position and normal, rest position; `f32x3` each, mesh units.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub rest: [f32; 3],
}

/// Light slots allocated at first; the buffer doubles when a frame has more lights.
const INITIAL_LIGHT_SLOTS: usize = 16;

/// The uniform buffers and their bind group (group 0 of the light and camera passes).
pub(super) struct Uniforms {
    frame: wgpu::Buffer,
    lights: wgpu::Buffer,
    /// Bytes between light slots (the adapter's dynamic-offset alignment).
    stride: u64,
    capacity: usize,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
}

impl Uniforms {
    pub fn new(device: &wgpu::Device) -> Uniforms {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("htsm uniforms"),
            entries: &[uniform_entry(0, false), uniform_entry(1, true)],
        });
        let align = device.limits().min_uniform_buffer_offset_alignment as u64;
        let stride = (std::mem::size_of::<LightUniforms>() as u64).div_ceil(align) * align;
        let frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("htsm frame uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (lights, bind_group) = Self::light_slots(device, &layout, &frame, stride, INITIAL_LIGHT_SLOTS);
        Uniforms { frame, lights, stride, capacity: INITIAL_LIGHT_SLOTS, layout, bind_group }
    }

    fn light_slots(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        frame: &wgpu::Buffer,
        stride: u64,
        capacity: usize,
    ) -> (wgpu::Buffer, wgpu::BindGroup) {
        let lights = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("htsm light uniforms"),
            size: stride * capacity as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("htsm uniforms"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: frame.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &lights,
                        offset: 0,
                        size: wgpu::BufferSize::new(std::mem::size_of::<LightUniforms>() as u64),
                    }),
                },
            ],
        });
        (lights, bind_group)
    }

    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Queues the frame's uniforms and one slot per light pass (growing the slots if needed).
    /// Queue writes land at the next submission: one frame per submission.
    pub fn write(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &FrameUniforms,
        lights: &[LightUniforms],
    ) {
        if lights.len() > self.capacity {
            let capacity = lights.len().next_power_of_two();
            (self.lights, self.bind_group) =
                Self::light_slots(device, &self.layout, &self.frame, self.stride, capacity);
            self.capacity = capacity;
        }
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(frame));
        let mut bytes = vec![0u8; self.stride as usize * lights.len()];
        for (slot, l) in bytes.chunks_exact_mut(self.stride as usize).zip(lights) {
            slot[..std::mem::size_of::<LightUniforms>()].copy_from_slice(bytemuck::bytes_of(l));
        }
        if !bytes.is_empty() {
            queue.write_buffer(&self.lights, 0, &bytes);
        }
    }

    /// Binds the uniforms as group 0 with light slot `light` selected.
    pub fn bind(&self, pass: &mut wgpu::RenderPass<'_>, light: usize) {
        pass.set_bind_group(0, &self.bind_group, &[(light as u64 * self.stride) as u32]);
    }
}

/// A shader module: `spot.wgsl` and `htsm_common.wgsl` followed by `body`.
pub(super) fn shader(device: &wgpu::Device, label: &str, body: &str) -> wgpu::ShaderModule {
    let common = concat!(include_str!("../shaders/spot.wgsl"), include_str!("../shaders/htsm_common.wgsl"));
    let source = format!("{common}\n{body}");
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

pub(super) fn texture_entry(
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

pub(super) fn sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    }
}

fn uniform_entry(binding: u32, dynamic: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Bilinear, trilinear between mips, clamped at the edges.
pub(super) fn linear_sampler(device: &wgpu::Device, label: &str) -> wgpu::Sampler {
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

/// A pipeline layout over `groups`.
pub(super) fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: groups,
        immediate_size: 0,
    })
}

/// A full-screen triangle (`vs_fullscreen` in `module`) with no depth buffer.
pub(super) fn fullscreen_pipeline(
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

/// How a mesh pipeline tests and writes depth.
#[derive(Clone, Copy)]
pub(super) struct DepthMode {
    pub compare: wgpu::CompareFunction,
    pub write: bool,
}

impl DepthMode {
    /// The nearest surface wins and is recorded.
    pub const NEAREST: DepthMode = DepthMode { compare: wgpu::CompareFunction::Less, write: true };
    /// Only the surface an earlier pass recorded (depth unchanged).
    pub const RECORDED: DepthMode = DepthMode { compare: wgpu::CompareFunction::LessEqual, write: false };
}

/// A mesh draw with the [`Vertex`] layout, entry points `entries` (vertex, fragment).
pub(super) fn mesh_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entries: (&str, &str),
    depth: DepthMode,
    targets: &[Option<wgpu::ColorTargetState>],
) -> wgpu::RenderPipeline {
    let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];
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
            format: crate::context::DEPTH_FORMAT,
            depth_write_enabled: Some(depth.write),
            depth_compare: Some(depth.compare),
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

/// A colour attachment cleared to transparent black (alpha 0: "nothing here").
pub(super) fn cleared(view: &wgpu::TextureView) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        },
    })
}

/// A render pass with `colour` attachments and an optional depth attachment.
pub(super) fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    colour: &[Option<wgpu::RenderPassColorAttachment<'_>>],
    depth: Option<wgpu::RenderPassDepthStencilAttachment<'_>>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: colour,
        depth_stencil_attachment: depth,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// A depth attachment: cleared to the far plane or loaded, stored when a later pass reads it.
pub(super) fn depth_attachment(
    view: &wgpu::TextureView,
    clear: bool,
    store: bool,
) -> Option<wgpu::RenderPassDepthStencilAttachment<'_>> {
    Some(wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: if clear { wgpu::LoadOp::Clear(1.0) } else { wgpu::LoadOp::Load },
            store: if store { wgpu::StoreOp::Store } else { wgpu::StoreOp::Discard },
        }),
        stencil_ops: None,
    })
}
