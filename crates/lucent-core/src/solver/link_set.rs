//! Stored links of render and incremental modes (Mertens et al. 2003, §5.5): for each receiver
//! cluster its emitters and packed coefficients ([`LinkCoef`]), and the candidate emitters its
//! ancestors handed it, which an incremental update needs to tell which links it may keep.
//!
//! An incremental update decides again only the links near what moved, a few percent of them
//! for a local deformation; copying the rest into new arrays every frame took 15 ms for 10.7M
//! kept links at 131K triangles, twice render mode's gather. So the links live in two stores: a
//! *base*, shared from update to update, and a *delta* holding what changed since the base was
//! built. Each receiver's `Span` says which store holds its run. An update writes a new delta
//! and shares the base; the base is built anew when nothing in it is live any more (the delta
//! becomes the base) or when more than half of it is dead (one copy, then shared again).

use super::link_coef::{FF_BIT, LinkCoef, receiver_scale};
use super::oracle::LinkKind;
use glam::Vec3A;
use rayon::prelude::*;
use std::sync::Arc;

/// Where a receiver's run of links (or candidates) lies: `len` entries from `start`, in the
/// delta store when `start` has [`Span::IN_DELTA`], else in the base; a run of links with a
/// dirty one has [`Span::HAS_DIRTY`] in `len`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Span {
    start: u32,
    len: u32,
}

impl Span {
    const IN_DELTA: u32 = 1 << 31;
    const HAS_DIRTY: u32 = 1 << 31;

    fn delta(start: usize, len: usize, dirty: bool) -> Self {
        Span { start: 0, len: len as u32 | if dirty { Self::HAS_DIRTY } else { 0 } }.moved(start, true)
    }

    /// The same run (length and dirty flag) at `start` of the delta, or of the base.
    fn moved(self, start: usize, in_delta: bool) -> Self {
        let start = u32::try_from(start).ok().filter(|&s| s < Self::IN_DELTA).expect("fewer than 2^31 links");
        Span { start: start | if in_delta { Self::IN_DELTA } else { 0 }, len: self.len }
    }

    #[inline]
    fn in_delta(self) -> bool {
        self.start & Self::IN_DELTA != 0
    }

    #[inline]
    fn range(self) -> std::ops::Range<usize> {
        let s = (self.start & !Self::IN_DELTA) as usize;
        s..s + self.len()
    }

    #[inline]
    fn len(self) -> usize {
        (self.len & !Self::HAS_DIRTY) as usize
    }

    #[inline]
    fn has_dirty(self) -> bool {
        self.len & Self::HAS_DIRTY != 0
    }
}

/// Flat arrays of links and candidates, indexed by [`Span`]s.
#[derive(Clone, Debug, Default)]
pub(crate) struct Store {
    /// Emitter cluster of each link, with [`FF_BIT`] for a form factor link.
    emitter: Vec<u32>,
    /// Coefficient of each link, relative to its receiver's scale.
    coef: Vec<LinkCoef>,
    /// Whether each link's coefficient is stale.
    dirty: Vec<bool>,
    /// Candidate emitters.
    cands: Vec<u32>,
}

impl Store {
    fn clear(&mut self) {
        self.emitter.clear();
        self.coef.clear();
        self.dirty.clear();
        self.cands.clear();
    }

    /// Link `j`, whose receiver's scale is `scale`.
    #[inline]
    fn link(&self, j: usize, scale: f32) -> Link {
        let w = self.emitter[j];
        Link {
            emitter: (w & !FF_BIT) as usize,
            kind: if w & FF_BIT != 0 { LinkKind::FormFactor } else { LinkKind::PointSample },
            coef: self.coef[j].unpack(scale),
            slope: self.coef[j].slope(),
            dirty: self.dirty[j],
        }
    }

    /// Appends the links `run` of `from`; returns where they start here.
    fn append_links(&mut self, from: &Store, run: std::ops::Range<usize>) -> usize {
        let at = self.emitter.len();
        self.emitter.extend_from_slice(&from.emitter[run.clone()]);
        self.coef.extend_from_slice(&from.coef[run.clone()]);
        self.dirty.extend_from_slice(&from.dirty[run]);
        at
    }

