//! A frame of the hierarchical solve (Mertens et al. 2003, §3.2, §5.5): *pull* (area-weighted
//! irradiance up the tree), *gather* (`B_R = Σ_E E_E F_ER` along the links into each receiver)
//! and *push* (a receiver's `B` added to all its leaves). Render mode gathers over the stored
//! links ([`HierarchicalSolver::solve_render`], with the packed kernels of [`super::link_coef`]
//! and [`super::gather_linear`]) and pushes in the same pass down the tree; on-the-fly mode
//! gathers each link as the refinement accepts it and pushes down the traversal
//! ([`HierarchicalSolver::solve_on_the_fly`]). Where the profile asks for it, `B` is scaled by
//! the energy bound of [`super::energy`].
//!
//! With linear receivers ([`super::Oracle::linear_receivers`]) a receiver cluster gathers its
//! `B` at its midpoint *and* the gradient of `B` there (each link's steepness along the line
//! from its emitter), and the push hands each child the parent's value moved to the child's
//! midpoint: first-order (linear-basis) hierarchical radiosity at the receiver, which lets
//! receivers stay whole as far as emitters do. With curved receivers
//! ([`super::Oracle::curved_receivers`], the default) each link also adds its curvature, and
//! the receiver carries a quadratic (value, gradient, Hessian) down to its leaves.

use super::gather_linear::sum_linear;
use super::hierarchical::{HierarchicalSolver, Solution, SolveStats, ms};
use super::link_coef;
use super::link_set::StoredLinks;
use super::oracle::curvature_along;
use super::refine::{Cands, Ctx, Deferred, Evaluate};
use crate::Rgb;
use crate::hierarchy::{Hierarchy, NO_NODE, PAR_LEAVES, split_leaves, split_subtrees};
use glam::Vec3A;
use rayon::prelude::*;
use std::time::Instant;

impl HierarchicalSolver {
    /// Area-weighted average irradiance of every cluster (the *pull* of §3.2), in parallel
    /// over subtrees.
    pub fn pull(&self, face_irradiance: &[Rgb]) -> Vec<Vec3A> {
        let mut e = vec![Vec3A::ZERO; self.hierarchy.len()];
        self.pull_into(face_irradiance, &mut e);
        e
    }

    /// [`HierarchicalSolver::pull`] into `e` (one entry per cluster).
    fn pull_into(&self, face_irradiance: &[Rgb], e: &mut [Vec3A]) {
        let h = &self.hierarchy;
        assert_eq!(face_irradiance.len(), h.leaf_count());
        if !h.is_empty() {
            pull_subtree(h, self.frame_geom(), face_irradiance, 0, e);
        }
    }

    /// The hierarchy's [`FrameGeom`], made on first use.
    fn frame_geom(&self) -> &FrameGeom {
        self.frame_geom.get_or_init(|| FrameGeom::new(&self.hierarchy))
    }

    /// Render mode: pull, gather over the stored links, push. Links are created on first use.
    pub fn solve_render(&mut self, face_irradiance: &[Rgb]) -> Solution {
        if self.links.is_none() {
            self.link();
        }
        let mut solution = self.render_stored(face_irradiance);
        if self.profile.bounds_energy() {
            let t0 = Instant::now();
            if self.bound.is_none() {
                let ones = vec![Rgb::ONE; self.hierarchy.leaf_count()];
                let uniform = self.render_stored(&ones).face_b;
                self.bound =
                    Some(uniform.into_iter().enumerate().map(|(f, u)| self.bound_factor(f, u)).collect());
            }
            let bound = self.bound.as_ref().expect("bound made above");
            solution.face_b.iter_mut().zip(bound).for_each(|(b, s)| *b *= *s);
            solution.stats.push_ms += ms(t0.elapsed());
            solution.stats.total_ms += ms(t0.elapsed());
        }
        solution
    }

