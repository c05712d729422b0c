//! The refinement oracle (Mertens et al. 2003, §5.2): Jensen & Buhler's maximum-solid-angle
//! criteria at the receiver (`ε1`) and the emitter (`ε2`), the `A'/A` curvature test for near
//! clusters (§5.1.1), and the choice between a one-point estimate and the semi-analytic form
//! factor (§4) for each accepted link, which `solver::evaluate` then evaluates. Two modes
//! ([`OracleMode`]): the paper's solid angles, and one-point transport estimates (the default).

use super::census::Cause;
use super::point_sample::point_samples_from;
pub use super::point_sample::{ProfileF32, ReceiverSources};
use crate::bssrdf::ProfileKind;
use crate::hierarchy::{ClusterGeom, Hierarchy, Node};
use glam::Vec3;

/// Solid angle standing in for "infinitely close": the point lies inside the cluster's
/// bounding sphere, so no finite distance describes it.
const INSIDE: f32 = f32::INFINITY;

/// In [`OracleMode::Transport`], emitters seen under a larger solid angle (sr) are always
/// near: the one-point estimates the test compares are meaningless that close.
const MAX_FAR_SOLID_ANGLE: f32 = 1.0;

/// In [`OracleMode::Transport`], a dipole source closer to an emitter's midpoint than this
/// many emitter radii makes the emitter near: `R_d` is singular at the sources, and a real
/// source (depth `z_r` below the receiver) can lie right under an emitter on the far side of a
/// thin part, where one-point estimates miss a spike that dominates `B` (translucent
/// materials at small scales).
const SOURCE_MARGIN: f32 = 2.0;

/// Which refinement criteria the oracle applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OracleMode {
    /// Mertens §5.2 as published: Jensen & Buhler's solid angles (`ε1` receiver deviation,
    /// `ε2` emitter size), plus the `A'/A` test for near clusters and the receiver normal test
    /// (`eps_normal`).
    SolidAngle,
    /// Magnitude-aware variant (the "alternatives which take the magnitude of the form factor
    /// into account" of §5.2 and §7.2): the same two questions, answered with one-point
    /// transport estimates `A_E R_d` relative to the material's total diffuse reflectance
    /// `R_d_total`. Receiver: the largest change of the estimate between `R`'s midpoint and its
    /// children's midpoints (each with its own normal) must stay below `eps1`. Emitter: the
    /// estimate from `E`'s midpoint and the sum of those from its children must agree within
    /// `eps2`. Negligible interactions stay coarse however close, and accuracy is spent where
    /// the transport is large (the default).
    Transport,
}

/// Thresholds of the refinement oracle. Solid angles are the projected-area estimate
/// `ω = A_E / d²` (steradians) of Jensen & Buhler 2002, with `d` the distance to the emitter's
/// midpoint; a point inside the emitter's bounding sphere sees `ω = ∞`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oracle {
    /// Which criteria to apply (default [`OracleMode::Transport`]).
    pub mode: OracleMode,
    /// `ε1` (sr): a receiver cluster `R` is opened when the solid angle of the emitter, seen from
    /// `R`'s children's midpoints, deviates from the one seen from `R`'s midpoint by more than
    /// this. Smaller is more accurate and gives more links. In [`OracleMode::Transport`]:
    /// the largest relative change (unitless) of the one-point transport estimate between
    /// `R`'s midpoint and its children's. Default 0.3 (transport; the solid-angle mode of the
    /// paper used 0.02).
    pub eps1: f32,
    /// `ε2` (sr): an emitter seen under a solid angle at most this large from the receiver's
    /// midpoint is linked with a single point sample `A_E R_d` ("far"); larger ones are "near"
    /// (Jensen & Buhler would take more than one sample) and are either integrated with the
    /// semi-analytic form factor (leaves, flat clusters) or opened. In
    /// [`OracleMode::Transport`]: the largest relative disagreement (unitless) between `E`'s
    /// one-point estimate and its children's (in total and in their spread over the children).
    /// Default 0.1 (transport; the solid-angle mode of the paper used 0.05).
    pub eps2: f32,
    /// Largest solid angle (sr) under which a *near* inner cluster may still be integrated
    /// with the form factor over its projected boundary polygon instead of being opened, if it
    /// is flat enough (`min_flatness`). Setting it to `eps2` or below opens every near cluster
    /// (only faces are integrated with the form factor). Default 0 (off).
    pub eps_near_cluster: f32,
    /// Least curvature measure `A'/A` (0..1) of a near cluster integrated with the form factor
    /// (§5.1.1); more curved near clusters are opened. Default 0.98.
    pub min_flatness: f32,
    /// Receiver normal criterion (unitless): the dipole sits at the receiver along its normal
    /// (§4), so a curved receiver cluster, gathering with one averaged normal, errs by about
    /// `δ_R z_v (σ_tr + 3/d)` relative, with `δ_R = sqrt(2 (1 - A'/A))` its normal spread and
    /// `d` the distance to the emitter. A receiver is opened when this exceeds `eps_normal`.
    /// Not in the paper (its oracle is purely geometric); it matters for very translucent
    /// materials whose dipole is as large as the object. Default 0.05.
    pub eps_normal: f32,
    /// [`OracleMode::Transport`] only: absolute error floor per link, relative to the
    /// material's largest `R_d_total` (unitless). Interactions whose estimated error is below
    /// this are accepted whatever their relative error, so negligible far transport stays
    /// coarse. Default 1e-3.
    pub eps_abs: f32,
    /// [`OracleMode::Transport`] only: share-weighted error allowance per link (unitless, 0
    /// and up). A link carrying the share `s = F / R_d_total` of its receiver's total may also
    /// err by `eps_share sqrt(s) R_d_total`: errors of many links of unrelated sign add in
    /// quadrature, and `Σ (eps_share sqrt(s_l))² = eps_share² Σ s_l ≈ eps_share²`, so the
    /// receiver's total still errs by about `eps_share` relative, while links with a small
    /// share of it stay coarser (hierarchical radiosity's "BF" refinement, with the
    /// receiver's total standing in for `B`). Default 0 (off).
    pub eps_share: f32,
    /// [`OracleMode::Transport`] only: the relative variation of irradiance over an emitter
    /// cluster that the emitter test guards against (0..1). A point-sample link spreads the
    /// emitter's average irradiance, which errs by the transport's deviation from area
    /// weighting over `E`'s children times the irradiance's deviation from its average; 1
    /// bounds the latter by the irradiance itself (a shadow edge across every emitter).
    /// Default 1.
    pub irradiance_contrast: f32,
    /// [`OracleMode::Transport`] with a distance-form profile only: a receiver cluster's
    /// point-sample links carry the transport's first-order change across the receiver (see
    /// `Samples::slope`), and the push hands each child the gathered `B` *plus* its gradient
    /// times the child's offset, instead of one value for the whole cluster. The receiver
    /// test then bounds the second-order remainder, not the first-order change, so receivers
    /// stay whole up to about a third of their distance to the emitter, as emitters do, not
    /// a fifteenth (the cause of most links on dense scanned meshes). Default true.
    pub linear_receivers: bool,
    /// With [`Oracle::linear_receivers`]: the links also carry the transport's second-order
    /// change across the receiver (its curvature, from the link's steepness and the profile's
    /// falloff, see `FALLOFF_POWER`), and the push hands each child the receiver's
    /// quadratic moved to its midpoint. The receiver test then bounds the third-order
    /// remainder `(k r)³ / 6`, so receivers stay whole up to about two fifths of their
    /// distance to the emitter, not a fifth, and the emitter need not clear each leaf's poles
    /// (no leaf takes its own estimate). Distance-form profiles only. Default true.
    pub curved_receivers: bool,
}

