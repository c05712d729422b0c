//! The receiver and emitter tests of [`OracleMode::Transport`] (the default): one-point
//! transport estimates `A_E R_d` from the emitter to the receiver and its children, compared
//! relative to the material's total diffuse reflectance, and the second-order corrections
//! from a point estimate to a face's average and to a linear receiver.

use super::{
    Cause, Decision, FALLOFF_POWER, INSIDE, LinkKind, MAX_FAR_SOLID_ANGLE, Oracle, Pair, ProfileF32,
    ReceiverView, SOURCE_MARGIN, Samples, curvature_along, solid_angle,
};
use crate::hierarchy::{ClusterGeom, Hierarchy, Node};
use crate::solver::point_sample::point_samples_from;

impl Oracle {
    /// [`OracleMode::Transport`]: the same two tests on one-point transport estimates.
    #[inline]
    pub(super) fn decide_transport(
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
    let s = crate::solver::link_coef::round_slope(s);
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
