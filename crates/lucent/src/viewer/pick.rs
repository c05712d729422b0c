//! Ray picking against the mesh (for denting and for choosing the figure 6.9 triangle).

use glam::Vec3;
use lucent_core::mesh::Mesh;
use rayon::prelude::*;

/// Where a ray first hits the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Face index.
    pub face: u32,
    /// Hit point, mesh units.
    pub point: Vec3,
    /// Distance along the ray, mesh units.
    pub t: f32,
}

/// The nearest hit of the ray `origin + t dir` (t > 0) with any face, both sides counted.
/// Brute force over the faces in parallel: picking happens on clicks, not per pixel.
pub fn pick(mesh: &Mesh, origin: Vec3, dir: Vec3) -> Option<Hit> {
    (0..mesh.triangles.len())
        .into_par_iter()
        .filter_map(|f| {
            let t = intersect(mesh.corners(f), origin, dir)?;
            Some(Hit { face: f as u32, point: origin + t * dir, t })
        })
        .min_by(|a, b| a.t.total_cmp(&b.t))
}

/// The vertex nearest to `p` (for scripted dents).
pub fn nearest_vertex(mesh: &Mesh, p: Vec3) -> Option<Vec3> {
    mesh.positions
        .iter()
        .copied()
        .min_by(|a, b| (*a - p).length_squared().total_cmp(&(*b - p).length_squared()))
}

/// Möller–Trumbore ray/triangle intersection; the distance `t > 0` or `None`.
fn intersect([a, b, c]: [Vec3; 3], origin: Vec3, dir: Vec3) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 1e-6).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ray down the z axis through a two-triangle square hits it at the square's depth.
    #[test]
    fn hits_the_nearest_face() {
        let near = [Vec3::new(-1., -1., 0.), Vec3::new(1., -1., 0.), Vec3::new(0., 1., 0.)];
        let far = near.map(|p| p - Vec3::Z);
        let mesh = Mesh::new([far, near].concat(), vec![[0, 1, 2], [3, 4, 5]]);
        let hit = pick(&mesh, Vec3::new(0.0, 0.0, 5.0), -Vec3::Z).unwrap();
        assert_eq!(hit.face, 1);
        assert!((hit.t - 5.0).abs() < 1e-5);
        assert!(pick(&mesh, Vec3::new(3.0, 0.0, 5.0), -Vec3::Z).is_none());
    }
}
