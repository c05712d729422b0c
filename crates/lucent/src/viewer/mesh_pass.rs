//! The viewer's 3D pass (Mertens §5.4): the mesh with its per-vertex diffuse radiance `B/pi`,
//! the exit Fresnel factor per pixel and a gamma tone curve, drawn with depth into a viewport
//! of any colour target (the window's surface, or an offscreen texture for screenshots).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use lucent_core::Rgb;
use lucent_core::mesh::Mesh;
use wgpu::util::DeviceExt as _;

const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Background colour of the 3D viewport (display values, also what the tests compare with).
pub const BACKGROUND: wgpu::Color = wgpu::Color { r: 0.055, g: 0.06, b: 0.07, a: 1.0 };

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Uniforms {
    view_proj: [[f32; 4]; 4],
    eye_eta: [f32; 4],
    params: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GeometryVertex {
    position: [f32; 3],
    normal: [f32; 3],
}

/// What one draw needs besides the geometry.
#[derive(Clone, Copy, Debug)]
pub struct DrawParams {
    /// World-to-clip matrix for the viewport's aspect ratio.
    pub view_proj: Mat4,
    /// Eye position, mesh units.
    pub eye: Vec3,
    /// Relative index of refraction for the exit Fresnel factor.
    pub eta: f32,
    /// Radiance multiplier before tone mapping (> 0).
    pub exposure: f32,
    /// Skip the Fresnel factor (false-colour overlays such as the figure 6.9 view).
    pub flat_colours: bool,
}

/// Viewport rectangle in physical pixels of the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Left edge.
    pub x: f32,
    /// Top edge.
    pub y: f32,
    /// Width (> 0).
    pub width: f32,
    /// Height (> 0).
    pub height: f32,
}

/// Pipeline, geometry and radiance buffers, and a depth buffer sized to the target.
pub struct MeshPass {
    pipeline: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    srgb_target: bool,
    geometry: Option<wgpu::Buffer>,
    radiance: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    index_count: u32,
    vertex_count: usize,
    depth: Option<(wgpu::TextureView, u32, u32)>,
}

impl MeshPass {
    /// Builds the pipeline for colour targets of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let shader = device.create_shader_module(wgpu::include_wgsl!("mesh_pass.wgsl"));
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewer mesh uniforms"),
            size: std::mem::size_of::<Uniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewer mesh"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewer mesh"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewer mesh"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("viewer mesh"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[
                    Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<GeometryVertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
                    }),
                    Some(wgpu::VertexBufferLayout {
                        array_stride: 12,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![2 => Float32x3],
                    }),
                ],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                front_face: wgpu::FrontFace::Ccw,
                // No culling: dents and open meshes show their inside.
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        MeshPass {
            pipeline,
            uniforms,
            bind_group,
            srgb_target: format.is_srgb(),
            geometry: None,
            radiance: None,
            indices: None,
            index_count: 0,
            vertex_count: 0,
            depth: None,
        }
    }

    /// Uploads new geometry (positions and vertex normals); indices are re-uploaded only when
    /// the topology's size changes. Radiance is reset to zero if the vertex count changed.
    pub fn set_geometry(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, mesh: &Mesh) {
        let vertices: Vec<GeometryVertex> = mesh
            .positions
            .iter()
            .zip(mesh.vertex_normals())
            .map(|(p, n)| GeometryVertex { position: p.to_array(), normal: n.to_array() })
            .collect();
        let same_size =
            self.vertex_count == vertices.len() && self.index_count as usize == mesh.triangles.len() * 3;
        match (&self.geometry, same_size) {
            (Some(buf), true) => queue.write_buffer(buf, 0, bytemuck::cast_slice(&vertices)),
            _ => {
                self.geometry =
                    Some(buffer(device, "viewer geometry", &vertices, wgpu::BufferUsages::VERTEX));
                self.indices =
                    Some(buffer(device, "viewer indices", &mesh.triangles, wgpu::BufferUsages::INDEX));
                let zeros = vec![[0f32; 3]; vertices.len()];
                self.radiance = Some(buffer(device, "viewer radiance", &zeros, wgpu::BufferUsages::VERTEX));
                self.vertex_count = vertices.len();
                self.index_count = (mesh.triangles.len() * 3) as u32;
            }
        }
    }

    /// Uploads per-vertex radiance (`B/pi`, or display colours with `flat_colours`); ignored if
    /// its length does not match the geometry (a result for an older topology).
    pub fn set_radiance(&mut self, queue: &wgpu::Queue, radiance: &[Rgb]) {
        if let Some(buf) = &self.radiance {
            if radiance.len() == self.vertex_count {
                let data: Vec<[f32; 3]> = radiance.iter().map(|c| c.to_array()).collect();
                queue.write_buffer(buf, 0, bytemuck::cast_slice(&data));
            }
        }
    }

    /// Records the pass: clears `target` to [`BACKGROUND`] and depth, then draws the mesh into
    /// `viewport`. `target_size` is the target's size in pixels.
    pub fn draw(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        target_size: (u32, u32),
        viewport: Viewport,
        params: &DrawParams,
    ) {
        let u = Uniforms {
            view_proj: params.view_proj.to_cols_array_2d(),
            eye_eta: params.eye.extend(params.eta).to_array(),
            params: [
                params.exposure,
                if self.srgb_target { 1.0 } else { 0.0 },
                if params.flat_colours { 1.0 } else { 0.0 },
                0.0,
            ],
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        let depth = self.depth_view(device, target_size);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("viewer mesh"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(self.clear_colour()),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        let (Some(geometry), Some(radiance), Some(indices)) = (&self.geometry, &self.radiance, &self.indices)
        else {
            return;
        };
        if viewport.width < 1.0 || viewport.height < 1.0 {
            return;
        }
        pass.set_viewport(viewport.x, viewport.y, viewport.width, viewport.height, 0.0, 1.0);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, geometry.slice(..));
        pass.set_vertex_buffer(1, radiance.slice(..));
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }

    /// [`BACKGROUND`] as the clear value: display values, linearised for an sRGB target.
    fn clear_colour(&self) -> wgpu::Color {
        let lin = |c: f64| if self.srgb_target { c.powf(2.2) } else { c };
        wgpu::Color { r: lin(BACKGROUND.r), g: lin(BACKGROUND.g), b: lin(BACKGROUND.b), a: 1.0 }
    }

    fn depth_view(&mut self, device: &wgpu::Device, (w, h): (u32, u32)) -> wgpu::TextureView {
        match &self.depth {
            Some((view, dw, dh)) if (*dw, *dh) == (w, h) => view.clone(),
            _ => {
                let texture = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("viewer depth"),
                    size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: DEPTH_FORMAT,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                });
                let view = texture.create_view(&Default::default());
                self.depth = Some((view.clone(), w, h));
                view
            }
        }
    }
}

fn buffer<T: Pod>(device: &wgpu::Device, label: &str, data: &[T], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(data),
        usage: usage | wgpu::BufferUsages::COPY_DST,
    })
}