    /// Appends the candidates `run` of `from`; returns where they start here.
    fn append_cands(&mut self, from: &Store, run: std::ops::Range<usize>) -> usize {
        let at = self.cands.len();
        self.cands.extend_from_slice(&from.cands[run]);
        at
    }
}

/// One stored link, as [`LinkSet::links_of`] yields it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    /// The emitter cluster.
    pub emitter: usize,
    /// How the coefficient was evaluated.
    pub kind: LinkKind,
    /// Transport coefficient `F(E, x_R)` per channel (unitless), as stored (half floats under
    /// the receiver's scale: relative error at most [`super::link_coef::MAX_REL_ERROR`]).
    pub coef: Vec3A,
    /// Its steepness across an inner receiver (`oracle::Samples::slope`, unitless; 0 where
    /// the receiver takes one value).
    pub slope: f32,
    /// Whether the coefficient is stale (an incremental update ran out of budget); the next
    /// update recomputes it first.
    pub dirty: bool,
}

/// The stored links, by receiver cluster (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct LinkSet {
    base: Arc<Store>,
    delta: Store,
    /// Per receiver: its links.
    links: Vec<Span>,
    /// Per receiver: the candidate emitters (disjoint clusters) its ancestors handed it.
    cands: Vec<Span>,
    /// Per receiver: its coefficients' scale, a power of two ([`receiver_scale`]).
    scale: Vec<f32>,
    /// Number of links.
    len: usize,
}

/// The arrays render mode's gather reads (see `solver::gather`'s `RenderFrame`).
#[derive(Clone, Copy)]
pub(crate) struct StoredLinks<'a> {
    links: &'a [Span],
    stores: [(&'a [u32], &'a [LinkCoef]); 2],
    scale: &'a [f32],
}

impl<'a> StoredLinks<'a> {
    /// Receiver `r`'s emitter words and coefficients, and its scale.
    #[inline]
    pub fn of(&self, r: usize) -> (&'a [u32], &'a [LinkCoef], f32) {
        let s = self.links[r];
        let (e, c) = self.stores[s.in_delta() as usize];
        let j = s.range();
        (&e[j.clone()], &c[j], self.scale[r])
    }

    /// The arrays of one receiver `r` with the given links (for tests of the gather).
    #[cfg(test)]
    pub fn single(links: &'a [Span], emitter: &'a [u32], coef: &'a [LinkCoef], scale: &'a [f32]) -> Self {
        StoredLinks { links, stores: [(emitter, coef), (emitter, coef)], scale }
    }
}

#[cfg(test)]
impl Span {
    /// A span of the base store (for tests of the gather).
    pub fn base(start: usize, len: usize) -> Self {
        Span { start: start as u32, len: len as u32 }
    }
}