    /// Render mode over the stored links (which must exist).
    fn render_stored(&mut self, face_irradiance: &[Rgb]) -> Solution {
        let t0 = Instant::now();
        let [mut e_node, mut b_node] = std::mem::take(&mut self.frame);
        e_node.resize(self.hierarchy.len(), Vec3A::ZERO);
        self.pull_into(face_irradiance, &mut e_node);
        let t1 = Instant::now();
        let links = self.links.as_ref().expect("links stored");
        // The gather and the push in one pass down the tree: an inner receiver's `B` (and
        // expansion) lives only while its subtree is visited.
        b_node.resize(self.hierarchy.len(), Vec3A::ZERO);
        let linear = self.linear_receivers();
        let mid: &[Vec3A] = if linear { &self.frame_geom().mid } else { &[] };
        let frame = RenderFrame {
            h: &self.hierarchy,
            links: links.view(),
            e_node: &e_node,
            mid,
            linear,
            curved: self.curved_receivers(),
        };
        if !self.hierarchy.is_empty() {
            frame.gather_push(0, Linear::default(), &mut b_node, 0);
        }
        let t2 = Instant::now();
        let face_b = self.leaf_values(&b_node);
        let t3 = Instant::now();
        let links = links.len();
        self.frame = [e_node, b_node];
        Solution {
            face_b,
            stats: SolveStats {
                links,
                pull_ms: ms(t1 - t0),
                gather_ms: ms(t2 - t1),
                push_ms: ms(t3 - t2),
                total_ms: ms(t3 - t0),
                ..Default::default()
            },
        }
    }

    /// `B` per original face, from the leaves' entries of `b_node`.
    fn leaf_values(&self, b_node: &[Vec3A]) -> Vec<Rgb> {
        self.hierarchy.face_node.par_iter().with_min_len(4096).map(|&n| b_node[n as usize].into()).collect()
    }

    /// On-the-fly mode: refine from the root's self-link and gather in one parallel traversal,
    /// storing nothing. Returns `B` per face.
    pub fn solve_on_the_fly(&self, face_irradiance: &[Rgb]) -> Solution {
        let t0 = Instant::now();
        let h = &self.hierarchy;
        let mut stats = SolveStats::default();
        if h.is_empty() {
            return Solution { face_b: Vec::new(), stats };
        }
        let e_node = self.pull(face_irradiance);
        let t1 = Instant::now();
        let mut leaf_b = vec![[Rgb::ZERO; 2]; h.leaf_count()];
        let mut ctx = Ctx::new(self);
        self.start_progress("on-the-fly");
        self.otf_rec(&mut ctx, 0, Cands::ROOT, [Linear::default(); 2], &e_node, &mut leaf_b);
        self.tick_progress(None, 0);
        let t2 = Instant::now();
        let bound = self.profile.bounds_energy();
        let mut face_b = vec![Rgb::ZERO; h.leaf_count()];
        for (pos, &f) in h.leaf_faces.iter().enumerate() {
            let [b, u] = leaf_b[pos];
            face_b[f as usize] = if bound { b * self.bound_factor(f as usize, u) } else { b };
        }
        let t3 = Instant::now();
        ctx.fill(&mut stats);
        stats.links = stats.form_factors + stats.cubatures + stats.polar_faces + stats.point_samples;
        stats.pull_ms = ms(t1 - t0);
        stats.link_ms = ms(t2 - t1);
        stats.push_ms = ms(t3 - t2);
        stats.total_ms = ms(t3 - t0);
        Solution { face_b, stats }
    }

