//! Stored links' transport coefficients, 16 bits per channel, and render mode's gather kernel
//! over them (driven by `solver::hierarchical::gather`).
//!
//! Render mode (Mertens et al. 2003, §5.5) is a gather `Σ E_e F_re` over millions of stored
//! links, every frame. A coefficient is kept as IEEE binary16 per channel ([`LinkCoef`]),
//! relative to a power-of-two scale per receiver ([`receiver_scale`]) that puts the
//! receiver's largest coefficient in `[2^14, 2^15)`. The scale is what makes half floats
//! usable: `F` usually stays below `R_d_total` < 1, but where a receiver's dipole source lies
//! just under an emitter on the far side of a thin part, the (exact) form factor reaches into
//! the thousands, and far links fall to `1e-20`; half floats alone span only 40 octaves.
//!
//! Error: coefficients at least `2^-28` times the receiver's largest keep 10 mantissa bits
//! (relative error at most [`MAX_REL_ERROR`] = `2^-11` ≈ 4.9e-4, twenty times below the
//! solver's 1% accuracy target); smaller ones are subnormal half floats with an absolute error
//! of at most `2^-39` times the largest. The terms of the sum are non-negative, so the same
//! bounds hold for `B`.
//!
//! The gather runs on [`Isa::best`]'s instruction set: AVX-512 converts four links' halves
//! in one instruction and fuses four multiply-adds in one 512-bit register, AVX2 two in a
//! 256-bit one (both with F16C and FMA); the portable path decodes the halves with integer
//! shifts (exact, as the hardware conversion), one link per 128-bit operation. Each keeps two
//! running sums, as one is bound by the add's latency. A link is 12 bytes streamed (emitter
//! word and coefficients) plus a 16-byte fetch of the emitter's `E` at an index read from the
//! stream. The gather is bound by memory, not arithmetic: by the dependent fetch of `E`, and
//! by the loads of the streams themselves, as a receiver's run is short (tens of links) and
//! the hardware prefetchers start over at each; so the gathers ask for the lines
//! [`PREFETCH_LINKS`] links ahead (`benches/kernel.rs` measures the paths). The wider paths gain
//! little; fewer links (or fewer bytes a link) are what would speed render mode up further.

use crate::simd::Isa;
use glam::Vec3A;

/// Flag in a link's emitter word marking a link evaluated with the form factor; the other
/// bits are the emitter cluster.
pub(crate) const FF_BIT: u32 = 1 << 31;

/// Half-float bits below the `f32` mantissa's top 10 bits.
const SHIFT: u32 = 13;

/// `2^112`: rescales an `f32` whose bits are a half float's shifted up by [`SHIFT`] (exponent
/// bias 127 instead of 15) to the half float's value, subnormals included.
pub(super) const HALF_RESCALE: f32 = f32::from_bits((127 + 112) << 23);

/// Smallest normal half float, `2^-14`.
const HALF_MIN_NORMAL: f32 = 1.0 / 16384.0;

/// Largest finite half float.
const HALF_MAX: f32 = 65504.0;

/// Largest relative rounding error of a coefficient at least `2^-28` times its receiver's
/// largest.
pub const MAX_REL_ERROR: f32 = 1.0 / 2048.0;

/// Largest absolute rounding error of any coefficient, relative to its receiver's largest.
pub const MAX_ABS_ERROR: f32 = 1.0 / (1u64 << 39) as f32;

/// The scale of a receiver whose largest coefficient (over links and channels) is `max`: the
/// power of two that maps `max` into `[2^14, 2^15)`, or 1 where `max` is 0 (or not finite).
pub fn receiver_scale(max: f32) -> f32 {
    if !(max.is_finite() && max >= f32::MIN_POSITIVE) {
        return 1.0;
    }
    // `max` is normal: its exponent field is floor(log2(max)) + 127.
    let field = ((max.to_bits() >> 23) as i32 - 14).max(1);
    f32::from_bits((field as u32) << 23)
}

/// A link's transport coefficient per channel (unitless, `F(E, x_R)` of Mertens eq. 6) as
/// IEEE half floats relative to its receiver's scale (see the module documentation), and in
/// the fourth lane its steepness across the receiver (`oracle::Samples::slope`, unitless,
/// as a half float of its own: no scale), so that eight aligned bytes load into one
/// register. The gather kernels multiply the fourth lane too; its product lands in the
/// fourth lane of `B`, which nothing reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Zeroable)]
#[repr(C, align(8))]
pub struct LinkCoef([u16; 4]);