impl LinkSet {
    /// Number of links.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no links.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Receiver cluster `r`'s links.
    pub fn links_of(&self, r: usize) -> impl ExactSizeIterator<Item = Link> + '_ {
        let (st, run, scale) = self.run(r);
        run.map(move |j| st.link(j, scale))
    }

    /// Whether any link's coefficient is stale.
    pub fn has_dirty(&self) -> bool {
        self.links.iter().any(|s| s.has_dirty())
    }

    /// Whether receiver `r` has a stale link.
    #[inline]
    pub(crate) fn is_stale(&self, r: usize) -> bool {
        self.links[r].has_dirty()
    }

    /// Receiver `r`'s links as (index in its run, emitter cluster), for [`LinkSet::link_at`].
    #[inline]
    pub(crate) fn emitters_of(&self, r: usize) -> impl Iterator<Item = (usize, u32)> + '_ {
        let (st, run, _) = self.run(r);
        run.map(move |j| (j, st.emitter[j] & !FF_BIT))
    }

    /// Receiver `r`'s store, the indices of its links there, and its scale.
    #[inline]
    fn run(&self, r: usize) -> (&Store, std::ops::Range<usize>, f32) {
        let s = self.links[r];
        (self.store(s), s.range(), self.scale[r])
    }

    #[inline]
    fn store(&self, s: Span) -> &Store {
        if s.in_delta() { &self.delta } else { &self.base }
    }

    /// The candidate emitters receiver `r` was handed (sorted).
    #[inline]
    pub(crate) fn cands_of(&self, r: usize) -> &[u32] {
        let s = self.cands[r];
        &self.store(s).cands[s.range()]
    }

    /// Link `j` of receiver `r`'s run (an index from [`LinkSet::emitters_of`]).
    #[inline]
    pub(crate) fn link_at(&self, r: usize, j: usize) -> Link {
        let (st, _, scale) = self.run(r);
        st.link(j, scale)
    }

    /// The arrays render mode gathers over.
    pub(crate) fn view(&self) -> StoredLinks<'_> {
        StoredLinks {
            links: &self.links,
            stores: [(&self.base.emitter, &self.base.coef), (&self.delta.emitter, &self.delta.coef)],
            scale: &self.scale,
        }
    }

    /// Marks every link stale (after a change of material).
    pub(crate) fn mark_all_dirty(&mut self) {
        Arc::make_mut(&mut self.base).dirty.iter_mut().for_each(|d| *d = true);
        self.delta.dirty.iter_mut().for_each(|d| *d = true);
        for s in &mut self.links {
            if s.len() > 0 {
                s.len |= Span::HAS_DIRTY;
            }
        }
    }

    /// Drops the shared base (a spare set is kept for its delta's buffers only).
    pub(crate) fn into_spare(mut self) -> Self {
        self.base = Arc::default();
        self
    }

    /// The link set of a (re)link from its chunks (in preorder). With `old` (an incremental
    /// relink), the chunks' kept subtrees take `old`'s runs: those in its base by reference,
    /// those in its delta by copy. `spare`'s buffers are reused. `clusters` is the hierarchy's
    /// size.
    ///
    /// Without `old` (a link from scratch, where the chunks hold every link), each chunk's
    /// buffers are freed once copied, and fresh delta buffers are zeroed lazily (mapped on
    /// first write), so the links are held about once, not twice, at the peak.
    pub(crate) fn build(
        chunks: &mut [LinkChunk],
        old: Option<&LinkSet>,
        spare: Option<LinkSet>,
        clusters: usize,
    ) -> Self {
        let mut set = spare.unwrap_or_default();
        set.base = old.map(|o| o.base.clone()).unwrap_or_default();
        set.delta.clear();
        set.links.clear();
        set.links.resize(clusters, Span::default());
        set.cands.clear();
        set.cands.resize(clusters, Span::default());
        set.scale.clear();
        set.scale.resize(clusters, 1.0);
        // The chunks' own links and candidates, each chunk into its own slice of the delta.
        let own_links: usize = chunks.iter().map(|c| c.emitter.len()).sum();
        let own_cands: usize = chunks.iter().map(|c| c.cands.len()).sum();
        let d = &mut set.delta;
        grow_zeroed(&mut d.emitter, own_links);
        grow_zeroed(&mut d.coef, own_links);
        grow_zeroed(&mut d.dirty, own_links);
        grow_zeroed(&mut d.cands, own_cands);
        let release = old.is_none();
        let (mut e, mut f, mut k, mut q) =
            (&mut d.emitter[..], &mut d.coef[..], &mut d.dirty[..], &mut d.cands[..]);
        let mut parts = Vec::with_capacity(chunks.len());
        let (mut at_link, mut at_cand) = (0, 0);
        for c in chunks.iter_mut() {
            let (n, m) = (c.emitter.len(), c.cands.len());
            let (e0, e1) = std::mem::take(&mut e).split_at_mut(n);
            let (f0, f1) = std::mem::take(&mut f).split_at_mut(n);
            let (k0, k1) = std::mem::take(&mut k).split_at_mut(n);
            let (q0, q1) = std::mem::take(&mut q).split_at_mut(m);
            (e, f, k, q) = (e1, f1, k1, q1);
            let mut j = at_link;
            for r in &c.receivers {
                let n = r.links as usize;
                let dirty = c.dirty[j - at_link..j - at_link + n].iter().any(|&x| x);
                set.links[r.r as usize] = Span::delta(j, n, dirty);
                set.scale[r.r as usize] = r.scale;
                j += n;
            }
            let mut j = at_cand;
            for &(r, n) in &c.cand_count {
                set.cands[r as usize] = Span::delta(j, n as usize, false);
                j += n as usize;
            }
            (at_link, at_cand) = (at_link + n, at_cand + m);
            parts.push((c, e0, f0, k0, q0));
        }
        parts.into_par_iter().for_each(|(c, e, f, k, q)| {
            e.copy_from_slice(&c.emitter);
            f.copy_from_slice(&c.coef);
            k.copy_from_slice(&c.dirty);
            q.copy_from_slice(&c.cands);
            if release {
                *c = LinkChunk { key: c.key, ..LinkChunk::default() };
            }
        });
        // Kept subtrees: runs in the old base are shared, runs in the old delta copied.
        if let Some(old) = old {
            for c in chunks.iter() {
                for &(a, z) in &c.kept {
                    for r in a as usize..z as usize {
                        let (l, m) = (old.links[r], old.cands[r]);
                        set.scale[r] = old.scale[r];
                        set.links[r] = if l.in_delta() {
                            l.moved(set.delta.append_links(&old.delta, l.range()), true)
                        } else {
                            l
                        };
                        set.cands[r] = if m.in_delta() {
                            m.moved(set.delta.append_cands(&old.delta, m.range()), true)
                        } else {
                            m
                        };
                    }
                }
            }
        }
        set.len = set.links.iter().map(|s| s.len()).sum();
        set.rebase();
        set
    }

    /// Builds a new base where the old one is mostly dead: moves the delta over when no run
    /// is left in the base, copies every live run (in receiver order) when less than half of
    /// the base is live.
    fn rebase(&mut self) {
        let live_in_base =
            |spans: &[Span]| spans.iter().filter(|s| !s.in_delta()).map(|s| s.len()).sum::<usize>();
        let (base_links, base_cands) = (live_in_base(&self.links), live_in_base(&self.cands));
        if base_links == 0 && base_cands == 0 {
            self.base = Arc::new(std::mem::take(&mut self.delta));
            for s in self.links.iter_mut().chain(self.cands.iter_mut()) {
                s.start &= !Span::IN_DELTA;
            }
        } else if 2 * base_links < self.base.emitter.len() || 2 * base_cands < self.base.cands.len() {
            let mut flat = Store::default();
            flat.emitter.reserve(self.len);
            flat.coef.reserve(self.len);
            flat.dirty.reserve(self.len);
            for r in 0..self.links.len() {
                let (l, m) = (self.links[r], self.cands[r]);
                let l = l.moved(flat.append_links(self.store(l), l.range()), false);
                let m = m.moved(flat.append_cands(self.store(m), m.range()), false);
                (self.links[r], self.cands[r]) = (l, m);
            }
            self.base = Arc::new(flat);
            self.delta.clear();
        }
    }
}

