//! The hierarchical boundary element solve of Mertens et al. 2003 (§3.2, §5.2, §5.5) over a
//! [`Hierarchy`], in its three modes:
//!
//! * **on-the-fly** ([`HierarchicalSolver::solve_on_the_fly`]): every frame, refine from the
//!   root's self-link and gather while traversing; nothing is stored. Parallel over receiver
//!   subtrees.
//! * **render** ([`HierarchicalSolver::link`] once, then
//!   [`HierarchicalSolver::solve_render`] per frame): the links are stored flat, a run per
//!   receiver ([`LinkSet`]), and a frame is only *pull* (area-weighted
//!   irradiance up the tree), *gather* (`Σ E_e F_re` per receiver) and *push* (a receiver's `B`
//!   added to all its leaves).
//! * **incremental** ([`HierarchicalSolver::update_incremental`]): after a geometry or material
//!   change, re-evaluate the links touching changed clusters, moving links down (refining) or up
//!   (coarsening) where the oracle's verdict changed, optionally within a budget of form factor
//!   evaluations per frame; then render as above.
//!
//! The receiver-driven traversal: a receiver `R` is handed the candidate emitters its ancestors
//! deferred to it; each candidate is linked at `R`, opened at the emitter (its children become
//! candidates of `R`) or deferred to `R`'s children, per [`Oracle::decide`]. This is the
//! recursive refinement of §3.2 reordered by receiver, so subtrees are independent and run in
//! parallel, and links come out sorted by receiver in preorder.

use super::energy;
use super::link_coef;
use super::link_set::{ChunkPool, LinkChunk, LinkSet};
use super::oracle::{Decision, Evaluator, LinkKind, Oracle, ReceiverView, Samples};
use super::point_sample::ReceiverSources;
use crate::Rgb;
use crate::bssrdf::Dipole;
use crate::formfactor::FormFactorOptions;
use crate::hierarchy::{Hierarchy, PAR_LEAVES, split_leaves, split_subtrees};
use crate::mesh::Mesh;
use glam::Vec3A;
use rayon::prelude::*;
use std::sync::atomic::{AtomicI64, Ordering};
use std::time::Instant;

/// Counters and timings of one solve or update. Times in milliseconds (wall clock).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveStats {
    /// Links used (stored links in render/incremental mode, traversed ones on the fly).
    pub links: usize,
    /// Semi-analytic form factor evaluations in this call.
    pub form_factors: usize,
    /// Near (form factor) links evaluated by the seven-point cubature instead, where `R_d` is
    /// smooth over the emitter face (see [`crate::formfactor::cubature`]).
    pub cubatures: usize,
    /// One-point evaluations in this call.
    pub point_samples: usize,
    /// Time spent refining / relinking (and evaluating link coefficients), ms.
    pub link_ms: f64,
    /// Time spent pulling irradiance up the hierarchy, ms.
    pub pull_ms: f64,
    /// Time spent gathering over links, ms (on the fly: included in `link_ms`).
    pub gather_ms: f64,
    /// Time spent pushing `B` down to the leaves and reordering, ms.
    pub push_ms: f64,
    /// Whole call, ms.
    pub total_ms: f64,
}

/// The result of a solve: `B` per face (original face order) and statistics.
#[derive(Clone, Debug)]
pub struct Solution {
    /// `B(x_o)` at each face midpoint (Mertens eq. 4), in the units of the irradiance.
    pub face_b: Vec<Rgb>,
    /// What it took.
    pub stats: SolveStats,
}

