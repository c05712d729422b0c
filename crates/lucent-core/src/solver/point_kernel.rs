//! The one-point estimate kernel (Mertens et al. 2003, §4.2: the far-field coefficient
//! `A_E R_d(x_E, x_o)`, and the transport oracle's estimates of §5.2), written once over
//! lanes and compiled per instruction set ([`crate::simd`]).
//!
//! A batch is four points × three channels, lane `4 c + j` being channel `c`, point `j`:
//! twelve lanes, padded to sixteen (area 0) in the vector paths, so that AVX-512 takes a
//! batch in one register and AVX2 in two. Each lane is the radial profile `R(r)` of its
//! channel from the squared distances to the channel's real and virtual poles: the analytic
//! dipole (Jensen et al. 2001, eq. 5: two square roots, two divisions, two exponentials), the
//! tabulated `r R(r)` of photon beam diffusion (two square roots, a gather of two table
//! entries, one division), or both. The loops are plain Rust over fixed-size arrays, branch
//! free (a table lookup beyond `r_max` is masked, not skipped) and without bounds checks the
//! compiler cannot remove, so that inside a `#[target_feature]` function it emits one vector
//! instruction per operation and a hardware gather for the table.
//!
//! Lanes do not interact, so a single estimate, a batch of four points and a batch of four
//! receivers give one channel the same bits on one path; the portable and AVX2 paths differ
//! only by fused multiply-adds (see [`crate::simd`]). AVX-512 has its own hand-written copy
//! without square roots and divisions ([`super::point_kernel_avx512`]).

use super::point_sample::ReceiverSources;
use crate::bssrdf::tables::TABLE_SIZE;
use crate::fastexp::exp_neg_with;
use crate::simd::Madd;
use glam::Vec3;

/// Lanes of the vector paths' batch (twelve used).
pub(super) const WIDTH: usize = 16;

/// Channel of lane `i` in a batch of four points: channel-major, lane `4 c + j` is channel `c`,
/// point `j` (so a point's coordinates repeat every four lanes and a pole's fill four
/// neighbouring lanes: broadcasts, not gathers); the padding lanes `12..16` repeat channel 2.
#[inline(always)]
fn batch_channel(i: usize) -> usize {
    (i / 4).min(2)
}

/// Channel of lane `i` of a single estimate (lane 3 pads with channel 2).
#[inline(always)]
fn single_channel(i: usize) -> usize {
    i.min(2)
}

/// A profile's per-channel coefficients over `W` lanes (lane `i` of channel `channel(i)`; see
/// `ProfileF32` for their meaning).
#[derive(Clone, Copy, Debug)]
pub(super) struct Lanes<const W: usize> {
    pub sigma_tr: [f32; W],
    pub z_r: [f32; W],
    pub z_v: [f32; W],
    pub k: [f32; W],
    pub off_r: [f32; W],
    pub off_v: [f32; W],
    /// The table's `1 / r_max` and `r_floor` (0 without a table).
    pub inv_r_max: [f32; W],
    pub r_floor: [f32; W],
    /// For the AVX-512 kernel: `1 / r_floor` (0 without a table), `N² / r_max` (`N` the
    /// table size), `k z` and `k z σ_tr` per pole, `-σ_tr log2 e`.
    pub inv_r_floor: [f32; W],
    pub x_scale: [f32; W],
    pub kz_r: [f32; W],
    pub kz_v: [f32; W],
    pub kzs_r: [f32; W],
    pub kzs_v: [f32; W],
    pub exp2_scale: [f32; W],
    /// Where the lane's channel starts in the table.
    pub table_start: [u32; W],
}

impl<const W: usize> Lanes<W> {
    /// Per-channel values `[sigma_tr, z_r, z_v, k, off_r, off_v, inv_r_max, r_floor]` over
    /// the lanes.
    fn new(per_channel: [[f32; 3]; 8], channel: fn(usize) -> usize) -> Self {
        let rep = |a: [f32; 3]| std::array::from_fn(|i| a[channel(i)]);
        let [sigma_tr, z_r, z_v, k, off_r, off_v, inv_r_max, r_floor] = per_channel.map(rep);
        let table_start = std::array::from_fn(|i| (channel(i) * (TABLE_SIZE + 1)) as u32);
        let inv_r_floor = r_floor.map(|f| if f > 0.0 { 1.0 / f } else { 0.0 });
        let x_scale = inv_r_max.map(|v| v * (TABLE_SIZE * TABLE_SIZE) as f32);
        let kz = |z: [f32; W]| std::array::from_fn(|i| k[i] * z[i]);
        let (kz_r, kz_v) = (kz(z_r), kz(z_v));
        let kzs = |kz: [f32; W]| std::array::from_fn(|i| kz[i] * sigma_tr[i]);
        let (kzs_r, kzs_v) = (kzs(kz_r), kzs(kz_v));
        let exp2_scale = sigma_tr.map(|s| -s * std::f32::consts::LOG2_E);
        Lanes {
            sigma_tr,
            z_r,
            z_v,
            k,
            off_r,
            off_v,
            inv_r_max,
            r_floor,
            inv_r_floor,
            x_scale,
            kz_r,
            kz_v,
            kzs_r,
            kzs_v,
            exp2_scale,
            table_start,
        }
    }
}

