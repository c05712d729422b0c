//! The semi-analytic point-to-polygon form factor of Mertens et al. 2003, §4:
//! `F(A, x_o) = ∫_A R(x_i, x_o) dx_i`, with the profile placed at the receiver `x_o`
//! (the "inverse interpretation" of §4) and the area integral reduced to the polygon's edges.
//!
//! Every profile of [`crate::bssrdf::profile`] is a sum of radial terms, each a function of the
//! distance `s` from a point `d` at height `h` over the polygon's plane, with a radial tail
//! `Q(s) = ∫_s^∞ R(t) t dt`. In polar coordinates around `d'`, the orthogonal projection of `d`
//! onto the plane, the radial integral is `Q(h) - Q(s_edge)` (eq. 10), which leaves, per edge
//! `e` with signed angle `Δθ_e` seen from `d'`,
//!
//! ```text
//! I = Σ_e [ Δθ_e Q(h)  -  sign_e ∫_e Q(s(θ)) |dθ| ]      (I1 - I2, eqs. 10-13)
//! ```
//!
//! The terms: Mertens' six dipole poles on the receiver's normal (`Q = z e^{-σs}/s`, the paper's
//! form); the distance-form dipole's poles, which sit at `x_o` with the effective height
//! `√(h² + z²)` (its `R` depends on `√(r² + z²)` only); and a tabulated `Q` per channel (photon
//! beam diffusion, single scattering) at `x_o` itself.
//!
//! `Σ_e Δθ_e` is `2π` when `d'` is inside the polygon, `0` outside (and the interior angle when
//! `d'` lies on the boundary), so the I1 terms need only the winding number of the polygon
//! around `d'` (the angles themselves only when `d'` is on an edge's line). The I2 integral along
//! an edge, `R ∫ Q(√(S²+t²)) / (R²+t²) dt` (eq. 13), is split into
//! segments under condition (19) (`L / r_0 < ratio`, `σ L < limit`) as in the paper, laid out outwards from the
//! foot point `t = 0`, but each
//! segment is integrated with 3-point Gauss-Legendre instead of the paper's one-term Taylor
//! expansion (17): that expansion is the midpoint rule and errs by up to 16% on Mertens' own
//! figure 3 set-up, while Gauss-Legendre on the same kind of segments errs by well under 0.1%.
//!
//! Signs follow the signed-angle formulation, which is equivalent to the paper's "back facing
//! edges count positive, front facing negative" rule and works for any planar polygon (convex
//! or not) in either winding: angles are measured around the polygon's own (Newell) normal.
//!
//! Numerical choices, each for robustness:
//! * When `d'` lies close to an edge's supporting line (`R ≪ L`), the `1/(R²+t²)` factor of the
//!   I2 integrand is a narrow spike around the foot point `t = 0`. Segments are laid out from
//!   the foot point outwards, growing geometrically under the `L / r_0` condition, so the cost
//!   grows like `log(L/R)`; below `|t| < 10⁻³ S` one segment in `φ = atan(t/R)` absorbs the
//!   spike, which caps the count at `O(log(L/S))` even as `R → 0`. (Integrating whole segments
//!   in `φ` would avoid the spike everywhere, but it moves the branch points `t = ±iS` of
//!   `e^{-σs}/s` to within `R/S` of the ends `φ = ±π/2` and costs accuracy.)
//! * `d'` exactly on an edge's line (`R = 0`): the triangle `(d', a, b)` has zero area and that
//!   edge contributes nothing (the limit of `I1 - I2` as `R → 0` is 0 from both sides).
//! * A Mertens pole (nearly) in the polygon's plane (`h → 0`): the true integral diverges like
//!   `1/h` when `d'` is inside the polygon (the dipole model breaks down there), so `h` is clamped to
//!   [`HEIGHT_FLOOR`]` · z`. When `d'` is outside, the angle sum is exactly 0 (a winding number) and the
//!   finite result is the difference of the I2 terms, with no `1/h` cancellation. The
//!   distance-form terms never diverge (`h ≥ z`, and tables give a finite `Q(0)`).
//! * Degenerate polygons (fewer than 3 vertices, zero area) and non-finite input give 0;
//!   round-off below 0 is clamped to 0. Never NaN.
//!
//! * A profile of tables alone (photon beam diffusion) has its three channels' sources at one
//!   point and height, so one pass over the edges serves all three: the segments are laid out
//!   for the channel that needs the shortest, and each node's distance and square root are
//!   shared (a fifth to a quarter less time a form factor; `benches/formfactor.rs`).
//!
//! Everything is `f64`, allocation free and deterministic.