impl Oracle {
    /// The default oracle for profile `kind`: [`Oracle::default`] for Mertens' dipole; for the
    /// distance-form profiles the thresholds that keep them within 1% of the exact solve on
    /// the bunny at 1 cm (measured with
    /// `cargo test --release -p lucent-core --test solver_hierarchical -- --nocapture`):
    /// `dipole` ε1 = 0.1, ε2 = 0.03, ε_abs = 3e-4 (worst 0.71%, ketchup at 1 cm); `pbd`, the
    /// default, 0.3, 0.1, 5e-4 (worst 0.72%, skim milk at 1 cm, at 53-100 links per face in
    /// the six cases at 1 and 10 cm; ε_abs 6e-4 took the bunny's sampled median error in
    /// `lucent bench solver --real` to 1.08%, through its dimmest faces, which only far
    /// transport reaches). Curved receivers ([`Oracle::curved_receivers`]) and the far faces'
    /// midpoint-rule gain (`midpoint_rule_gain`) are what leave that room: with linear
    /// receivers `pbd` needed 0.2, 0.05, 6e-4 for 0.71% at 97-128 links per face, and without
    /// the gain it erred by 0.87% at 117-166. Neither has room for `eps_share` or
    /// `irradiance_contrast`.
    pub fn for_profile(kind: ProfileKind) -> Oracle {
        match kind.oracle_thresholds() {
            None => Oracle::default(),
            Some((eps1, eps2, eps_abs)) => Oracle { eps1, eps2, eps_abs, ..Oracle::default() },
        }
    }
}

impl Default for Oracle {
    fn default() -> Self {
        Oracle {
            mode: OracleMode::Transport,
            eps1: 0.3,
            eps2: 0.1,
            eps_near_cluster: 0.0,
            min_flatness: 0.98,
            eps_normal: 0.05,
            eps_abs: 1e-3,
            eps_share: 0.0,
            irradiance_contrast: 1.0,
            linear_receivers: true,
            curved_receivers: true,
        }
    }
}

/// How a link's transport coefficient is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkKind {
    /// One sample, `A_E R_d(m_E)` (far emitters).
    PointSample,
    /// The semi-analytic form factor over the emitter's (projected) polygon (near emitters);
    /// where `R_d` is smooth over an emitter face, its seven-point cubature short cut (in
    /// `f32`, see [`crate::formfactor::cubature`]), which is more accurate there and cheaper.
    FormFactor,
}