/// Entries of a [`Table32`]: three channels of `TABLE_SIZE + 1` samples.
pub(super) const TABLE_LEN: usize = 3 * (TABLE_SIZE + 1);

/// A tabulated profile in `f32`: `r R(r)` per channel on the grid of
/// [`crate::bssrdf::RadialTable`] (`r = r_max x²`, linear in `x`), channel `c`'s samples
/// (the last 0) from `c (TABLE_SIZE + 1)`. Fixed size, so that a clamped index needs no
/// bounds check; one array, so that a lane's entry is one 32-bit-indexed gather.
pub(super) type Table32 = Box<[f32; TABLE_LEN]>;

/// `R(r)` in lane `i` from the squared distance `s2` to the receiver point; 0 beyond `r_max`
/// (and for NaN).
#[inline(always)]
fn radial<M: Madd, const W: usize>(t: &[f32; TABLE_LEN], l: &Lanes<W>, i: usize, s2: f32) -> f32 {
    const N: f32 = TABLE_SIZE as f32;
    // Adding 1.5 · 2^23 rounds to an integer in the mantissa: `x - 0.5` to nearest is
    // `floor(x)` but at integers, where the neighbouring cell interpolates the same value.
    const ROUND: f32 = 12_582_912.0;
    let r = s2.sqrt();
    let x = (r * l.inv_r_max[i]).sqrt() * N;
    let inside = x < N;
    let x = if inside { x } else { 0.0 };
    let shifted = (x - 0.5) + ROUND;
    let cell = shifted.to_bits().wrapping_sub(ROUND.to_bits()).min(TABLE_SIZE as u32 - 1);
    let f = x - (shifted - ROUND);
    let at = (l.table_start[i] + cell).min(TABLE_LEN as u32 - 2) as usize;
    let w = M::madd(t[at], 1.0 - f, t[at + 1] * f);
    if inside { w / r.max(l.r_floor[i]) } else { 0.0 }
}

/// What a batch needs of the profile (a part of `ProfileF32`).
#[derive(Clone, Debug)]
pub(super) struct ProfileLanes {
    /// Lanes of a batch of four points.
    pub batch: Lanes<WIDTH>,
    /// Lanes of a single estimate.
    pub single: Lanes<4>,
    /// Sixteen lanes of one channel each, for sums over sixteen points at a time
    /// ([`super::point_kernel_avx512::weighted_sum`]).
    pub channel: [Lanes<WIDTH>; 3],
    /// Whether the analytic poles are part of the profile (all but PBD).
    pub analytic: bool,
    /// The tabulated part, if any.
    pub table: Option<Table32>,
}

impl ProfileLanes {
    /// Per-channel `[sigma_tr, z_r, z_v, k, off_r, off_v, inv_r_max, r_floor]`, the analytic
    /// flag and the table.
    pub fn new(per_channel: [[f32; 3]; 8], analytic: bool, table: Option<Table32>) -> Self {
        ProfileLanes {
            batch: Lanes::new(per_channel, batch_channel),
            single: Lanes::new(per_channel, single_channel),
            channel: [
                Lanes::new(per_channel, |_| 0),
                Lanes::new(per_channel, |_| 1),
                Lanes::new(per_channel, |_| 2),
            ],
            analytic,
            table,
        }
    }
}

/// One source's term of `R_d`, `z (1 + σ s) e^{-σ s} / s³`, from the squared distance `s2`.
#[inline(always)]
fn pole<M: Madd>(z: f32, sigma_tr: f32, s2: f32) -> f32 {
    let s = s2.sqrt();
    z * M::madd(sigma_tr, s, 1.0) * exp_neg_with::<M>(-sigma_tr * s) / (s2 * s)
}

/// `|a - b|²`, summed in glam's order.
#[inline(always)]
fn dist2<M: Madd>(a: Vec3, b: Vec3) -> f32 {
    let d = a - b;
    M::madd(d.z, d.z, M::madd(d.y, d.y, d.x * d.x))
}

/// `area R` over `N` lanes (`N ≤ W`) with coefficients `l`, lane `i` at squared distances `s2_r[i]`, `s2_v[i]` from its real and virtual poles, scaled by
/// `area[i]`.
#[inline(always)]
fn lanes<M: Madd, const N: usize, const W: usize>(
    k: &ProfileLanes,
    l: &Lanes<W>,
    s2_r: &[f32; N],
    s2_v: &[f32; N],
    area: &[f32; N],
) -> [f32; N] {
    const { assert!(N <= W) };
    let mut out = [0.0f32; N];
    if k.analytic {
        for i in 0..N {
            let sig = l.sigma_tr[i];
            out[i] = l.k[i]
                * (pole::<M>(l.z_r[i], sig, s2_r[i] + l.off_r[i])
                    + pole::<M>(l.z_v[i], sig, s2_v[i] + l.off_v[i]));
        }
    }
    if let Some(t) = &k.table {
        for i in 0..N {
            out[i] += radial::<M, W>(t, l, i, s2_r[i]);
        }
    }
    for i in 0..N {
        out[i] *= area[i];
    }
    out
}