use crate::bssrdf::{Profile, RadialTable};
use crate::fastexp::exp_neg_f64;
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

pub mod cubature;
pub mod montecarlo;

/// Smallest height of a dipole source above the polygon's plane, relative to its `z`
/// (`h ≥ HEIGHT_FLOOR · z`). Only matters when a source lies (almost) in the plane of the
/// polygon, where the integral over a polygon containing `d'` diverges like `1/h`.
pub const HEIGHT_FLOOR: f64 = 1e-6;

/// Polygons whose doubled area is below `DEGENERATE_AREA · (longest edge)²` count as zero area.
const DEGENERATE_AREA: f64 = 1e-12;

/// Angle sums within this distance (radians) of a multiple of `2π` are snapped to it.
const WINDING_SNAP: f64 = 1e-7;

/// 3-point Gauss-Legendre nodes on `[-1, 1]` (±√(3/5) and 0) and their weights.
const GL_X: f64 = 0.774_596_669_241_483_4;
const GL_W_OUTER: f64 = 5.0 / 9.0;
const GL_W_CENTER: f64 = 8.0 / 9.0;

/// Options of the semi-analytic integration (the segment conditions of Mertens eq. 19).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormFactorOptions {
    /// Largest allowed `L / r_0` of an edge segment, where `L` is the segment's length and
    /// `r_0` the distance from `d'` to its midpoint (unitless, in `(0, 2)`; larger values
    /// mean one segment per edge, values below 1e-3 are raised to 1e-3). Mertens eq. (19)
    /// uses 2/5 with a one-term Taylor rule. Segments are as long as allowed, and with 3-point
    /// Gauss-Legendre 1/2 errs by < 1e-4 relative on Mertens' fig. 3 and on random
    /// near-field triangles (0.6: 3.5e-4, 0.8: 2e-3; the error falls ~64x per halving).
    /// Default 0.5.
    pub max_segment_ratio: f64,
    /// Largest allowed `σ L` of a segment, `σ = sigma_tr` (unitless, > 0; values below 1e-3
    /// are raised to 1e-3; `f64::INFINITY` disables the test). Mertens eq. (19) uses 2/5 with
    /// the Taylor rule and notes it hardly matters for translucent materials; it keeps
    /// `e^{-σs}` resolved for opaque ones (ketchup, skin). Gauss-Legendre needs less: with 2
    /// the error is set by `max_segment_ratio` alone. Default 2.
    pub max_segment_sigma: f64,
    /// Largest `k ρ` (unitless, ≥ 0) at which the edge integrals give way to a seven-point
    /// cubature over the polygon: `ρ` is the polygon's radius, `k = σ_tr + 3/s` with `s` the
    /// distance from the nearest dipole source (see [`cubature`]). There `R_d` is smooth over
    /// the polygon, the cubature errs by under 1e-4, and the edge integrals lose accuracy to
    /// cancellation. 0 disables the short cut. Default [`cubature::MAX_K_RHO`] (1).
    pub cubature_max_k_rho: f64,
}

impl Default for FormFactorOptions {
    fn default() -> Self {
        FormFactorOptions {
            max_segment_ratio: 0.5,
            max_segment_sigma: 2.0,
            cubature_max_k_rho: cubature::MAX_K_RHO,
        }
    }
}

/// `F(A, x_o)` per channel for the planar polygon `polygon` (vertices in order, any winding,
/// at least 3), seen from the receiver `x_o` with unit normal `n_o`. Mesh units; the result is
/// unitless (the fraction of irradiance `E` on `A` that leaves as radiosity `B` at `x_o`).
///
/// Finite and non-negative for every input (0 for degenerate or non-finite input).
pub fn form_factor(
    polygon: &[DVec3],
    x_o: DVec3,
    n_o: DVec3,
    profile: &Profile,
    opts: &FormFactorOptions,
) -> [f64; 3] {
    form_factor_counted(polygon, x_o, n_o, profile, opts).0
}