/// What the oracle decides for a candidate link from emitter `E` to receiver `R`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decision {
    /// Accept the link, evaluated as given.
    Link(LinkKind),
    /// Move the link down at the receiver (to each child of `R`).
    SplitReceiver,
    /// Move the link down at the emitter (from each child of `E`).
    SplitEmitter,
}

/// One-point estimates that [`Oracle::decide`] takes and leaves for its caller, so none is
/// made twice.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Samples {
    /// In: the estimate `A_E R_d` from the emitter to the receiver's midpoint, if known (left
    /// by the decision that opened the emitter's parent, or by the receiver test at the
    /// receiver's parent). Consumed.
    pub f_mid: Option<[f32; 3]>,
    /// Out, with a point-sample link: its coefficient's estimate (`f_mid` for a face, a
    /// better one for a cluster).
    pub estimate: Option<[f32; 3]>,
    /// Out, with a point-sample link at an inner receiver: the factor from the estimate at the
    /// receiver's midpoint to its average over the receiver.
    pub recv_scale: Option<[f32; 3]>,
    /// Out, with [`Decision::SplitEmitter`]: the estimates from the emitter's children (in
    /// order), when the emitter test made them.
    pub children: Option<[[f32; 3]; 4]>,
    /// Out, with [`Decision::SplitReceiver`]: the estimates from the emitter to the receiver's
    /// children's midpoints (in order), when the receiver test made them.
    pub at_children: Option<[[f32; 3]; 4]>,
    /// Out, with a link at an inner receiver that passed the linear receiver test
    /// ([`Oracle::linear_receivers`]): the link's *steepness* `s` (unitless, >= 0; 0 when
    /// the receiver is taken as one value). Within the receiver the coefficient is
    /// `F(x) = F (1 - s (x - m_R).D / |D|^2)`, with `D = m_R - m_E` the line from the
    /// emitter's midpoint to the receiver's: the distance-form profile's gradient points
    /// along it, and `s = -dln F/dln d` is about `σ_tr d + 3` for a dipole tail.
    pub slope: f32,
    /// Out: why the receiver test and the emitter test decided as they did (for
    /// [`super::census`]; [`Cause::None`] where a test did not run).
    pub why: [Cause; 2],
}

/// Solid angle `A_E / d²` of cluster `e` seen from `x`, or infinity inside its bounding sphere.
#[inline]
pub fn solid_angle(x: Vec3, e: &ClusterGeom) -> f32 {
    let d2 = (x - e.midpoint).length_squared();
    if d2 <= e.radius * e.radius { INSIDE } else { e.area / d2 }
}

/// What the oracle needs to know about the current receiver, computed once per receiver.
pub(crate) struct ReceiverView {
    /// Dipole sources at the receiver's midpoint.
    pub src: ReceiverSources,
    /// Dipole sources at each child's midpoint (first `child_count`).
    pub child_src: [ReceiverSources; 4],
    /// `1 / R_d_total` per channel.
    pub inv_rtot: [f32; 3],
    /// Bound on how far the receiver's leaves' normals stray from its average normal (0 for a
    /// face, up to 2; 0 for the distance form, whose poles do not move with the normal): the
    /// leaves' dipole sources lie within `radius + spread z` of the receiver's own sources.
    pub spread: f32,
}

impl ReceiverView {
    pub fn new(h: &Hierarchy, d: &ProfileF32, inv_rtot: [f32; 3], r: usize) -> Self {
        let g = &h.geom[r];
        let src = ReceiverSources::new(d, g.midpoint, g.normal);
        let mut child_src = [src; 4];
        for (k, &c) in h.nodes[r].children().iter().enumerate() {
            let cg = &h.geom[c as usize];
            child_src[k] = ReceiverSources::new(d, cg.midpoint, cg.normal);
        }
        // `sqrt(2 (1 - A'/A))` is an RMS normal deviation; twice it stands in for the maximum.
        // The distance form's poles sit at the receiver point whatever its normal, so its
        // leaves' poles lie within the radius of the receiver's (`clear_of`'s `base`): a margin
        // of `spread z` (`z_v` a few faces across on a scanned mesh) kept every noisy cluster
        // from linking its neighbourhood, at every resolution.
        let spread = if h.nodes[r].is_leaf() || d.normal_weight == 0.0 {
            0.0
        } else {
            (2.0 * (2.0 * (1.0 - g.flatness())).sqrt()).min(2.0)
        };
        ReceiverView { src, child_src, inv_rtot, spread }
    }
}

/// A candidate pair `E -> R` as both oracle modes first see it.
struct Pair<'h> {
    /// Receiver `R`'s node and geometry.
    rn: &'h Node,
    rg: &'h ClusterGeom,
    /// Emitter `E`'s cluster index, node and geometry.
    e: usize,
    en: &'h Node,
    eg: &'h ClusterGeom,
    /// Solid angle of `E` from `R`'s midpoint ([`INSIDE`] within `E`'s bounding sphere).
    w: f32,
    /// Whether the two bounding spheres are disjoint.
    separated: bool,
}

impl<'h> Pair<'h> {
    #[inline]
    fn new(h: &'h Hierarchy, r: usize, e: usize) -> Self {
        let rg = &h.geom[r];
        let eg = &h.geom[e];
        let w = solid_angle(rg.midpoint, eg);
        let separated = w != INSIDE
            && (rg.midpoint - eg.midpoint).length_squared()
                > (rg.radius + eg.radius) * (rg.radius + eg.radius);
        Pair { rn: &h.nodes[r], rg, e, en: &h.nodes[e], eg, w, separated }
    }