impl LinkCoef {
    /// Packs `f` relative to `scale` (a power of two, from [`receiver_scale`]), rounding to
    /// nearest; negative and NaN values (numerical noise of a form factor that is 0) become 0,
    /// values above the half float range saturate.
    #[inline]
    pub fn pack(f: Vec3A, scale: f32) -> Self {
        Self::pack_with_slope(f, scale, 0.0)
    }

    /// [`LinkCoef::pack`] with the link's steepness `slope` (>= 0; see the type).
    #[inline]
    pub fn pack_with_slope(f: Vec3A, scale: f32, slope: f32) -> Self {
        let y = f / scale;
        LinkCoef([half_bits(y.x), half_bits(y.y), half_bits(y.z), half_bits(slope)])
    }

    /// The link's steepness across its receiver (0 for a receiver taken as one value).
    #[inline]
    pub fn slope(self) -> f32 {
        half_value(self.0[3])
    }

    /// The coefficient per channel, given its receiver's scale.
    #[inline]
    pub fn unpack(self, scale: f32) -> Vec3A {
        let h = |c: usize| half_value(self.0[c]);
        Vec3A::new(h(0), h(1), h(2)) * scale
    }
}

/// `s` rounded to the half float it is stored as (see [`LinkCoef`]), so that the oracle
/// tests the steepness the gather will use.
#[inline]
pub(crate) fn round_slope(s: f32) -> f32 {
    half_value(half_bits(s))
}

/// The value of the half float with bits `h`.
#[inline]
fn half_value(h: u16) -> f32 {
    f32::from_bits((h as u32) << SHIFT) * HALF_RESCALE
}

/// The half float nearest `y` (`y` ≥ 0, below the largest half float), as bits.
#[inline]
fn half_bits(y: f32) -> u16 {
    if y.is_nan() || y <= 0.0 {
        0
    } else if y >= HALF_MAX {
        0x7bff
    } else if y < HALF_MIN_NORMAL {
        // Subnormal: multiples of 2^-24 (2^10 of them is the smallest normal's encoding).
        (y * (1u32 << 24) as f32).round() as u16
    } else {
        // Rebias the exponent and round the mantissa to 10 bits (ties away from zero).
        ((y.to_bits() - (112 << 23) + (1 << (SHIFT - 1))) >> SHIFT) as u16
    }
}

/// How many links ahead of the one being gathered the gathers ask for the streams' cache
/// lines (2 KiB of coefficients): the hardware prefetchers lose the streams at every
/// receiver's start, as a run is short. Far fewer gains little; more gains nothing.
pub(super) const PREFETCH_LINKS: usize = 256;

/// Asks for the cache lines of link `k + PREFETCH_LINKS` of both streams; `k` may run past
/// the slices' ends (the next receivers' runs lie there), as a prefetch reads nothing
/// architecturally.
#[inline(always)]
pub(super) fn prefetch_links(emitter: &[u32], coef: &[LinkCoef], k: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let ahead = k + PREFETCH_LINKS;
        // SAFETY: a prefetch is a hint: it never faults and changes no memory, whatever the
        // address (the pointers are formed with wrapping arithmetic and never dereferenced).
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(emitter.as_ptr().wrapping_add(ahead).cast());
            _mm_prefetch::<_MM_HINT_T0>(coef.as_ptr().wrapping_add(ahead).cast());
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (emitter, coef, k);
}

/// One receiver's `Σ E F` before its scale (`emitter` and `coef` its links), on
/// [`Isa::best`]'s instruction set: render mode's gather. Unlike [`gather_sum`] it asks the CPU
/// nothing per call (feature tests per receiver are a measurable share of a frame).
#[inline]
pub(crate) fn gather_sum_best(e_node: &[Vec3A], emitter: &[u32], coef: &[LinkCoef]) -> Vec3A {
    match Isa::best() {
        // SAFETY: `Isa::best` is an instruction set this CPU has (AVX-512 F/VL, AVX2, FMA, F16C).
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => unsafe { wide::sum_avx512(e_node, emitter, coef) },
        // SAFETY: as above (AVX2, FMA, F16C).
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { wide::sum_avx2(e_node, emitter, coef) },
        _ => gather_one(e_node, emitter, coef),
    }
}

