//! Shadows for the leaf irradiance (Mertens §5.3): one ray from each face midpoint to each
//! shadow-casting light, against a bounding volume hierarchy of the mesh ([`Bvh`]) that is
//! *refitted* every frame, so shadows follow a deforming mesh.
//!
//! Mertens use shadow maps on the GPU. Ray casting on the CPU fits this solver better: the
//! per-face irradiance is needed on the CPU anyway (it feeds the hierarchical gather), so there is
//! no GPU read-back and its latency; the test is exact at the face midpoints where the solver
//! samples irradiance (no shadow-map resolution, bias or acne trade-offs); and it runs without a
//! GPU. Deformations keep the topology (§5.1), so the tree is built once and only its boxes are
//! refitted each frame, with a rebuild when refitting has made the tree much worse (its surface
//! area heuristic cost grew past [`ShadowCaster::rebuild_ratio`] times the cost when built).

use super::lights::Incident;
use crate::mesh::Mesh;
use crate::mesh::bvh::Bvh;
use glam::Vec3;

/// How [`ShadowCaster::update`] brought the tree up to date.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Update {
    /// Boxes refitted, tree kept.
    Refit,
    /// Tree rebuilt (topology changed, or refitting degraded it past the rebuild ratio).
    Rebuild,
}

/// Casts shadow rays from face midpoints against the mesh. Create once, [`update`] each frame
/// after the mesh deforms.
///
/// [`update`]: ShadowCaster::update
#[derive(Clone, Debug)]
pub struct ShadowCaster {
    bvh: Bvh,
    /// Rebuild instead of refit when the refitted tree's SAH cost exceeds this many times its
    /// cost when built (default 2.0; `f32::INFINITY` always refits).
    pub rebuild_ratio: f32,
    /// Ray origins are moved this far along the face normal, and rays stop this short of the
    /// light, as a fraction of the mesh's bounding-box diagonal (default 1e-4), so a face does not
    /// shadow itself through rounding.
    pub relative_offset: f32,
}

impl ShadowCaster {
    /// Builds the tree for `mesh`.
    pub fn new(mesh: &Mesh) -> Self {
        ShadowCaster { bvh: Bvh::build(mesh), rebuild_ratio: 2.0, relative_offset: 1e-4 }
    }

    /// Brings the tree up to date with the mesh's current positions: a refit, or a rebuild when
    /// the triangle count changed or refitting made the tree too slow (see `rebuild_ratio`).
    pub fn update(&mut self, mesh: &Mesh) -> Update {
        if mesh.triangles.len() != self.bvh.len() {
            self.bvh = Bvh::build(mesh);
            return Update::Rebuild;
        }
        self.bvh.refit(mesh);
        if self.bvh.sah_cost() > self.rebuild_ratio * self.bvh.built_cost() {
            self.bvh = Bvh::build(mesh);
            return Update::Rebuild;
        }
        Update::Refit
    }

    /// The tree.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// The offset in mesh units (see `relative_offset`).
    pub fn offset(&self) -> f32 {
        let (lo, hi) = self.bvh.bounds();
        self.relative_offset * (hi - lo).length()
    }

    /// Whether the light described by `inc` reaches point `p` on a surface with unit normal
    /// `n` (the ray starts `offset()` above the surface).
    pub fn visible(&self, p: Vec3, n: Vec3, inc: &Incident) -> bool {
        let eps = self.offset();
        let origin = p + n * eps;
        !self.bvh.occluded(origin, inc.to_light, 0.0, inc.distance - eps)
    }
}