    /// On-the-fly mode below receiver `r`: refines its candidates `cands`, gathering `E F`
    /// of every accepted link into `acc` (`B` and, for the energy bound, `B` under uniform
    /// irradiance 1, both at `r`'s midpoint with what `r`'s ancestors gathered), and writes
    /// the totals at `r`'s leaves into `out` (one entry per leaf of the subtree, in leaf
    /// order).
    fn otf_rec(
        &self,
        ctx: &mut Ctx,
        r: usize,
        cands: Cands,
        acc: [Linear; 2],
        e_node: &[Vec3A],
        out: &mut [[Rgb; 2]],
    ) {
        let h = &self.hierarchy;
        let mut defer = Deferred::default();
        // `B` and, for the energy bound, `B` under uniform irradiance 1.
        let [mut b, mut u] = acc;
        let m_r = Vec3A::from(h.geom[r].midpoint);
        let curved = self.curved_receivers();
        ctx.receive(
            &self.oracle,
            r,
            cands.iter(),
            &mut defer,
            &mut Evaluate(|e: usize, _, f: [f32; 3], slope: f32| {
                let f = Vec3A::from_array(f);
                let t = e_node[e] * f;
                b.value += t;
                u.value += f;
                if slope > 0.0 {
                    let dv = m_r - Vec3A::from(h.geom[e].midpoint);
                    b.add_link(t, slope, dv, curved);
                    u.add_link(f, slope, dv, curved);
                }
            }),
        );
        let n = self.hierarchy.nodes[r];
        if n.is_leaf() {
            out[0] = [b.value.into(), u.value.into()];
            return;
        }
        let at = |c: usize| {
            let offset = Vec3A::from(h.geom[c].midpoint) - m_r;
            [b.moved(offset), u.moved(offset)]
        };
        let parts = split_leaves(&self.hierarchy.nodes, r, out);
        if n.leaf_count() > PAR_LEAVES {
            let subs: Vec<Ctx> = parts
                .into_par_iter()
                .enumerate()
                .map(|(k, (c, o))| {
                    let mut sub = Ctx::new(self);
                    self.otf_rec(&mut sub, c, Cands::of_child(&defer, k), at(c), e_node, o);
                    self.tick_progress(Some(r), c);
                    sub
                })
                .collect();
            subs.iter().for_each(|s| ctx.absorb(s));
        } else {
            for (k, (c, o)) in parts.into_iter().enumerate() {
                self.otf_rec(ctx, c, Cands::of_child(&defer, k), at(c), e_node, o);
                self.tick_progress(Some(r), c);
            }
        }
    }
}

/// Per channel, the gradient of `B` (per mesh unit of length) at a receiver's midpoint.
pub(crate) type Grad = [Vec3A; 3];

/// Per channel, the Hessian of `B` (per mesh unit of length squared) at a receiver's
/// midpoint, symmetric: its diagonal (xx, yy, zz) and its off-diagonal (yz, xz, xy).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Hess {
    pub(super) diag: Grad,
    pub(super) off: Grad,
}

impl Hess {
    /// `self += o`, channel by channel.
    #[inline]
    fn add(&mut self, o: &Hess) {
        add_grad(&mut self.diag, &o.diag);
        add_grad(&mut self.off, &o.off);
    }

    /// Adds `w[c] dv dvᵀ + iso[c] I` to channel `c`.
    #[inline]
    fn add_link(&mut self, w: Vec3A, iso: Vec3A, dv: Vec3A) {
        let (dd, dx) = (dv * dv, Vec3A::new(dv.y * dv.z, dv.x * dv.z, dv.x * dv.y));
        for c in 0..3 {
            self.diag[c] += dd * w[c] + Vec3A::splat(iso[c]);
            self.off[c] += dx * w[c];
        }
    }

    /// Per channel `½ oᵀ H o`.
    #[inline]
    fn half_quad(&self, o: Vec3A) -> Vec3A {
        let (oo, ox) = (o * o, Vec3A::new(o.y * o.z, o.x * o.z, o.x * o.y));
        Vec3A::new(
            0.5 * self.diag[0].dot(oo) + self.off[0].dot(ox),
            0.5 * self.diag[1].dot(oo) + self.off[1].dot(ox),
            0.5 * self.diag[2].dot(oo) + self.off[2].dot(ox),
        )
    }

    /// Per channel `H o`.
    #[inline]
    fn apply(&self, o: Vec3A) -> Grad {
        std::array::from_fn(|c| {
            let (d, f) = (self.diag[c], self.off[c]);
            Vec3A::new(
                d.x * o.x + f.z * o.y + f.y * o.z,
                f.z * o.x + d.y * o.y + f.x * o.z,
                f.y * o.x + f.x * o.y + d.z * o.z,
            )
        })
    }
}

/// A receiver's gathered `B` as a local expansion about its midpoint: its value, its
/// gradient and (with curved receivers) its Hessian there.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Linear {
    pub(super) value: Vec3A,
    pub(super) grad: Grad,
    pub(super) hess: Hess,
}

