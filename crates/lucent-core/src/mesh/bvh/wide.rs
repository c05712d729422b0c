//! The binary tree of [`super::Bvh`] collapsed to four children a node, their boxes side by
//! side so that one ray tests all four in a few SIMD operations (glam's `Vec4`: SSE2 on
//! x86-64, NEON on aarch64, scalar elsewhere). The rays of subsurface bounces, shadows and
//! single scattering start on the surface and mostly escape, so they visit many boxes and few
//! triangles: on the 48K Stanford dragon a bounce ray popped 38 binary nodes (76 box tests)
//! for 7.5 leaves.
//!
//! The binary tree stays the one built and refitted; this copy is made from it after each,
//! and each of its child slots remembers the binary node it mirrors.

use super::BvhNode;
use glam::{Vec3, Vec4};

/// A slot of [`Node4`] with no child.
const EMPTY: u32 = u32::MAX;

/// Four children: a box per lane, and per slot a leaf's triangle range or an inner child.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node4 {
    /// Box minima and maxima per axis, one child a lane (mesh units).
    min: [Vec4; 3],
    max: [Vec4; 3],
    /// A leaf child's first triangle slot, or an inner child's index among the `Node4`s.
    first: [u32; 4],
    /// A leaf child's triangle count (> 0); 0 for an inner child; [`EMPTY`] for no child.
    count: [u32; 4],
    /// The binary node each child mirrors (for refits).
    src: [u32; 4],
    /// Bit `k`: slot `k` holds a child.
    valid: u32,
}

/// The four-wide copy of the binary tree `bin` (root first; empty for an empty tree).
pub(super) fn collapse(bin: &[BvhNode]) -> Vec<Node4> {
    let mut out = Vec::with_capacity(bin.len() / 2 + 1);
    if !bin.is_empty() {
        add(bin, 0, &mut out);
    }
    out
}

/// Appends the `Node4` over binary node `b`'s children (or `b` itself, a leaf root) and those
/// below it, depth first; returns its index.
fn add(bin: &[BvhNode], b: usize, out: &mut Vec<Node4>) -> u32 {
    let at = out.len();
    out.push(Node4 {
        min: [Vec4::ZERO; 3],
        max: [Vec4::ZERO; 3],
        first: [0; 4],
        count: [EMPTY; 4],
        src: [0; 4],
        valid: 0,
    });
    let mut kids = [0usize; 4];
    let mut n = if bin[b].is_leaf() {
        kids[0] = b;
        1
    } else {
        kids[..2].copy_from_slice(&[b + 1, bin[b].first as usize]);
        2
    };
    // Open the largest inner child until four: the tree a four-wide traversal would want.
    while n < 4 {
        let Some(k) = (0..n)
            .filter(|&k| !bin[kids[k]].is_leaf())
            .max_by(|&i, &j| bin[kids[i]].half_area().total_cmp(&bin[kids[j]].half_area()))
        else {
            break;
        };
        let open = kids[k];
        kids[k] = open + 1;
        kids[n] = bin[open].first as usize;
        n += 1;
    }
    for (k, &c) in kids[..n].iter().enumerate() {
        let (first, count) =
            if bin[c].is_leaf() { (bin[c].first, bin[c].count) } else { (add(bin, c, out), 0) };
        let node = &mut out[at];
        node.first[k] = first;
        node.count[k] = count;
        node.src[k] = c as u32;
        node.valid |= 1 << k;
    }
    refit_node(&mut out[at], bin);
    at as u32
}

