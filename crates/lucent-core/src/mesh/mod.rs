//! Triangle meshes: the flat data every later stage reads (positions and index triples),
//! loading and validation, generators and deformers (Mertens §5.1, §6), and the bounding volume
//! hierarchy that answers ray and closest-point queries against a (deforming) mesh ([`bvh`]).

use glam::Vec3;

pub mod bvh;
pub mod deform;
pub mod embedded;
mod error;
pub mod generate;
pub mod gltf_material;
pub mod io;
mod io_gltf;
pub mod refine;
pub mod texture;
pub mod unfold;
pub mod validate;

pub use bvh::Bvh;
pub use error::MeshError;
pub use gltf_material::{GltfMaterial, load_gltf_material, parse_gltf_material};
pub use io::{MeshFormat, load_mesh, load_mesh_with_report, load_textured_mesh};
pub use io_gltf::load_gltf_volume_params;
pub use validate::MeshReport;

/// An indexed triangle mesh. Faces are counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, in mesh units (the model scale maps them to metres).
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// A mesh from its parts (not validated; see [`validate::validate`]).
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Self {
        Mesh { positions, triangles }
    }

    /// The three corner positions of face `f`.
    #[inline]
    pub fn corners(&self, f: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[f];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// `(b - a) x (c - a)` of face `f`: twice its area times its unit normal.
    #[inline]
    pub fn face_cross(&self, f: usize) -> Vec3 {
        let [a, b, c] = self.corners(f);
        (b - a).cross(c - a)
    }

    /// Area of face `f`, in mesh units^2.
    #[inline]
    pub fn face_area(&self, f: usize) -> f32 {
        0.5 * self.face_cross(f).length()
    }

    /// Unit normal of face `f` (zero for a degenerate face).
    #[inline]
    pub fn face_normal(&self, f: usize) -> Vec3 {
        self.face_cross(f).normalize_or_zero()
    }

    /// Barycentric coordinates `(u, v)` of `p` (projected on face `f`'s plane) in face `f`:
    /// `p ≈ a + u (b - a) + v (c - a)` for its corners `a, b, c`; `(0, 0)` for a degenerate
    /// face. [`Mesh::point_at`] goes back, and follows the face as the mesh deforms.
    pub fn barycentric(&self, f: usize, p: Vec3) -> [f32; 2] {
        let [a, b, c] = self.corners(f);
        let (e1, e2, d) = (b - a, c - a, p - a);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d1, d2) = (d.dot(e1), d.dot(e2));
        let det = d11 * d22 - d12 * d12;
        if det.is_nan() || det <= 0.0 {
            return [0.0, 0.0];
        }
        [(d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det]
    }

    /// The point at barycentric coordinates `uv` ([`Mesh::barycentric`]) of face `f`.
    #[inline]
    pub fn point_at(&self, f: usize, [u, v]: [f32; 2]) -> Vec3 {
        let [a, b, c] = self.corners(f);
        a + (b - a) * u + (c - a) * v
    }

    /// Centroid of face `f` (the "midpoint" of Mertens §3.1).
    #[inline]
    pub fn face_centroid(&self, f: usize) -> Vec3 {
        let [a, b, c] = self.corners(f);
        (a + b + c) / 3.0
    }

    /// Area-weighted vertex normals (zero where a vertex has no non-degenerate face).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut n = vec![Vec3::ZERO; self.positions.len()];
        for (f, tri) in self.triangles.iter().enumerate() {
            let c = self.face_cross(f);
            for &v in tri {
                n[v as usize] += c;
            }
        }
        n.iter_mut().for_each(|v| *v = v.normalize_or_zero());
        n
    }

    /// Axis-aligned bounding box `(min, max)`; `(0, 0)` for an empty mesh.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.positions.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        self.positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
    }

    /// The largest side of the bounding box, in mesh units: the length that the model scale
    /// (metres) refers to.
    pub fn extent(&self) -> f32 {
        let (lo, hi) = self.bounds();
        (hi - lo).max_element()
    }

    /// Total surface area, in mesh units^2.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len()).map(|f| self.face_area(f) as f64).sum()
    }

    /// Averages per-face values to vertices, weighting each face by its area (Mertens §3.2:
    /// "the accumulated results at the leaf nodes are averaged at the vertices").
    pub fn face_to_vertex(&self, face_values: &[Vec3]) -> Vec<Vec3> {
        self.face_to_vertex_over(face_values, |_| true)
    }

    /// [`Mesh::face_to_vertex`] over the faces `counts` picks only (a vertex on none gets 0):
    /// e.g. only the faces a view ray was traced at.
    pub fn face_to_vertex_over(&self, face_values: &[Vec3], counts: impl Fn(usize) -> bool) -> Vec<Vec3> {
        assert_eq!(face_values.len(), self.triangles.len());
        let mut sum = vec![Vec3::ZERO; self.positions.len()];
        let mut weight = vec![0.0f32; self.positions.len()];
        for (f, tri) in self.triangles.iter().enumerate().filter(|&(f, _)| counts(f)) {
            let a = self.face_area(f);
            for &v in tri {
                sum[v as usize] += a * face_values[f];
                weight[v as usize] += a;
            }
        }
        sum.iter().zip(&weight).map(|(s, w)| if *w > 0.0 { *s / *w } else { Vec3::ZERO }).collect()
    }

    /// Each vertex's faces as compressed rows `(offsets, faces)`: vertex `v`'s faces are
    /// `faces[offsets[v]..offsets[v + 1]]`.
    pub fn vertex_faces(&self) -> (Vec<u32>, Vec<u32>) {
        let mut offsets = vec![0u32; self.positions.len() + 1];
        for tri in &self.triangles {
            for &v in tri {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..self.positions.len() {
            offsets[v + 1] += offsets[v];
        }
        let mut next = offsets.clone();
        let mut faces = vec![0u32; offsets[self.positions.len()] as usize];
        for (f, tri) in self.triangles.iter().enumerate() {
            for &v in tri {
                faces[next[v as usize] as usize] = f as u32;
                next[v as usize] += 1;
            }
        }
        (offsets, faces)
    }
}

/// `(from, to)` pairs, sorted, as compressed rows over `n` sources: the `to`s of source `i`
/// are `targets[start[i]..start[i + 1]]`. Returns `(start, targets)`.
pub(crate) fn compressed_rows(sorted_pairs: Vec<(u32, u32)>, n: usize) -> (Vec<u32>, Vec<u32>) {
    debug_assert!(sorted_pairs.is_sorted_by_key(|p| p.0));
    let mut start = vec![0u32; n + 1];
    for &(a, _) in &sorted_pairs {
        start[a as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    (start, sorted_pairs.into_iter().map(|(_, b)| b).collect())
}