/// The hierarchical solver: a mesh, its hierarchy, the material and the oracle, plus the
/// stored links once [`HierarchicalSolver::link`] has run.
#[derive(Clone, Debug)]
pub struct HierarchicalSolver {
    /// The mesh in its current shape (updated by [`HierarchicalSolver::update_incremental`]).
    pub mesh: Mesh,
    /// The cluster hierarchy over `mesh`.
    pub hierarchy: Hierarchy,
    /// The material at the model's scale.
    pub dipole: Dipole,
    /// The refinement oracle.
    pub oracle: Oracle,
    /// Options of the semi-analytic form factor.
    pub ff_opts: FormFactorOptions,
    /// Integrate near links by uniform point sampling (about one sample per squared mean free
    /// path, after Jensen & Buhler 2002) instead of the semi-analytic form factor: the
    /// comparison of Mertens table 5. Default false.
    pub near_point_sampling: bool,
    links: Option<LinkSet>,
    /// The link set an incremental update replaced, kept for its buffers.
    spare: Option<LinkSet>,
    /// Chunk buffers of the last relink, for the same reason.
    chunk_pool: ChunkPool,
    /// Render mode's per-cluster irradiance and gathered `B`, kept between frames for the
    /// same reason (each is 4 MB at 131K triangles).
    frame: [Vec<Vec3A>; 2],
    /// Render mode's energy bound per face (see [`super::energy`]), made from the stored links
    /// under uniform irradiance, until the links change.
    bound: Option<Vec<Rgb>>,
}

/// Per-task state of a traversal.
struct Ctx<'a> {
    ev: Evaluator<'a>,
    /// Candidate emitters of the current receiver still to decide, with their one-point
    /// estimate when the decision that opened their parent made it.
    stack: Vec<(u32, Option<[f32; 3]>)>,
    inv_rtot: [f32; 3],
    point_samples: usize,
}

impl<'a> Ctx<'a> {
    fn new(s: &'a HierarchicalSolver) -> Self {
        let mut ev = Evaluator::new(&s.hierarchy, &s.dipole, s.ff_opts);
        ev.near_point_sampling = s.near_point_sampling;
        Ctx {
            ev,
            stack: Vec::with_capacity(64),
            // One scale for all channels (the largest `R_d_total`): the oracle bounds absolute
            // errors relative to the brightest channel, not each dim channel on its own.
            inv_rtot: {
                let r = s.dipole.total_diffuse_reflectance();
                [(1.0 / r[0].max(r[1]).max(r[2]).max(1e-12)) as f32; 3]
            },
            point_samples: 0,
        }
    }

    /// The transport coefficient of an accepted link `e -> r`: the oracle's one-point
    /// `estimate` for a point sample when it made one (scaled to the receiver by `recv_scale`),
    /// else a fresh evaluation; counted by kind.
    fn coefficient(
        &mut self,
        src: &ReceiverSources,
        r: usize,
        e: usize,
        kind: LinkKind,
        estimate: Option<[f32; 3]>,
        recv_scale: Option<[f32; 3]>,
    ) -> [f32; 3] {
        let mut f = match (kind, estimate) {
            (LinkKind::PointSample, Some(f)) => f,
            _ => self.ev.eval(src, r, e, kind),
        };
        if let (LinkKind::PointSample, Some(s)) = (kind, recv_scale) {
            f = std::array::from_fn(|c| f[c] * s[c]);
        }
        if kind == LinkKind::PointSample {
            self.point_samples += 1;
        }
        f
    }

    /// Copies the evaluation counts into `stats`.
    fn fill(&self, stats: &mut SolveStats) {
        stats.form_factors = self.ev.form_factors;
        stats.cubatures = self.ev.cubatures;
        stats.point_samples = self.point_samples;
    }

    fn absorb(&mut self, o: &Ctx) {
        self.ev.form_factors += o.ev.form_factors;
        self.ev.cubatures += o.ev.cubatures;
        self.point_samples += o.point_samples;
    }

    /// Processes the candidates of receiver `r` (see the module documentation): hands every
    /// accepted link to `sink` and fills `defer` with the candidates for `r`'s children.
    fn receive(
        &mut self,
        oracle: &Oracle,
        r: usize,
        cands: impl IntoIterator<Item = (u32, Option<[f32; 3]>)>,
        defer: &mut Deferred,
        sink: &mut impl LinkSink,
    ) {
        let h = self.ev.h;
        let view = ReceiverView::new(h, &self.ev.d32, self.inv_rtot, r);
        self.stack.clear();
        self.stack.extend(cands);
        let mut samples = Samples::default();
        while let Some((e, f_mid)) = self.stack.pop() {
            let e = e as usize;
            if sink.kept(r, e) {
                continue;
            }
            samples.f_mid = f_mid;
            match oracle.decide(h, &self.ev.d32, &view, r, e, &mut samples) {
                Decision::Link(kind) => sink.link(self, &view.src, r, e, kind, &samples),
                Decision::SplitReceiver => {
                    defer.emitters.push(e as u32);
                    defer.at_children.push(samples.at_children);
                }
                Decision::SplitEmitter => self.open_emitter(e, &samples),
            }
        }
    }