/// Resizes `v` to `n` default (all-zero) elements; where it must grow, into a fresh zeroed
/// allocation, which the allocator maps lazily, instead of writing every element.
fn grow_zeroed<T: Copy + Default + bytemuck::Zeroable>(v: &mut Vec<T>, n: usize) {
    if v.capacity() >= n {
        v.clear();
        v.resize(n, T::default());
        return;
    }
    *v = Vec::new();
    if n == 0 || size_of::<T>() == 0 {
        return;
    }
    let layout = std::alloc::Layout::array::<T>(n).expect("link buffers fit in memory");
    // SAFETY: the layout has non-zero size; `T: Zeroable`, so zeroed memory holds `n` valid
    // `T`s, and the pointer comes from the global allocator with `Vec`'s layout for capacity
    // `n`.
    unsafe {
        let p = std::alloc::alloc_zeroed(layout) as *mut T;
        if p.is_null() {
            std::alloc::handle_alloc_error(layout);
        }
        *v = Vec::from_raw_parts(p, n, n);
    }
}

/// Links found in one part of a (re)link traversal, in receiver preorder: the links and
/// candidates it decided ("own"), and the subtrees it kept from the previous set.
#[derive(Debug, Default)]
pub(crate) struct LinkChunk {
    /// Its key in the [`ChunkPool`].
    key: u32,
    /// The receivers with own links, in preorder.
    receivers: Vec<ReceiverLinks>,
    emitter: Vec<u32>,
    coef: Vec<LinkCoef>,
    /// The coefficients (and steepness) of the receiver being linked, packed by
    /// [`LinkChunk::close_receiver`] once its scale is known.
    staged: Vec<(Vec3A, f32)>,
    dirty: Vec<bool>,
    /// `(receiver, candidate count)` of the receivers visited, in preorder, and their
    /// candidates.
    pub cand_count: Vec<(u32, u32)>,
    pub cands: Vec<u32>,
    /// Preorder ranges `r..subtree_end` of receivers whose links and candidates are the
    /// previous set's.
    pub kept: Vec<(u32, u32)>,
}

