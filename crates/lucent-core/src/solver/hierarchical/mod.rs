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
//! This module holds the solver and its public entry points. Its submodules hold the rest of
//! its `impl`: the receiver-driven refinement that every mode runs and the incremental relink
//! ([`link`]), a frame's pull, gather and push (render mode's over the stored links,
//! on-the-fly mode's during the traversal: [`gather`], [`gather_linear`], with the receiver
//! expansion of [`expansion`]), and the [`census`] of a solve's links.

use super::bound;
use super::link_set::{ChunkPool, LinkSet};
use super::local::Locality;
use super::oracle::Oracle;
use crate::Rgb;
use crate::bssrdf::Profile;
use crate::formfactor::FormFactorOptions;
use crate::hierarchy::Hierarchy;
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::Vec3A;
use link::Reuse;
use std::sync::Arc;
use std::sync::atomic::AtomicI64;
use std::time::Instant;

pub mod census;
mod expansion;
mod gather;
mod gather_linear;
mod link;
mod refit;

pub use refit::{RefitOptions, RefitStats};

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
    /// Near links to the receiver's own face or a face beside it evaluated in polar
    /// coordinates about the receiver instead (the tabulated profile; see `near_face`).
    pub polar_faces: usize,
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
    /// Faces whose `B` is the local limit `R_d_total E` (transport reaches less far than the
    /// face's own extent around its midpoint), without links to other faces.
    pub local_faces: usize,
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
    pub profile: Profile,
    /// The refinement oracle.
    pub oracle: Oracle,
    /// Options of the semi-analytic form factor.
    pub ff_opts: FormFactorOptions,
    /// Integrate near links by uniform point sampling (about one sample per squared mean free
    /// path, after Jensen & Buhler 2002) instead of the semi-analytic form factor: the
    /// comparison of Mertens table 5. Default false.
    pub near_point_sampling: bool,
    /// Record each receiver's candidate emitters while linking: what an incremental update
    /// reuses, about 5.5 bytes per link (a quarter of a link set). Off for render-only use
    /// (the frame session turns it off in render mode); an incremental update over links made
    /// without them turns it back on and links from scratch first. Default true.
    pub keep_candidates: bool,
    /// Whether the stored links were made with their candidates.
    pub(super) links_have_candidates: bool,
    /// Where a front end watches long refinements (leaves of finished receiver subtrees out of
    /// all leaves); `None` (default): not counted.
    pub progress: Option<Arc<Progress>>,
    /// The finite-body gain per face ([`super::finite_body`]), applied with the energy bound
    /// where the profile bounds energy; `None` (default): none. Set through
    /// [`HierarchicalSolver::set_face_gain`].
    pub(super) face_gain: Option<Arc<Vec<Rgb>>>,
    /// Per face, what it adds to `B` after the solve under uniform irradiance 1, which the
    /// energy bound leaves room for ([`HierarchicalSolver::set_face_term`]); `None` (default):
    /// nothing.
    pub(super) face_term: Option<Arc<Vec<Rgb>>>,
    pub(super) links: Option<LinkSet>,
    /// The link set an incremental update replaced, kept for its buffers.
    pub(super) spare: Option<LinkSet>,
    /// Chunk buffers of the last relink, for the same reason.
    pub(super) chunk_pool: ChunkPool,
    /// Render mode's per-cluster irradiance and gathered `B`, kept between frames for the
    /// same reason (each is 4 MB at 131K triangles).
    pub(super) frame: [Vec<Vec3A>; 2],
    /// What a frame's pull and gather read of the hierarchy, packed flat; made on first use,
    /// dropped wherever the hierarchy is refitted.
    pub(super) frame_geom: std::sync::OnceLock<gather::FrameGeom>,
    /// Render mode's energy bound per face (see [`super::bound`]), made from the stored links
    /// under uniform irradiance, until the links change.
    pub(super) bound: Option<Vec<Rgb>>,
    /// The profile's reach (see [`super::local`]).
    pub(super) locality: Locality,
    /// Per cluster, whether all its faces take the local limit (made with the geometry).
    pub(super) local: Vec<bool>,
}