    /// Whether `R` must be opened whatever the mode: it has no usable normal, or it lies
    /// inside `E`'s bounding sphere.
    #[inline]
    fn receiver_degenerate(&self) -> bool {
        self.rg.normal == Vec3::ZERO || self.w == INSIDE
    }

    /// Whether a failed receiver test should open the emitter instead: it is an inner
    /// cluster larger than the receiver (and would be opened anyway).
    #[inline]
    fn emitter_first(&self) -> bool {
        !self.en.is_leaf() && self.eg.area > self.rg.area
    }
}

impl Samples {
    /// Takes the known `f_mid` and clears the outputs of the previous decision.
    #[inline]
    fn start(&mut self) -> Option<[f32; 3]> {
        let known = self.f_mid.take();
        self.estimate = None;
        self.recv_scale = None;
        self.children = None;
        self.at_children = None;
        self.slope = 0.0;
        self.why = [Cause::None; 2];
        known
    }
}

impl Oracle {
    /// Whether the error estimate `err` of transport `f` is within
    /// `eps_rel f + eps_share sqrt(f R_tot) + eps_abs R_tot` in every channel.
    #[inline]
    fn within(&self, err: [f32; 3], f: [f32; 3], eps_rel: f32, inv_rtot: [f32; 3]) -> bool {
        (0..3).all(|c| {
            let s = f[c] * inv_rtot[c];
            // Off by default: no square root per decision then.
            let share = if self.eps_share > 0.0 { self.eps_share * s.max(0.0).sqrt() } else { 0.0 };
            err[c] * inv_rtot[c] <= eps_rel * s + share + self.eps_abs
        })
    }

    /// The decision for receiver `r` and emitter `e` (cluster indices of `h`); `view` is
    /// `r`'s [`ReceiverView`].
    ///
    /// Order (§5.2): first the receiver test (`ε1`), then, before connecting, the emitter test
    /// (`ε2`). When the receiver test fails but the emitter is near and larger, the emitter is
    /// opened first (it would be anyway), which keeps links at the higher receiver level.
    #[inline]
    pub(crate) fn decide(
        &self,
        h: &Hierarchy,
        d: &ProfileF32,
        view: &ReceiverView,
        r: usize,
        e: usize,
        samples: &mut Samples,
    ) -> Decision {
        let known_f_mid = samples.start();
        if r == e && h.nodes[r].is_leaf() {
            return Decision::Link(LinkKind::FormFactor);
        }
        let pair = Pair::new(h, r, e);
        match self.mode {
            OracleMode::SolidAngle => self.decide_solid_angle(h, d, &pair),
            OracleMode::Transport => self.decide_transport(h, d, view, &pair, known_f_mid, samples),
        }
    }

    /// The tail both modes share once the emitter is near: a face is integrated with the form
    /// factor, so is a flat inner cluster seen under at most `eps_near_cluster`; any other
    /// cluster is opened.
    #[inline]
    fn decide_near(&self, h: &Hierarchy, p: &Pair) -> Decision {
        if p.en.is_leaf() {
            return Decision::Link(LinkKind::FormFactor);
        }
        if p.w <= self.eps_near_cluster
            && p.eg.flatness() >= self.min_flatness
            && p.eg.polygon_area > 0.0
            && !h.polygon(p.e).is_empty()
        {
            return Decision::Link(LinkKind::FormFactor);
        }
        Decision::SplitEmitter
    }

    /// [`OracleMode::SolidAngle`]: Jensen & Buhler's solid angles as in Mertens §5.2.
    #[inline]
    fn decide_solid_angle(&self, h: &Hierarchy, d: &ProfileF32, p: &Pair) -> Decision {
        let far = p.w <= self.eps2;
        if !p.rn.is_leaf() && (p.receiver_degenerate() || self.solid_angle_opens_receiver(h, d, p)) {
            if p.emitter_first() && !far {
                return Decision::SplitEmitter;
            }
            return Decision::SplitReceiver;
        }
        if far {
            return Decision::Link(LinkKind::PointSample);
        }
        self.decide_near(h, p)
    }

    /// The receiver test of [`OracleMode::SolidAngle`] at an inner receiver: the normal
    /// criterion (`eps_normal`) for a curved receiver, then `ε1` on the solid angles from the
    /// children's midpoints.
    #[inline]
    fn solid_angle_opens_receiver(&self, h: &Hierarchy, d: &ProfileF32, p: &Pair) -> bool {
        let (rg, eg) = (p.rg, p.eg);
        if rg.projected_area < rg.area {
            let spread = (2.0 * (1.0 - rg.flatness())).sqrt();
            let inv_d = 1.0 / (rg.midpoint - eg.midpoint).length();
            let mut sens = 0.0f32;
            for c in 0..3 {
                sens = sens.max(d.normal_weight * d.z_v[c] * (d.sigma_tr[c] + 3.0 * inv_d));
            }
            if spread * sens > self.eps_normal {
                return true;
            }
        }
        p.rn.children().iter().any(|&c| {
            let wc = solid_angle(h.geom[c as usize].midpoint, eg);
            wc == INSIDE || (wc - p.w).abs() > self.eps1
        })
    }