/// [`form_factor`] plus the number of edge segments it integrated (over all six dipole
/// sources and all edges): the paper's cost measure (Mertens fig. 4 calls them "samples").
pub fn form_factor_counted(
    polygon: &[DVec3],
    x_o: DVec3,
    n_o: DVec3,
    profile: &Profile,
    opts: &FormFactorOptions,
) -> ([f64; 3], usize) {
    let n = polygon.len();
    if n < 3 || !x_o.is_finite() || !n_o.is_finite() {
        return ([0.0; 3], 0);
    }
    let n_o = n_o.normalize_or_zero();
    if n_o == DVec3::ZERO {
        return ([0.0; 3], 0);
    }

    // Plane of the polygon: origin at the vertex average, normal from Newell's formula (the
    // plain cross product for triangles), so a slightly non-planar polygon is projected.
    let (origin, twice_area_vec, max_edge2) = if n == 3 {
        let (a, b, c) = (polygon[0], polygon[1], polygon[2]);
        let m = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
        ((a + b + c) / 3.0, (b - a).cross(c - a), m)
    } else {
        let origin = polygon.iter().copied().sum::<DVec3>() / n as f64;
        let mut nv = DVec3::ZERO;
        let mut m = 0.0f64;
        for i in 0..n {
            let a = polygon[i] - origin;
            let b = polygon[(i + 1) % n] - origin;
            nv += a.cross(b);
            m = m.max((b - a).length_squared());
        }
        (origin, nv, m)
    };
    let twice_area = twice_area_vec.length();
    if !twice_area.is_finite() || !origin.is_finite() || twice_area <= DEGENERATE_AREA * max_edge2 {
        return ([0.0; 3], 0);
    }
    let n_p = twice_area_vec / twice_area;
    if opts.cubature_max_k_rho > 0.0 {
        let radius = polygon.iter().map(|p| p.distance_squared(origin)).fold(0.0, f64::max).sqrt();
        if cubature::k_rho(profile, x_o, n_o, origin, radius) <= opts.cubature_max_k_rho {
            return (cubature::polygon_integral(polygon, n_p, x_o, n_o, profile), 7 * (n - 2));
        }
    }
    let (e1, e2) = n_p.any_orthonormal_pair();
    let to_2d = |v: DVec3| {
        let d = v - origin;
        DVec2::new(d.dot(e1), d.dot(e2))
    };
    let (src, n_src) = sources(profile, x_o, n_o, origin, n_p, e1, e2);
    let mut src = src;
    let src = &mut src[..n_src];

    let seg = Segmenter::new(opts);
    // A profile of tables alone (PBD) has its three sources at one point: one pass serves all.
    let channels = match &profile.tables {
        Some(t) if !profile.has_analytic() => Some(ChannelTails::new(&t.channels, profile.sigma_t)),
        _ => None,
    };
    let passes = if channels.is_some() { 1 } else { src.len() };
    let mut segments = 0usize;
    let mut b2 = to_2d(polygon[0]);
    for i in 0..n {
        let a2 = b2;
        b2 = to_2d(polygon[(i + 1) % n]);
        let e = b2 - a2;
        let len = e.length();
        if len <= 0.0 {
            continue;
        }
        let u = e / len;
        for k in 0..passes {
            let s = &mut src[k];
            let w = a2 - s.d;
            // Signed distance from d' to the edge's line: > 0 when (d', a, b) winds
            // counter-clockwise around n_p, i.e. when the edge is a back-facing one.
            let r_s = w.perp_dot(u);
            if r_s == 0.0 {
                // d' on this edge's line: the edge adds nothing, but the angle sum is no longer
                // a multiple of 2π if d' is on the edge itself (see below).
                s.on_line = true;
                continue;
            }
            // Winding number of the polygon around d' (Sunday's crossing rule; the sign of
            // r_s is the side of d'), which gives Σ Δθ_e = 2π · winding without an atan2.
            if a2.y <= s.d.y {
                if b2.y > s.d.y && r_s > 0.0 {
                    s.winding += 1;
                }
            } else if b2.y <= s.d.y && r_s < 0.0 {
                s.winding -= 1;
            }
            let t_a = w.dot(u);
            let t_b = t_a + len;
            let s2 = r_s * r_s + s.h2;
            if let Some(tails) = &channels {
                let (i2, segs) = edge_i2(r_s.abs(), s2, tails, t_a, t_b, &seg);
                for (c, i2) in i2.into_iter().enumerate() {
                    src[c].i2 += i2.copysign(r_s);
                }
                // Counted per source, as the paper counts them.
                segments += 3 * segs;
                continue;
            }
            let ([i2], segs) = match s.tail {
                Tail::Pole => edge_i2(r_s.abs(), s2, &PoleTail { sigma: s.sigma, h: s.h }, t_a, t_b, &seg),
                Tail::Table(c) => {
                    let table = &profile.tables.as_ref().expect("table source without tables").channels[c];
                    edge_i2(r_s.abs(), s2, &TableTail { table, sigma: s.sigma }, t_a, t_b, &seg)
                }
            };
            s.i2 += i2.copysign(r_s);
            segments += segs;
        }
    }
    if channels.is_some() {
        // The other channels' sources share the first's point, so its winding and edges.
        let (winding, on_line) = (src[0].winding, src[0].on_line);
        for s in src.iter_mut() {
            (s.winding, s.on_line) = (winding, on_line);
        }
    }

    let mut f = [0.0; 3];
    for s in src.iter() {
        let theta = if s.on_line { boundary_angle(polygon, &to_2d, s.d) } else { TAU * s.winding as f64 };
        let q_h = match s.tail {
            Tail::Pole => PoleTail { sigma: s.sigma, h: s.h }.q(s.h)[0],
            Tail::Table(c) => profile.tables.as_ref().expect("tables").channels[c].tail(s.h),
        };
        f[s.channel] += s.weight * (theta * q_h - s.i2);
    }
    let f = f.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
    (f, segments)
}