/// One receiver's `Σ E F` before its scale (`emitter` and `coef` its links), on `isa` if this
/// CPU has it (else the portable path): the gather's inner loop, public for the benches.
pub fn gather_sum(isa: Isa, e_node: &[Vec3A], emitter: &[u32], coef: &[LinkCoef]) -> Vec3A {
    match isa {
        // SAFETY: checked here that this CPU has the instruction set.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if isa.is_available() => unsafe { wide::sum_avx512(e_node, emitter, coef) },
        // SAFETY: as above.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if isa.is_available() => unsafe { wide::sum_avx2(e_node, emitter, coef) },
        _ => gather_one(e_node, emitter, coef),
    }
}

/// One receiver's `Σ E F`, before its scale: halves decoded by shifts, two running sums.
#[inline]
fn gather_one(e_node: &[Vec3A], emitter: &[u32], coef: &[LinkCoef]) -> Vec3A {
    let term = |e: u32, c: LinkCoef| e_node[(e & !FF_BIT) as usize] * decode(c);
    let (mut s0, mut s1) = (Vec3A::ZERO, Vec3A::ZERO);
    for (k, (e, c)) in emitter.chunks_exact(2).zip(coef.chunks_exact(2)).enumerate() {
        if k % 4 == 0 {
            prefetch_links(emitter, coef, 2 * k);
        }
        s0 += term(e[0], c[0]);
        s1 += term(e[1], c[1]);
    }
    if emitter.len() % 2 == 1 {
        s0 += term(emitter[emitter.len() - 1], coef[coef.len() - 1]);
    }
    s0 + s1
}

/// The three half floats of `c` as one SIMD vector (its fourth lane the steepness), exactly,
/// before the receiver's scale.
#[inline]
pub(crate) fn decode(c: LinkCoef) -> Vec3A {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        let bits = u64::from_le_bytes(bytemuck::cast(c.0));
        // SAFETY: SSE2 register operations (no memory access); SSE2 is in the x86-64 baseline.
        let f = unsafe {
            let x = _mm_unpacklo_epi16(_mm_cvtsi64_si128(bits as i64), _mm_setzero_si128());
            let f = _mm_castsi128_ps(_mm_slli_epi32::<{ SHIFT as i32 }>(x));
            _mm_mul_ps(f, _mm_set1_ps(HALF_RESCALE))
        };
        Vec3A::from(f)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        c.unpack(1.0)
    }
}

#[cfg(target_arch = "x86_64")]
mod wide {
    use super::{FF_BIT, LinkCoef, prefetch_links};
    use glam::Vec3A;
    use std::arch::x86_64::*;

    /// `E` of the link with emitter word `e`, as a 128-bit vector (fourth lane 0).
    #[inline(always)]
    fn e_of(e_node: &[Vec3A], e: u32) -> __m128 {
        e_node[(e & !FF_BIT) as usize].into()
    }

    /// One receiver's `Σ E F` (before its scale), two links per 256-bit operation.
    #[inline]
    #[target_feature(enable = "avx2,fma,f16c")]
    pub(super) fn sum_avx2(e_node: &[Vec3A], emitter: &[u32], coef: &[LinkCoef]) -> Vec3A {
        let n = emitter.len().min(coef.len());
        let (mut s0, mut s1) = (_mm256_setzero_ps(), _mm256_setzero_ps());
        let mut k = 0;
        while k + 4 <= n {
            prefetch_links(emitter, coef, k);
            // SAFETY: `k + 4 <= coef.len()`, so both 16-byte reads lie inside `coef`; the CPU
            // has AVX2, FMA and F16C (this function's features, checked by the caller).
            let (c0, c1) = unsafe {
                let p = coef.as_ptr().add(k) as *const __m128i;
                (_mm256_cvtph_ps(_mm_loadu_si128(p)), _mm256_cvtph_ps(_mm_loadu_si128(p.add(1))))
            };
            let e0 = _mm256_insertf128_ps::<1>(
                _mm256_castps128_ps256(e_of(e_node, emitter[k])),
                e_of(e_node, emitter[k + 1]),
            );
            let e1 = _mm256_insertf128_ps::<1>(
                _mm256_castps128_ps256(e_of(e_node, emitter[k + 2])),
                e_of(e_node, emitter[k + 3]),
            );
            s0 = _mm256_fmadd_ps(e0, c0, s0);
            s1 = _mm256_fmadd_ps(e1, c1, s1);
            k += 4;
        }
        let s = _mm256_add_ps(s0, s1);
        let mut t = _mm_add_ps(_mm256_castps256_ps128(s), _mm256_extractf128_ps::<1>(s));
        for j in k..n {
            t = _mm_fmadd_ps(e_of(e_node, emitter[j]), half4(coef[j]), t);
        }
        Vec3A::from(t)
    }