    /// [`OracleMode::Transport`]: the same two tests on one-point transport estimates.
    #[inline]
    fn decide_transport(
        &self,
        h: &Hierarchy,
        d: &ProfileF32,
        view: &ReceiverView,
        p: &Pair,
        known_f_mid: Option<[f32; 3]>,
        samples: &mut Samples,
    ) -> Decision {
        // Both transport tests stop at `!separated` before reading it.
        let f_mid = if p.separated {
            known_f_mid.unwrap_or_else(|| view.src.point_sample(d, p.eg.midpoint, p.eg.area))
        } else {
            [0.0; 3]
        };
        if p.receiver_degenerate() && !p.rn.is_leaf() {
            samples.why[0] = Cause::Degenerate;
        }
        if !p.rn.is_leaf()
            && (p.receiver_degenerate() || self.transport_opens_receiver(h, d, view, p, f_mid, samples))
        {
            if p.emitter_first() && !self.transport_far(h, d, view, p, f_mid, samples) {
                samples.at_children = None;
                return Decision::SplitEmitter;
            }
            samples.estimate = None;
            samples.children = None;
            return Decision::SplitReceiver;
        }
        if self.transport_far(h, d, view, p, f_mid, samples) {
            return Decision::Link(LinkKind::PointSample);
        }
        self.decide_near(h, p)
    }

    /// The receiver test of [`OracleMode::Transport`] at an inner receiver whose estimate from
    /// the emitter at its midpoint is `f_mid`. Leaves the estimates at the children in
    /// `samples.at_children` when it makes them, and, when the receiver stays whole (and is
    /// not curved), the factor to its average in `samples.recv_scale`.
    #[inline]
    fn transport_opens_receiver(
        &self,
        h: &Hierarchy,
        d: &ProfileF32,
        view: &ReceiverView,
        p: &Pair,
        f_mid: [f32; 3],
        samples: &mut Samples,
    ) -> bool {
        let (rn, rg, eg) = (p.rn, p.rg, p.eg);
        if !p.separated {
            samples.why[0] = Cause::NotSeparated;
            return true;
        }
        // The emitter's estimates at the children's midpoints: made in one batch whether the
        // receiver splits (the children would make each alone) or stays whole (the test below).
        let at_children = || point_samples_from(&view.child_src, d, eg.midpoint, eg.area);
        let linear = self.linear_receivers && d.normal_weight == 0.0;
        let curved = linear && self.curved_receivers;
        // Each leaf's poles lie within `r_R` of the receiver's (plus the normals' spread), so
        // the emitter must clear them all, unless the receiver is curved: then no leaf takes
        // its own estimate from the emitter, the receiver's expansion stands in for all of
        // them, and the size test below bounds what it leaves out. Clearing the leaves took 118
        // links per triangle on the 48K dragon at 0.67% median error, against 90 at 0.94%
        // without; with the thresholds retuned, 88 at 0.80% (ε_abs 4e-4) or 83 at 0.92%.
        let base = if curved { 0.0 } else { rg.radius };
        if !view.src.clear_of(d, eg.midpoint, SOURCE_MARGIN * eg.radius, base, view.spread) {
            samples.why[0] = Cause::Poles;
            samples.at_children = Some(at_children());
            return true;
        }
        // The distance-form profiles do not depend on the receiver's normal, so nothing above
        // splits a receiver for its size: estimate the variation of `R` over the receiver from
        // its radius, as the emitter test does: its first-order change over half the radius
        // (the children's midpoints), or with a linear receiver the second-order remainder
        // `(k r)² / 2` at its edge (at the children's midpoints, a quarter of that let the
        // bunny at 1 cm err by 2%: the children's estimates cannot see the leaves' curvature).
        if d.normal_weight == 0.0 {
            let dist = view.src.nearest(d, eg.midpoint);
            let err: [f32; 3] = std::array::from_fn(|c| {
                let x = (d.sigma_tr[c] + 3.0 / dist[c]) * rg.radius;
                let order = if curved {
                    x * x * x / 6.0
                } else if linear {
                    0.5 * x * x
                } else {
                    0.5 * x
                };
                order * f_mid[c]
            });
            if !self.within(err, f_mid, self.eps1, view.inv_rtot) {
                samples.why[0] = Cause::Size;
                samples.at_children = Some(at_children());
                return true;
            }
        }
        let f = f_mid;
        let mut avg = [0.0f32; 3];
        let inv_a = if rg.area > 0.0 { 1.0 / rg.area } else { 0.0 };
        let f_children = at_children();
        samples.at_children = Some(f_children);
        // With a linear receiver, the children are measured against the line through the
        // midpoint's estimate along `D` (its steepness fitted to theirs), not against the
        // midpoint's estimate itself.
        let (slope, line) =
            if linear { linear_slope(h, d, rn, rg, eg, f, &f_children, curved) } else { (0.0, [1.0; 4]) };
        for (k, &c) in rn.children().iter().enumerate() {
            let cg = &h.geom[c as usize];
            if solid_angle(cg.midpoint, eg) == INSIDE {
                samples.why[0] = Cause::Degenerate;
                return true;
            }
            let fc = f_children[k];
            let diff = std::array::from_fn(|c| (f[c] * line[k] - fc[c]).abs());
            if !self.within(diff, f, self.eps1, view.inv_rtot) {
                samples.why[0] = Cause::Variation;
                return true;
            }
            for c in 0..3 {
                avg[c] += fc[c] * cg.area * inv_a;
            }
        }
        // R's value goes to all its leaves, so it should be the *average* of F over R, which
        // exceeds F at R's midpoint (R_d is convex): as at the emitter, extrapolate from the
        // children's average.
        samples.why[0] = Cause::Pass;
        samples.slope = slope;
        if curved {
            // The quadratic already moves the midpoint's estimate to each leaf.
            return false;
        }
        let k = rn.child_count as f32;
        samples.recv_scale = Some(std::array::from_fn(|c| {
            if f[c] > 0.0 { ((avg[c] + (avg[c] - f[c]) / (k - 1.0)) / f[c]).max(0.0) } else { 1.0 }
        }));
        false
    }