/// Which radial tail `Q(s)` a source integrates.
#[derive(Clone, Copy, Default, PartialEq)]
enum Tail {
    /// One pole of the analytic dipole: `Q(s) = e^{-σs} / s` (times `z`, in the weight).
    #[default]
    Pole,
    /// A channel's tabulated profile (`Q` from the table, weight 1).
    Table(usize),
}

/// One source of the profile, in the polygon's 2D frame, with its running sums.
#[derive(Clone, Copy, Default)]
struct Source {
    /// Projection `d'` onto the polygon's plane (2D plane coordinates, mesh units).
    d: DVec2,
    /// Height above the plane (floored for Mertens' poles; `√(h² + z²)` for the distance
    /// form, whose poles sit at `x_o` but `z` away in distance), and its square.
    h: f64,
    h2: f64,
    /// Factor of `(I1 - I2)` in `F`: `α'/4π · z` for a pole, 1 for a table.
    weight: f64,
    /// The rate (per mesh unit) the segment conditions use: `σ_tr` for a pole, `σ_t` for a
    /// table (tabulated profiles vary on the mean free path near 0).
    sigma: f64,
    tail: Tail,
    channel: usize,
    /// Winding number of the polygon around `d'`, whether `d'` lies on some edge's line, and
    /// the running sum of the signed I2 terms.
    winding: i32,
    on_line: bool,
    i2: f64,
}

/// The profile's sources for the receiver `x_o` (normal `n_o`) in the frame of a polygon
/// (origin, unit normal `n_p`, in-plane axes `e1`, `e2`): Mertens' six poles on the normal,
/// the distance form's six poles at `x_o`, and a tabulated source per channel. Returns the
/// array and how many are used.
fn sources(
    profile: &Profile,
    x_o: DVec3,
    n_o: DVec3,
    origin: DVec3,
    n_p: DVec3,
    e1: DVec3,
    e2: DVec3,
) -> ([Source; 9], usize) {
    let mut src = [Source::default(); 9];
    let mut n = 0;
    let mut push = |pos: DVec3, h: f64, weight: f64, sigma: f64, tail: Tail, channel: usize| {
        let rel = pos - origin;
        src[n] = Source {
            d: DVec2::new(rel.dot(e1), rel.dot(e2)),
            h,
            h2: h * h,
            weight,
            sigma,
            tail,
            channel,
            ..Default::default()
        };
        n += 1;
    };
    let h_o = (x_o - origin).dot(n_p).abs();
    for c in 0..3 {
        let k = profile.alpha_prime[c] / (4.0 * PI);
        let sigma = profile.sigma_tr[c];
        if profile.has_analytic() {
            for (z, sign) in [(profile.z_r[c], -1.0), (profile.z_v[c], 1.0)] {
                if profile.kind.uses_normals() {
                    let pos = x_o + sign * z * n_o;
                    let h = (pos - origin).dot(n_p).abs().max(HEIGHT_FLOOR * z);
                    push(pos, h, k * z, sigma, Tail::Pole, c);
                } else {
                    push(x_o, (h_o * h_o + z * z).sqrt(), k * z, sigma, Tail::Pole, c);
                }
            }
        }
        if profile.tables.is_some() {
            push(x_o, h_o, 1.0, profile.sigma_t[c], Tail::Table(c), c);
        }
    }
    (src, n)
}