    /// One receiver's `Σ E F` (before its scale), four links per 512-bit operation.
    #[inline]
    #[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
    pub(super) fn sum_avx512(e_node: &[Vec3A], emitter: &[u32], coef: &[LinkCoef]) -> Vec3A {
        let n = emitter.len().min(coef.len());
        let (mut s0, mut s1) = (_mm512_setzero_ps(), _mm512_setzero_ps());
        let mut k = 0;
        while k + 8 <= n {
            prefetch_links(emitter, coef, k);
            // SAFETY: `k + 8 <= coef.len()`, so both 32-byte reads lie inside `coef`; the CPU
            // has AVX-512 F and F16C (this function's features, checked by the caller).
            let (c0, c1) = unsafe {
                let p = coef.as_ptr().add(k) as *const __m256i;
                (_mm512_cvtph_ps(_mm256_loadu_si256(p)), _mm512_cvtph_ps(_mm256_loadu_si256(p.add(1))))
            };
            s0 = _mm512_fmadd_ps(quad(e_node, &emitter[k..k + 4]), c0, s0);
            s1 = _mm512_fmadd_ps(quad(e_node, &emitter[k + 4..k + 8]), c1, s1);
            k += 8;
        }
        let s = _mm512_add_ps(s0, s1);
        let lo = _mm_add_ps(_mm512_castps512_ps128(s), _mm512_extractf32x4_ps::<1>(s));
        let hi = _mm_add_ps(_mm512_extractf32x4_ps::<2>(s), _mm512_extractf32x4_ps::<3>(s));
        let mut t = _mm_add_ps(lo, hi);
        for j in k..n {
            t = _mm_fmadd_ps(e_of(e_node, emitter[j]), half4(coef[j]), t);
        }
        Vec3A::from(t)
    }

