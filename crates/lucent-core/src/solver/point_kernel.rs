//! The one-point estimate kernel (Mertens et al. 2003, §4.2: the far-field coefficient
//! `A_E R_d(x_E, x_o)`, and the transport oracle's estimates of §5.2), written once over
//! lanes and compiled per instruction set ([`crate::simd`]).
//!
//! A batch is four points × three channels, lane `3 j + c` being point `j`, channel `c`:
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
//! receivers give one channel the same bits on one path; the paths differ only by fused
//! multiply-adds (see [`crate::simd`]).

use super::point_sample::ReceiverSources;
use crate::bssrdf::profile::TABLE_SIZE;
use crate::fastexp::exp_neg_with;
use crate::simd::Madd;
use glam::Vec3;

/// Lanes of the vector paths' batch (twelve used).
pub(super) const WIDTH: usize = 16;

/// A profile's per-channel coefficients repeated over [`WIDTH`] lanes (lane `i`: channel
/// `i % 3`; see `DipoleF32` for their meaning).
#[derive(Clone, Copy, Debug)]
pub(super) struct Lanes {
    pub sigma_tr: [f32; WIDTH],
    pub z_r: [f32; WIDTH],
    pub z_v: [f32; WIDTH],
    pub k: [f32; WIDTH],
    pub off_r: [f32; WIDTH],
    pub off_v: [f32; WIDTH],
}

impl Lanes {
    /// Per-channel values `[sigma_tr, z_r, z_v, k, off_r, off_v]` over the lanes.
    pub fn new(per_channel: [[f32; 3]; 6]) -> Self {
        let rep = |a: [f32; 3]| std::array::from_fn(|i| a[i % 3]);
        let [sigma_tr, z_r, z_v, k, off_r, off_v] = per_channel.map(rep);
        Lanes { sigma_tr, z_r, z_v, k, off_r, off_v }
    }
}

/// A tabulated profile in `f32`: `r R(r)` per channel on the grid of
/// [`crate::bssrdf::RadialTable`] (`r = r_max x²`, linear in `x`).
#[derive(Clone, Debug)]
pub(super) struct TableF32 {
    /// Per channel, `TABLE_SIZE + 1` samples (the last 0); fixed size, so that a clamped
    /// index needs no bounds check.
    pub values: Box<[[f32; TABLE_SIZE + 1]; 3]>,
    pub inv_r_max: [f32; 3],
    pub r_floor: [f32; 3],
}

impl TableF32 {
    /// `R(r)` in channel `c` from the squared distance `s2` to the receiver point; 0 beyond
    /// `r_max` (and for NaN).
    #[inline(always)]
    fn radial<M: Madd>(&self, c: usize, s2: f32) -> f32 {
        const N: f32 = TABLE_SIZE as f32;
        // Adding 1.5 · 2^23 rounds to an integer in the mantissa: `x - 0.5` to nearest is
        // `floor(x)` but at integers, where the neighbouring cell interpolates the same value.
        const ROUND: f32 = 12_582_912.0;
        let r = s2.sqrt();
        let x = (r * self.inv_r_max[c]).sqrt() * N;
        let inside = x < N;
        let x = if inside { x } else { 0.0 };
        let shifted = (x - 0.5) + ROUND;
        let i = (shifted.to_bits().wrapping_sub(ROUND.to_bits()) as usize).min(TABLE_SIZE - 1);
        let f = x - (shifted - ROUND);
        let t = &self.values[c];
        let w = M::madd(t[i], 1.0 - f, t[i + 1] * f);
        if inside { w / r.max(self.r_floor[c]) } else { 0.0 }
    }
}