/// A radial tail `Q(s)` as the edge integrals see it, for `N` sources that share their
/// position and height (so every segment and distance): one pole or table (`N = 1`), or the
/// three channels' tables of a tabulated profile (`N = 3`).
trait TailFn<const N: usize> {
    /// `Q(s)` at distance `s` (mesh units), per source.
    fn q(&self, s: f64) -> [f64; N];
    /// The rate (per mesh unit) for the `σ L` segment condition (the largest of the sources').
    fn sigma(&self) -> f64;
    /// Whether everything at distance `s` and beyond is negligible (with `s_min` the least
    /// distance along the edge).
    fn negligible(&self, s: f64, s_min: f64) -> bool;
}

/// One analytic pole, `e^{-σs} / s`, at height `h` over the polygon's plane.
struct PoleTail {
    sigma: f64,
    h: f64,
}

impl TailFn<1> for PoleTail {
    #[inline(always)]
    fn q(&self, s: f64) -> [f64; 1] {
        [exp_neg_f64(-self.sigma * s) / s]
    }
    #[inline(always)]
    fn sigma(&self) -> f64 {
        self.sigma
    }
    #[inline(always)]
    fn negligible(&self, s: f64, s_min: f64) -> bool {
        // Stop once e^{-σ(s - S)} < e^{-40}: nothing further along the edge can matter; and
        // once below e^{-50} of the pole's own peak `e^{-σh}/h`, however the edge runs (an
        // edge far out of an opaque material's reach costs no segments).
        self.sigma * (s - s_min) > 40.0 || self.sigma * (s - self.h) > 50.0
    }
}

/// A tabulated channel.
struct TableTail<'a> {
    table: &'a RadialTable,
    sigma: f64,
}

impl TailFn<1> for TableTail<'_> {
    #[inline(always)]
    fn q(&self, s: f64) -> [f64; 1] {
        [self.table.tail(s)]
    }
    #[inline(always)]
    fn sigma(&self) -> f64 {
        self.sigma
    }
    #[inline(always)]
    fn negligible(&self, s: f64, _s_min: f64) -> bool {
        s >= self.table.r_max
    }
}

/// The three channels' tables of a profile with no analytic part (photon beam diffusion): its
/// three sources sit at the receiver with one height, so they share every segment, distance
/// and square root, and one pass integrates all three (the segments are those of the channel
/// that needs the shortest, so no channel is integrated more coarsely than alone).
struct ChannelTails<'a> {
    tables: &'a [RadialTable; 3],
    /// [`RadialTable::root_scale`] per channel.
    scale: [f64; 3],
    sigma: f64,
    r_max: f64,
}

impl<'a> ChannelTails<'a> {
    fn new(tables: &'a [RadialTable; 3], sigma_t: [f64; 3]) -> Self {
        ChannelTails {
            tables,
            scale: tables.each_ref().map(RadialTable::root_scale),
            sigma: sigma_t.into_iter().fold(0.0, f64::max),
            r_max: tables.iter().map(|t| t.r_max).fold(0.0, f64::max),
        }
    }
}

impl TailFn<3> for ChannelTails<'_> {
    #[inline(always)]
    fn q(&self, s: f64) -> [f64; 3] {
        let root = s.max(0.0).sqrt();
        std::array::from_fn(|c| self.tables[c].tail_at_root(root, self.scale[c]))
    }
    #[inline(always)]
    fn sigma(&self) -> f64 {
        self.sigma
    }
    #[inline(always)]
    fn negligible(&self, s: f64, _s_min: f64) -> bool {
        s >= self.r_max
    }
}

