//! Ray picking against the mesh (for denting and for choosing the figure 6.9 triangle), through
//! lucent-core's BVH: built once per mesh, refitted when the mesh deforms.

use glam::Vec3;
// The one place the viewer names the tree's module (it is moving to `lucent_core::mesh::bvh`).
use lucent_core::mesh::Mesh;
use lucent_core::mesh::bvh::Bvh;
use std::sync::Arc;

/// Where a ray first hits the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Face index.
    pub face: u32,
    /// Hit point, mesh units.
    pub point: Vec3,
    /// Distance along the ray, in units of the direction's length (mesh units for a unit one).
    pub t: f32,
}

/// The nearest hit of the ray `origin + t dir` (t > 0) with any face of the tree, both sides
/// counted.
pub fn pick(bvh: &Bvh, origin: Vec3, dir: Vec3) -> Option<Hit> {
    let (t, face) = bvh.closest_hit(origin, dir, 0.0, f32::INFINITY)?;
    Some(Hit { face, point: origin + t * dir, t })
}

/// Refitting stretches the boxes of a deforming mesh; past this many times the tree's cost when
/// built (its SAH estimate), a rebuild is cheaper over the next clicks (as the shadow caster
/// does).
const REBUILD_RATIO: f32 = 2.0;

/// The BVH of the mesh last picked, kept between clicks. Brought up to date lazily, at the next
/// pick: a deformation (same triangles, moved positions) refits it, a new mesh rebuilds it, and
/// frames without clicks cost nothing.
#[derive(Debug, Default)]
pub struct Picker {
    /// The mesh the tree fits (held, so a new `Arc` is a new mesh) and the tree.
    fitted: Option<(Arc<Mesh>, Bvh)>,
}

impl Picker {
    /// The nearest hit of the ray with `mesh` (see [`pick`]).
    pub fn pick(&mut self, mesh: &Arc<Mesh>, origin: Vec3, dir: Vec3) -> Option<Hit> {
        pick(self.tree(mesh), origin, dir)
    }

    /// The tree for `mesh`, refitted or rebuilt as needed.
    fn tree(&mut self, mesh: &Arc<Mesh>) -> &Bvh {
        let bvh = match self.fitted.take() {
            Some((fitted, bvh)) if Arc::ptr_eq(&fitted, mesh) => bvh,
            // Deformations keep the triangles: move the boxes, keep the tree.
            Some((fitted, mut bvh)) if fitted.triangles == mesh.triangles => {
                bvh.refit(mesh);
                if bvh.sah_cost() > REBUILD_RATIO * bvh.built_cost() {
                    bvh = Bvh::build(mesh);
                }
                bvh
            }
            _ => Bvh::build(mesh),
        };
        &self.fitted.insert((mesh.clone(), bvh)).1
    }
}

/// The vertex nearest to `p` (for scripted dents).
pub fn nearest_vertex(mesh: &Mesh, p: Vec3) -> Option<Vec3> {
    mesh.positions
        .iter()
        .copied()
        .min_by(|a, b| (*a - p).length_squared().total_cmp(&(*b - p).length_squared()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles, one behind the other along z.
    fn two_layers() -> Mesh {
        let near = [Vec3::new(-1., -1., 0.), Vec3::new(1., -1., 0.), Vec3::new(0., 1., 0.)];
        let far = near.map(|p| p - Vec3::Z);
        Mesh::new([far, near].concat(), vec![[0, 1, 2], [3, 4, 5]])
    }

    /// A ray down the z axis through two stacked triangles hits the nearer one.
    #[test]
    fn hits_the_nearest_face() {
        let bvh = Bvh::build(&two_layers());
        let hit = pick(&bvh, Vec3::new(0.0, 0.0, 5.0), -Vec3::Z).unwrap();
        assert_eq!(hit.face, 1);
        assert!((hit.t - 5.0).abs() < 1e-5);
        assert_eq!(hit.point, Vec3::ZERO);
        assert!(pick(&bvh, Vec3::new(3.0, 0.0, 5.0), -Vec3::Z).is_none());
    }

    /// The cached tree follows the mesh: a deformation (refit) and a new mesh (rebuild) are
    /// both picked where they are now, not where the tree was first built.
    #[test]
    fn picker_follows_deformation_and_new_meshes() {
        let mut picker = Picker::default();
        let mesh = Arc::new(two_layers());
        let (o, d) = (Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
        assert_eq!(picker.pick(&mesh, o, d).unwrap().face, 1);

        // Move the front triangle behind the back one: same triangles, new positions.
        let mut moved = (*mesh).clone();
        moved.positions[3..].iter_mut().for_each(|p| p.z = -2.0);
        let moved = Arc::new(moved);
        let hit = picker.pick(&moved, o, d).unwrap();
        assert_eq!(hit.face, 0);
        assert!((hit.t - 6.0).abs() < 1e-5);

        // A different mesh: the back triangle alone.
        let single = Arc::new(Mesh::new(mesh.positions[..3].to_vec(), vec![[0, 1, 2]]));
        assert_eq!(picker.pick(&single, o, d).unwrap().face, 0);
        assert!(picker.pick(&single, Vec3::new(0.0, 0.0, -5.0), Vec3::Z).is_some(), "both sides");
    }
}