impl Linear {
    /// Adds one link's `t = E F` with steepness `slope` from an emitter at `-dv` from the
    /// receiver's midpoint (`dv = m_R - m_E`): its gradient and, if `curved`, its Hessian.
    #[inline]
    pub(super) fn add_link(&mut self, t: Vec3A, slope: f32, dv: Vec3A, curved: bool) {
        let (k, w) = steepness(dv, slope, curved);
        let tk = t * k;
        self.grad[0] += dv * tk.x;
        self.grad[1] += dv * tk.y;
        self.grad[2] += dv * tk.z;
        if curved {
            self.hess.add_link(t * w, tk, dv);
        }
    }

    /// Every term times `s`.
    #[inline]
    fn scaled(self, s: f32) -> Self {
        let g = |g: Grad| g.map(|v| v * s);
        Linear {
            value: self.value * s,
            grad: g(self.grad),
            hess: Hess { diag: g(self.hess.diag), off: g(self.hess.off) },
        }
    }

    /// `self += o`.
    #[inline]
    pub(super) fn add(&mut self, o: &Linear) {
        self.value += o.value;
        add_grad(&mut self.grad, &o.grad);
        self.hess.add(&o.hess);
    }

    /// The value at a point `offset` from the midpoint.
    #[inline]
    fn value_at(&self, offset: Vec3A) -> Vec3A {
        self.value + along(&self.grad, offset) + self.hess.half_quad(offset)
    }

    /// The same function about a point `offset` from the midpoint.
    #[inline]
    fn moved(self, offset: Vec3A) -> Self {
        let mut grad = self.grad;
        add_grad(&mut grad, &self.hess.apply(offset));
        Linear { value: self.value_at(offset), grad, hess: self.hess }
    }
}

/// `g += h`, channel by channel.
#[inline]
fn add_grad(g: &mut Grad, h: &Grad) {
    g.iter_mut().zip(h).for_each(|(g, h)| *g += *h);
}

/// Each channel's gradient of `g` dotted with `offset`.
#[inline]
fn along(g: &Grad, offset: Vec3A) -> Vec3A {
    Vec3A::new(g[0].dot(offset), g[1].dot(offset), g[2].dot(offset))
}

/// For a link of steepness `s = slope` along `D = dv = m_R - m_E`, `|D| = ρ`: the factors
/// `k` and `w` such that the link's `E F` contributes `k E F D` to the receiver's gradient
/// and, with a curved receiver, `E F (w D Dᵀ + k I)` to its Hessian: `F (1 - s t + ½ ((q +
/// s) t² - s |δ|² / ρ²))` with `t = δ.D / ρ²` at an offset `δ`, for a profile of distance
/// alone whose log-curvature `q = ρ² F'' / F` is `s² + a` ([`FALLOFF_POWER`](super::oracle::FALLOFF_POWER):
/// `F ~ ρ^-a e^(-σ ρ)`). A link without steepness gives `k = w = 0`, whatever `D`.
#[inline]
fn steepness(dv: Vec3A, slope: f32, curved: bool) -> (f32, f32) {
    let inv_d2 = 1.0 / dv.length_squared().max(f32::MIN_POSITIVE);
    let k = -slope * inv_d2;
    let w = if curved && slope > 0.0 { curvature_along(slope) * inv_d2 * inv_d2 } else { 0.0 };
    (k, w)
}

/// Render mode's gather and push over the stored links, in one pass down the tree.
struct RenderFrame<'a> {
    h: &'a Hierarchy,
    links: StoredLinks<'a>,
    /// Every cluster's irradiance.
    e_node: &'a [Vec3A],
    /// Every cluster's midpoint (with linear receivers; else empty).
    mid: &'a [Vec3A],
    /// Whether inner receivers carry an expansion ([`super::Oracle::linear_receivers`]).
    linear: bool,
    /// Whether the expansion has a Hessian ([`super::Oracle::curved_receivers`]).
    curved: bool,
}