impl HierarchicalSolver {
    /// A solver for `mesh` (whose topology `hierarchy` was built on) with `dipole` and
    /// `oracle`, using the default form factor options. The hierarchy is refitted to `mesh`'s
    /// positions. No links are stored yet.
    pub fn new(mesh: Mesh, mut hierarchy: Hierarchy, profile: Profile, oracle: Oracle) -> Self {
        assert_eq!(hierarchy.leaf_count(), mesh.triangles.len());
        hierarchy.refit(&mesh);
        let locality = Locality::of(&profile);
        let local = locality.local_clusters(&hierarchy, &mesh);
        HierarchicalSolver {
            mesh,
            hierarchy,
            profile,
            oracle,
            ff_opts: FormFactorOptions::default(),
            near_point_sampling: false,
            keep_candidates: true,
            links_have_candidates: false,
            progress: None,
            links: None,
            spare: None,
            chunk_pool: ChunkPool::default(),
            frame: Default::default(),
            frame_geom: Default::default(),
            bound: None,
            face_gain: None,
            face_term: None,
            locality,
            local,
        }
    }

    /// Whether receivers take links with a steepness ([`Oracle::linear_receivers`]): the
    /// transport oracle with a distance-form profile.
    pub(super) fn linear_receivers(&self) -> bool {
        self.oracle.linear_receivers
            && self.oracle.mode == super::oracle::OracleMode::Transport
            && !self.profile.kind.uses_normals()
    }

    /// Whether linear receivers also carry their links' curvature
    /// ([`Oracle::curved_receivers`]).
    pub(super) fn curved_receivers(&self) -> bool {
        self.linear_receivers() && self.oracle.curved_receivers
    }

    /// Per face of the mesh, `Some(k)` where it takes the local limit (`super::local`): its
    /// `B` is `k E` of its own irradiance `E`, `k` its own `∫ R dA` (`R_d_total`) times the
    /// energy bound and finite-body gain the solve applies (the factor of its one link);
    /// `None` where light crosses it from elsewhere.
    pub fn local_factors(&self) -> Vec<Option<Rgb>> {
        let mut out = vec![None; self.mesh.triangles.len()];
        let r_total = Rgb::from_array(self.locality.r_total);
        for (i, n) in self.hierarchy.nodes.iter().enumerate() {
            if n.is_leaf() && self.local[i] {
                let f = self.hierarchy.leaf_faces[n.leaf_start as usize] as usize;
                let bound =
                    if self.profile.bounds_energy() { self.bound_factor(f, r_total) } else { Rgb::ONE };
                out[f] = Some(r_total * bound);
            }
        }
        out
    }

    /// The stored links, if [`HierarchicalSolver::link`] has run.
    pub fn links(&self) -> Option<&LinkSet> {
        self.links.as_ref()
    }

