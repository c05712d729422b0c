//! The rays that measure the body under each face for its finite-body gain ([`super`]): the
//! thickness along the inward normal and the slabness from four tilted rays, traced once and
//! moved with a deforming mesh.

use crate::mesh::Mesh;
use crate::mesh::bvh::Bvh;
use crate::mesh::deform::TracedPose;
use rayon::prelude::*;

/// How far the part under a face is a slab (1) rather than a sphere (0) of its thickness `t`
/// along the inward normal, from the `chords` of the four rays tilted 45° from it (`offset`
/// inside the face): the mean of where each falls between a sphere's `t cos 45°` and a slab's
/// `t / cos 45°`. A ray that left the mesh (`None`) counts as a slab.
pub(super) fn slabness(chords: [Option<f32>; 4], t: f32, offset: f32) -> f64 {
    let cos = std::f32::consts::FRAC_1_SQRT_2;
    let s: f32 = chords
        .iter()
        .map(|c| c.map_or(1.0, |c| (((c + offset) / t - cos) / (1.0 / cos - cos)).clamp(0.0, 1.0)))
        .sum();
    s as f64 / 4.0
}

/// Where a ray under a face hit the mesh: the face, and the place on it (barycentric), which a
/// deformation carries along.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RayHit {
    k: u32,
    uv: [f32; 2],
}

/// The rays that measure the body under each face for its gain: one along the inward normal
/// (the thickness) and four tilted 45° from it (the slabness). Traced once and kept; a deformed
/// mesh moves their hits with it while the traced pose holds ([`TracedPose::holds`]), and
/// traces again only the faces that turned more than [`MAX_TURN`] ([`Self::refresh`]), so an
/// animation does not trace them every frame (tracing them was most of a deforming frame's
/// irradiance).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ThicknessRays {
    /// Per face: the inward ray's hit, then the four tilted rays' (`None`: it left the mesh).
    hits: Vec<[Option<RayHit>; 5]>,
    /// Per face: its unit normal when its rays were traced.
    normals: Vec<glam::Vec3>,
    pose: TracedPose,
}

/// Largest turn of a face's normal (radians) since its rays were traced up to which they are
/// moved with the mesh; past it they are traced again. On a thin part a turning face's rays
/// find the far side elsewhere: under a bump growing on the bunny's ear the worst face's `B`
/// was 31% off a new trace's without this limit, 13% with it (as with the bounce rays alone).
pub const MAX_TURN: f32 = 0.05;

/// Face `f`'s rays traced against `bvh` (over `mesh`) from `offset` inside it.
fn trace_face(mesh: &Mesh, bvh: &Bvh, offset: f32, f: usize) -> [Option<RayHit>; 5] {
    let n = mesh.face_normal(f);
    if n == glam::Vec3::ZERO {
        return [None; 5];
    }
    let origin = mesh.face_centroid(f) - n * offset;
    ray_directions(n).map(|d| {
        let (t, k) = bvh.closest_hit(origin, d, 0.0, f32::INFINITY)?;
        Some(RayHit { k, uv: mesh.barycentric(k as usize, origin + d * t) })
    })
}

impl ThicknessRays {
    /// Traces the rays of every face of `mesh` against `bvh` (over `mesh`) from `offset`
    /// inside each face.
    pub fn trace(mesh: &Mesh, bvh: &Bvh, offset: f32) -> Self {
        let faces = mesh.triangles.len();
        // In the tree's leaf order: neighbours' rays walk the same nodes.
        let hits = bvh.map_faces(|f| trace_face(mesh, bvh, offset, f));
        let normals = (0..faces).map(|f| mesh.face_normal(f)).collect();
        ThicknessRays { hits, normals, pose: TracedPose::of(mesh) }
    }

    /// How many faces these rays measure.
    pub(super) fn faces(&self) -> usize {
        self.hits.len()
    }

    /// Whether these rays serve `mesh`: the same faces, and the pose traced still holds.
    pub fn fits(&self, mesh: &Mesh) -> bool {
        self.hits.len() == mesh.triangles.len() && self.pose.holds(mesh)
    }

    /// Traces again, against `bvh` (over `mesh`, which these rays fit), the rays of the faces
    /// whose normal turned more than [`MAX_TURN`] since they were traced.
    pub fn refresh(&mut self, mesh: &Mesh, bvh: &Bvh, offset: f32) {
        let min_cos = MAX_TURN.cos();
        self.hits.par_iter_mut().zip(self.normals.par_iter_mut()).enumerate().for_each(|(f, (hits, n0))| {
            let n = mesh.face_normal(f);
            if n.dot(*n0) < min_cos {
                *hits = trace_face(mesh, bvh, offset, f);
                *n0 = n;
            }
        });
    }

    /// The body under face `f` of `mesh` as it is now: its thickness along the inward normal
    /// (mesh units, from the face) and its [`slabness`] (0..=1); `None` where the inward ray
    /// left the mesh or the face has no normal. What the gain and the exit chord read.
    pub(crate) fn body(&self, mesh: &Mesh, f: usize, offset: f32) -> Option<(f32, f64)> {
        let [inward, tilted @ ..] = self.chords(mesh, f, offset);
        let t = inward? + offset;
        Some((t, slabness(tilted, t, offset)))
    }

    /// The face that face `f`'s inward ray hit (the far side of the body under it), `None` where
    /// it left the mesh.
    pub(crate) fn inward_face(&self, f: usize) -> Option<usize> {
        self.hits[f][0].map(|h| h.k as usize)
    }

    /// Face `f`'s five chords on `mesh` as it is now (mesh units): from the rays' origin,
    /// `offset` inside the face's centroid, along the rays as [`Self::trace`] casts them from
    /// the face's normal now, to the plane of the face each hit (to the place it hit on that
    /// face where the ray runs nearly along it). The inward ray first; `None` where a ray left
    /// the mesh or the face has no normal. A thin part's thickness along the normal changes
    /// faster than the distance to a point on its far side as its faces tilt (the bunny's ear
    /// under a growing bump: 0.11 -> 0.20 along the normal, 0.14 to the point).
    pub(super) fn chords(&self, mesh: &Mesh, f: usize, offset: f32) -> [Option<f32>; 5] {
        let n = mesh.face_normal(f);
        if n == glam::Vec3::ZERO {
            return [None; 5];
        }
        let origin = mesh.face_centroid(f) - n * offset;
        let dirs = ray_directions(n);
        std::array::from_fn(|i| {
            let h = self.hits[f][i]?;
            let at = mesh.point_at(h.k as usize, h.uv);
            let nk = mesh.face_normal(h.k as usize);
            let along = dirs[i].dot(nk);
            let t = (at - origin).dot(nk) / along;
            Some(if along.abs() > 0.1 && t > 0.0 { t } else { at.distance(origin) })
        })
    }
}

/// The five rays under a face of unit normal `n`: along the inward normal, then tilted 45°
/// from it four ways.
fn ray_directions(n: glam::Vec3) -> [glam::Vec3; 5] {
    let cos = std::f32::consts::FRAC_1_SQRT_2;
    let (u, v) = n.any_orthonormal_pair();
    [-n, (u - n) * cos, (-u - n) * cos, (v - n) * cos, (-v - n) * cos]
}