impl RenderFrame<'_> {
    /// Gathers cluster `r`'s links (with linear receivers, an inner cluster's expansion at
    /// its midpoint, [`sum_linear`]; else, and for a leaf, its value alone), adds its
    /// ancestors' `above`, and passes the sum on to its children (moved to their midpoints);
    /// a leaf's `B` lands in `b`, which holds clusters `base..` in preorder (`r`'s subtree
    /// among them). Subtrees of more than [`PAR_LEAVES`] leaves run in parallel. No
    /// cluster's gathered `B` is stored: an expansion is 160 bytes, and written by a gather
    /// and read back by a push, expansions cost as much as the push's arithmetic.
    fn gather_push(&self, r: usize, above: Linear, b: &mut [Vec3A], base: usize) {
        let h = self.h;
        let n = h.nodes[r];
        if n.is_leaf() {
            b[r - base] = self.value(r) + above.value;
            return;
        }
        let own = if self.linear {
            let (emitter, coef, scale) = self.links.of(r);
            let sum = sum_linear(
                crate::simd::Isa::best(),
                self.e_node,
                self.mid,
                emitter,
                coef,
                self.mid[r],
                self.curved,
            );
            let mut own = sum.scaled(scale);
            own.add(&above);
            own
        } else {
            Linear { value: self.value(r) + above.value, ..Linear::default() }
        };
        // Only linear receivers move their sum, and they have the flat midpoints.
        let offset = |c: usize| self.mid[c] - self.mid[r];
        let moved = |c: usize| if self.linear { own.moved(offset(c)) } else { own };
        if n.leaf_count() > PAR_LEAVES {
            let parts = split_subtrees(&h.nodes, r, &mut b[r - base + 1..]);
            parts.into_par_iter().for_each(|(c, b)| self.gather_push(c, moved(c), b, c));
            return;
        }
        for &c in n.children() {
            let c = c as usize;
            if h.nodes[c].is_leaf() {
                // A leaf needs only the value of its parent's expansion.
                let above = if self.linear { own.value_at(offset(c)) } else { own.value };
                b[c - base] = self.value(c) + above;
            } else {
                self.gather_push(c, moved(c), b, base);
            }
        }
    }

    /// Cluster `r`'s gathered `B`, taken as one value (a leaf, or any cluster with constant
    /// receivers).
    #[inline]
    fn value(&self, r: usize) -> Vec3A {
        let (emitter, coef, scale) = self.links.of(r);
        link_coef::gather_sum_best(self.e_node, emitter, coef) * scale
    }
}

/// What a frame reads of the hierarchy, one flat array a quantity (the pull read two
/// 40-byte records a cluster: on the 203K dragon it was 8% of a render frame).
#[derive(Clone, Debug)]
pub(crate) struct FrameGeom {
    /// Every cluster's midpoint (mesh units), for linear receivers.
    pub(super) mid: Vec<Vec3A>,
    /// Every cluster's parent ([`NO_NODE`] for the root).
    parent: Vec<u32>,
    /// Every cluster's weight in its parent's average irradiance: its share of the parent's
    /// area, or `1 / children` where the parent has no area (the root's is unused).
    weight: Vec<f32>,
    /// Every leaf's face, `u32::MAX` for inner clusters.
    leaf_face: Vec<u32>,
}

impl FrameGeom {
    /// In parallel (a mesh moved without [`FrameGeom::refit`] makes this anew).
    fn new(h: &Hierarchy) -> Self {
        let weight = (0..h.len()).into_par_iter().with_min_len(4096).map(|i| area_weight(h, i)).collect();
        let leaf_face = h
            .nodes
            .par_iter()
            .with_min_len(4096)
            .map(|n| if n.is_leaf() { h.leaf_faces[n.leaf_start as usize] } else { u32::MAX })
            .collect();
        FrameGeom {
            mid: h.geom.par_iter().with_min_len(4096).map(|g| g.midpoint.into()).collect(),
            parent: h.nodes.par_iter().with_min_len(4096).map(|n| n.parent).collect(),
            weight,
            leaf_face,
        }
    }

    /// After `h` was refitted where `changed` says (an incremental update): the midpoints of
    /// the changed clusters and the weights of their children and themselves. The topology
    /// stays, so this visits each cluster once instead of making every array anew.
    pub(super) fn refit(&mut self, h: &Hierarchy, changed: &[bool]) {
        debug_assert_eq!(changed.len(), self.mid.len());
        for i in (0..h.len()).filter(|&i| changed[i]) {
            self.mid[i] = h.geom[i].midpoint.into();
            self.weight[i] = area_weight(h, i);
            for &c in h.nodes[i].children() {
                self.weight[c as usize] = area_weight(h, c as usize);
            }
        }
    }
}