/// `Σ_e Δθ_e`, the signed angle the polygon's edges subtend at `d'` (2D), for the rare case
/// that `d'` lies on an edge's supporting line, where it may be a fraction of `2π` (`π` on an
/// edge, the interior angle at a vertex). Edges whose line holds `d'` subtend nothing.
#[cold]
fn boundary_angle(polygon: &[DVec3], to_2d: &impl Fn(DVec3) -> DVec2, d: DVec2) -> f64 {
    let n = polygon.len();
    let mut theta = 0.0;
    for i in 0..n {
        // The same arithmetic as the main loop, so that exactly the same edges are skipped.
        let a2 = to_2d(polygon[i]);
        let e = to_2d(polygon[(i + 1) % n]) - a2;
        let len = e.length();
        if len <= 0.0 {
            continue;
        }
        let w = a2 - d;
        let r_s = w.perp_dot(e / len);
        if r_s != 0.0 {
            let t_a = w.dot(e / len);
            theta += (len * r_s).atan2(r_s * r_s + t_a * (t_a + len));
        }
    }
    // Snap to a multiple of 2π when d' is on an edge's line but off the polygon's boundary
    // (removes the round-off of ~1e-16 · z/h that would otherwise survive when h is tiny).
    let k = (theta / TAU).round();
    if (theta - k * TAU).abs() < WINDING_SNAP { k * TAU } else { theta }
}

/// `∫_{t_a}^{t_b} R e^{-σ√(S²+t²)} / (√(S²+t²) (R²+t²)) dt` (Mertens eq. 13 without `z`) for
/// `R > 0`, with `s2 = S²`. Returns the integral and the number of segments.
///
/// The integrand is even in `t`, so the edge is split at the foot point `t = 0` and each half
/// integrated over `|t|`.
#[inline]
fn edge_i2<const N: usize>(
    r: f64,
    s2: f64,
    tail: &impl TailFn<N>,
    t_a: f64,
    t_b: f64,
    seg: &Segmenter,
) -> ([f64; N], usize) {
    if t_a >= 0.0 {
        half_edge_i2(r, s2, tail, t_a, t_b, seg)
    } else if t_b <= 0.0 {
        half_edge_i2(r, s2, tail, -t_b, -t_a, seg)
    } else {
        let (i1, n1) = half_edge_i2(r, s2, tail, 0.0, -t_a, seg);
        let (i2, n2) = half_edge_i2(r, s2, tail, 0.0, t_b, seg);
        (std::array::from_fn(|k| i1[k] + i2[k]), n1 + n2)
    }
}

/// Three-point Gauss-Legendre over a segment of half-length `half`, from the values at its
/// centre and at its two outer nodes.
#[inline(always)]
fn gauss3<const N: usize>(half: f64, centre: [f64; N], lo: [f64; N], hi: [f64; N]) -> [f64; N] {
    std::array::from_fn(|k| half * (GL_W_CENTER * centre[k] + GL_W_OUTER * (lo[k] + hi[k])))
}

/// The segment conditions, prepared once per call.
struct Segmenter {
    /// `ρ²` and `1 - ρ²/4` for `ρ = max_segment_ratio`; `kappa ≤ 0` means "no limit".
    ratio2: f64,
    kappa: f64,
    /// Largest `σ L`.
    sigma_limit: f64,
}

impl Segmenter {
    fn new(opts: &FormFactorOptions) -> Self {
        // Guard against zero, negative or NaN options: they would mean endless subdivision.
        let ratio = if opts.max_segment_ratio > 1e-3 { opts.max_segment_ratio } else { 1e-3 };
        let sigma_limit = if opts.max_segment_sigma > 1e-3 { opts.max_segment_sigma } else { 1e-3 };
        let ratio2 = ratio * ratio;
        Segmenter { ratio2, kappa: 1.0 - 0.25 * ratio2, sigma_limit }
    }
}

