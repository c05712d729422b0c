//! The queries on a [`Bvh`]: any hit (shadow rays), closest hit (picking, subsurface
//! bounces), farthest hit and hit count (shrink-wrapping's projection and inside test), and the
//! closest point of the mesh (shrink-wrapping, Mertens §5.1.2). Rays hit triangles from either
//! side, and a ray's parameter `t` is in units of the length of its direction.

use super::wide::RayWalk;
use super::{Bvh, BvhNode};
use glam::Vec3;
use std::ops::Range;

impl Bvh {
    /// Whether any triangle (either side) is hit by the ray `origin + t dir` for
    /// `t_min < t < t_max` (`dir` need not be unit; `t` is in units of its length).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        let any_hit = |range: Range<usize>, lo: f32| {
            self.tris[range].iter().any(|t| ray_triangle(origin, dir, t, lo, t_max))
        };
        match self.ray_leaves(origin, dir, t_min, t_max, |range, lo, _| any_hit(range, *lo)) {
            RayWalk::Stopped => true,
            RayWalk::Done => false,
            RayWalk::TooDeep => any_hit(0..self.tris.len(), t_min),
        }
    }

    /// The nearest intersection of the ray `origin + t dir` with the mesh (either side) for
    /// `t_min < t < t_max`: `(t, mesh face)`, or `None` if it hits nothing.
    ///
    /// This is the ray pick: the hit point is `origin + t dir` (`t` in units of `|dir|`), and
    /// the face indexes the mesh's `triangles` (refitting keeps the indices). A ray from a
    /// camera wants `t_min` a little above 0 and `t_max = f32::INFINITY`.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        let mut nearest = |range: Range<usize>, _: &mut f32, hi: &mut f32| {
            for (slot, t) in range.clone().zip(&self.tris[range]) {
                if let Some(th) = ray_triangle_t(origin, dir, t, t_min, *hi) {
                    best = Some((th, self.faces[slot]));
                    *hi = th;
                }
            }
            false
        };
        if let RayWalk::TooDeep = self.ray_leaves(origin, dir, t_min, t_max, &mut nearest) {
            // All triangles again: the nearest of them all, whatever was found before.
            let (mut lo, mut hi) = (t_min, t_max);
            nearest(0..self.tris.len(), &mut lo, &mut hi);
        }
        best
    }

    /// The farthest intersection of the ray `origin + t dir` with the mesh (either side) for
    /// `t_min < t < t_max`: `(t, mesh face)`, or `None` if it hits nothing.
    pub fn farthest_hit(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        let mut farthest = |range: Range<usize>, lo: &mut f32, _: &mut f32| {
            for (slot, t) in range.clone().zip(&self.tris[range]) {
                if let Some(th) = ray_triangle_t(origin, dir, t, *lo, t_max) {
                    best = Some((th, self.faces[slot]));
                    *lo = th;
                }
            }
            false
        };
        if let RayWalk::TooDeep = self.ray_leaves(origin, dir, t_min, t_max, &mut farthest) {
            let (mut lo, mut hi) = (t_min, t_max);
            farthest(0..self.tris.len(), &mut lo, &mut hi);
        }
        best
    }

    /// How many triangles (either side) the ray `origin + t dir` hits for `t_min < t < t_max`
    /// (an inside/outside test for a closed mesh: odd inside).
    pub fn hit_count(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> usize {
        let hits = |range: Range<usize>| {
            self.tris[range].iter().filter(|t| ray_triangle(origin, dir, t, t_min, t_max)).count()
        };
        let mut count = 0;
        match self.ray_leaves(origin, dir, t_min, t_max, |range, _, _| {
            count += hits(range);
            false
        }) {
            RayWalk::TooDeep => hits(0..self.tris.len()),
            _ => count,
        }
    }

    /// The point of the mesh nearest to `p`: `(mesh face, point, squared distance)`, or `None`
    /// for an empty tree. Branch and bound over the boxes, nearer child first. Used by
    /// shrink-wrapping (Mertens §5.1.2) to project vertices onto a target surface.
    pub fn closest_point(&self, p: Vec3) -> Option<(u32, Vec3, f32)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best = (u32::MAX, Vec3::ZERO, f32::INFINITY);
        let mut stack = [(0u32, 0.0f32); 64];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let (index, d2) = stack[top];
            if d2 >= best.2 {
                continue;
            }
            let node = &self.nodes[index as usize];
            if node.is_leaf() {
                let range = node.first as usize..(node.first + node.count) as usize;
                for (slot, t) in range.clone().zip(&self.tris[range]) {
                    let q = closest_on_triangle(p, t);
                    let d = (q - p).length_squared();
                    if d < best.2 {
                        best = (self.faces[slot], q, d);
                    }
                }
                continue;
            }
            let (l, r) = (index + 1, node.first);
            let (dl, dr) =
                (box_distance2(p, &self.nodes[l as usize]), box_distance2(p, &self.nodes[r as usize]));
            if top + 2 > stack.len() {
                // Pathologically deep tree: finish by brute force rather than overflow.
                for (slot, t) in self.tris.iter().enumerate() {
                    let q = closest_on_triangle(p, t);
                    let d = (q - p).length_squared();
                    if d < best.2 {
                        best = (self.faces[slot], q, d);
                    }
                }
                break;
            }
            // Push the farther child first so the nearer one is popped next.
            let (first, second) = if dl <= dr { ((r, dr), (l, dl)) } else { ((l, dl), (r, dr)) };
            stack[top] = first;
            stack[top + 1] = second;
            top += 2;
        }
        Some(best)
    }

    /// The leaves the ray `origin + t dir` enters for `t_min < t < t_max`, nearer first
    /// ([`super::wide::walk`] over the four-wide tree).
    #[inline]
    fn ray_leaves(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
        leaf: impl FnMut(Range<usize>, &mut f32, &mut f32) -> bool,
    ) -> RayWalk {
        super::wide::walk(&self.wide, origin, dir, t_min, t_max, leaf)
    }
}

