//! A frame of the hierarchical solve (Mertens et al. 2003, §3.2, §5.5): *pull* (area-weighted
//! irradiance up the tree), *gather* (`B_R = Σ_E E_E F_ER` along the links into each receiver)
//! and *push* (a receiver's `B` added to all its leaves). Render mode gathers over the stored
//! links ([`HierarchicalSolver::solve_render`], with the packed kernel of [`super::link_coef`]);
//! on-the-fly mode gathers each link as the refinement accepts it and pushes down the traversal
//! ([`HierarchicalSolver::solve_on_the_fly`]). Where the profile asks for it, `B` is scaled by
//! the energy bound of [`super::energy`].
//!
//! With linear receivers ([`super::Oracle::linear_receivers`]) a receiver cluster gathers its
//! `B` at its midpoint *and* the gradient of `B` there (each link's steepness along the line
//! from its emitter), and the push hands each child the parent's value moved to the child's
//! midpoint: first-order (linear-basis) hierarchical radiosity at the receiver, which lets
//! receivers stay whole as far as emitters do.

use super::hierarchical::{HierarchicalSolver, Solution, SolveStats, ms};
use super::link_coef::{self, LinkCoef};
use super::link_set::LinkSet;
use super::refine::{Cands, Ctx, Deferred, Evaluate};
use crate::Rgb;
use crate::hierarchy::{Hierarchy, PAR_LEAVES, split_leaves, split_subtrees};
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
            pull_subtree(h, face_irradiance, 0, e);
        }
    }

    /// Render mode: pull, gather over the stored links, push. Links are created on first use.
    pub fn solve_render(&mut self, face_irradiance: &[Rgb]) -> Solution {
        if self.links.is_none() {
            self.link();
        }
        let mut solution = self.render_stored(face_irradiance);
        if self.dipole.bounds_energy() {
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
        let mut g_node = std::mem::take(&mut self.frame_grad);
        e_node.resize(self.hierarchy.len(), Vec3A::ZERO);
        b_node.resize(self.hierarchy.len(), Vec3A::ZERO);
        self.pull_into(face_irradiance, &mut e_node);
        let t1 = Instant::now();
        let links = self.links.as_ref().expect("links stored");
        let linear = self.linear_receivers();
        if linear {
            g_node.resize(self.hierarchy.len(), [Vec3A::ZERO; 3]);
            let mid = self
                .midpoints
                .get_or_init(|| self.hierarchy.geom.iter().map(|g| g.midpoint.into()).collect());
            gather_links_linear(&self.hierarchy, links, &e_node, mid, &mut b_node, &mut g_node);
        } else {
            gather_links(links, &e_node, &mut b_node);
        }
        let t2 = Instant::now();
        let face_b = self.push(&mut b_node, linear.then_some(&mut g_node[..]));
        let t3 = Instant::now();
        let links = links.len();
        self.frame = [e_node, b_node];
        self.frame_grad = g_node;
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

    /// Push: accumulates every cluster's gathered `B` (and, with linear receivers, its
    /// gradient `g_node`) down to its leaves, in parallel over subtrees, and returns `B` per
    /// original face.
    fn push(&self, b_node: &mut [Vec3A], g_node: Option<&mut [Grad]>) -> Vec<Rgb> {
        let h = &self.hierarchy;
        if !h.is_empty() {
            match g_node {
                Some(g) => push_linear(h, 0, Linear::default(), b_node, g),
                None => push_subtree(h, 0, Vec3A::ZERO, b_node),
            }
        }
        h.face_node.par_iter().with_min_len(4096).map(|&n| b_node[n as usize].into()).collect()
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
        let bound = self.dipole.bounds_energy();
        let mut face_b = vec![Rgb::ZERO; h.leaf_count()];
        for (pos, &f) in h.leaf_faces.iter().enumerate() {
            let [b, u] = leaf_b[pos];
            face_b[f as usize] = if bound { b * self.bound_factor(f as usize, u) } else { b };
        }
        let t3 = Instant::now();
        ctx.fill(&mut stats);
        stats.links = stats.form_factors + stats.cubatures + stats.point_samples;
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
                    let (k, dv) = steepness(m_r, h.geom[e].midpoint.into(), slope);
                    b.add_gradient(t * k, dv);
                    u.add_gradient(f * k, dv);
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

/// Render mode's gather: `b_node[r] = Σ E(e) F` over receiver `r`'s stored links, for every
/// cluster `r`, with `e_node` the pulled irradiance; in parallel over runs of receivers.
fn gather_links(links: &LinkSet, e_node: &[Vec3A], b_node: &mut [Vec3A]) {
    const CHUNK: usize = 1024;
    let stored = links.view();
    b_node.par_chunks_mut(CHUNK).enumerate().for_each(|(ci, b)| {
        link_coef::gather(e_node, stored, ci * CHUNK, b);
    });
}

/// Per channel, the gradient of `B` (per mesh unit of length) at a receiver's midpoint.
pub(crate) type Grad = [Vec3A; 3];

/// A receiver's gathered `B` as a linear function: its value at the receiver's midpoint and
/// its gradient there.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Linear {
    value: Vec3A,
    grad: Grad,
}

impl Linear {
    /// Adds `w[c] dv` to channel `c`'s gradient.
    #[inline]
    fn add_gradient(&mut self, w: Vec3A, dv: Vec3A) {
        self.grad[0] += dv * w.x;
        self.grad[1] += dv * w.y;
        self.grad[2] += dv * w.z;
    }

    /// The same function about a point `offset` from the midpoint.
    #[inline]
    fn moved(self, offset: Vec3A) -> Self {
        Linear { value: self.value + along(&self.grad, offset), grad: self.grad }
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

/// For a link from an emitter at `m_e` to a receiver at `m_r` with steepness `slope`: the
/// factor `k` and the line `D = m_r - m_e` such that the link's `E F` contributes `k E F D`
/// to the receiver's gradient (`F (1 - s (x - m_r).D / |D|^2)`, `oracle::Samples::slope`).
/// A link without steepness gives `k = 0`, whatever `D`.
#[inline]
fn steepness(m_r: Vec3A, m_e: Vec3A, slope: f32) -> (f32, Vec3A) {
    let dv = m_r - m_e;
    (-slope / dv.length_squared().max(f32::MIN_POSITIVE), dv)
}

/// [`gather_links`] with linear receivers: a leaf's `B` as there, an inner receiver's `B`
/// and its gradient `g_node` in one pass over its links (`mid`: every cluster's midpoint).
fn gather_links_linear(
    h: &Hierarchy,
    links: &LinkSet,
    e_node: &[Vec3A],
    mid: &[Vec3A],
    b_node: &mut [Vec3A],
    g_node: &mut [Grad],
) {
    const CHUNK: usize = 1024;
    let stored = links.view();
    b_node.par_chunks_mut(CHUNK).zip(g_node.par_chunks_mut(CHUNK)).enumerate().for_each(|(ci, (b, g))| {
        let isa = crate::simd::Isa::best();
        for (i, (b, g)) in b.iter_mut().zip(g.iter_mut()).enumerate() {
            let r = ci * CHUNK + i;
            let (emitter, coef, scale) = stored.of(r);
            if h.nodes[r].is_leaf() {
                *b = link_coef::gather_sum(isa, e_node, emitter, coef) * scale;
                *g = [Vec3A::ZERO; 3];
                continue;
            }
            let m_r = mid[r];
            // Four independent sums: one is bound by the adds' latency.
            let mut acc = [Linear::default(); 4];
            let term = |acc: &mut Linear, w: u32, c: LinkCoef| {
                let e = (w & !link_coef::FF_BIT) as usize;
                let t = e_node[e] * link_coef::decode(c);
                acc.value += t;
                // Links without steepness add nothing (no branch: most links have one).
                let (k, dv) = steepness(m_r, mid[e], c.slope());
                acc.add_gradient(t * k, dv);
            };
            let n4 = emitter.len() / 4 * 4;
            for (w, c) in emitter.chunks_exact(4).zip(coef.chunks_exact(4)) {
                for k in 0..4 {
                    term(&mut acc[k], w[k], c[k]);
                }
            }
            for (k, (&w, &c)) in emitter[n4..].iter().zip(&coef[n4..]).enumerate() {
                term(&mut acc[k], w, c);
            }
            *b = acc.iter().map(|a| a.value).sum::<Vec3A>() * scale;
            *g = std::array::from_fn(|c| acc.iter().map(|a| a.grad[c]).sum::<Vec3A>() * scale);
        }
    });
}

/// [`push_subtree`] with gradients: every cluster's `B` and gradient `g`, gathered at its
/// midpoint, plus its ancestors' `above` (moved to its midpoint), parents before children.
fn push_linear(h: &Hierarchy, r: usize, above: Linear, b: &mut [Vec3A], g: &mut [Grad]) {
    let n = h.nodes[r];
    b[0] += above.value;
    add_grad(&mut g[0], &above.grad);
    if n.leaf_count() > PAR_LEAVES {
        let own = Linear { value: b[0], grad: g[0] };
        let m_r = h.geom[r].midpoint;
        let (_, b_rest) = b.split_at_mut(1);
        let (_, g_rest) = g.split_at_mut(1);
        split_subtrees(&h.nodes, r, b_rest)
            .into_par_iter()
            .zip(split_subtrees(&h.nodes, r, g_rest))
            .for_each(|((c, bs), (_, gs))| {
                push_linear(h, c, own.moved(Vec3A::from(h.geom[c].midpoint - m_r)), bs, gs);
            });
        return;
    }
    for i in r + 1..n.subtree_end as usize {
        let p = h.nodes[i].parent as usize;
        let offset = Vec3A::from(h.geom[i].midpoint - h.geom[p].midpoint);
        let gp = g[p - r];
        b[i - r] += b[p - r] + along(&gp, offset);
        add_grad(&mut g[i - r], &gp);
    }
}

/// The pull below cluster `r`, whose subtree is `e` (`r..subtree_end` in preorder): children
/// before parents, subtrees of more than [`PAR_LEAVES`] leaves in parallel.
fn pull_subtree(h: &Hierarchy, face_irradiance: &[Rgb], r: usize, e: &mut [Vec3A]) {
    let n = h.nodes[r];
    if n.leaf_count() > PAR_LEAVES {
        let (_, rest) = e.split_at_mut(1);
        split_subtrees(&h.nodes, r, rest)
            .into_par_iter()
            .for_each(|(c, s)| pull_subtree(h, face_irradiance, c, s));
        e[0] = average_children(h, r, |c| e[c - r]);
        return;
    }
    for i in (r..n.subtree_end as usize).rev() {
        let m = &h.nodes[i];
        e[i - r] = if m.is_leaf() {
            face_irradiance[h.leaf_faces[m.leaf_start as usize] as usize].into()
        } else {
            average_children(h, i, |c| e[c - r])
        };
    }
}

/// The area-weighted average over cluster `i`'s children of `value(child)`.
#[inline]
fn average_children(h: &Hierarchy, i: usize, value: impl Fn(usize) -> Vec3A) -> Vec3A {
    let n = &h.nodes[i];
    let area = h.geom[i].area;
    let mut s = Vec3A::ZERO;
    for &c in n.children() {
        let c = c as usize;
        s += if area > 0.0 { value(c) * (h.geom[c].area / area) } else { value(c) / n.child_count as f32 };
    }
    s
}

/// The push below cluster `r` (subtree `b`, preorder), whose ancestors gathered `above`:
/// parents before children, subtrees of more than [`PAR_LEAVES`] leaves in parallel.
fn push_subtree(h: &Hierarchy, r: usize, above: Vec3A, b: &mut [Vec3A]) {
    let n = h.nodes[r];
    b[0] += above;
    if n.leaf_count() > PAR_LEAVES {
        let (own, rest) = b.split_at_mut(1);
        let own = own[0];
        split_subtrees(&h.nodes, r, rest).into_par_iter().for_each(|(c, s)| push_subtree(h, c, own, s));
        return;
    }
    for i in r + 1..n.subtree_end as usize {
        let p = h.nodes[i].parent as usize;
        b[i - r] += b[p - r];
    }
}