    /// Replaces emitter `e` on the stack by its children, with their estimates if `decide`
    /// made them.
    fn open_emitter(&mut self, e: usize, samples: &Samples) {
        let kids = self.ev.h.nodes[e].children();
        match samples.children {
            Some(f) => self.stack.extend(kids.iter().zip(f).map(|(&k, f)| (k, Some(f)))),
            None => self.stack.extend(kids.iter().map(|&k| (k, None))),
        }
    }
}

/// The candidates a receiver defers to its children, each with the one-point estimates at
/// the children's midpoints when the receiver test made them (the children's oracle would
/// make the same ones).
#[derive(Debug, Default)]
struct Deferred {
    emitters: Vec<u32>,
    at_children: Vec<Option<[[f32; 3]; 4]>>,
}

/// The candidates of a receiver: child `child`'s share of its parent's [`Deferred`].
#[derive(Clone, Copy)]
struct Cands<'a> {
    emitters: &'a [u32],
    at_children: &'a [Option<[[f32; 3]; 4]>],
    child: usize,
}

impl<'a> Cands<'a> {
    /// The root's: its self-link.
    const ROOT: Cands<'static> = Cands { emitters: &[0], at_children: &[None], child: 0 };

    fn of_child(d: &'a Deferred, child: usize) -> Self {
        Cands { emitters: &d.emitters, at_children: &d.at_children, child }
    }

    /// Each candidate with its estimate at this receiver's midpoint, if known.
    fn iter(self) -> impl Iterator<Item = (u32, Option<[f32; 3]>)> + 'a {
        let k = self.child;
        self.emitters.iter().zip(self.at_children).map(move |(&e, f)| (e, f.map(|f| f[k])))
    }
}

/// What [`Ctx::receive`] does with links: on the fly and when linking from scratch, evaluate
/// every accepted link; in an incremental relink, also keep old ones.
trait LinkSink {
    /// Whether the pair `e -> r` is settled without asking the oracle.
    fn kept(&mut self, _r: usize, _e: usize) -> bool {
        false
    }

    /// Takes the link `e -> r` the oracle accepted, with the estimates `decide` left.
    fn link(
        &mut self,
        ctx: &mut Ctx,
        src: &ReceiverSources,
        r: usize,
        e: usize,
        kind: LinkKind,
        samples: &Samples,
    );
}

/// Evaluates each accepted link and passes `(e, kind, F)` on.
struct Evaluate<F>(F);

impl<F: FnMut(usize, LinkKind, [f32; 3])> LinkSink for Evaluate<F> {
    #[inline]
    fn link(
        &mut self,
        ctx: &mut Ctx,
        src: &ReceiverSources,
        r: usize,
        e: usize,
        kind: LinkKind,
        samples: &Samples,
    ) {
        let f = ctx.coefficient(src, r, e, kind, samples.estimate, samples.recv_scale);
        (self.0)(e, kind, f);
    }
}

/// An incremental relink's links, into `chunk`: a pair whose clusters both kept their
/// geometry and that was linked before (clean) is linked again with its old coefficient
/// without asking the oracle (its verdict depends only on the two clusters and their
/// children); form factor evaluations draw on `reuse.remaining`, and once it is spent a link
/// keeps its old coefficient of the same kind (or gets a one-point estimate) and is marked
/// dirty.
struct Reusing<'a, 'b> {
    reuse: &'a Reuse<'a>,
    chunk: &'b mut LinkChunk,
}

impl LinkSink for Reusing<'_, '_> {
    #[inline]
    fn kept(&mut self, r: usize, e: usize) -> bool {
        let unchanged = !self.reuse.changed[r] && !self.reuse.changed[e];
        if unchanged && let Some((kind, f, false)) = self.reuse.old_link(r, e) {
            self.chunk.push(r, e, kind, f, false);
            return true;
        }
        false
    }

