//! The refinement oracle (Mertens et al. 2003, §5.2): Jensen & Buhler's maximum-solid-angle
//! criteria at the receiver (`ε1`) and the emitter (`ε2`), the `A'/A` curvature test for near
//! clusters (§5.1.1), and the choice between a one-point estimate and the semi-analytic form
//! factor (§4) for each accepted link, which `solver::evaluate` then evaluates. Two modes
//! ([`OracleMode`]): the paper's solid angles, and one-point transport estimates (the default).

pub use super::point_sample::{ProfileF32, ReceiverSources};
use crate::bssrdf::ProfileKind;
use crate::hierarchy::{ClusterGeom, Hierarchy, Node};
use glam::Vec3;

mod transport;

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

/// Why one of the oracle's two tests decided as it did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Cause {
    /// The test did not run.
    #[default]
    None,
    /// Passed: the receiver stays whole, or the emitter is far.
    Pass,
    /// The receiver has no normal, or lies (or a child lies) inside the emitter's bounding
    /// sphere.
    Degenerate,
    /// The two bounding spheres overlap.
    NotSeparated,
    /// The emitter is seen under more than `MAX_FAR_SOLID_ANGLE`.
    WideAngle,
    /// A dipole pole lies within the margin of the emitter.
    Poles,
    /// The distance-form receiver test: the profile varies too much over the receiver's radius.
    Size,
    /// The one-point estimates disagree beyond `eps1` (receiver) or `eps2` (emitter).
    Variation,
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
}

/// The local power of a distance-form profile's falloff beyond its exponential, `a` in
/// `R ~ d^-a e^(-σ d)`: 3 where the dipole's `1/d³` dominates (near), 2 in its tail.
pub(super) const FALLOFF_POWER: f32 = 2.5;

/// The `t²` coefficient `q + s = s² + s + a` of a curved receiver's expansion of a link of
/// steepness `s`, `F (1 - s t + ½ ((q + s) t² - s |δ|² / ρ²))` (`q = s² + a` the
/// log-curvature of `F ~ ρ^-a e^(-σ ρ)`, `a` = [`FALLOFF_POWER`]): one formula for the
/// receiver test ([`transport::linear_slope`]) and the gather that must agree with it.
#[inline]
pub(super) fn curvature_along(s: f32) -> f32 {
    s * s + s + FALLOFF_POWER
}
