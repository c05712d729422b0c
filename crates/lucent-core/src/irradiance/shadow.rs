//! Shadows for the leaf irradiance (Mertens §5.3): one ray from each face midpoint to each
//! shadow-casting light, against a bounding volume hierarchy of the mesh that is *refitted* every
//! frame, so shadows follow a deforming mesh.
//!
//! Mertens use shadow maps on the GPU. Ray casting on the CPU fits this solver better: the
//! per-face irradiance is needed on the CPU anyway (it feeds the hierarchical gather), so there is
//! no GPU read-back and its latency; the test is exact at the face midpoints where the solver
//! samples irradiance (no shadow-map resolution, bias or acne trade-offs); and it runs without a
//! GPU. Deformations keep the topology (§5.1), so the tree is built once and only its boxes are
//! refitted each frame, with a rebuild when refitting has made the tree much worse (its surface
//! area heuristic cost grew past [`ShadowCaster::rebuild_ratio`] times the cost when built).
//!
//! The BVH is a binary tree built by binned SAH (Wald 2007, "On fast construction of SAH-based
//! bounding volume hierarchies"), written here rather than taken from a crate: `obvhs` 0.4 pins
//! glam 0.33 (a second glam and a copy per frame) and `bvh` 0.13 brings nalgebra, while lucent
//! needs only build, refit and an any-hit query, about 300 lines.

use super::lights::Incident;
use crate::mesh::Mesh;
use glam::Vec3;
use rayon::prelude::*;
use std::ops::Range;

/// Bins per axis for the SAH sweep.
const BINS: usize = 12;
/// Leaves hold at most this many triangles unless their centroids coincide.
const MAX_LEAF: usize = 4;
/// Subtrees with more triangles than this are built in parallel.
const PARALLEL_MIN: usize = 4096;
/// Relative cost of one box test against one triangle test, for the SAH.
const TRAVERSAL_COST: f32 = 1.0;

/// One node of the flat tree, depth-first order: an inner node's left child is the next node and
/// its right child is `first`; every child comes after its parent, so a reverse sweep refits.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhNode {
    /// Box minimum corner, mesh units.
    pub min: Vec3,
    /// Leaf: index of its first triangle in the tree's triangle order. Inner: index of the right
    /// child.
    pub first: u32,
    /// Box maximum corner, mesh units.
    pub max: Vec3,
    /// Leaf: number of triangles (> 0). Inner: 0.
    pub count: u32,
}

impl BvhNode {
    /// Whether this node is a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    fn half_area(&self) -> f32 {
        half_area(self.min, self.max)
    }
}

#[inline]
fn half_area(min: Vec3, max: Vec3) -> f32 {
    let e = (max - min).max(Vec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// A triangle during the build: its box and centroid, and the mesh face it is.
#[derive(Clone, Copy)]
struct Item {
    min: Vec3,
    max: Vec3,
    centroid: Vec3,
    face: u32,
}

/// A bounding volume hierarchy over a mesh's triangles for any-hit (shadow) queries.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
    /// Mesh face index of each triangle slot, in leaf order.
    faces: Vec<u32>,
    /// Corner positions of each triangle slot (copied from the mesh at build and refit, so
    /// queries read contiguous memory and need no mesh).
    tris: Vec<[Vec3; 3]>,
    /// SAH cost when last built (see [`Bvh::sah_cost`]).
    built_cost: f32,
}

impl Bvh {
    /// Builds the tree over every triangle of `mesh` (binned SAH, parallel for large subtrees).
    pub fn build(mesh: &Mesh) -> Bvh {
        let mut items: Vec<Item> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|f| {
                let [a, b, c] = mesh.corners(f);
                Item {
                    min: a.min(b).min(c),
                    max: a.max(b).max(c),
                    centroid: (a + b + c) / 3.0,
                    face: f as u32,
                }
            })
            .collect();
        let nodes = if items.is_empty() { Vec::new() } else { build_subtree(&mut items, 0) };
        let faces: Vec<u32> = items.iter().map(|i| i.face).collect();
        let tris = faces.iter().map(|&f| mesh.corners(f as usize)).collect();
        let mut bvh = Bvh { nodes, faces, tris, built_cost: 0.0 };
        bvh.built_cost = bvh.sah_cost();
        bvh
    }

    /// Moves the boxes to the mesh's current positions without changing the tree. `mesh` must
    /// have the same triangles (indices) as when the tree was built; only positions may differ.
    ///
    /// # Panics
    /// If the triangle count differs from the build's (use [`Bvh::build`] after a topology
    /// change; [`ShadowCaster::update`] does that for you).
    pub fn refit(&mut self, mesh: &Mesh) {
        assert_eq!(mesh.triangles.len(), self.faces.len(), "refit needs the mesh the tree was built for");
        self.tris.par_iter_mut().zip(self.faces.par_iter()).for_each(|(t, &f)| *t = mesh.corners(f as usize));
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            let (min, max) = if n.is_leaf() {
                let tris = &self.tris[n.first as usize..(n.first + n.count) as usize];
                tris.iter().flatten().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| {
                    (lo.min(*p), hi.max(*p))
                })
            } else {
                let (l, r) = (self.nodes[i + 1], self.nodes[n.first as usize]);
                (l.min.min(r.min), l.max.max(r.max))
            };
            self.nodes[i].min = min;
            self.nodes[i].max = max;
        }
    }

    /// The surface area heuristic cost of the tree: expected box and triangle tests for a random
    /// ray that hits the root, `Σ_inner A·c_trav + Σ_leaf A·n` over the root's area `A_root`.
    /// Grows as refitting stretches the boxes of a deforming mesh.
    pub fn sah_cost(&self) -> f32 {
        let Some(root) = self.nodes.first() else {
            return 0.0;
        };
        let root_area = root.half_area().max(f32::MIN_POSITIVE);
        let sum: f32 = self
            .nodes
            .iter()
            .map(|n| {
                let per = if n.is_leaf() { n.count as f32 } else { TRAVERSAL_COST };
                n.half_area() * per
            })
            .sum();
        sum / root_area
    }

    /// [`Bvh::sah_cost`] when the tree was last built.
    pub fn built_cost(&self) -> f32 {
        self.built_cost
    }

    /// The nodes, root first (empty for an empty mesh).
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// Number of triangles in the tree.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// Whether the tree holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// Box `(min, max)` around the whole mesh (zero for an empty tree).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.nodes.first().map_or((Vec3::ZERO, Vec3::ZERO), |n| (n.min, n.max))
    }

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

