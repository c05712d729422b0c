//! Refit before relink (issue 51; after Mertens et al. 2003, §5.5, whose incremental mode
//! relinks what moved): after a deformation the stored links are *kept* and every link whose
//! receiver or emitter moved gets its coefficient re-evaluated at the new pose, as a BVH is
//! refitted rather than rebuilt. The oracle's tests then run on a sample of receivers only,
//! which estimates the refit's error; where the estimate passes the tolerance, every receiver
//! is decided again (and the links the oracle no longer accepts are refined there).
//!
//! * **The refit** of a one-point link keeps what the oracle's second-order corrections made of
//!   its estimate (the midpoint-rule gain of a face, the Richardson step of a cluster, the
//!   average over an inner receiver, its steepness) and scales it by how the one-point estimate
//!   itself changed: `F' = F · f(new pose) / f(old pose)`, with `f = A_E R_d(x_R)` from the
//!   emitter's midpoint to the receiver's, four links a kernel call (the lanes of
//!   [`crate::solver::point_sample`]). Those corrections are second order in the clusters'
//!   size over their distance, and a deformation changes them by that order again. A form
//!   factor link (near) is evaluated afresh by the same rules as when linking (cubature, the
//!   polar rule or the edge integrals): scaling it by its one-point estimate's change, which
//!   near the profile's cut-off or its peak no longer follows the integral, took the bunny's
//!   skim milk at 5 cm from 0.2% to 21% relative RMSE against the exact solve.
//! * **The estimate**: every `stride`-th receiver with a moved link is decided again by the
//!   oracle; for each, the relative difference of its gathered transport under uniform
//!   irradiance, `Σ F`, between the refit and the oracle's fresh decision (links it would open
//!   refined at the receiver, links it defers to the children counted at their refit value).
//!   Each face's `B` is a sum of non-negative terms gathered at its ancestors, so its relative
//!   error is at most the largest of its receivers'. When the sampled receivers' 90th
//!   percentile exceeds [`RefitOptions::tolerance`], every receiver with a moved link is
//!   decided again in the following pass; otherwise only the sampled receivers beyond the
//!   tolerance are. A local deformation (at most an eighth of the clusters moved) is decided
//!   in full without an estimate: it moves few links.
//! * A receiver decided again keeps its links to unmoved emitters; the others are handed to
//!   [`super::link::Ctx::receive`], so a link the oracle now opens at the emitter is refined
//!   there and one it opens at the receiver is handed to the children as an extra candidate,
//!   which they decide in turn. Links are never coarsened: a refit keeps links at least as fine
//!   as a fresh link would make them.
//!
//! * **A material change** is refitted the same way ([`HierarchicalSolver::update_refit_with`]):
//!   every link's one-point estimate is taken under the old profile and the new one at the
//!   same pose, and the estimate of the error decides where the oracle links again. The
//!   oracle's accuracy test depends on the profile, so a large change (another material, a
//!   scale several times larger) fails the estimate and is decided in full, as a relink would
//!   be; a slider's step keeps nearly every link.
//!
//! Nothing moved: nothing changes (the stored links, bit for bit). The refit stores no
//! candidates, so an incremental update after it links from scratch first.

use super::link::{Cands, Ctx, Deferred, Evaluate};
use super::{HierarchicalSolver, ms};
use crate::bssrdf::Profile;
use crate::hierarchy::{ClusterGeom, PAR_LEAVES};
use crate::solver::link_set::{ChunkPool, Link, LinkChunk, LinkSet};
use crate::solver::local::Locality;
use crate::solver::oracle::LinkKind;
use crate::solver::point_sample::{ProfileF32, ReceiverSources};
use glam::{Vec3, Vec3A};
use rayon::prelude::*;
use std::time::Instant;