/// The part of [`edge_i2`] over `0 ≤ a ≤ t ≤ b`.
///
/// Segments are laid out greedily from the foot point outwards, each as long as condition (19)
/// allows: `L = ρ r_0` with `r_0 = √(R² + (a + L/2)²)` solved for `L`, and `σ L ≤` the σ limit.
/// They grow geometrically (by `(2+ρ)/(2-ρ)`), so an edge whose line passes at distance `R`
/// from `d'` needs `O(log(L/R))` segments; below `|t| < 10⁻³ S` (only reached when
/// `R < 10⁻³ S`) one segment in `φ = atan(t/R)` absorbs the `1/(R²+t²)` spike, which bounds the
/// count by `O(log(L/S))` even for `R → 0`. Beyond `σ(s - S) > 40` the integrand is below
/// `e^{-40}` of its peak and the rest of the edge is dropped.
#[inline]
fn half_edge_i2<const N: usize>(
    r: f64,
    s2: f64,
    tail: &impl TailFn<N>,
    a: f64,
    b: f64,
    seg: &Segmenter,
) -> ([f64; N], usize) {
    let r2 = r * r;
    let s = s2.sqrt();
    let sigma = tail.sigma();
    let f = |t: f64| {
        let inv = 1.0 / (r2 + t * t);
        tail.q((s2 + t * t).sqrt()).map(|q| q * inv)
    };
    let mut sum = [0.0; N];
    let mut segments = 0;
    let mut pos = a;
    let phi_zone = 1e-3 * s;
    if pos < phi_zone && r < phi_zone {
        let end = phi_zone.min(b);
        let p1 = (pos / r).atan();
        let p2 = (end / r).atan();
        let hp = 0.5 * (p2 - p1);
        let p0 = p1 + hp;
        let g = |p: f64| {
            let t = r * p.tan();
            tail.q((s2 + t * t).sqrt())
        };
        let dp = hp * GL_X;
        sum = gauss3(hp, g(p0), g(p0 - dp), g(p0 + dp));
        segments += 1;
        pos = end;
    }
    let sigma_len = if sigma > 0.0 { seg.sigma_limit / sigma } else { f64::INFINITY };
    let mut t_sum = [0.0; N];
    while pos < b {
        if tail.negligible((s2 + pos * pos).sqrt(), s) {
            break;
        }
        let l_ratio = if seg.kappa > 0.0 {
            let q = seg.ratio2 * pos;
            (q + (q * q + 4.0 * seg.kappa * seg.ratio2 * (r2 + pos * pos)).sqrt()) / (2.0 * seg.kappa)
        } else {
            f64::INFINITY
        };
        let l = l_ratio.min(sigma_len);
        // Take the rest of the edge in one go when it is (nearly) within reach, and halve the
        // last two segments' leftover otherwise, so no sliver segment is left at the end.
        let rest = b - pos;
        let l = if rest <= l {
            rest
        } else if rest < 2.0 * l {
            0.5 * rest
        } else {
            l
        };
        let half = 0.5 * l;
        let t0 = pos + half;
        let dt = half * GL_X;
        let part = gauss3(half, f(t0), f(t0 - dt), f(t0 + dt));
        t_sum.iter_mut().zip(part).for_each(|(s, p)| *s += p);
        segments += 1;
        pos = if rest <= l { b } else { pos + l };
    }
    (std::array::from_fn(|k| sum[k] + r * t_sum[k]), segments)
}

/// One-sample estimate: `R_d` from the polygon's centroid times its area (the far-field
/// approximation used for distant links, Mertens §4.2).
pub fn point_sample(polygon: &[DVec3], x_o: DVec3, n_o: DVec3, profile: &Profile) -> [f64; 3] {
    let (centroid, area) = polygon_centroid_area(polygon);
    let rd = profile.rd(x_o, n_o, centroid);
    rd.map(|v| v * area)
}

/// Area centroid and area (mesh units², ≥ 0) of a planar polygon (vertices in order, any
/// winding, convex or not). Fewer than 3 vertices or zero area give the first vertex (or the
/// origin) and 0.
pub fn polygon_centroid_area(polygon: &[DVec3]) -> (DVec3, f64) {
    let n = polygon.len();
    if n < 3 {
        return (polygon.first().copied().unwrap_or_default(), 0.0);
    }
    let p0 = polygon[0];
    // Fan triangles weighted by their *signed* area along the polygon's normal, so concave
    // polygons come out right.
    let mut area_vec = DVec3::ZERO;
    for i in 1..n - 1 {
        area_vec += (polygon[i] - p0).cross(polygon[i + 1] - p0);
    }
    let twice_area = area_vec.length();
    if twice_area <= 0.0 || !twice_area.is_finite() {
        return (p0, 0.0);
    }
    let normal = area_vec / twice_area;
    let mut weighted = DVec3::ZERO;
    for i in 1..n - 1 {
        let a = (polygon[i] - p0).cross(polygon[i + 1] - p0).dot(normal);
        weighted += a * (p0 + polygon[i] + polygon[i + 1]);
    }
    (weighted / (3.0 * twice_area), 0.5 * twice_area)
}