    /// Refines from the root's self-link and stores the links (render and incremental modes).
    pub fn link(&mut self) -> SolveStats {
        let t0 = Instant::now();
        self.start_progress("link");
        // A link from scratch reads nothing of the old set: free it before the new one grows.
        self.links = None;
        let mut stats = self.relink(None);
        stats.link_ms = ms(t0.elapsed());
        stats.total_ms = stats.link_ms;
        stats
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
        if self.links.is_none() || !self.links_have_candidates {
            self.keep_candidates = true;
            self.mesh.positions.copy_from_slice(positions);
            self.hierarchy.refit(&self.mesh);
            self.frame_geom = Default::default();
            self.local = self.locality.local_clusters(&self.hierarchy, &self.mesh);
            return self.link();
        }
        let moved = refit::moved_clusters(self, &self.mesh.positions, positions);
        let any_moved = moved.is_some();
        let old = self.links.take().expect("links stored");
        let h = &self.hierarchy;
        let changed = moved.unwrap_or_else(|| vec![false; h.len()]);
        let mut stale = vec![false; h.len()];
        if old.has_dirty() {
            for i in (0..h.len()).rev() {
                stale[i] |= old.is_stale(i);
                let p = h.nodes[i].parent;
                if p != crate::hierarchy::NO_NODE {
                    stale[p as usize] |= stale[i];
                }
            }
        }
        if any_moved {
            self.mesh.positions.copy_from_slice(positions);
            self.hierarchy.refit_changed(&self.mesh, &changed);
            if let Some(g) = self.frame_geom.get_mut() {
                g.refit(&self.hierarchy, &changed);
            }
            self.local = self.locality.local_clusters(&self.hierarchy, &self.mesh);
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
        self.start_progress("incremental");
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
        self.frame_geom = Default::default();
        self.local = self.locality.local_clusters(&self.hierarchy, &self.mesh);
        self.links = None;
        self.bound = None;
    }

    /// Sets the finite-body gain per face (`None`: none); the stored bound is remade.
    pub fn set_face_gain(&mut self, gain: Option<Arc<Vec<Rgb>>>) {
        if self.face_gain != gain {
            self.face_gain = gain;
            self.bound = None;
        }
    }

    /// The energy-bound factor (times the finite-body gain, if any) of face `f` whose `B` under
    /// uniform irradiance 1 is `uniform`.
    #[inline]
    pub(super) fn bound_factor(&self, f: usize, uniform: Rgb) -> Rgb {
        match (&self.face_gain, &self.face_term) {
            (Some(g), Some(t)) => bound::bound_with_gain_and_term(uniform, g[f], t[f]),
            (Some(g), None) => bound::bound_with_gain(uniform, g[f]),
            (None, _) => bound::bound(uniform),
        }
    }

    /// Sets what each face adds to its `B` after the solve under uniform irradiance 1 (the
    /// slab transmission, [`super::transmission`]; `None`: nothing), which the energy bound
    /// leaves room for; the stored bound is remade.
    pub fn set_face_term(&mut self, term: Option<Arc<Vec<Rgb>>>) {
        if self.face_term != term {
            self.face_term = term;
            self.bound = None;
        }
    }

    /// Changes the material: every stored link's coefficient becomes stale and is recomputed by
    /// the next [`HierarchicalSolver::update_incremental`] (the oracle is geometric, so the
    /// links themselves stay).
    pub fn set_profile(&mut self, profile: Profile) {
        self.locality = Locality::of(&profile);
        self.local = self.locality.local_clusters(&self.hierarchy, &self.mesh);
        self.profile = profile;
        self.spare = None;
        self.bound = None;
        if let Some(l) = self.links.as_mut() {
            l.mark_all_dirty();
        }
    }
}

impl HierarchicalSolver {
    /// Starts `stage` on the progress counter, if any, over all leaves.
    pub(super) fn start_progress(&self, stage: &'static str) {
        if let Some(p) = &self.progress {
            p.start(stage, self.hierarchy.leaf_count());
        }
    }

    /// Counts child `c`'s subtree (of parent `r`, or the root when `r` is `None`) as finished
    /// if it is one of the largest with at most [`TICK_LEAVES`] leaves: called by the
    /// refinements after each child and after the root, so every leaf is counted exactly once,
    /// one relaxed atomic add per such subtree (never per link).
    #[inline]
    pub(super) fn tick_progress(&self, r: Option<usize>, c: usize) {
        if let Some(p) = &self.progress {
            let n = self.hierarchy.nodes[c].leaf_count();
            let above = r.map_or(u32::MAX, |r| self.hierarchy.nodes[r].leaf_count());
            if n <= TICK_LEAVES && above > TICK_LEAVES {
                p.add(n as usize);
            }
        }
    }
}

/// Progress is counted per receiver subtree of at most this many leaves.
const TICK_LEAVES: u32 = 256;

/// Milliseconds in `d`.
#[inline]
pub(super) fn ms(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