/// Copies the boxes of the binary nodes the slots of `node` mirror.
fn refit_node(node: &mut Node4, bin: &[BvhNode]) {
    for k in 0..4 {
        let (lo, hi) = if node.valid & (1 << k) != 0 {
            let b = &bin[node.src[k] as usize];
            (b.min, b.max)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        for a in 0..3 {
            node.min[a][k] = lo[a];
            node.max[a][k] = hi[a];
        }
    }
}

/// Moves the boxes of `wide` to those of the refitted binary tree `bin`. Serial: the copy is a
/// small part of a refit, and splitting it over threads cost more than it saved.
pub(super) fn refit(wide: &mut [Node4], bin: &[BvhNode]) {
    for node in wide {
        refit_node(node, bin);
    }
}

/// How [`walk`] ended.
pub(super) enum RayWalk {
    /// The leaf callback asked to stop.
    Stopped,
    /// Every leaf the ray enters was visited.
    Done,
    /// The tree is deeper than the traversal stack.
    TooDeep,
}

/// Depth-first walk over the leaves whose boxes the ray `origin + t dir` enters for
/// `lo < t < hi` (from `t_min` and `t_max`), nearer boxes first, calling `leaf(triangle
/// slots, &mut lo, &mut hi)` for each: `leaf` may raise `lo` (a farthest-hit search) or lower
/// `hi` (a closest-hit search, which then skips every box beyond its best hit), and stops the
/// walk by returning true. A tree deeper than the fixed stack (only for pathological inputs)
/// ends the walk with [`RayWalk::TooDeep`], and the caller answers by brute force.
pub(super) fn walk(
    wide: &[Node4],
    origin: Vec3,
    dir: Vec3,
    t_min: f32,
    t_max: f32,
    mut leaf: impl FnMut(std::ops::Range<usize>, &mut f32, &mut f32) -> bool,
) -> RayWalk {
    if wide.is_empty() {
        return RayWalk::Done;
    }
    // A direction component of 0 gets a huge finite reciprocal rather than an infinite one, so
    // that no slab gives 0 · ∞ = NaN: a ray in a box's face plane counts as inside it
    // (conservative: the triangle test decides).
    let inv = dir.map(|d| 1.0 / if d.abs() > 1e-30 { d } else { 1e-30f32.copysign(d) });
    let o = [origin.x, origin.y, origin.z].map(Vec4::splat);
    let iv = [inv.x, inv.y, inv.z].map(Vec4::splat);
    let (mut lo, mut hi) = (t_min, t_max);
    // Entries: an inner `Node4` (count 0) or a leaf's triangles, with the span of the ray in
    // its box when it was pushed.
    const STACK: usize = 128;
    let mut stack = [(0u32, 0u32, t_min, t_max); STACK];
    let mut top = 1usize;
    while top > 0 {
        top -= 1;
        let (first, count, near, far) = stack[top];
        // The bounds may have moved since the entry was pushed.
        if near > hi || far < lo {
            continue;
        }
        if count > 0 {
            if leaf(first as usize..(first + count) as usize, &mut lo, &mut hi) {
                return RayWalk::Stopped;
            }
            continue;
        }
        let node = &wide[first as usize];
        let (mut t_near, mut t_far) = (Vec4::splat(lo), Vec4::splat(hi));
        for a in 0..3 {
            let t0 = (node.min[a] - o[a]) * iv[a];
            let t1 = (node.max[a] - o[a]) * iv[a];
            t_near = t_near.max(t0.min(t1));
            t_far = t_far.min(t0.max(t1));
        }
        let hit = t_near.cmple(t_far).bitmask() & node.valid;
        if hit == 0 {
            continue;
        }
        if top + 4 > STACK {
            return RayWalk::TooDeep;
        }
        // Push the hit children farthest first, so that the nearest is popped next.
        let mut order = [0usize; 4];
        let mut n = 0;
        for k in 0..4 {
            if hit & (1 << k) != 0 {
                let mut i = n;
                while i > 0 && t_near[order[i - 1]] < t_near[k] {
                    order[i] = order[i - 1];
                    i -= 1;
                }
                order[i] = k;
                n += 1;
            }
        }
        for &k in &order[..n] {
            stack[top] = (node.first[k], node.count[k], t_near[k], t_far[k]);
            top += 1;
        }
    }
    RayWalk::Done
}
