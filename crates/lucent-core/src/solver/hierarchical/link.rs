//! The receiver-driven refinement of the hierarchical solve (Mertens et al. 2003, §3.2, §5.2),
//! which all three modes run: a receiver `R` is handed the candidate emitters its ancestors
//! deferred to it; each candidate is linked at `R`, opened at the emitter (its children become
//! candidates of `R`) or deferred to `R`'s children, per the oracle's decision. This is the
//! recursive refinement of §3.2 reordered by receiver, so subtrees are independent and run in
//! parallel, and links come out sorted by receiver in preorder. Render and incremental modes
//! store the links ([`HierarchicalSolver::link`]; an incremental relink keeps what did not
//! change, §5.5); on-the-fly mode gathers as it goes ([`super::gather`]).

use super::{HierarchicalSolver, SolveStats};
use crate::hierarchy::{Hierarchy, PAR_LEAVES};
use crate::solver::evaluate::Evaluator;
use crate::solver::link_set::{ChunkPool, Link, LinkChunk, LinkSet};
use crate::solver::local::Locality;
use crate::solver::oracle::{Decision, LinkKind, Oracle, ReceiverView, Samples};
use crate::solver::point_sample::ReceiverSources;
use glam::Vec3A;
use rayon::prelude::*;
use std::sync::atomic::{AtomicI64, Ordering};

/// Per-task state of a traversal.
pub(super) struct Ctx<'a> {
    pub(super) ev: Evaluator<'a>,
    /// Candidate emitters of the current receiver still to decide, with their one-point
    /// estimate when the decision that opened their parent made it.
    stack: Vec<(u32, Option<[f32; 3]>)>,
    inv_rtot: [f32; 3],
    point_samples: usize,
    /// The profile's reach and the clusters whose faces all take the local limit.
    locality: &'a Locality,
    local: &'a [bool],
    /// Faces linked to themselves only, by the local limit.
    local_faces: usize,
}