/// A batch's lanes (`N` of 12 or 16, channel-major) from their poles and points.
#[inline(always)]
fn batch<M: Madd, const N: usize>(
    k: &ProfileLanes,
    pole_r: impl Fn(usize, usize) -> Vec3,
    pole_v: impl Fn(usize, usize) -> Vec3,
    p: impl Fn(usize) -> Vec3,
    area: impl Fn(usize) -> f32,
) -> [[f32; 3]; 4] {
    let (mut s2_r, mut s2_v, mut a) = ([1.0f32; N], [1.0f32; N], [0.0f32; N]);
    for c in 0..3 {
        for j in 0..4 {
            s2_r[4 * c + j] = dist2::<M>(pole_r(j, c), p(j));
            a[4 * c + j] = area(j);
        }
    }
    // A table alone (PBD) needs only the distance to the receiver point.
    if k.analytic {
        for c in 0..3 {
            for j in 0..4 {
                s2_v[4 * c + j] = dist2::<M>(pole_v(j, c), p(j));
            }
        }
    }
    let v = lanes::<M, N, WIDTH>(k, &k.batch, &s2_r, &s2_v, &a);
    std::array::from_fn(|j| [v[j], v[4 + j], v[8 + j]])
}

/// `A R` from one receiver's poles to four points (areas 0 pad).
#[inline(always)]
pub(super) fn to_points<M: Madd, const N: usize>(
    k: &ProfileLanes,
    src: &ReceiverSources,
    p: &[Vec3; 4],
    area: &[f32; 4],
) -> [[f32; 3]; 4] {
    batch::<M, N>(k, |_, c| src.x_r[c], |_, c| src.x_v[c], |j| p[j], |j| area[j])
}

/// `A R` from four receivers' poles to one point.
#[inline(always)]
pub(super) fn from_point<M: Madd, const N: usize>(
    k: &ProfileLanes,
    src: &[ReceiverSources; 4],
    p: Vec3,
    area: f32,
) -> [[f32; 3]; 4] {
    batch::<M, N>(k, |j, c| src[j].x_r[c], |j, c| src[j].x_v[c], |_| p, |_| area)
}

/// `A R` from one receiver's poles to one point (`N` of 3 or 4).
#[inline(always)]
pub(super) fn to_point<M: Madd, const N: usize>(
    k: &ProfileLanes,
    src: &ReceiverSources,
    p: Vec3,
    area: f32,
) -> [f32; 3] {
    let s2_r = std::array::from_fn(|i| dist2::<M>(src.x_r[single_channel(i)], p));
    let s2_v = std::array::from_fn(|i| dist2::<M>(src.x_v[single_channel(i)], p));
    let v = lanes::<M, N, 4>(k, &k.single, &s2_r, &s2_v, &[area; N]);
    [v[0], v[1], v[2]]
}

/// The kernels compiled for one instruction set: `#[target_feature]` copies of the generic
/// ones above, with fused multiply-adds.
macro_rules! isa_kernels {
    ($name:ident, $features:literal) => {
        #[cfg(target_arch = "x86_64")]
        pub(super) mod $name {
            use super::{ProfileLanes, ReceiverSources, WIDTH};
            use crate::simd::Fused;
            use glam::Vec3;

            #[target_feature(enable = $features)]
            pub(in crate::solver) fn to_points(
                k: &ProfileLanes,
                src: &ReceiverSources,
                p: &[Vec3; 4],
                area: &[f32; 4],
            ) -> [[f32; 3]; 4] {
                super::to_points::<Fused, WIDTH>(k, src, p, area)
            }

            #[target_feature(enable = $features)]
            pub(in crate::solver) fn from_point(
                k: &ProfileLanes,
                src: &[ReceiverSources; 4],
                p: Vec3,
                area: f32,
            ) -> [[f32; 3]; 4] {
                super::from_point::<Fused, WIDTH>(k, src, p, area)
            }

            #[target_feature(enable = $features)]
            pub(in crate::solver) fn to_point(
                k: &ProfileLanes,
                src: &ReceiverSources,
                p: Vec3,
                area: f32,
            ) -> [f32; 3] {
                super::to_point::<Fused, 4>(k, src, p, area)
            }
        }
    };
}

isa_kernels!(avx2, "avx2,fma,f16c");
#[cfg(target_arch = "x86_64")]
pub(super) use super::point_kernel_avx512 as avx512;