/// How a refit checks itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefitOptions {
    /// Every `stride`-th receiver (by cluster index) with a moved link is decided again by the
    /// oracle, which estimates the refit's error; 1 decides every one. Range 1.., default 16.
    pub stride: usize,
    /// The largest relative error of a receiver's gathered transport (90th percentile over
    /// the sampled receivers, brightest channel) that the refit may leave; beyond it every
    /// receiver is decided again. Unitless, range 0.., default 0.005 (half of the solver's 1%
    /// target, the other half being the fresh link's own error).
    pub tolerance: f32,
}

impl Default for RefitOptions {
    fn default() -> Self {
        RefitOptions { stride: 16, tolerance: 0.005 }
    }
}

/// What one [`HierarchicalSolver::update_refit`] did. Times in milliseconds (wall clock).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefitStats {
    /// Links stored after the update.
    pub links: usize,
    /// Links whose coefficient was re-evaluated (receiver or emitter moved).
    pub refitted: usize,
    /// Receivers whose moved links the oracle decided again in the pass (the sampled ones
    /// beyond the tolerance, or all of them), and those their parents handed candidates.
    pub decided_receivers: usize,
    /// Of the links decided again, those the oracle no longer accepted as they were (opened
    /// at the receiver or the emitter, or changed kind).
    pub opened: usize,
    /// Receivers in the error estimate's sample.
    pub sampled: usize,
    /// The sampled receivers' median and 90th-percentile relative error of `Σ F` (unitless).
    pub sampled_median: f32,
    /// See `sampled_median`.
    pub sampled_q90: f32,
    /// Whether the estimate exceeded the tolerance, so that every receiver was decided again.
    pub decided_all: bool,
    /// Whether the update linked from scratch instead (no links yet, or the set of faces
    /// taking the local limit changed, which a refit cannot follow).
    pub relinked: bool,
    /// The error estimate (the sampled receivers decided again), ms.
    pub estimate_ms: f64,
    /// The pass over every receiver (refit, and the decisions), ms.
    pub pass_ms: f64,
    /// The whole update, ms.
    pub ms: f64,
}

/// Per cluster, whether a face in its subtree has a vertex that differs between `from` and
/// `to` (`None`: nothing moved).
pub(super) fn moved_clusters(s: &HierarchicalSolver, from: &[Vec3], to: &[Vec3]) -> Option<Vec<bool>> {
    let moved_vertex: Vec<bool> = from.iter().zip(to).map(|(a, b)| a != b).collect();
    if !moved_vertex.iter().any(|&m| m) {
        return None;
    }
    let h = &s.hierarchy;
    let mut changed = vec![false; h.len()];
    for i in (0..h.len()).rev() {
        let n = &h.nodes[i];
        if n.is_leaf() {
            let t = s.mesh.triangles[h.leaf_faces[n.leaf_start as usize] as usize];
            changed[i] |= t.iter().any(|&v| moved_vertex[v as usize]);
        }
        if n.parent != crate::hierarchy::NO_NODE {
            changed[n.parent as usize] |= changed[i];
        }
    }
    Some(changed)
}

/// A deformation that moves at most `1 / LOCAL_SHARE` of the clusters is local: every
/// receiver with a moved link is decided again, without an estimate.
const LOCAL_SHARE: usize = 8;

/// What a refit reads: the links and geometry before the update, and what moved.
struct Refit<'a> {
    s: &'a HierarchicalSolver,
    old: &'a LinkSet,
    old_geom: &'a [ClusterGeom],
    /// The profile before a material change (`None`: the profile did not change).
    old_profile: Option<&'a ProfileF32>,
    /// Per cluster, whether its links' coefficients changed (it moved, or the material did).
    changed: &'a [bool],
    /// Decide every receiver with a moved link again (else those in `redo`).
    all: bool,
    stride: usize,
    /// The sampled receivers whose estimate exceeded the tolerance, sorted.
    redo: Vec<u32>,
}

/// Counts of one part of the traversal.
#[derive(Default)]
struct Tally {
    refitted: usize,
    decided_receivers: usize,
    opened: usize,
}