impl<'a> Ctx<'a> {
    pub(super) fn new(s: &'a HierarchicalSolver) -> Self {
        let mut ev = Evaluator::new(&s.hierarchy, &s.profile, s.ff_opts);
        ev.near_point_sampling = s.near_point_sampling;
        Ctx {
            ev,
            stack: Vec::with_capacity(64),
            // One scale for all channels (the largest `R_d_total`): the oracle bounds absolute
            // errors relative to the brightest channel, not each dim channel on its own.
            inv_rtot: {
                let r = s.profile.total_diffuse_reflectance();
                [(1.0 / r[0].max(r[1]).max(r[2]).max(1e-12)) as f32; 3]
            },
            point_samples: 0,
            locality: &s.locality,
            local: &s.local,
            local_faces: 0,
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
    pub(super) fn fill(&self, stats: &mut SolveStats) {
        stats.form_factors = self.ev.form_factors;
        stats.cubatures = self.ev.cubatures;
        stats.polar_faces = self.ev.polar_faces;
        stats.point_samples = self.point_samples;
        stats.local_faces = self.local_faces;
    }

    pub(super) fn absorb(&mut self, o: &Ctx) {
        self.ev.form_factors += o.ev.form_factors;
        self.ev.cubatures += o.ev.cubatures;
        self.ev.polar_faces += o.ev.polar_faces;
        self.point_samples += o.point_samples;
        self.local_faces += o.local_faces;
    }

    /// Processes the candidates of receiver `r` (see the module documentation): hands every
    /// accepted link to `sink` and fills `defer` with the candidates for `r`'s children.
    pub(super) fn receive(
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
            // Out of reach: what `e` sends to `r` is below the profile's tail.
            if self.locality.apart(h, r, e) {
                continue;
            }
            let decision = if self.local[r] {
                samples = Samples::default();
                match local_decision(h, r, e) {
                    Some(d) => d,
                    None => continue,
                }
            } else {
                if sink.kept(r, e) {
                    continue;
                }
                samples.f_mid = f_mid;
                oracle.decide(h, &self.ev.d32, &view, r, e, &mut samples)
            };
            match decision {
                Decision::Link(LinkKind::PointSample) if self.local[r] => {
                    // The local limit: the face's own `∫ R dA`, `R_d_total`.
                    samples.estimate = Some(self.locality.r_total);
                    self.local_faces += 1;
                    sink.link(self, &view.src, r, e, LinkKind::PointSample, &samples);
                }
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

/// The decision for candidate `e` at a receiver `r` all of whose faces take the local limit
/// (`None`: drop it). No other face comes within the profile's reach of theirs, so only the
/// candidates that hold faces of `r` matter: opened down to each face's link to itself.
#[inline]
fn local_decision(h: &Hierarchy, r: usize, e: usize) -> Option<Decision> {
    let (rn, en) = (&h.nodes[r], &h.nodes[e]);
    if en.leaf_end <= rn.leaf_start || rn.leaf_end <= en.leaf_start {
        return None;
    }
    Some(if r == e && rn.is_leaf() {
        Decision::Link(LinkKind::PointSample)
    } else if rn.is_leaf() {
        Decision::SplitEmitter
    } else {
        Decision::SplitReceiver
    })
}

/// The candidates a receiver defers to its children, each with the one-point estimates at
/// the children's midpoints when the receiver test made them (the children's oracle would
/// make the same ones).
#[derive(Debug, Default)]
pub(super) struct Deferred {
    emitters: Vec<u32>,
    at_children: Vec<Option<[[f32; 3]; 4]>>,
}

impl Deferred {
    /// The deferred emitters.
    pub(super) fn emitters(&self) -> &[u32] {
        &self.emitters
    }
}

/// The candidates of a receiver: child `child`'s share of its parent's [`Deferred`].
#[derive(Clone, Copy)]
pub(super) struct Cands<'a> {
    emitters: &'a [u32],
    at_children: &'a [Option<[[f32; 3]; 4]>],
    child: usize,
}

impl<'a> Cands<'a> {
    /// The root's: its self-link.
    pub(super) const ROOT: Cands<'static> = Cands { emitters: &[0], at_children: &[None], child: 0 };

    /// None.
    pub(super) const NONE: Cands<'static> = Cands { emitters: &[], at_children: &[], child: 0 };

    pub(super) fn of_child(d: &'a Deferred, child: usize) -> Self {
        Cands { emitters: &d.emitters, at_children: &d.at_children, child }
    }

    /// Each candidate with its estimate at this receiver's midpoint, if known.
    pub(super) fn iter(self) -> impl Iterator<Item = (u32, Option<[f32; 3]>)> + 'a {
        let k = self.child;
        self.emitters.iter().zip(self.at_children).map(move |(&e, f)| (e, f.map(|f| f[k])))
    }
}

/// What [`Ctx::receive`] does with links: on the fly and when linking from scratch, evaluate
/// every accepted link; in an incremental relink, also keep old ones.
pub(super) trait LinkSink {
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

/// Evaluates each accepted link and passes `(e, kind, F, steepness)` on.
pub(super) struct Evaluate<F>(pub(super) F);

impl<F: FnMut(usize, LinkKind, [f32; 3], f32)> LinkSink for Evaluate<F> {
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
        (self.0)(e, kind, f, samples.slope);
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
    /// The receiver's old links as (emitter, index in its run), sorted by emitter, made on
    /// the first look-up: a scan per candidate cost O(links²) per receiver, and real meshes
    /// have receivers with thousands of links.
    old_of_r: Option<Vec<(u32, u32)>>,
}

impl Reusing<'_, '_> {
    /// The old link `e -> r`, if any.
    #[inline]
    fn old_link(&mut self, r: usize, e: usize) -> Option<Link> {
        let old = self.reuse.old;
        let index = self.old_of_r.get_or_insert_with(|| {
            let mut v: Vec<(u32, u32)> = old.emitters_of(r).map(|(j, x)| (x, j as u32)).collect();
            v.sort_unstable();
            v
        });
        let i = index.binary_search_by_key(&(e as u32), |&(x, _)| x).ok()?;
        Some(old.link_at(r, index[i].1 as usize))
    }
}

impl LinkSink for Reusing<'_, '_> {
    #[inline]
    fn kept(&mut self, r: usize, e: usize) -> bool {
        let unchanged = !self.reuse.changed[r] && !self.reuse.changed[e];
        if unchanged && let Some(l) = self.old_link(r, e).filter(|l| !l.dirty) {
            self.chunk.push(r, e, l.kind, l.coef, l.slope, false);
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
        let f = if kind != LinkKind::FormFactor {
            ctx.coefficient(src, r, e, kind, samples.estimate, samples.recv_scale)
        } else if let Some(f) = ctx.ev.cheap_form_factor(src, r, e) {
            f
        } else if self.reuse.remaining.fetch_sub(1, Ordering::Relaxed) > 0 {
            ctx.ev.edge_form_factor(r, e)
        } else {
            // Over the budget: the old coefficient, or a point sample, marked stale.
            let f = match self.old_link(r, e) {
                Some(l) if l.kind == LinkKind::FormFactor => l.coef,
                _ => {
                    ctx.point_samples += 1;
                    Vec3A::from_array(ctx.ev.eval(src, r, e, LinkKind::PointSample))
                }
            };
            self.chunk.push(r, e, kind, f, samples.slope, true);
            return;
        };
        self.chunk.push(r, e, kind, Vec3A::from_array(f), samples.slope, false);
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
pub(super) struct Reuse<'a> {
    /// The links before the update.
    pub(super) old: &'a LinkSet,
    /// Clusters with a moved face in their subtree (their geometry, or a descendant's, changed).
    pub(super) changed: &'a [bool],
    /// Receivers with a dirty link in their subtree.
    pub(super) stale: &'a [bool],
    /// Form factor evaluations left in this update's budget.
    pub(super) remaining: &'a AtomicI64,
}

/// A candidate emitter with its one-point estimate at the receiver, if known.
type Candidate = (u32, Option<[f32; 3]>);

/// A preorder range of clusters: the first and one past the last.
type PreorderRange = (u32, u32);

impl HierarchicalSolver {
    /// Runs the receiver-driven refinement from the root and stores the resulting links. With
    /// `reuse`, receiver subtrees whose candidates and own geometry are unchanged take their old
    /// links verbatim, and unchanged pairs keep their old coefficients (see
    /// [`HierarchicalSolver::update_incremental`]).
    pub(super) fn relink(&mut self, reuse: Option<&Reuse>) -> SolveStats {
        let h = &self.hierarchy;
        let mut stats = SolveStats::default();
        let mut chunks = Vec::new();
        if !h.is_empty() {
            let mut ctx = Ctx::new(self);
            chunks.push(self.chunk_pool.take(ChunkPool::subtree(0)));
            self.link_rec(&mut ctx, 0, Cands::ROOT, &[], &mut chunks, reuse);
            self.tick_progress(None, 0);
            ctx.fill(&mut stats);
        }
        // The set the last update replaced lends its buffers, already paged in: large fresh
        // allocations are mapped anew by the allocator and fault on first touch.
        let set = LinkSet::build(&mut chunks, reuse.map(|u| u.old), self.spare.take(), h.len());
        // After a link from scratch the chunks are emptied shells: an incremental relink's
        // chunks hold only what changed, so sizing them for every link would hold the links
        // twice.
        if reuse.is_some() {
            self.chunk_pool.put(chunks);
        }
        stats.links = set.len();
        self.links = Some(set);
        self.links_have_candidates = self.keep_candidates;
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
        let n = self.hierarchy.nodes[r];
        let chunk = chunks.last_mut().expect("a chunk");
        let Some((fresh, kept_here)) = self.sort_candidates(r, cands, kept, chunk, reuse) else {
            return;
        };
        let mut defer = Deferred::default();
        match reuse {
            None => ctx.receive(
                &self.oracle,
                r,
                fresh,
                &mut defer,
                &mut Evaluate(|e, kind, f, slope| chunk.push(r, e, kind, Vec3A::from_array(f), slope, false)),
            ),
            Some(reuse) => {
                ctx.receive(&self.oracle, r, fresh, &mut defer, &mut Reusing { reuse, chunk, old_of_r: None })
            }
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
                    self.tick_progress(Some(r), c as usize);
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
                self.tick_progress(Some(r), c as usize);
            }
        }
    }

    /// Sorts the candidates `cands` handed to receiver `r` into the *fresh* ones, decided
    /// again, and the preorder ranges *kept* from the old links (see [`Self::link_rec`]), and
    /// records `r`'s candidates in `chunk` where they are stored. `None` when the whole subtree
    /// takes over its old links.
    fn sort_candidates(
        &self,
        r: usize,
        cands: Cands,
        kept: &[(u32, u32)],
        chunk: &mut LinkChunk,
        reuse: Option<&Reuse>,
    ) -> Option<(Vec<Candidate>, Vec<PreorderRange>)> {
        let h = &self.hierarchy;
        let n = h.nodes[r];
        let range = |e: u32| (e, h.nodes[e as usize].subtree_end);
        let mut fresh = Vec::new();
        let mut kept_here = Vec::new();
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
                    return None;
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
                if self.keep_candidates {
                    let start = chunk.cands.len();
                    chunk.cands.extend_from_slice(cands.emitters);
                    chunk.cands[start..].sort_unstable();
                    chunk.cand_count.push((r as u32, cands.emitters.len() as u32));
                }
            }
        }
        Some((fresh, kept_here))
    }
}
