//! How the lights' transmitted irradiance changes across a face (issue 51, dense materials):
//! from its centroid, where the solve samples it (Mertens §5.3), to each of its corners, on the
//! face's own plane and normal, shadowed as at the centroid. Where transport is far below a
//! face's size, `B` follows the irradiance point by point (the local limit `B = R_d E`), so
//! these changes are what a face's one `B` misses of a shadow edge or of the light's cosine
//! across it (`session::local_limit` adds them at the vertices instead of splitting the face).
//! The environment's change across a face is left out: its nine-coefficient radiance varies
//! slowly with the normal, which is the face's own at every corner, and its shadows are
//! estimated with 64 rays per point (`occlusion`), too many to spend three times a face.

use super::{Entering, SceneLight, ShadowCaster, add_lights};
use crate::Rgb;
use crate::bssrdf::Entry;
use crate::mesh::Mesh;
use rayon::prelude::*;

/// The change of one part of [`Entering`] from a face's centroid to a corner, per channel
/// (signed, irradiance units).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CornerChange {
    /// Of the irradiance the profile carries ([`Entering::carried`]).
    pub carried: Rgb,
    /// Of the irradiance returned at the entry face ([`Entering::local`]).
    pub local: Rgb,
}

/// For each face in `faces`, the lights' transmitted irradiance at its three corners (in the
/// order of `mesh.triangles`) less that at its centroid, on the face's plane with its normal,
/// through the `entry` term, shadowed by `caster` where a light says so: one ray per light and
/// point, as the solve's irradiance at the centroid.
pub fn corner_changes(
    mesh: &Mesh,
    faces: &[u32],
    lights: &[SceneLight],
    entry: &Entry,
    caster: Option<&ShadowCaster>,
) -> Vec<[CornerChange; 3]> {
    faces
        .par_iter()
        .map(|&f| {
            let f = f as usize;
            let n = mesh.face_normal(f);
            let at = |p| {
                let mut e = Entering::default();
                add_lights(&mut e, p, n, lights, entry, caster, &mut []);
                e
            };
            let centre = at(mesh.face_centroid(f));
            mesh.corners(f).map(|p| {
                let e = at(p);
                CornerChange { carried: e.carried - centre.carried, local: e.local - centre.local }
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::irradiance::Light;
    use glam::Vec3;

    /// A point light above one corner of a flat triangle: the corner under it gets more than
    /// the centroid and the far corners less, by the inverse square and cosine of each point;
    /// a light behind the face gives no change.
    #[test]
    fn corners_follow_the_inverse_square_and_the_cosine() {
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
        let entry = Entry::fresnel(1.0);
        let light = |z: f32| {
            vec![SceneLight::from(Light::Point { position: Vec3::new(0.0, 0.0, z), intensity: Rgb::ONE })]
        };
        let c = corner_changes(&mesh, &[0], &light(1.0), &entry, None)[0];
        let e = |p: Vec3| {
            let d = Vec3::new(0.0, 0.0, 1.0) - p;
            let cos = d.normalize().z;
            cos / d.length_squared() * entry.at(cos).x
        };
        let centre = e(Vec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0));
        for (k, p) in [Vec3::ZERO, Vec3::X, Vec3::Y].into_iter().enumerate() {
            let want = e(p) - centre;
            assert!(
                (c[k].carried.x - want).abs() < 1e-5 * e(Vec3::ZERO),
                "corner {k}: {} vs {want}",
                c[k].carried.x
            );
        }
        assert!(c[0].carried.x > 0.0 && c[1].carried.x < 0.0);
        let behind = corner_changes(&mesh, &[0], &light(-1.0), &entry, None)[0];
        assert_eq!(behind, [CornerChange::default(); 3]);
    }
}