    fn link(
        &mut self,
        ctx: &mut Ctx,
        src: &ReceiverSources,
        r: usize,
        e: usize,
        kind: LinkKind,
        samples: &Samples,
    ) {
        let over = kind == LinkKind::FormFactor
            && ctx.ev.is_analytic(src, e)
            && self.reuse.remaining.fetch_sub(1, Ordering::Relaxed) <= 0;
        if over {
            let f = match self.reuse.old_link(r, e) {
                Some((LinkKind::FormFactor, f, _)) => f,
                _ => {
                    ctx.point_samples += 1;
                    Vec3A::from_array(ctx.ev.eval(src, r, e, LinkKind::PointSample))
                }
            };
            self.chunk.push(r, e, kind, f, true);
            return;
        }
        let f = ctx.coefficient(src, r, e, kind, samples.estimate, samples.recv_scale);
        self.chunk.push(r, e, kind, Vec3A::from_array(f), false);
    }
}

/// The index of the range of `ranges` (sorted, disjoint preorder ranges `start..end`; a
/// cluster's subtree is `e..subtree_end`) that holds cluster `e`, if any.
#[inline]
fn find_range(ranges: &[(u32, u32)], e: u32) -> Option<usize> {
    let i = ranges.partition_point(|&(a, _)| a <= e);
    (i > 0 && e < ranges[i - 1].1).then(|| i - 1)
}

/// What an incremental relink may keep from the previous link set.
struct Reuse<'a> {
    /// The links before the update.
    old: &'a LinkSet,
    /// Clusters with a moved face in their subtree (their geometry, or a descendant's, changed).
    changed: &'a [bool],
    /// Receivers with a dirty link in their subtree.
    stale: &'a [bool],
    /// Form factor evaluations left in this update's budget.
    remaining: &'a AtomicI64,
}

impl Reuse<'_> {
    /// The old, clean link `e -> r` of this kind, if any.
    #[inline]
    fn old_link(&self, r: usize, e: usize) -> Option<(LinkKind, Vec3A, bool)> {
        let (j, _) = self.old.emitters_of(r).find(|&(_, x)| x as usize == e)?;
        let l = self.old.link_at(r, j);
        Some((l.kind, l.coef, l.dirty))
    }
}

impl HierarchicalSolver {
    /// A solver for `mesh` (whose topology `hierarchy` was built on) with `dipole` and
    /// `oracle`, using the default form factor options. The hierarchy is refitted to `mesh`'s
    /// positions. No links are stored yet.
    pub fn new(mesh: Mesh, mut hierarchy: Hierarchy, dipole: Dipole, oracle: Oracle) -> Self {
        assert_eq!(hierarchy.leaf_count(), mesh.triangles.len());
        hierarchy.refit(&mesh);
        HierarchicalSolver {
            mesh,
            hierarchy,
            dipole,
            oracle,
            ff_opts: FormFactorOptions::default(),
            near_point_sampling: false,
            links: None,
            spare: None,
            chunk_pool: ChunkPool::default(),
            frame: Default::default(),
            bound: None,
        }
    }

