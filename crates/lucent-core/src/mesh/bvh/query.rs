//! The queries on a [`Bvh`]: any hit (shadow rays), closest hit (picking, subsurface
//! bounces), farthest hit and hit count (shrink-wrapping's projection and inside test), and the
//! closest point of the mesh (shrink-wrapping, Mertens §5.1.2). Rays hit triangles from either
//! side, and a ray's parameter `t` is in units of the length of its direction.

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
        match self.ray_leaves(origin, dir, t_min, t_max, |range, lo| any_hit(range, *lo)) {
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
        let mut nearest = |range: Range<usize>, _: &mut f32| {
            for (slot, t) in range.clone().zip(&self.tris[range]) {
                let upper = best.map_or(t_max, |b| b.0);
                if let Some(th) = ray_triangle_t(origin, dir, t, t_min, upper) {
                    best = Some((th, self.faces[slot]));
                }
            }
            false
        };
        if let RayWalk::TooDeep = self.ray_leaves(origin, dir, t_min, t_max, &mut nearest) {
            let mut lo = t_min;
            nearest(0..self.tris.len(), &mut lo);
        }
        best
    }

    /// The farthest intersection of the ray `origin + t dir` with the mesh (either side) for
    /// `t_min < t < t_max`: `(t, mesh face)`, or `None` if it hits nothing.
    pub fn farthest_hit(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        let mut farthest = |range: Range<usize>, lo: &mut f32| {
            for (slot, t) in range.clone().zip(&self.tris[range]) {
                if let Some(th) = ray_triangle_t(origin, dir, t, *lo, t_max) {
                    best = Some((th, self.faces[slot]));
                    *lo = th;
                }
            }
            false
        };
        if let RayWalk::TooDeep = self.ray_leaves(origin, dir, t_min, t_max, &mut farthest) {
            let mut lo = t_min;
            farthest(0..self.tris.len(), &mut lo);
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
        match self.ray_leaves(origin, dir, t_min, t_max, |range, _| {
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

    /// Depth-first walk over the leaves whose boxes the ray `origin + t dir` enters for
    /// `lo < t < t_max`, calling `leaf(triangle slots, &mut lo)` for each; `leaf` may raise `lo`
    /// (a farthest-hit search) and stops the walk by returning true. A tree deeper than the
    /// fixed stack (only for pathological inputs) ends the walk with [`RayWalk::TooDeep`], and
    /// the caller answers by brute force rather than overflow.
    fn ray_leaves(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
        mut leaf: impl FnMut(Range<usize>, &mut f32) -> bool,
    ) -> RayWalk {
        if self.nodes.is_empty() {
            return RayWalk::Done;
        }
        let inv = dir.recip();
        let mut lo = t_min;
        let mut stack = [0u32; 64];
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let index = stack[top];
            let node = &self.nodes[index as usize];
            if !ray_box(origin, inv, node.min, node.max, lo, t_max) {
                continue;
            }
            if node.is_leaf() {
                if leaf(node.first as usize..(node.first + node.count) as usize, &mut lo) {
                    return RayWalk::Stopped;
                }
            } else if top + 2 <= stack.len() {
                stack[top] = node.first;
                stack[top + 1] = index + 1;
                top += 2;
            } else {
                return RayWalk::TooDeep;
            }
        }
        RayWalk::Done
    }
}

/// How [`Bvh::ray_leaves`] ended.
enum RayWalk {
    /// The leaf callback asked to stop.
    Stopped,
    /// Every leaf the ray enters was visited.
    Done,
    /// The tree is deeper than the traversal stack.
    TooDeep,
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

/// Slab test: whether the ray overlaps the box within `(t_min, t_max)`.
#[inline]
fn ray_box(origin: Vec3, inv_dir: Vec3, min: Vec3, max: Vec3, t_min: f32, t_max: f32) -> bool {
    let t0 = (min - origin) * inv_dir;
    let t1 = (max - origin) * inv_dir;
    // NaN (0 * inf on a slab the ray lies in) is ignored by min/max of glam's lane-wise ops on
    // most targets; a ray parallel to a face counts as inside, which is conservative.
    let near = t0.min(t1).max_element().max(t_min);
    let far = t0.max(t1).min_element().min(t_max);
    near <= far
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
