//! The I2 term of the form factor along one edge (Mertens et al. 2003, eqs. 13 and 17-19):
//! `R ∫ Q(√(S²+t²)) / (R²+t²) dt` for the radial tails `Q` of an analytic pole, a channel's
//! table, or the three channels' tables at once, over segments laid out from the foot point
//! outwards under condition (19) and integrated with 3-point Gauss-Legendre (see [`super`]).

use super::FormFactorOptions;
use crate::bssrdf::RadialTable;
use crate::fastexp::exp_neg_f64;

/// 3-point Gauss-Legendre nodes on `[-1, 1]` (±√(3/5) and 0) and their weights.
const GL_X: f64 = 0.774_596_669_241_483_4;
const GL_W_OUTER: f64 = 5.0 / 9.0;
const GL_W_CENTER: f64 = 8.0 / 9.0;

/// A radial tail `Q(s)` as the edge integrals see it, for `N` sources that share their
/// position and height (so every segment and distance): one pole or table (`N = 1`), or the
/// three channels' tables of a tabulated profile (`N = 3`).
pub(super) trait TailFn<const N: usize> {
    /// `Q(s)` at distance `s` (mesh units), per source.
    fn q(&self, s: f64) -> [f64; N];
    /// The rate (per mesh unit) for the `σ L` segment condition (the largest of the sources').
    fn sigma(&self) -> f64;
    /// Whether everything at distance `s` and beyond is negligible (with `s_min` the least
    /// distance along the edge).
    fn negligible(&self, s: f64, s_min: f64) -> bool;
}

/// One analytic pole, `e^{-σs} / s`, at height `h` over the polygon's plane.
pub(super) struct PoleTail {
    pub(super) sigma: f64,
    pub(super) h: f64,
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
pub(super) struct TableTail<'a> {
    pub(super) table: &'a RadialTable,
    pub(super) sigma: f64,
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
pub(super) struct ChannelTails<'a> {
    tables: &'a [RadialTable; 3],
    /// [`RadialTable::root_scale`] per channel.
    scale: [f64; 3],
    sigma: f64,
    r_max: f64,
}

impl<'a> ChannelTails<'a> {
    pub(super) fn new(tables: &'a [RadialTable; 3], sigma_t: [f64; 3]) -> Self {
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

/// `∫_{t_a}^{t_b} R e^{-σ√(S²+t²)} / (√(S²+t²) (R²+t²)) dt` (Mertens eq. 13 without `z`) for
/// `R > 0`, with `s2 = S²`. Returns the integral and the number of segments.
///
/// The integrand is even in `t`, so the edge is split at the foot point `t = 0` and each half
/// integrated over `|t|`.
#[inline]
pub(super) fn edge_i2<const N: usize>(
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
pub(super) struct Segmenter {
    /// `ρ²` and `1 - ρ²/4` for `ρ = max_segment_ratio`; `kappa ≤ 0` means "no limit".
    ratio2: f64,
    kappa: f64,
    /// Largest `σ L`.
    sigma_limit: f64,
}

impl Segmenter {
    pub(super) fn new(opts: &FormFactorOptions) -> Self {
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
