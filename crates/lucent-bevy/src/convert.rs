//! A Bevy mesh as lucent's mesh: positions welded where they coincide (Bevy meshes split
//! vertices at UV and normal seams; lucent's solve wants one surface), degenerate faces dropped.
//! [`Weld`] maps every Bevy vertex to its lucent vertex, both ways.

use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::Mesh;
use lucent_core::Rgb;
use lucent_core::mesh::Mesh as LucentMesh;
use std::collections::HashMap;
use std::hash::{DefaultHasher, Hash, Hasher};

/// How a Bevy mesh's vertices map onto lucent's welded ones.
#[derive(Clone, Debug)]
pub struct Weld {
    /// For every Bevy vertex, its lucent vertex.
    to_lucent: Vec<u32>,
    /// For every lucent vertex, the first Bevy vertex at its position.
    from_lucent: Vec<u32>,
    /// A hash of the Bevy mesh's index buffer (its topology).
    topology: u64,
}

/// The mesh's positions, or a one-line error saying why it cannot be solved.
pub fn positions(mesh: &Mesh) -> Result<&[[f32; 3]], String> {
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return Err(format!("a {:?} mesh: lucent solves triangle lists", mesh.primitive_topology()));
    }
    match mesh.attribute(Mesh::ATTRIBUTE_POSITION) {
        Some(VertexAttributeValues::Float32x3(p)) => Ok(p),
        Some(_) => Err("the mesh's positions are not Float32x3".into()),
        None => Err("the mesh has no positions".into()),
    }
}

/// The mesh's triangles as Bevy vertex indices (consecutive triples without an index buffer).
fn triangles(mesh: &Mesh, vertices: usize) -> Vec<[u32; 3]> {
    let flat: Vec<u32> = match mesh.indices() {
        Some(Indices::U16(i)) => i.iter().map(|&v| u32::from(v)).collect(),
        Some(Indices::U32(i)) => i.clone(),
        None => (0..vertices as u32).collect(),
    };
    flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
}

fn topology_hash(triangles: &[[u32; 3]], vertices: usize) -> u64 {
    let mut h = DefaultHasher::new();
    (vertices, triangles).hash(&mut h);
    h.finish()
}

impl Weld {
    /// lucent's mesh of `mesh` and the map between the two, or a one-line error.
    pub fn new(mesh: &Mesh) -> Result<(LucentMesh, Weld), String> {
        let p = positions(mesh)?;
        if mesh.attribute(Mesh::ATTRIBUTE_NORMAL).is_none() {
            return Err("the mesh has no normals (Mesh::compute_normals adds them)".into());
        }
        let tris = triangles(mesh, p.len());
        if let Some(t) = tris.iter().find(|t| t.iter().any(|&v| v as usize >= p.len())) {
            return Err(format!("a triangle {t:?} indexes past the {} vertices", p.len()));
        }
        if let Some(v) = p.iter().find(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(format!("a vertex {v:?} is not finite"));
        }
        let mut at: HashMap<[u32; 3], u32> = HashMap::new();
        let mut from_lucent = Vec::new();
        let to_lucent: Vec<u32> = p
            .iter()
            .enumerate()
            .map(|(i, v)| {
                *at.entry(v.map(f32::to_bits)).or_insert_with(|| {
                    from_lucent.push(i as u32);
                    from_lucent.len() as u32 - 1
                })
            })
            .collect();
        let positions: Vec<glam::Vec3> =
            from_lucent.iter().map(|&i| glam::Vec3::from(p[i as usize])).collect();
        let welded: Vec<[u32; 3]> = tris
            .iter()
            .map(|t| t.map(|v| to_lucent[v as usize]))
            .filter(|t| !lucent_core::mesh::validate::is_degenerate(&positions, t))
            .collect();
        if welded.is_empty() {
            return Err("the mesh has no triangle with an area".into());
        }
        let weld = Weld { to_lucent, from_lucent, topology: topology_hash(&tris, p.len()) };
        Ok((LucentMesh::new(positions, welded), weld))
    }

    /// Whether `mesh` still has the topology this weld was made for (same vertex count and
    /// index buffer): then a change of its positions is a deformation.
    pub fn same_topology(&self, mesh: &Mesh) -> bool {
        positions(mesh).is_ok_and(|p| topology_hash(&triangles(mesh, p.len()), p.len()) == self.topology)
    }

    /// lucent's positions for the Bevy `positions` (each lucent vertex at its first Bevy vertex).
    pub fn lucent_positions(&self, positions: &[[f32; 3]]) -> Vec<glam::Vec3> {
        self.from_lucent.iter().map(|&i| glam::Vec3::from(positions[i as usize])).collect()
    }

    /// Per-lucent-vertex values spread to every Bevy vertex (empty stays empty).
    pub fn spread(&self, values: &[Rgb]) -> Vec<[f32; 3]> {
        if values.is_empty() {
            return Vec::new();
        }
        self.to_lucent.iter().map(|&v| values.get(v as usize).map_or([0.0; 3], |r| r.to_array())).collect()
    }

    /// Bevy vertices.
    pub fn bevy_vertices(&self) -> usize {
        self.to_lucent.len()
    }
}

/// A Bevy mesh of lucent's `mesh` with lucent's area-weighted vertex normals (what lucent's own
/// mesh pass draws with). Its positions stay readable on the
/// CPU, as the plugin needs them.
pub fn bevy_mesh(mesh: &LucentMesh) -> Mesh {
    let p: Vec<[f32; 3]> = mesh.positions.iter().map(|v| v.to_array()).collect();
    let n: Vec<[f32; 3]> = mesh.vertex_normals().iter().map(|v| v.to_array()).collect();
    let i: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    Mesh::new(PrimitiveTopology::TriangleList, bevy::asset::RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, p)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, n)
        .with_inserted_indices(Indices::U32(i))
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::asset::RenderAssetUsages;

    /// Two triangles of a unit square, split along the diagonal (four corners, six vertices).
    fn split_square() -> Mesh {
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
            .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, p)
            .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vec![[0.0, 0.0, 1.0]; 6])
    }

    #[test]
    fn a_split_square_welds_to_four_vertices_and_spreads_back_to_six() {
        let (m, w) = Weld::new(&split_square()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(w.bevy_vertices(), 6);
        let values: Vec<Rgb> = (0..4).map(|i| Rgb::splat(i as f32)).collect();
        let spread = w.spread(&values);
        assert_eq!(spread.iter().map(|v| v[0]).collect::<Vec<_>>(), vec![0.0, 1.0, 2.0, 0.0, 2.0, 3.0]);
        assert!(w.same_topology(&split_square()));
    }

    #[test]
    fn meshes_lucent_cannot_solve_get_a_one_line_reason() {
        let no_normals = Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
            .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, vec![[0.0f32; 3]; 3]);
        assert!(Weld::new(&no_normals).unwrap_err().contains("normals"));
        let flat = split_square().with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, vec![[0.0f32; 3]; 6]);
        assert!(Weld::new(&flat).unwrap_err().contains("area"));
        let lines = Mesh::new(PrimitiveTopology::LineList, RenderAssetUsages::default());
        assert!(Weld::new(&lines).unwrap_err().contains("triangle lists"));
    }
}