/// Squared distance from `p` to the node's box (0 inside).
#[inline]
fn box_distance2(p: Vec3, n: &BvhNode) -> f32 {
    let d = (n.min - p).max(p - n.max).max(Vec3::ZERO);
    d.length_squared()
}

/// The point of triangle `t` nearest to `p`, by the Voronoi region of `p` (vertex, edge or
/// face region; Ericson, "Real-Time Collision Detection" §5.1.5).
pub fn closest_on_triangle(p: Vec3, t: &[Vec3; 3]) -> Vec3 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom.abs() < f32::MIN_POSITIVE {
        // Degenerate (zero-area) triangle that fell through: its first corner will do.
        return a;
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

/// Möller–Trumbore, both sides: whether the ray hits triangle `t` at `t_min < t < t_max`.
#[inline]
fn ray_triangle(origin: Vec3, dir: Vec3, tri: &[Vec3; 3], t_min: f32, t_max: f32) -> bool {
    ray_triangle_t(origin, dir, tri, t_min, t_max).is_some()
}

/// Möller–Trumbore, both sides: the ray parameter of the hit with triangle `t` if it lies in
/// `t_min < t < t_max`.
#[inline]
fn ray_triangle_t(origin: Vec3, dir: Vec3, tri: &[Vec3; 3], t_min: f32, t_max: f32) -> Option<f32> {
    use glam::Vec3A;
    let (origin, dir) = (Vec3A::from(origin), Vec3A::from(dir));
    let tri = tri.map(Vec3A::from);
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-20 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - tri[0];
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
    (t > t_min && t < t_max).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ray queries against every triangle tried in turn on `rays` random rays through and
    /// around `mesh`, from outside and from on its surface (as the bounce and thickness rays
    /// are); returns how many hit.
    fn agree_with_brute_force(mesh: &crate::mesh::Mesh, bvh: &Bvh, rays: usize) -> usize {
        let (lo, hi) = mesh.bounds();
        let mut seed = 0x2545_f491_u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32
        };
        let tris: Vec<[Vec3; 3]> = (0..mesh.triangles.len()).map(|f| mesh.corners(f)).collect();
        let mut hits = 0;
        for i in 0..rays {
            let origin = if i % 2 == 0 || tris.is_empty() {
                lo - (hi - lo) * 0.25 + (hi - lo) * 1.5 * Vec3::new(rnd(), rnd(), rnd())
            } else {
                mesh.face_centroid((rnd() * mesh.triangles.len() as f32) as usize % mesh.triangles.len())
            };
            // Every seventh ray along an axis: direction components of exactly 0.
            let dir = if i % 7 == 3 {
                [Vec3::X, Vec3::NEG_Y, Vec3::Z][i % 3]
            } else {
                Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize()
            };
            let (t_min, t_max) = (1e-4, if i % 3 == 0 { 5.0 } else { f32::INFINITY });
            let ts: Vec<f32> =
                tris.iter().filter_map(|t| ray_triangle_t(origin, dir, t, t_min, t_max)).collect();
            let nearest = ts.iter().copied().fold(f32::INFINITY, f32::min);
            let farthest = ts.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            assert_eq!(
                bvh.closest_hit(origin, dir, t_min, t_max).map(|h| h.0),
                (!ts.is_empty()).then_some(nearest)
            );
            assert_eq!(
                bvh.farthest_hit(origin, dir, t_min, t_max).map(|h| h.0),
                (!ts.is_empty()).then_some(farthest)
            );
            assert_eq!(bvh.occluded(origin, dir, t_min, t_max), !ts.is_empty());
            assert_eq!(bvh.hit_count(origin, dir, t_min, t_max), ts.len());
            if let Some((t, f)) = bvh.closest_hit(origin, dir, t_min, t_max) {
                assert_eq!(
                    ray_triangle_t(origin, dir, &tris[f as usize], t_min, t_max),
                    Some(t),
                    "the face hit"
                );
            }
            hits += ts.len().min(1);
        }
        hits
    }

    #[test]
    fn ray_queries_agree_with_brute_force() {
        let mesh = crate::mesh::embedded::bunny();
        let hits = agree_with_brute_force(&mesh, &Bvh::build(&mesh), 400);
        assert!(hits > 100, "{hits} of 400 rays hit");
    }

    /// The four-wide tree the queries walk follows a refit (a twisted bunny, without a
    /// rebuild), and trees of no, one and two triangles (a root that is a leaf).
    #[test]
    fn ray_queries_agree_after_a_refit_and_on_tiny_trees() {
        let mut mesh = crate::mesh::embedded::bunny();
        let mut bvh = Bvh::build(&mesh);
        let (lo, hi) = mesh.bounds();
        for p in &mut mesh.positions {
            let a = 1.5 * (p.y - lo.y) / (hi.y - lo.y);
            *p = Vec3::new(p.x * a.cos() - p.z * a.sin(), p.y, p.x * a.sin() + p.z * a.cos());
        }
        bvh.refit(&mesh);
        let hits = agree_with_brute_force(&mesh, &bvh, 300);
        assert!(hits > 60, "{hits} of 300 rays hit");
        let (p, t) = (mesh.positions.clone(), mesh.triangles.clone());
        for n in [0, 1, 2] {
            let small = crate::mesh::Mesh::new(p.clone(), t[..n].to_vec());
            agree_with_brute_force(&small, &Bvh::build(&small), 100);
        }
    }
}