/// Cluster `i`'s weight in its parent's average irradiance ([`FrameGeom`]'s `weight`).
#[inline]
fn area_weight(h: &Hierarchy, i: usize) -> f32 {
    let p = h.nodes[i].parent;
    if p == NO_NODE {
        return 1.0;
    }
    let p = p as usize;
    let area = h.geom[p].area;
    if area > 0.0 { h.geom[i].area / area } else { 1.0 / h.nodes[p].child_count.max(1) as f32 }
}

/// The pull below cluster `r`, whose subtree is `e` (`r..subtree_end` in preorder): children
/// before parents, each adding its share to its parent, subtrees of more than [`PAR_LEAVES`]
/// leaves in parallel.
fn pull_subtree(h: &Hierarchy, g: &FrameGeom, face_irradiance: &[Rgb], r: usize, e: &mut [Vec3A]) {
    let n = h.nodes[r];
    if n.leaf_count() > PAR_LEAVES {
        let (_, rest) = e.split_at_mut(1);
        split_subtrees(&h.nodes, r, rest)
            .into_par_iter()
            .for_each(|(c, s)| pull_subtree(h, g, face_irradiance, c, s));
        e[0] = n.children().iter().map(|&c| e[c as usize - r] * g.weight[c as usize]).sum();
        return;
    }
    e.fill(Vec3A::ZERO);
    for i in (r..n.subtree_end as usize).rev() {
        let f = g.leaf_face[i];
        let v = if f == u32::MAX { e[i - r] } else { face_irradiance[f as usize].into() };
        e[i - r] = v;
        if i > r {
            e[g.parent[i] as usize - r] += v * g.weight[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::oracle::FALLOFF_POWER;
    use super::*;

    /// The pull gives every cluster the area-weighted mean irradiance of its faces, on a
    /// binary face-cluster tree and a four-way subdivision tree, both past [`PAR_LEAVES`]
    /// leaves (so that subtrees run in parallel).
    #[test]
    fn pull_averages_each_clusters_faces_by_area() {
        use crate::hierarchy::{face_cluster, subdivision};
        let sub =
            subdivision::butterfly(&subdivision::octahedron(glam::Vec3::new(1.0, 1.25, 0.9)), 5).unwrap();
        let binary = face_cluster::build(&sub.mesh);
        for h in [sub.hierarchy, binary] {
            let n = h.leaf_count();
            assert!(n > 2 * PAR_LEAVES as usize);
            let e: Vec<Rgb> = (0..n).map(|f| Rgb::new(f as f32, 1.0, (f % 7) as f32)).collect();
            let mut got = vec![Vec3A::ZERO; h.len()];
            pull_subtree(&h, &FrameGeom::new(&h), &e, 0, &mut got);
            let area: Vec<f64> = (0..n).map(|f| sub.mesh.face_area(f) as f64).collect();
            for (i, node) in h.nodes.iter().enumerate().step_by(97) {
                let faces = &h.leaf_faces[node.leaf_start as usize..node.leaf_end as usize];
                let total: f64 = faces.iter().map(|&f| area[f as usize]).sum();
                for c in 0..3 {
                    let want = faces.iter().map(|&f| area[f as usize] * e[f as usize][c] as f64).sum::<f64>()
                        / total;
                    let err = (got[i][c] as f64 - want).abs();
                    assert!(
                        err <= 1e-5 * want.abs().max(1.0),
                        "cluster {i} channel {c}: {} vs {want}",
                        got[i][c]
                    );
                }
            }
        }
    }

    /// After a local deformation, refitting the frame's geometry where clusters changed gives
    /// what making it anew gives (the same bits: the same formulas on the same inputs).
    #[test]
    fn refit_equals_a_new_frame_geometry() {
        use crate::hierarchy::subdivision;
        let sub =
            subdivision::butterfly(&subdivision::octahedron(glam::Vec3::new(1.0, 1.25, 0.9)), 4).unwrap();
        let (mut mesh, mut h) = (sub.mesh, sub.hierarchy);
        let mut g = FrameGeom::new(&h);
        // Lift the vertices near one pole: a bump, as an incremental update sees it.
        let moved: Vec<bool> = mesh.positions.iter().map(|p| p.z > 0.8).collect();
        assert!(moved.iter().any(|&m| m) && !moved.iter().all(|&m| m));
        for (p, &m) in mesh.positions.iter_mut().zip(&moved) {
            if m {
                p.z += 0.05 * (1.0 + p.x);
            }
        }
        let mut changed = vec![false; h.len()];
        for i in (0..h.len()).rev() {
            let n = h.nodes[i];
            if n.is_leaf() {
                let t = mesh.triangles[h.leaf_faces[n.leaf_start as usize] as usize];
                changed[i] = t.iter().any(|&v| moved[v as usize]);
            }
            if n.parent != NO_NODE {
                changed[n.parent as usize] |= changed[i];
            }
        }
        h.refit_changed(&mesh, &changed);
        let before = g.weight.clone();
        g.refit(&h, &changed);
        let want = FrameGeom::new(&h);
        assert_ne!(before, want.weight, "the bump changes areas");
        assert_eq!(g.mid, want.mid);
        assert_eq!(g.weight, want.weight);
        assert_eq!((&g.parent, &g.leaf_face), (&want.parent, &want.leaf_face));
    }

    /// A curved receiver's expansion of one link reproduces a profile of distance alone,
    /// `F ~ ρ^-a e^(-σ ρ)` (`a` = [`FALLOFF_POWER`]), at offsets `δ` in every direction as far
    /// as the receiver test lets a receiver reach, with a third-order error (relative to the
    /// midpoint's value, as the receiver test bounds it): within `(k |δ|)³ / 6` relative for
    /// `k = σ + (a + 2) / ρ` (the power law's third derivative is `a (a + 1) (a + 2) / ρ³`;
    /// the receiver test's `3 / ρ` is a threshold's scale, tuned with `ε1`), where the linear
    /// expansion's error, of second order, exceeds that bound. The moved expansion's value
    /// matches too.
    #[test]
    fn curved_expansion_matches_a_distance_profile() {
        let a = FALLOFF_POWER;
        let m_e = Vec3A::new(0.3, -0.2, 0.1);
        for sigma in [0.0f32, 2.0, 8.0] {
            for dir in [Vec3A::X, Vec3A::new(0.6, 0.8, 0.0), Vec3A::new(-0.36, 0.48, 0.8)] {
                let rho = 1.0f32;
                let m_r = m_e + dir * rho;
                let f = |x: Vec3A| {
                    let d = (x - m_e).length() as f64;
                    d.powf(-a as f64) * (-(sigma as f64) * d).exp()
                };
                let f0 = f(m_r);
                let s = a + sigma * rho;
                let t = Vec3A::splat(f0 as f32);
                let mut worst_linear = 0.0f64;
                let (mut curved, mut linear) = (Linear::default(), Linear::default());
                curved.value = t;
                linear.value = t;
                curved.add_link(t, s, m_r - m_e, true);
                linear.add_link(t, s, m_r - m_e, false);
                for off in [Vec3A::X, Vec3A::Y, Vec3A::Z, Vec3A::new(0.6, -0.48, 0.64)] {
                    // Where the receiver test lets receivers stay whole: `(σ + 3 / ρ) |δ|` up
                    // to about 1.2 at `pbd`'s `ε1` = 0.3 (`(6 ε1)^(1/3)`).
                    for len in
                        [0.05f32, 0.1, 0.2, 0.33].into_iter().filter(|l| (sigma + 3.0 / rho) * l <= 1.2)
                    {
                        let delta = off * len;
                        let exact = f(m_r + delta);
                        // Relative to the midpoint's value, as the receiver test bounds it.
                        let rel = |v: Vec3A| (v.x as f64 - exact).abs() / f0;
                        let (ec, el) = (rel(curved.value_at(delta)), rel(linear.value_at(delta)));
                        let k = (sigma + (a + 2.0) / rho) as f64 * len as f64;
                        assert!(
                            ec <= k * k * k / 6.0,
                            "σ {sigma} δ {delta}: curved {ec:.2e}, bound {:.2e}",
                            k * k * k / 6.0
                        );
                        assert!(rel(curved.moved(delta).value) == ec);
                        worst_linear = worst_linear.max(el / (k * k * k / 6.0));
                    }
                }
                assert!(worst_linear > 1.0, "σ {sigma}: the linear expansion never exceeds the bound");
            }
        }
    }
}
