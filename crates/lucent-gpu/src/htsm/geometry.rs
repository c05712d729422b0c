//! The mesh on the GPU for HTSM (§4.2's polygonal half of the hybrid representation), with
//! deformation: each vertex carries its deformed position and normal, which
//! [`super::HtsmRenderer::set_positions`] replaces, and its rest position, which stays. The
//! density volume spans the rest bounding box, so the shaders' texture coordinate (the rest
//! position in that box, `[0,1]^3`) ties every surface point to the density of its rest position
//! however the mesh moves.

use super::HtsmError;
use super::pipeline::Vertex;
use glam::Vec3;
use lucent_core::camera::bounding_sphere;
use lucent_core::mesh::Mesh;
use wgpu::util::DeviceExt;

/// Vertex and index buffers, and the bounds the passes need.
pub(super) struct Geometry {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    triangles: Vec<[u32; 3]>,
    rest: Vec<Vec3>,
    /// Rest bounding box (mesh units): the density volume's extent, fixed.
    pub box_min: Vec3,
    pub box_size: Vec3,
    /// Bounding sphere of the current (deformed) positions, for the light frusta.
    pub sphere: (Vec3, f32),
    /// Whether any deformed position differs from its rest position. At rest every deformation
    /// offset is exactly zero, so the camera pass skips reading the lit surface's.
    pub deformed: bool,
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

/// Vertices of `positions` (deformed) over `rest`, with area-weighted normals of the deformed
/// surface.
fn vertices(positions: &[Vec3], rest: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vertex> {
    let normals = Mesh::new(positions.to_vec(), triangles.to_vec()).vertex_normals();
    positions
        .iter()
        .zip(&normals)
        .zip(rest)
        .map(|((p, n), r)| Vertex { position: p.to_array(), normal: n.to_array(), rest: r.to_array() })
        .collect()
}

impl Geometry {
    /// Uploads `mesh` at rest (deformed = rest positions).
    pub fn new(device: &wgpu::Device, mesh: &Mesh) -> Result<Geometry, HtsmError> {
        validate_mesh(mesh)?;
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("htsm vertices"),
            contents: bytemuck::cast_slice(&vertices(&mesh.positions, &mesh.positions, &mesh.triangles)),
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("htsm indices"),
            contents: bytemuck::cast_slice(&mesh.triangles),
            usage: wgpu::BufferUsages::INDEX,
        });
        let (box_min, box_max) = mesh.bounds();
        Ok(Geometry {
            vertices,
            indices,
            index_count: (mesh.triangles.len() * 3) as u32,
            triangles: mesh.triangles.clone(),
            rest: mesh.positions.clone(),
            box_min,
            box_size: box_max - box_min,
            sphere: bounding_sphere(&mesh.positions),
            deformed: false,
        })
    }

    /// Replaces the deformed positions (and their normals); rest positions stay.
    pub fn set_positions(&mut self, queue: &wgpu::Queue, positions: &[Vec3]) -> Result<(), HtsmError> {
        if positions.len() != self.rest.len() {
            return Err(HtsmError::Mesh(format!(
                "{} deformed positions for a mesh of {} vertices (the topology must stay)",
                positions.len(),
                self.rest.len()
            )));
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(HtsmError::Mesh("a deformed vertex position is not finite".into()));
        }
        let data = vertices(positions, &self.rest, &self.triangles);
        queue.write_buffer(&self.vertices, 0, bytemuck::cast_slice(&data));
        self.sphere = bounding_sphere(positions);
        self.deformed = positions != self.rest.as_slice();
        Ok(())
    }

    /// The rest mesh's largest bounding-box side, mesh units: one object unit.
    pub fn extent(&self) -> f32 {
        self.box_size.max_element()
    }

    /// Records the indexed draw of the whole mesh.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}