/// A receiver's own links in a [`LinkChunk`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct ReceiverLinks {
    r: u32,
    links: u32,
    /// The receiver's coefficient scale.
    scale: f32,
}

impl LinkChunk {
    /// Adds the link `e -> r` to the receiver being linked (`r`, until
    /// [`LinkChunk::close_receiver`]).
    #[inline]
    pub fn push(&mut self, r: usize, e: usize, kind: LinkKind, f: Vec3A, slope: f32, dirty: bool) {
        match self.receivers.last_mut() {
            Some(q) if q.r == r as u32 => q.links += 1,
            _ => self.receivers.push(ReceiverLinks { r: r as u32, links: 1, scale: 1.0 }),
        }
        self.emitter.push(match kind {
            LinkKind::FormFactor => e as u32 | FF_BIT,
            LinkKind::PointSample => e as u32,
        });
        self.staged.push((f, slope));
        self.dirty.push(dirty);
    }

    /// Copies link `j` of receiver `r`'s run in `old` unchanged (re-packing its coefficient
    /// under the receiver's new scale is lossless unless it grew past `2^28` times the old
    /// one).
    #[inline]
    pub fn push_old(&mut self, old: &LinkSet, r: usize, j: usize) {
        let l = old.link_at(r, j);
        self.push(r, l.emitter, l.kind, l.coef, l.slope, l.dirty);
    }

    /// Packs the staged coefficients of the receiver being linked, under its scale.
    pub fn close_receiver(&mut self) {
        if self.staged.is_empty() {
            return;
        }
        let max = self.staged.iter().fold(0.0f32, |m, (f, _)| m.max(f.max_element()));
        let scale = receiver_scale(max);
        self.receivers.last_mut().expect("staged links have a receiver").scale = scale;
        self.coef.extend(self.staged.drain(..).map(|(f, s)| LinkCoef::pack_with_slope(f, scale, s)));
    }

    /// Empties the chunk, keeping its buffers.
    fn clear(&mut self) {
        self.receivers.clear();
        self.emitter.clear();
        self.coef.clear();
        self.staged.clear();
        self.dirty.clear();
        self.cand_count.clear();
        self.cands.clear();
        self.kept.clear();
    }
}

/// Emptied [`LinkChunk`]s for reuse, by the key of the part of the traversal that filled
/// them (so that each gets back a buffer of about its size); a clone starts empty.
#[derive(Debug, Default)]
pub(crate) struct ChunkPool(std::sync::Mutex<std::collections::HashMap<u32, LinkChunk>>);

impl Clone for ChunkPool {
    fn clone(&self) -> Self {
        ChunkPool::default()
    }
}