/// What a batch needs of the profile (a part of `DipoleF32`).
#[derive(Clone, Debug)]
pub(super) struct Profile32 {
    pub lanes: Lanes,
    /// Whether the analytic poles are part of the profile (all but PBD).
    pub analytic: bool,
    /// The tabulated part, if any.
    pub table: Option<TableF32>,
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

/// `area R` over `N` lanes (`N ≤ WIDTH`), lane `i` from the real and virtual poles
/// `x_r(i)`, `x_v(i)` of its channel to the point `p(i)` of area `area(i)`.
#[inline(always)]
fn lanes<M: Madd, const N: usize>(
    k: &Profile32,
    x_r: impl Fn(usize) -> Vec3,
    x_v: impl Fn(usize) -> Vec3,
    p: impl Fn(usize) -> Vec3,
    area: impl Fn(usize) -> f32,
) -> [f32; N] {
    const { assert!(N <= WIDTH) };
    let l = &k.lanes;
    let (mut s2_r, mut s2_v, mut out) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for i in 0..N {
        s2_r[i] = dist2::<M>(x_r(i), p(i));
        s2_v[i] = dist2::<M>(x_v(i), p(i));
    }
    if k.analytic {
        for i in 0..N {
            let sig = l.sigma_tr[i];
            out[i] = l.k[i]
                * (pole::<M>(l.z_r[i], sig, s2_r[i] + l.off_r[i]) + pole::<M>(l.z_v[i], sig, s2_v[i] + l.off_v[i]));
        }
    }
    if let Some(t) = &k.table {
        for i in 0..N {
            out[i] += t.radial::<M>(i % 3, s2_r[i]);
        }
    }
    for i in 0..N {
        out[i] *= area(i);
    }
    out
}

/// Point `j` of lane `i` (the padding lanes repeat the last point).
#[inline(always)]
fn point_of(i: usize) -> usize {
    (i / 3).min(3)
}

#[inline(always)]
fn unpack<const N: usize>(v: [f32; N]) -> [[f32; 3]; 4] {
    std::array::from_fn(|j| [v[3 * j], v[3 * j + 1], v[3 * j + 2]])
}

/// `A R` from one receiver's poles to four points (areas 0 pad).
#[inline(always)]
pub(super) fn to_points<M: Madd, const N: usize>(
    k: &Profile32,
    src: &ReceiverSources,
    p: &[Vec3; 4],
    area: &[f32; 4],
) -> [[f32; 3]; 4] {
    let a = |i: usize| if i < 12 { area[point_of(i)] } else { 0.0 };
    unpack(lanes::<M, N>(k, |i| src.x_r[i % 3], |i| src.x_v[i % 3], |i| p[point_of(i)], a))
}

/// `A R` from four receivers' poles to one point.
#[inline(always)]
pub(super) fn from_point<M: Madd, const N: usize>(
    k: &Profile32,
    src: &[ReceiverSources; 4],
    p: Vec3,
    area: f32,
) -> [[f32; 3]; 4] {
    let a = |i: usize| if i < 12 { area } else { 0.0 };
    unpack(lanes::<M, N>(k, |i| src[point_of(i)].x_r[i % 3], |i| src[point_of(i)].x_v[i % 3], |_| p, a))
}

/// `A R` from one receiver's poles to one point.
#[inline(always)]
pub(super) fn to_point<M: Madd, const N: usize>(k: &Profile32, src: &ReceiverSources, p: Vec3, area: f32) -> [f32; 3] {
    let v = lanes::<M, N>(k, |i| src.x_r[i % 3], |i| src.x_v[i % 3], |_| p, |_| area);
    [v[0], v[1], v[2]]
}

/// The kernels compiled for one instruction set: `#[target_feature]` copies of the generic
/// ones above, with fused multiply-adds.
macro_rules! isa_kernels {
    ($name:ident, $features:literal) => {
        #[cfg(target_arch = "x86_64")]
        pub(super) mod $name {
            use super::{Profile32, ReceiverSources, WIDTH};
            use crate::simd::Fused;
            use glam::Vec3;

            #[target_feature(enable = $features)]
            pub(in crate::solver) fn to_points(
                k: &Profile32,
                src: &ReceiverSources,
                p: &[Vec3; 4],
                area: &[f32; 4],
            ) -> [[f32; 3]; 4] {
                super::to_points::<Fused, WIDTH>(k, src, p, area)
            }

            #[target_feature(enable = $features)]
            pub(in crate::solver) fn from_point(
                k: &Profile32,
                src: &[ReceiverSources; 4],
                p: Vec3,
                area: f32,
            ) -> [[f32; 3]; 4] {
                super::from_point::<Fused, WIDTH>(k, src, p, area)
            }

            #[target_feature(enable = $features)]
            pub(in crate::solver) fn to_point(k: &Profile32, src: &ReceiverSources, p: Vec3, area: f32) -> [f32; 3] {
                super::to_point::<Fused, 4>(k, src, p, area)
            }
        }
    };
}

isa_kernels!(avx2, "avx2,fma,f16c");
isa_kernels!(avx512, "avx512f,avx512vl,avx2,fma,f16c");