    /// The stored links, if [`HierarchicalSolver::link`] has run.
    pub fn links(&self) -> Option<&LinkSet> {
        self.links.as_ref()
    }

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
        self.otf_rec(&mut ctx, 0, Cands::ROOT, [Vec3A::ZERO; 2], &e_node, &mut leaf_b);
        let t2 = Instant::now();
        let bound = self.dipole.bounds_energy();
        let mut face_b = vec![Rgb::ZERO; h.leaf_count()];
        for (pos, &f) in h.leaf_faces.iter().enumerate() {
            let [b, u] = leaf_b[pos];
            face_b[f as usize] = if bound { b * energy::bound(u) } else { b };
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

    fn otf_rec(
        &self,
        ctx: &mut Ctx,
        r: usize,
        cands: Cands,
        b_acc: [Vec3A; 2],
        e_node: &[Vec3A],
        out: &mut [[Rgb; 2]],
    ) {
        let mut defer = Deferred::default();
        // `B` and, for the energy bound, `B` under uniform irradiance 1.
        let [mut b, mut u] = b_acc;
        ctx.receive(
            &self.oracle,
            r,
            cands.iter(),
            &mut defer,
            &mut Evaluate(|e, _, f| {
                let f = Vec3A::from_array(f);
                b += e_node[e] * f;
                u += f;
            }),
        );
        let b = [b, u];
        let n = self.hierarchy.nodes[r];
        if n.is_leaf() {
            out[0] = b.map(Into::into);
            return;
        }
        let parts = split_leaves(&self.hierarchy.nodes, r, out);
        if n.leaf_count() > PAR_LEAVES {
            let subs: Vec<Ctx> = parts
                .into_par_iter()
                .enumerate()
                .map(|(k, (c, o))| {
                    let mut sub = Ctx::new(self);
                    self.otf_rec(&mut sub, c, Cands::of_child(&defer, k), b, e_node, o);
                    sub
                })
                .collect();
            subs.iter().for_each(|s| ctx.absorb(s));
        } else {
            for (k, (c, o)) in parts.into_iter().enumerate() {
                self.otf_rec(ctx, c, Cands::of_child(&defer, k), b, e_node, o);
            }
        }
    }

    /// Refines from the root's self-link and stores the links (render and incremental modes).
    pub fn link(&mut self) -> SolveStats {
        let t0 = Instant::now();
        let mut stats = self.relink(None);
        stats.link_ms = ms(t0.elapsed());
        stats.total_ms = stats.link_ms;
        stats
    }

    /// Runs the receiver-driven refinement from the root and stores the resulting links. With
    /// `reuse`, receiver subtrees whose candidates and own geometry are unchanged take their old
    /// links verbatim, and unchanged pairs keep their old coefficients (see
    /// [`HierarchicalSolver::update_incremental`]).
    fn relink(&mut self, reuse: Option<&Reuse>) -> SolveStats {
        let h = &self.hierarchy;
        let mut stats = SolveStats::default();
        let mut chunks = Vec::new();
        if !h.is_empty() {
            let mut ctx = Ctx::new(self);
            chunks.push(self.chunk_pool.take(ChunkPool::subtree(0)));
            self.link_rec(&mut ctx, 0, Cands::ROOT, &[], &mut chunks, reuse);
            ctx.fill(&mut stats);
        }
        // The set the last update replaced lends its buffers, already paged in: large fresh
        // allocations are mapped anew by the allocator and fault on first touch.
        let set = LinkSet::build(&chunks, reuse.map(|u| u.old), self.spare.take(), h.len());
        self.chunk_pool.put(chunks);
        stats.links = set.len();
        self.links = Some(set);
        self.bound = None;
        stats
    }

    /// Links receiver `r` and its subtree, given the candidate emitters `cands` its ancestors
    /// deferred to it. With `reuse`, `kept` are the preorder ranges of the candidates an
    /// ancestor kept (see below): old links of this subtree whose emitter lies in them are
    /// taken over verbatim.
    ///
    /// Each candidate's fate depends only on the pair (receiver, candidate) and the clusters
    /// below them, and the candidates of a receiver are disjoint clusters, so the links of a
    /// subtree are the union over its candidates of what each one refines into. In a subtree
    /// where nothing moved and nothing is stale, a candidate that did not move and was a
    /// candidate here before therefore refines exactly as before: its range is *kept*, and
    /// only the other (*fresh*) candidates are traversed again.
    fn link_rec(
        &self,
        ctx: &mut Ctx,
        r: usize,
        cands: Cands,
        kept: &[(u32, u32)],
        chunks: &mut Vec<LinkChunk>,
        reuse: Option<&Reuse>,
    ) {
        let h = &self.hierarchy;
        let n = h.nodes[r];
        let range = |e: u32| (e, h.nodes[e as usize].subtree_end);
        let mut fresh = Vec::new();
        let mut kept_here = Vec::new();
        let chunk = chunks.last_mut().expect("a chunk");
        match reuse {
            Some(u) if !u.changed[r] && !u.stale[r] => {
                // Stored candidate lists are sorted.
                let old_cands = u.old.cands_of(r);
                // Of the ancestors' kept ranges only those holding an old candidate of `r`
                // matter below (the old candidates of the subtree lie inside those of `r`),
                // which keeps the list as short as `r`'s candidates.
                let mut last = None;
                for &c in old_cands {
                    if let Some(i) = find_range(kept, c)
                        && last != Some(i)
                    {
                        kept_here.push(kept[i]);
                        last = Some(i);
                    }
                }
                for (e, f) in cands.iter() {
                    if !u.changed[e as usize] && old_cands.binary_search(&e).is_ok() {
                        kept_here.push(range(e));
                    } else {
                        fresh.push((e, f));
                    }
                }
                kept_here.sort_unstable();
                let old = u.old;
                if fresh.is_empty() && old_cands.iter().all(|&c| find_range(&kept_here, c).is_some()) {
                    // Everything here refines as before: the subtree's links wholesale.
                    chunk.kept.push((r as u32, n.subtree_end));
                    return;
                }
                // This receiver's candidates: the ones handed down now, plus those that the
                // kept ranges of ancestors handed down before (and would again).
                let start = chunk.cands.len();
                chunk.cands.extend_from_slice(cands.emitters);
                chunk.cands.extend(old_cands.iter().filter(|&&c| find_range(kept, c).is_some()));
                chunk.cands[start..].sort_unstable();
                chunk.cand_count.push((r as u32, (chunk.cands.len() - start) as u32));
                for (j, e) in old.emitters_of(r) {
                    if find_range(&kept_here, e).is_some() {
                        chunk.push_old(old, r, j);
                    }
                }
            }
            _ => {
                // Something below moved (or is stale): every candidate is decided again (an
                // ancestor cannot have kept a range, as it would be unmoved and clean too).
                debug_assert!(kept.is_empty());
                fresh.extend(cands.iter());
                let start = chunk.cands.len();
                chunk.cands.extend_from_slice(cands.emitters);
                chunk.cands[start..].sort_unstable();
                chunk.cand_count.push((r as u32, cands.emitters.len() as u32));
            }
        }
        let mut defer = Deferred::default();
        match reuse {
            None => ctx.receive(
                &self.oracle,
                r,
                fresh,
                &mut defer,
                &mut Evaluate(|e, kind, f| chunk.push(r, e, kind, Vec3A::from_array(f), false)),
            ),
            Some(reuse) => ctx.receive(&self.oracle, r, fresh, &mut defer, &mut Reusing { reuse, chunk }),
        }
        chunk.close_receiver();
        if n.is_leaf() {
            return;
        }
        if n.leaf_count() > PAR_LEAVES {
            let subs: Vec<(Ctx, Vec<LinkChunk>)> = n
                .children()
                .par_iter()
                .enumerate()
                .map(|(k, &c)| {
                    let mut sub = Ctx::new(self);
                    let mut sub_chunks = vec![self.chunk_pool.take(ChunkPool::subtree(c as usize))];
                    let cands = Cands::of_child(&defer, k);
                    self.link_rec(&mut sub, c as usize, cands, &kept_here, &mut sub_chunks, reuse);
                    (sub, sub_chunks)
                })
                .collect();
            for (s, c) in subs {
                ctx.absorb(&s);
                chunks.extend(c);
            }
            chunks.push(self.chunk_pool.take(ChunkPool::after(r)));
        } else {
            for (k, &c) in n.children().iter().enumerate() {
                self.link_rec(ctx, c as usize, Cands::of_child(&defer, k), &kept_here, chunks, reuse);
            }
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
                self.bound = Some(uniform.into_iter().map(energy::bound).collect());
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
        b_node.resize(self.hierarchy.len(), Vec3A::ZERO);
        self.pull_into(face_irradiance, &mut e_node);
        let t1 = Instant::now();
        let links = self.links.as_ref().expect("links stored");
        const CHUNK: usize = 1024;
        let stored = links.view();
        b_node.par_chunks_mut(CHUNK).enumerate().for_each(|(ci, b)| {
            link_coef::gather(&e_node, stored, ci * CHUNK, b);
        });
        let t2 = Instant::now();
        let face_b = self.push(&mut b_node);
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

    /// Push: accumulates every cluster's gathered `B` down to its leaves (in parallel over
    /// subtrees) and returns `B` per original face.
    fn push(&self, b_node: &mut [Vec3A]) -> Vec<Rgb> {
        let h = &self.hierarchy;
        if !h.is_empty() {
            push_subtree(h, 0, Vec3A::ZERO, b_node);
        }
        h.face_node.par_iter().with_min_len(4096).map(|&n| b_node[n as usize].into()).collect()
    }

    /// Incremental mode (§5.5): moves the mesh to `positions` (same topology), refits the
    /// hierarchy and brings the stored links up to date with the oracle, locally: the
    /// receiver-driven refinement is re-run from the root, but a receiver subtree whose own
    /// clusters did not move, holds no stale link, and whose candidate emitters did not move
    /// keeps its old links wholesale, and a link between two unmoved clusters keeps its old
    /// coefficient. Links are thus promoted or demoted only where geometry changed, and the
    /// result is the link set on-the-fly mode would build (identical once no link is stale).
    ///
    /// `budget` bounds the number of semi-analytic form factor evaluations in this call; links
    /// beyond it keep their old coefficient (or a one-point estimate if they are new), are
    /// marked dirty, and are recomputed first by the next call, which bounds the frame time as
    /// in the paper. `stats.link_ms` is the whole update.
    pub fn update_incremental(&mut self, positions: &[glam::Vec3], budget: Option<usize>) -> SolveStats {
        let t0 = Instant::now();
        assert_eq!(positions.len(), self.mesh.positions.len(), "topology must not change");
        if self.links.is_none() {
            self.mesh.positions.copy_from_slice(positions);
            self.hierarchy.refit(&self.mesh);
            return self.link();
        }
        let moved_vertex: Vec<bool> =
            self.mesh.positions.iter().zip(positions).map(|(a, b)| a != b).collect();
        let any_moved = moved_vertex.iter().any(|&m| m);
        let old = self.links.take().expect("links stored");
        let any_dirty = old.has_dirty();
        let h = &self.hierarchy;
        let mut changed = vec![false; h.len()];
        let mut stale = vec![false; h.len()];
        for i in (0..h.len()).rev() {
            let n = &h.nodes[i];
            if n.is_leaf() && any_moved {
                let t = self.mesh.triangles[h.leaf_faces[n.leaf_start as usize] as usize];
                changed[i] |= t.iter().any(|&v| moved_vertex[v as usize]);
            }
            if any_dirty {
                stale[i] |= old.is_stale(i);
            }
            if n.parent != crate::hierarchy::NO_NODE {
                let p = n.parent as usize;
                changed[p] |= changed[i];
                stale[p] |= stale[i];
            }
        }
        if any_moved {
            self.mesh.positions.copy_from_slice(positions);
            self.hierarchy.refit_changed(&self.mesh, &changed);
        }
        if !changed[0] && !stale[0] {
            self.links = Some(old);
            let stats = SolveStats {
                links: self.links.as_ref().map_or(0, |l| l.len()),
                link_ms: ms(t0.elapsed()),
                ..Default::default()
            };
            return SolveStats { total_ms: stats.link_ms, ..stats };
        }
        let remaining = AtomicI64::new(budget.map(|b| b as i64).unwrap_or(i64::MAX));
        let reuse = Reuse { old: &old, changed: &changed, stale: &stale, remaining: &remaining };
        let mut stats = self.relink(Some(&reuse));
        self.spare = Some(old.into_spare());
        stats.link_ms = ms(t0.elapsed());
        stats.total_ms = stats.link_ms;
        stats
    }

    /// Moves the mesh to `positions` (same topology) and refits the hierarchy, dropping any
    /// stored links (use [`HierarchicalSolver::update_incremental`] to keep and update them).
    pub fn set_positions(&mut self, positions: &[glam::Vec3]) {
        assert_eq!(positions.len(), self.mesh.positions.len(), "topology must not change");
        self.mesh.positions.copy_from_slice(positions);
        self.hierarchy.refit(&self.mesh);
        self.links = None;
        self.bound = None;
    }

    /// Changes the material: every stored link's coefficient becomes stale and is recomputed by
    /// the next [`HierarchicalSolver::update_incremental`] (the oracle is geometric, so the
    /// links themselves stay).
    pub fn set_dipole(&mut self, dipole: Dipole) {
        self.dipole = dipole;
        self.spare = None;
        self.bound = None;
        if let Some(l) = self.links.as_mut() {
            l.mark_all_dirty();
        }
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

#[inline]
fn ms(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