impl ChunkPool {
    /// Key of the chunk that holds the subtree of cluster `r`.
    pub fn subtree(r: usize) -> u32 {
        r as u32
    }

    /// Key of the chunk that continues after the parallel subtrees below cluster `r`.
    pub fn after(r: usize) -> u32 {
        r as u32 | 1 << 31
    }

    pub fn take(&self, key: u32) -> LinkChunk {
        let mut c = self.0.lock().ok().and_then(|mut m| m.remove(&key)).unwrap_or_default();
        c.key = key;
        c
    }

    pub fn put(&self, chunks: Vec<LinkChunk>) {
        if let Ok(mut m) = self.0.lock() {
            for mut c in chunks {
                c.clear();
                m.insert(c.key, c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::bssrdf::{Material, Profile};
    use crate::hierarchy::face_cluster;
    use crate::irradiance::{Light, face_irradiance};
    use crate::mesh::deform::{Deformer, bump, twist};
    use crate::solver::{HierarchicalSolver, Oracle};
    use glam::Vec3;
    use std::sync::Arc;

    /// A run of local bumps, each somewhere else, then a twist: after every update the stored
    /// links give exactly what a fresh link of the same shape gives, while the base is shared
    /// (local updates), rebuilt by copy (once most of it is dead) and taken over from the
    /// delta (everything moved), each at least once.
    #[test]
    fn updates_share_rebuild_and_take_over_the_base_and_stay_exact() {
        let mesh = crate::mesh::embedded::bunny();
        let h = face_cluster::build(&mesh);
        let ext = mesh.extent();
        let (lo, hi) = mesh.bounds();
        let d = Profile::for_model_scale(&Material::by_name("skimmilk").unwrap(), ext as f64, 0.05);
        let light =
            [Light::Point { position: hi + Vec3::splat(ext), intensity: Vec3::splat(4.0 * ext * ext) }];
        let mut inc = HierarchicalSolver::new(mesh.clone(), h.clone(), d.clone(), Oracle::default());
        inc.link();
        assert!(inc.links().unwrap().delta.emitter.is_empty(), "a fresh link is all base");
        let (mut shared, mut rebuilt, mut taken_over) = (0, 0, 0);
        let mut shape = mesh.clone();
        for k in 0..9 {
            shape = if k < 8 {
                let t = k as f32 / 8.0;
                let at = mesh.positions[(k * 997) % mesh.positions.len()];
                bump(at, 0.04 * ext, 0.01 * ext * (1.0 + t)).deformed(&shape)
            } else {
                twist(0.5 * (lo + hi), Vec3::Y, 0.5 / ext).deformed(&shape)
            };
            let before = inc.links().unwrap().base.clone();
            inc.update_incremental(&shape.positions, None);
            let l = inc.links().unwrap();
            let same_base = Arc::ptr_eq(&before, &l.base);
            match (same_base, l.delta.emitter.is_empty()) {
                (true, false) => shared += 1,
                (false, true) if l.base.emitter.len() == l.len() => {
                    // Either every run moved into the new base or the live runs were copied.
                    if k == 8 { taken_over += 1 } else { rebuilt += 1 }
                }
                other => panic!("update {k}: unexpected storage {other:?}"),
            }
            let e = face_irradiance(&shape, &light, &d.entry);
            let mut fresh = HierarchicalSolver::new(shape.clone(), h.clone(), d.clone(), Oracle::default());
            let want_links = fresh.link().links;
            let want = fresh.solve_render(&e).face_b;
            assert_eq!(l.len(), want_links, "update {k}");
            let got = inc.solve_render(&e).face_b;
            for (a, b) in want.iter().zip(&got) {
                assert!((*a - *b).abs().max_element() <= 1e-5 * a.max_element(), "update {k}: {a} vs {b}");
            }
        }
        assert!(
            shared > 0 && rebuilt > 0 && taken_over > 0,
            "{shared} shared, {rebuilt} rebuilt, {taken_over} taken over"
        );
    }
}