impl Tally {
    fn absorb(&mut self, o: &Tally) {
        self.refitted += o.refitted;
        self.decided_receivers += o.decided_receivers;
        self.opened += o.opened;
    }
}

/// A stored link during a refit: `(emitter, kind, coefficient, steepness, moved)`.
type RefitLink = (usize, LinkKind, Vec3A, f32, bool);

/// The range of `f(new) / f(old)` over which a one-point link keeps its corrections (the
/// estimate at most quadrupled or quartered); beyond it the new estimate stands bare.
const MAX_POINT_CHANGE: (f32, f32) = (0.25, 4.0);

/// One receiver's links after the refit, before they are decided again (if they are).
#[derive(Default)]
struct Scratch {
    /// The links in the stored order.
    links: Vec<RefitLink>,
    /// Of those, the form factors to evaluate afresh.
    fresh: Vec<usize>,
    /// The oracle's links, when it decided again.
    decided: Vec<(usize, LinkKind, Vec3A, f32)>,
    cands: Vec<(u32, Option<[f32; 3]>)>,
    /// The task's counts.
    tally: Tally,
}

impl Refit<'_> {
    /// Receiver `r`'s stored links into `sc.links`, the moved ones refitted (see the module
    /// documentation); false if none moved.
    fn refit_receiver(&self, ctx: &mut Ctx, r: usize, sc: &mut Scratch) -> bool {
        let (s, h) = (self.s, &self.s.hierarchy);
        sc.links.clear();
        let mut any = false;
        for l in self.old.links_of(r) {
            let Link { emitter: e, kind, coef, slope, dirty } = l;
            let moved = (self.changed[r] || self.changed[e] || dirty) && !s.local[r];
            any |= moved;
            sc.links.push((e, kind, coef, slope, moved));
        }
        if !any {
            return false;
        }
        let d = &ctx.ev.d32;
        let d_old = self.old_profile.unwrap_or(d);
        let (g_old, g) = (&self.old_geom[r], &h.geom[r]);
        let (src_old, src) = (
            ReceiverSources::new(d_old, g_old.midpoint, g_old.normal),
            ReceiverSources::new(d, g.midpoint, g.normal),
        );
        // One-point links four at a time: their estimate at both poses, the coefficient scaled;
        // one whose estimate vanished or changed by more than [`MAX_POINT_CHANGE`] takes the
        // new estimate bare. Form factors are evaluated afresh.
        let mut batch = [0usize; 4];
        let mut n = 0;
        sc.fresh.clear();
        let flush = |batch: &[usize], links: &mut Vec<RefitLink>| {
            let (mut p0, mut p1, mut a0, mut a1) = ([Vec3::ZERO; 4], [Vec3::ZERO; 4], [0.0; 4], [0.0; 4]);
            for (k, &i) in batch.iter().enumerate() {
                let e = links[i].0;
                (p0[k], a0[k]) = (self.old_geom[e].midpoint, self.old_geom[e].area);
                (p1[k], a1[k]) = (h.geom[e].midpoint, h.geom[e].area);
            }
            let (f0, f1) = (src_old.point_samples(d_old, &p0, &a0), src.point_samples(d, &p1, &a1));
            for (k, &i) in batch.iter().enumerate() {
                let l = &mut links[i];
                let (lo, hi) = MAX_POINT_CHANGE;
                let ratio: [f32; 3] = std::array::from_fn(|ch| f1[k][ch] / f0[k][ch]);
                l.2 = if ratio.iter().all(|&q| q >= lo && q <= hi) {
                    l.2 * Vec3A::from_array(ratio)
                } else {
                    Vec3A::from_array(f1[k])
                };
            }
        };
        for i in 0..sc.links.len() {
            let (_, kind, _, _, moved) = sc.links[i];
            if !moved {
                continue;
            }
            sc.tally.refitted += 1;
            if kind == LinkKind::FormFactor {
                sc.fresh.push(i);
                continue;
            }
            batch[n] = i;
            n += 1;
            if n == 4 {
                flush(&batch, &mut sc.links);
                n = 0;
            }
        }
        if n > 0 {
            flush(&batch[..n], &mut sc.links);
        }
        for &i in &sc.fresh {
            let l = &mut sc.links[i];
            l.2 = Vec3A::from_array(ctx.ev.eval(&src, r, l.0, LinkKind::FormFactor));
        }
        true
    }

    /// Decides receiver `r`'s moved links and the `extra` candidates its parent handed down
    /// again, into `sc.decided` (deferrals into `defer`); the relative difference of `Σ F`
    /// between the refit and the oracle, brightest channel.
    fn decide_receiver(
        &self,
        ctx: &mut Ctx,
        r: usize,
        extra: Cands,
        sc: &mut Scratch,
        defer: &mut Deferred,
    ) -> f32 {
        sc.cands.clear();
        sc.cands.extend(sc.links.iter().filter(|l| l.4).map(|l| (l.0 as u32, None)));
        sc.cands.extend(extra.iter());
        sc.decided.clear();
        let decided = &mut sc.decided;
        let cands = std::mem::take(&mut sc.cands);
        ctx.receive(
            &self.s.oracle,
            r,
            cands.iter().copied(),
            defer,
            &mut Evaluate(|e, kind, f, slope| decided.push((e, kind, Vec3A::from_array(f), slope))),
        );
        sc.cands = cands;
        let moved = || sc.links.iter().filter(|l| l.4);
        let refit: Vec3A = moved().map(|l| l.2).sum();
        let mut fresh: Vec3A = sc.decided.iter().map(|l| l.2).sum();
        // What the oracle defers to the children reaches them at about its refit value, or,
        // for a piece of an emitter it opened, its one-point estimate at the receiver.
        let (h, d) = (&self.s.hierarchy, &ctx.ev.d32);
        let g = &h.geom[r];
        let src = ReceiverSources::new(d, g.midpoint, g.normal);
        for &x in defer.emitters() {
            let x = x as usize;
            fresh += match moved().find(|l| l.0 == x) {
                Some(l) => l.2,
                None => Vec3A::from_array(src.point_sample(d, h.geom[x].midpoint, h.geom[x].area)),
            };
        }
        let base: Vec3A = sc.links.iter().filter(|l| !l.4).map(|l| l.2).sum::<Vec3A>() + refit;
        let m = base.max_element();
        if m > 0.0 { (refit - fresh).abs().max_element() / m } else { 0.0 }
    }

    /// Receiver `r`'s links into `chunk`: refitted, and decided again where the pass decides
    /// it (or its parent handed it `extra` candidates). Fills `defer` for `r`'s children.
    fn receiver(
        &self,
        ctx: &mut Ctx,
        r: usize,
        extra: Cands,
        sc: &mut Scratch,
        chunk: &mut LinkChunk,
        defer: &mut Deferred,
    ) {
        let moved = self.refit_receiver(ctx, r, sc);
        let has_extra = extra.iter().next().is_some();
        let decide = has_extra || (moved && (self.all || self.redo.binary_search(&(r as u32)).is_ok()));
        if !decide {
            for &(e, kind, c, slope, _) in &sc.links {
                chunk.push(r, e, kind, c, slope, false);
            }
            chunk.close_receiver();
            return;
        }
        sc.tally.decided_receivers += 1;
        self.decide_receiver(ctx, r, extra, sc, defer);
        for &(e, kind, c, slope, _) in sc.links.iter().filter(|l| !l.4) {
            chunk.push(r, e, kind, c, slope, false);
        }
        for &(e, kind, c, slope) in &sc.decided {
            chunk.push(r, e, kind, c, slope, false);
        }
        let kept = |l: &&RefitLink| sc.decided.iter().any(|d| d.0 == l.0 && d.1 == l.1);
        sc.tally.opened += sc.links.iter().filter(|l| l.4).filter(|l| !kept(l)).count();
        chunk.close_receiver();
    }

    /// Receiver `r` and its subtree into `chunks` (in preorder, parallel over large subtrees
    /// as [`HierarchicalSolver::relink`] is), `extra` the candidates its parent handed down.
    fn subtree(&self, ctx: &mut Ctx, r: usize, extra: Cands, sc: &mut Scratch, chunks: &mut Vec<LinkChunk>) {
        let (s, n) = (self.s, self.s.hierarchy.nodes[r]);
        let mut defer = Deferred::default();
        let chunk = chunks.last_mut().expect("a chunk");
        self.receiver(ctx, r, extra, sc, chunk, &mut defer);
        if n.is_leaf() {
            return;
        }
        if n.leaf_count() > PAR_LEAVES {
            let subs: Vec<(Tally, Vec<LinkChunk>)> = n
                .children()
                .par_iter()
                .enumerate()
                .map(|(k, &c)| {
                    let (mut sub, mut sc) = (Ctx::new(s), Scratch::default());
                    let mut sub_chunks = vec![s.chunk_pool.take(ChunkPool::subtree(c as usize))];
                    let cands = Cands::of_child(&defer, k);
                    self.subtree(&mut sub, c as usize, cands, &mut sc, &mut sub_chunks);
                    s.tick_progress(Some(r), c as usize);
                    (sc.tally, sub_chunks)
                })
                .collect();
            for (t, c) in subs {
                sc.tally.absorb(&t);
                chunks.extend(c);
            }
            chunks.push(s.chunk_pool.take(ChunkPool::after(r)));
        } else {
            for (k, &c) in n.children().iter().enumerate() {
                self.subtree(ctx, c as usize, Cands::of_child(&defer, k), sc, chunks);
                s.tick_progress(Some(r), c as usize);
            }
        }
    }

    /// The estimate: every `stride`-th receiver with a moved link decided again, with the
    /// relative error of its `Σ F` (in receiver order).
    fn estimate(&self) -> Vec<(u32, f32)> {
        let s = self.s;
        let sample: Vec<usize> = (0..s.hierarchy.len()).step_by(self.stride).collect();
        sample
            .par_iter()
            .map_init(
                || (Ctx::new(s), Scratch::default()),
                |(ctx, sc), &r| {
                    if !self.refit_receiver(ctx, r, sc) {
                        return None;
                    }
                    let mut defer = Deferred::default();
                    Some((r as u32, self.decide_receiver(ctx, r, Cands::NONE, sc, &mut defer)))
                },
            )
            .flatten()
            .collect()
    }
}