    /// The emitter test of [`OracleMode::Transport`]: whether one point sample is enough for
    /// `E` (far), given the estimate `f_mid` from its midpoint. Bounding spheres must be
    /// disjoint: one-point estimates at midpoints say nothing about the near field where two
    /// adjacent clusters touch. Evaluated only when needed (it costs up to five point samples).
    #[inline]
    fn transport_far(
        &self,
        h: &Hierarchy,
        d: &ProfileF32,
        view: &ReceiverView,
        p: &Pair,
        f_mid: [f32; 3],
        samples: &mut Samples,
    ) -> bool {
        let (far, why) = if !p.separated {
            (false, Cause::NotSeparated)
        } else if p.w > MAX_FAR_SOLID_ANGLE {
            (false, Cause::WideAngle)
        } else if !view.src.clear_of(d, p.eg.midpoint, SOURCE_MARGIN * p.eg.radius, 0.0, 0.0) {
            (false, Cause::Poles)
        } else if p.en.is_leaf() {
            let far = self.far_face(d, view, p.eg, f_mid, samples);
            (far, if far { Cause::Pass } else { Cause::Variation })
        } else {
            let far = self.far_cluster(h, d, view, p, f_mid, samples);
            (far, if far { Cause::Pass } else { Cause::Variation })
        };
        samples.why[1] = why;
        far
    }

    /// [`Oracle::transport_far`] for a face, which cannot be opened: estimates the one-point
    /// (midpoint rule) error from `R_d`'s curvature, ~ `(σ_tr + 3/d)² r² / 16` relative for a
    /// face of circumradius `r` at distance `d` (a stand-in for Jensen & Buhler's sample count
    /// that, unlike a solid angle, sees `σ_tr`). The link's coefficient is `f_mid` with that
    /// error's systematic part added back ([`midpoint_rule_gain`]).
    #[inline]
    fn far_face(
        &self,
        d: &ProfileF32,
        view: &ReceiverView,
        eg: &ClusterGeom,
        f: [f32; 3],
        samples: &mut Samples,
    ) -> bool {
        let dist = view.src.nearest(d, eg.midpoint);
        let r2 = eg.radius * eg.radius;
        let err: [f32; 3] = std::array::from_fn(|c| {
            let k = d.sigma_tr[c] + 3.0 / dist[c];
            k * k * r2 * (1.0 / 16.0) * f[c]
        });
        // The distance form only: Mertens' dipole sits along the receiver's normal, and the
        // gain, derived for a profile of distance alone, took the blob's ketchup at 1 cm from
        // within 1% of the exact solve to 2.2%.
        samples.estimate = Some(if d.normal_weight == 0.0 {
            std::array::from_fn(|c| f[c] * midpoint_rule_gain(d.sigma_tr[c], dist[c], r2, self.eps2))
        } else {
            f
        });
        self.within(err, f, self.eps2, view.inv_rtot)
    }