impl Bvh {
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
}

impl Bvh {
    /// The nearest intersection of the ray `origin + t dir` with the mesh (either side) for
    /// `t_min < t < t_max`: `(t, mesh face)`, or `None` if it hits nothing.
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

/// Builds the subtree over `items` (whose first element is triangle slot `offset` overall) and
/// returns its nodes in local indices, root at 0.
fn build_subtree(items: &mut [Item], offset: usize) -> Vec<BvhNode> {
    let (min, max) = items.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), it| {
        (lo.min(it.min), hi.max(it.max))
    });
    let n = items.len();
    let leaf = || vec![BvhNode { min, max, first: offset as u32, count: n as u32 }];
    if n <= 2 {
        return leaf();
    }
    let Some(mid) = sah_split(items, half_area(min, max)) else {
        return leaf();
    };
    let (left_items, right_items) = items.split_at_mut(mid);
    let (left, right) = if n > PARALLEL_MIN {
        rayon::join(|| build_subtree(left_items, offset), || build_subtree(right_items, offset + mid))
    } else {
        (build_subtree(left_items, offset), build_subtree(right_items, offset + mid))
    };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    let right_root = 1 + left.len() as u32;
    nodes.push(BvhNode { min, max, first: right_root, count: 0 });
    let shift = |mut node: BvhNode, by: u32| {
        if !node.is_leaf() {
            node.first += by;
        }
        node
    };
    nodes.extend(left.into_iter().map(|nd| shift(nd, 1)));
    nodes.extend(right.into_iter().map(|nd| shift(nd, right_root)));
    nodes
}

/// Partitions `items` by the best binned-SAH plane over the three axes and returns the split
/// index, or `None` when a leaf is cheaper (and small enough).
fn sah_split(items: &mut [Item], parent_half_area: f32) -> Option<usize> {
    let n = items.len();
    let (cmin, cmax) = items.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), it| {
        (lo.min(it.centroid), hi.max(it.centroid))
    });
    let extent = cmax - cmin;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bins left of the plane)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let mut count = [0u32; BINS];
        let mut bmin = [Vec3::splat(f32::MAX); BINS];
        let mut bmax = [Vec3::splat(f32::MIN); BINS];
        for it in items.iter() {
            let b = (((it.centroid[axis] - cmin[axis]) * scale) as usize).min(BINS - 1);
            count[b] += 1;
            bmin[b] = bmin[b].min(it.min);
            bmax[b] = bmax[b].max(it.max);
        }
        // Sweep from the right to get the right-side areas, then from the left.
        let mut right_cost = [0.0f32; BINS];
        let (mut lo, mut hi, mut c) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN), 0u32);
        for b in (1..BINS).rev() {
            lo = lo.min(bmin[b]);
            hi = hi.max(bmax[b]);
            c += count[b];
            right_cost[b] = if c > 0 { half_area(lo, hi) * c as f32 } else { 0.0 };
        }
        let (mut lo, mut hi, mut c) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN), 0u32);
        for b in 0..BINS - 1 {
            lo = lo.min(bmin[b]);
            hi = hi.max(bmax[b]);
            c += count[b];
            if c == 0 || c as usize == n {
                continue;
            }
            let cost = half_area(lo, hi) * c as f32 + right_cost[b + 1];
            if best.is_none_or(|(bc, _, _)| cost < bc) {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    let leaf_cost = n as f32;
    match best {
        Some((cost, axis, split_bin))
            if n > MAX_LEAF
                || TRAVERSAL_COST + cost / parent_half_area.max(f32::MIN_POSITIVE) < leaf_cost =>
        {
            let scale = BINS as f32 / extent[axis];
            let goes_left =
                |it: &Item| (((it.centroid[axis] - cmin[axis]) * scale) as usize).min(BINS - 1) < split_bin;
            Some(partition(items, goes_left))
        }
        // Every centroid in one spot (or no better plane): split the list in half if it is too
        // large for a leaf, so leaves stay small.
        None if n > 2 * MAX_LEAF => Some(n / 2),
        _ => None,
    }
}

/// In-place partition; returns the number of items for which `pred` holds (now at the front).
fn partition(items: &mut [Item], pred: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if pred(&items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
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