    /// `E` of four links' emitters (`emitter.len() == 4`) in one 512-bit register.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn quad(e_node: &[Vec3A], emitter: &[u32]) -> __m512 {
        let e = |m: usize| e_of(e_node, emitter[m]);
        let lo = _mm512_insertf32x4::<1>(_mm512_castps128_ps512(e(0)), e(1));
        _mm512_insertf32x4::<3>(_mm512_insertf32x4::<2>(lo, e(2)), e(3))
    }

    /// The four half floats of `c` in hardware.
    #[inline]
    #[target_feature(enable = "f16c")]
    fn half4(c: LinkCoef) -> __m128 {
        let bits = u64::from_le_bytes(bytemuck::cast(c.0));
        _mm_cvtph_ps(_mm_cvtsi64_si128(bits as i64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::link_set::{Span, StoredLinks};

    #[test]
    fn round_trip_is_within_the_stated_error() {
        for max in [1e-20f32, 3e-7, 0.37, 1.0, 5000.0, 3e7] {
            let scale = receiver_scale(max);
            let top = max / scale;
            assert!((16384.0..32768.0).contains(&top), "{max:e}: {top}");
            let mut x = max;
            while x > max * 1e-14 {
                for t in [1.0f32, 0.999_9, 0.77, 0.500_1, 0.5] {
                    let v = x * t;
                    let p = LinkCoef::pack(Vec3A::new(v, 0.5 * v, 0.25 * v), scale);
                    let got = p.unpack(scale);
                    assert_eq!(decode(p) * scale, got);
                    let err = (got.x - v).abs();
                    let bound =
                        if v >= max / (1u32 << 28) as f32 { MAX_REL_ERROR * v } else { MAX_ABS_ERROR * max };
                    assert!(err <= bound, "max {max:e}: {v:e} -> {:e}", got.x);
                }
                x *= 0.5;
            }
        }
    }

    #[test]
    fn edge_values() {
        assert_eq!(LinkCoef::pack(Vec3A::new(0.0, -1.0, f32::NAN), 1.0).unpack(1.0), Vec3A::ZERO);
        assert_eq!(receiver_scale(0.0), 1.0);
        assert_eq!(receiver_scale(f32::INFINITY), 1.0);
        // Saturates at the largest half float.
        assert_eq!(
            LinkCoef::pack(Vec3A::new(1e9, f32::INFINITY, 65504.0), 1.0).unpack(1.0),
            Vec3A::splat(65504.0)
        );
        // Exactly representable values survive unchanged, so re-packing is lossless, also
        // under another receiver's scale while they stay normal.
        for v in [1.0f32, 0.5, 0.75, 3.0 / 1024.0, 1.0 / (1u32 << 24) as f32] {
            let p = LinkCoef::pack(Vec3A::splat(v), 1.0);
            assert_eq!(p.unpack(1.0), Vec3A::splat(v));
            assert_eq!(decode(p), Vec3A::splat(v));
            assert_eq!(LinkCoef::pack(p.unpack(1.0), 1.0), p);
        }
        let p = LinkCoef::pack(Vec3A::splat(0.75), 2.0);
        assert_eq!(LinkCoef::pack(p.unpack(2.0), 0.25).unpack(0.25), Vec3A::splat(0.75));
    }

    /// The gather on every instruction set this CPU has against an `f64` sum.
    #[test]
    fn gather_matches_a_double_precision_sum() {
        let e_node: Vec<Vec3A> =
            (0..50).map(|i| Vec3A::new(1.0 + i as f32, 0.5, 2.0 / (1.0 + i as f32))).collect();
        let mut spans = vec![];
        let (mut emitter, mut coef, mut scale, mut want) = (vec![], vec![], vec![], vec![]);
        for r in 0..20usize {
            let f: Vec<Vec3A> = (0..r).map(|j| Vec3A::new(0.3, 1e-3, 7.0) / (1.0 + (j * j) as f32)).collect();
            let s = receiver_scale(f.iter().map(|v| v.max_element()).fold(0.0, f32::max));
            let mut sum = [0f64; 3];
            for (j, v) in f.iter().enumerate() {
                let e = (7 * j + r) % e_node.len();
                let c = LinkCoef::pack(*v, s);
                let u = c.unpack(s);
                for k in 0..3 {
                    sum[k] += e_node[e][k] as f64 * u[k] as f64;
                }
                emitter.push(e as u32 | if j % 3 == 0 { FF_BIT } else { 0 });
                coef.push(c);
            }
            spans.push(Span::base(emitter.len() - r, r));
            scale.push(s);
            want.push(sum);
        }
        let links = StoredLinks::single(&spans, &emitter, &coef, &scale);
        let per_isa: Vec<Vec<Vec3A>> = Isa::available()
            .into_iter()
            .map(|isa| {
                (0..20)
                    .map(|r| {
                        let (e, c, s) = links.of(r);
                        gather_sum(isa, &e_node, e, c) * s
                    })
                    .collect()
            })
            .collect();
        for r in 0..20 {
            for k in 0..3 {
                for got in per_isa.iter().map(|v| v[r][k]) {
                    assert!(
                        (got as f64 - want[r][k]).abs() <= 1e-6 * want[r][k],
                        "receiver {r}: {got} vs {}",
                        want[r][k]
                    );
                }
            }
        }
    }

    /// A link's steepness rides in the fourth lane without touching its coefficient, and
    /// every gather path gives the same `B` with and without it (its product lands in the
    /// fourth lane of the sum, which nothing reads), whatever the irradiance's fourth lane.
    #[test]
    fn steepness_leaves_coefficients_and_gathers_unchanged() {
        let f = Vec3A::new(0.3, 1e-3, 7.0);
        let scale = receiver_scale(7.0);
        for s in [0.0f32, 0.37, 3.0, 41.5, 6.0e4] {
            let c = LinkCoef::pack_with_slope(f, scale, s);
            assert_eq!(c.unpack(scale), LinkCoef::pack(f, scale).unpack(scale));
            assert_eq!(c.slope(), round_slope(s));
            assert!((c.slope() - s).abs() <= s * MAX_REL_ERROR);
        }
        // Irradiance whose fourth lane is not 0 (glam's `Vec3A::new` repeats z there).
        let e_node: Vec<Vec3A> = (0..9).map(|i| Vec3A::new(1.0 + i as f32, 0.5, 3.0e4)).collect();
        let emitter: Vec<u32> = (0..9).map(|j| (5 * j % 9) as u32).collect();
        let flat: Vec<LinkCoef> = (0..9).map(|j| LinkCoef::pack(f / (1.0 + j as f32), scale)).collect();
        let steep: Vec<LinkCoef> =
            (0..9).map(|j| LinkCoef::pack_with_slope(f / (1.0 + j as f32), scale, 1e3 * j as f32)).collect();
        for isa in Isa::available() {
            let a = gather_sum(isa, &e_node, &emitter, &flat);
            let b = gather_sum(isa, &e_node, &emitter, &steep);
            assert_eq!(a.to_array(), b.to_array(), "{isa:?}");
        }
    }
}