    /// [`Oracle::transport_far`] for an inner cluster: `E`'s estimate `f` against the sum of
    /// its children's, in total and in their spread over the children. Leaves the children's
    /// estimates in `samples.children` and an extrapolated estimate for the link in
    /// `samples.estimate`.
    #[inline]
    fn far_cluster(
        &self,
        h: &Hierarchy,
        d: &ProfileF32,
        view: &ReceiverView,
        p: &Pair,
        f: [f32; 3],
        samples: &mut Samples,
    ) -> bool {
        let (en, eg) = (p.en, p.eg);
        // Padding lanes have area 0 and add nothing.
        let mut pts = [eg.midpoint; 4];
        let mut areas = [0.0f32; 4];
        for (j, &k) in en.children().iter().enumerate() {
            let kg = &h.geom[k as usize];
            pts[j] = kg.midpoint;
            areas[j] = kg.area;
        }
        let fk = view.src.point_samples(d, &pts, &areas);
        samples.children = Some(fk);
        let sum: [f32; 3] = std::array::from_fn(|c| fk.iter().map(|f| f[c]).sum());
        // The link spreads E's *average* irradiance: besides the total, the transport must be
        // spread over E's children like their areas, or a non-uniform irradiance would be
        // mis-weighted.
        let mut err = [0.0f32; 3];
        let inv_a = if eg.area > 0.0 { 1.0 / eg.area } else { 0.0 };
        for c in 0..3 {
            let mut spread = 0.0;
            for j in 0..en.child_count as usize {
                spread += (fk[j][c] - areas[j] * inv_a * sum[c]).abs();
            }
            err[c] = (f[c] - sum[c]).abs() + self.irradiance_contrast * spread;
        }
        // Keep a better estimate for the link: R_d is convex, so one-point estimates fall short
        // systematically, by ~ area x extent² (midpoint rule); k children of 1/k the area each
        // err 1/k as much in total, and Richardson extrapolation removes the leading term.
        let k = en.child_count as f32;
        samples.estimate = Some(std::array::from_fn(|c| (sum[c] + (sum[c] - f[c]) / (k - 1.0)).max(0.0)));
        self.within(err, sum, self.eps2, view.inv_rtot)
    }
}

/// The local power of a distance-form profile's falloff beyond its exponential, `a` in
/// `R ~ d^-a e^(-σ d)`: 3 where the dipole's `1/d³` dominates (near), 2 in its tail.
pub(super) const FALLOFF_POWER: f32 = 2.5;

/// The `t²` coefficient `q + s = s² + s + a` of a curved receiver's expansion of a link of
/// steepness `s`, `F (1 - s t + ½ ((q + s) t² - s |δ|² / ρ²))` (`q = s² + a` the
/// log-curvature of `F ~ ρ^-a e^(-σ ρ)`, `a` = [`FALLOFF_POWER`]): one formula for the
/// receiver test ([`linear_slope`]) and the gather that must agree with it.
#[inline]
pub(super) fn curvature_along(s: f32) -> f32 {
    s * s + s + FALLOFF_POWER
}

/// The factor from a profile's value at a face's midpoint to its average over the face, for
/// a face of circumradius² `r2` at distance `dist` from the receiver's pole, to second
/// order: `R ~ d^-a e^(-σ d)` has steepness `s = a + σ d` and `d² R'' / R = s² + a`, and over
/// a face in the plane of the line to the receiver with the equilateral triangle's second
/// moment (`tr M = r² / 4`), the average exceeds the midpoint's value by
/// `r² (s² - s + a) / (16 d²)` relative (the radial curvature along the line, the distance's
/// sideways growth across it). A convex profile's one-point estimates otherwise fall short
/// systematically: −0.35% median on the 48K dragon, the larger part of its error. The gain
/// is at most `max_gain` (the emitter test's `ε2`): a face farther from being a point passed
/// that test only by the absolute floor, and there the expansion overshoots (capped at 0.25,
/// the bunny's marble erred by +0.77% median, at `ε2`, +0.09%).
#[inline]
fn midpoint_rule_gain(sigma_tr: f32, dist: f32, r2: f32, max_gain: f32) -> f32 {
    let s = FALLOFF_POWER + sigma_tr * dist;
    1.0 + (r2 * (s * s - s + FALLOFF_POWER) / (16.0 * dist * dist)).min(max_gain)
}