impl HierarchicalSolver {
    /// Refit before relink: moves the mesh to `positions` (same topology), refits the
    /// hierarchy, re-evaluates every stored link that moved, estimates the error on a sample
    /// of receivers and decides every receiver again where it exceeds `opts.tolerance` (see
    /// the module documentation). Links from scratch first when there are none.
    pub fn update_refit(&mut self, positions: &[Vec3], opts: RefitOptions) -> RefitStats {
        self.update_refit_with(positions, None, opts)
    }

    /// Changes the material to `p` as `set_profile` does, but leaves `local` the stored links'
    /// (compared after the pose's refit): the old profile, or `None` if `p` is the same.
    fn switch_profile(&mut self, p: Profile) -> Option<ProfileF32> {
        if p == self.profile {
            return None;
        }
        let old = ProfileF32::new(&self.profile);
        self.locality = Locality::of(&p);
        self.profile = p;
        self.bound = None;
        Some(old)
    }

    /// [`HierarchicalSolver::update_refit`] that also changes the material to `profile` (when
    /// given and different): the stored links are refitted from the old profile's one-point
    /// estimates to the new one's (module docs), instead of linking again.
    pub fn update_refit_with(
        &mut self,
        positions: &[Vec3],
        profile: Option<Profile>,
        opts: RefitOptions,
    ) -> RefitStats {
        let t0 = Instant::now();
        assert_eq!(positions.len(), self.mesh.positions.len(), "topology must not change");
        let done = |mut st: RefitStats, s: &Self| {
            st.links = s.links.as_ref().map_or(0, |l| l.len());
            st.ms = ms(t0.elapsed());
            st
        };
        let moved = moved_clusters(self, &self.mesh.positions, positions);
        let old_profile = profile.and_then(|p| self.switch_profile(p));
        if self.links.is_none() {
            if moved.is_some() {
                self.set_positions(positions);
            }
            self.local = self.locality.local_clusters(&self.hierarchy, &self.mesh);
            self.link();
            return done(RefitStats { relinked: true, ..Default::default() }, self);
        }
        let changed = match (&moved, &old_profile) {
            (_, Some(_)) => vec![true; self.hierarchy.len()],
            (Some(m), None) => m.clone(),
            (None, None) => return done(RefitStats::default(), self),
        };
        let old_geom = self.hierarchy.geom.clone();
        if let Some(moved) = &moved {
            self.mesh.positions.copy_from_slice(positions);
            self.hierarchy.refit_changed(&self.mesh, moved);
            if let Some(g) = self.frame_geom.get_mut() {
                g.refit(&self.hierarchy, moved);
            }
        }
        let local = self.locality.local_clusters(&self.hierarchy, &self.mesh);
        if local != self.local {
            // A face that took the local limit has no stored links to refit, and one that
            // now takes it would keep links it no longer has: link afresh.
            self.local = local;
            self.links = None;
            self.link();
            return done(RefitStats { relinked: true, ..Default::default() }, self);
        }
        let old = self.links.take().expect("links stored");
        let mut refit = Refit {
            s: self,
            old: &old,
            old_geom: &old_geom,
            old_profile: old_profile.as_ref(),
            changed: &changed,
            all: opts.stride <= 1,
            stride: opts.stride.max(1),
            redo: Vec::new(),
        };
        let mut st = RefitStats::default();
        // A local deformation moves few links: deciding them all costs little.
        let moved = changed.iter().filter(|&&c| c).count();
        refit.all |= moved * LOCAL_SHARE <= changed.len();
        let t = Instant::now();
        if !refit.all {
            let sample = refit.estimate();
            let mut err: Vec<f32> = sample.iter().map(|x| x.1).collect();
            err.sort_unstable_by(f32::total_cmp);
            st.sampled = err.len();
            let q = |p: f32| {
                err.get(((err.len() as f32 * p) as usize).min(err.len().max(1) - 1)).copied().unwrap_or(0.0)
            };
            (st.sampled_median, st.sampled_q90) = (q(0.5), q(0.9));
            refit.all = st.sampled_q90 > opts.tolerance;
            refit.redo = sample.iter().filter(|x| x.1 > opts.tolerance).map(|x| x.0).collect();
        }
        st.decided_all = refit.all;
        st.estimate_ms = ms(t.elapsed());
        let t = Instant::now();
        self.start_progress("refit");
        let mut chunks = vec![self.chunk_pool.take(ChunkPool::subtree(0))];
        let mut tally = Tally::default();
        if !self.hierarchy.is_empty() {
            let (mut ctx, mut sc) = (Ctx::new(self), Scratch::default());
            refit.subtree(&mut ctx, 0, Cands::NONE, &mut sc, &mut chunks);
            self.tick_progress(None, 0);
            tally = sc.tally;
        }
        st.pass_ms = ms(t.elapsed());
        let set = LinkSet::build(&mut chunks, Some(&old), self.spare.take(), self.hierarchy.len());
        self.chunk_pool.put(chunks);
        self.spare = Some(old.into_spare());
        self.links = Some(set);
        self.links_have_candidates = false;
        self.bound = None;
        (st.refitted, st.decided_receivers, st.opened) =
            (tally.refitted, tally.decided_receivers, tally.opened);
        done(st, self)
    }
}
