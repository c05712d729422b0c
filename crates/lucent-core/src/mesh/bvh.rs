//! A bounding volume hierarchy over a mesh's triangles: the ray and distance queries of the
//! later stages. Shadow rays from face midpoints to the lights (Mertens §5.3, through
//! [`crate::irradiance::ShadowCaster`]), the closest hits of subsurface bounces between facing
//! parts, the farthest hits, closest points and inside tests of shrink-wrapping (§5.1.2), and
//! ray picking.
//!
//! Deformations keep the topology (§5.1), so the tree is built once and only its boxes are
//! refitted each frame ([`Bvh::refit`]); [`Bvh::sah_cost`] against [`Bvh::built_cost`] tells a
//! caller when refitting has made the tree much worse and a rebuild pays.
//!
//! The tree is a binary one built by binned SAH (Wald 2007, "On fast construction of SAH-based
//! bounding volume hierarchies"), written here rather than taken from a crate: `obvhs` 0.4 pins
//! glam 0.33 (a second glam and a copy per frame) and `bvh` 0.13 brings nalgebra, while lucent
//! needs only build, refit and a handful of queries ([`query`]).

use crate::mesh::Mesh;
use glam::Vec3;
use rayon::prelude::*;

pub mod query;
mod wide;

pub use query::closest_on_triangle;

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

/// A bounding volume hierarchy over a mesh's triangles, for ray and closest-point queries
/// (see [`query`]).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
    /// Mesh face index of each triangle slot, in leaf order.
    faces: Vec<u32>,
    /// Corner positions of each triangle slot (copied from the mesh at build and refit, so
    /// queries read contiguous memory and need no mesh).
    tris: Vec<[Vec3; 3]>,
    /// The tree with four children a node, which the ray queries walk ([`wide`]).
    wide: Vec<wide::Node4>,
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
        let wide = wide::collapse(&nodes);
        let mut bvh = Bvh { nodes, faces, tris, wide, built_cost: 0.0 };
        bvh.built_cost = bvh.sah_cost();
        bvh
    }

    /// Moves the boxes to the mesh's current positions without changing the tree. `mesh` must
    /// have the same triangles (indices) as when the tree was built; only positions may differ.
    ///
    /// # Panics
    /// If the triangle count differs from the build's (use [`Bvh::build`] after a topology
    /// change; [`crate::irradiance::ShadowCaster::update`] does that for you).
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
        wide::refit(&mut self.wide, &self.nodes);
    }

    /// Every mesh face once, in the tree's leaf order: faces near each other in space are near
    /// each other here, so rays cast from them in this order walk the same nodes while those
    /// are in cache.
    pub fn leaf_order(&self) -> &[u32] {
        &self.faces
    }

    /// `f` of every face, evaluated in parallel in the tree's [leaf order](Bvh::leaf_order) and
    /// returned in face order: for work that casts rays from each face.
    pub fn map_faces<T: Send + Clone + Default>(&self, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
        let in_leaf_order: Vec<T> = self.faces.par_iter().map(|&face| f(face as usize)).collect();
        let mut out = vec![T::default(); self.faces.len()];
        for (&face, v) in self.faces.iter().zip(in_leaf_order) {
            out[face as usize] = v;
        }
        out
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