/// The steepness `s` of [`Samples::slope`] that best fits the estimates `fk` at receiver
/// `rn`'s children to the line `f (1 - s t_k)` through the midpoint's estimate `f`, with
/// `t_k = (m_k - m_R).D / |D|^2` the children's offsets along `D = m_R - m_E`, and the
/// prediction `1 - s t_k` (with `curved`, plus the curvature term of the gather's
/// expansion) at each child, to test the children against. Least squares over children and
/// channels, each channel weighted by its estimate (so relative to `f`, the brighter channels
/// count more); with `curved`, fitted again once with the curvature term of the first fit
/// taken off. 0 when the fit says the transport grows away from the emitter (no
/// distance-form profile does). One steepness serves all channels: a channel that falls off
/// differently fails the test. The line must stay non-negative over the receiver's bounding
/// sphere (`s <= |D| / r_R`), and where the children barely spread along `D` the fit says
/// nothing about the leaves that do (a fitted `s` of thousands put black blotches on a
/// sphere): then, with `curved`, the profile's own steepness `a + σ_tr |D|` (weighted like
/// the fit), else 0 and the children are tested against the constant. Such a receiver
/// barely extends along `D`, the one direction the transport changes in to first order, so
/// the first-order bound is not asked for again: asking it cost 3% more links on the 48K
/// dragon at the same error (0.83%). Across `D` a curved receiver's transport still falls by
/// `s |δ|² / 2 |D|²`, which the profile's steepness carries.
#[inline]
#[allow(clippy::too_many_arguments)]
fn linear_slope(
    h: &Hierarchy,
    d: &ProfileF32,
    rn: &Node,
    rg: &ClusterGeom,
    eg: &ClusterGeom,
    f: [f32; 3],
    fk: &[[f32; 3]; 4],
    curved: bool,
) -> (f32, [f32; 4]) {
    let dv = rg.midpoint - eg.midpoint;
    let inv_d2 = 1.0 / dv.length_squared();
    let f_sum = f[0] + f[1] + f[2];
    let mut t = [0.0f32; 4];
    let mut q = [0.0f32; 4];
    for (k, &c) in rn.children().iter().enumerate() {
        let off = h.geom[c as usize].midpoint - rg.midpoint;
        t[k] = off.dot(dv) * inv_d2;
        q[k] = off.length_squared() * inv_d2;
    }
    // The curvature term `½ ((s² + s + a) t² - s |δ|²/|D|²)` at child `k` for steepness `s`.
    let bend = |s: f32, k: usize| {
        if curved { 0.5 * (curvature_along(s) * t[k] * t[k] - s * q[k]) } else { 0.0 }
    };
    // Σ_c f_c (fk_c / f_c - 1 - bend) t_k over Σ_c f_c t_k².
    let fit = |s0: f32| {
        let (mut num, mut den) = (0.0f32, 0.0f32);
        for k in 0..rn.child_count as usize {
            num += (f_sum * (1.0 + bend(s0, k)) - (fk[k][0] + fk[k][1] + fk[k][2])) * t[k];
            den += f_sum * t[k] * t[k];
        }
        if den > 0.0 { num / den } else { 0.0 }
    };
    // The children's offsets along `D`, against the receiver's extent along it (`r / |D|`).
    let extent2 = rg.radius * rg.radius * inv_d2;
    let spread2: f32 = t.iter().map(|t| t * t).sum();
    let s_max = (1.0 / extent2).sqrt();
    let s = if spread2 >= 0.01 * extent2 {
        let s = fit(0.0).clamp(0.0, s_max);
        if curved { fit(s).clamp(0.0, s_max) } else { s }
    } else if curved && f_sum > 0.0 {
        let dist = dv.length();
        let sigma = (0..3).map(|c| f[c] * d.sigma_tr[c]).sum::<f32>() / f_sum;
        (FALLOFF_POWER + sigma * dist).min(s_max)
    } else {
        0.0
    };
    // Stored as a half float (`LinkCoef`): test with the value the gather will use.
    let s = super::link_coef::round_slope(s);
    (s, std::array::from_fn(|k| 1.0 - s * t[k] + bend(s, k)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gain brings a face's one-point estimate to its average over the face: for
    /// `R ~ d^-a e^(-σ d)` (`a` = [`FALLOFF_POWER`]) over an equilateral triangle in the plane
    /// of the line to the receiver, at 4 to 16 circumradii, near and far in `σ d`, against a
    /// dense midpoint rule (64² sub-triangles): the relative error falls at least fourfold at 4
    /// circumradii and tenfold from 8 (measured: 2.0-15% -> 0.3-2.5% at 4, 0.14-0.95% ->
    /// 0.004-0.045% at 16).
    #[test]
    fn midpoint_rule_gain_matches_the_face_average() {
        let a = FALLOFF_POWER as f64;
        for sigma in [0.0f64, 1.0, 4.0] {
            for ratio in [4.0f64, 8.0, 16.0] {
                for turn in [0.0f64, 0.7, 1.9] {
                    let (dist, r) = (1.0f64, 1.0 / ratio);
                    let k = |p: [f64; 2]| {
                        let d = (p[0] * p[0] + p[1] * p[1]).sqrt();
                        d.powf(-a) * (-sigma * d).exp()
                    };
                    // The receiver's pole at the origin, the face's centroid at (dist, 0).
                    let v: Vec<[f64; 2]> = (0..3)
                        .map(|i| {
                            let t = turn + i as f64 * 2.0 * std::f64::consts::PI / 3.0;
                            [dist + r * t.cos(), r * t.sin()]
                        })
                        .collect();
                    let n = 64;
                    let mut sum = 0.0;
                    for i in 0..n {
                        for j in 0..n - i {
                            // Upward and downward sub-triangles' centroids in barycentric steps.
                            let mut add = |u: f64, w: f64| {
                                let p = [0, 1]
                                    .map(|c| v[0][c] + u * (v[1][c] - v[0][c]) + w * (v[2][c] - v[0][c]));
                                sum += k(p);
                            };
                            let (fi, fj, fnn) = (i as f64, j as f64, n as f64);
                            add((fi + 1.0 / 3.0) / fnn, (fj + 1.0 / 3.0) / fnn);
                            if i + j + 1 < n {
                                add((fi + 2.0 / 3.0) / fnn, (fj + 2.0 / 3.0) / fnn);
                            }
                        }
                    }
                    let avg = sum / (n * n) as f64;
                    let mid = k([dist, 0.0]);
                    let gain = midpoint_rule_gain(sigma as f32, dist as f32, (r * r) as f32, 1.0) as f64;
                    let (before, after) = ((mid / avg - 1.0).abs(), (mid * gain / avg - 1.0).abs());
                    // What is left is of higher order: it shrinks faster than the error as r/d falls.
                    let want = if ratio >= 8.0 { 0.1 } else { 0.25 };
                    assert!(
                        after <= want * before,
                        "σ d {sigma}, d/r {ratio}, turn {turn}: {before:.2e} -> {after:.2e}"
                    );
                }
            }
        }
    }
}
