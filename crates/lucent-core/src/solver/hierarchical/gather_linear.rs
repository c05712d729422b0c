//! Render mode's gather into an inner receiver with a linear or curved expansion (Mertens et
//! al. 2003, §5.5, with the receiver expansion of [`super::expansion`]): `B` at the receiver's
//! midpoint, its gradient and, for curved receivers, its Hessian, summed over the receiver's
//! stored links. Each link adds its term `t = E_e F` (per channel) and, where it is steep
//! (`s > 0`, its steepness across the receiver), `t k δ` to the gradient and `t w δδᵀ + t k I`
//! to the Hessian, with `δ` the line from the emitter's midpoint to the receiver's,
//! `k = -s / |δ|²` and `w = (s² + s + a) / |δ|⁴` ([`crate::solver::oracle::curvature_along`]).
//!
//! That is ten numbers a channel and link where the plain gather has one, so the portable
//! path, one link at a time in 128-bit vectors, is bound by its arithmetic. The AVX-512 path
//! takes sixteen links a step, one lane each (the emitter's `E` and midpoint by gathers, the
//! coefficients' halves split by shifts), keeps the thirty sums per channel set in registers
//! until the receiver is done, and takes `1 / |δ|²` from `vrcp14ps` and a Newton step rather
//! than the divider.

use super::expansion::{Hess, Linear};
use crate::simd::Isa;
use crate::solver::link_coef::{self, FF_BIT, LinkCoef};
use crate::solver::oracle::curvature_along;
use glam::Vec3A;

/// One inner receiver's expansion `Σ` over its links (emitter words `emitter`, coefficients
/// `coef`), before its scale: value, gradient and (if `curved`) Hessian at its midpoint `m_r`,
/// with `e_node` the clusters' irradiance and `mid` their midpoints; on `isa` where this CPU
/// has it (AVX-512; the portable path otherwise).
pub(super) fn sum_linear(
    isa: Isa,
    e_node: &[Vec3A],
    mid: &[Vec3A],
    emitter: &[u32],
    coef: &[LinkCoef],
    m_r: Vec3A,
    curved: bool,
) -> Linear {
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx512 && isa.is_available() && wide::fits(e_node, mid) {
        // SAFETY: this CPU has AVX-512 F/VL (checked above); `fits` bounds the node count so
        // that the gathers' offsets do not overflow, and the kernel checks every index.
        return unsafe {
            if curved {
                wide::sum_avx512::<true>(e_node, mid, emitter, coef, m_r)
            } else {
                wide::sum_avx512::<false>(e_node, mid, emitter, coef, m_r)
            }
        };
    }
    let _ = isa;
    sum_portable(e_node, mid, emitter, coef, m_r, curved)
}

/// [`sum_linear`] one link at a time, four running sums.
fn sum_portable(
    e_node: &[Vec3A],
    mid: &[Vec3A],
    emitter: &[u32],
    coef: &[LinkCoef],
    m_r: Vec3A,
    curved: bool,
) -> Linear {
    let mut acc = [Linear::default(); 4];
    let term = |acc: &mut Linear, w: u32, c: LinkCoef| {
        let e = (w & !FF_BIT) as usize;
        let t = e_node[e] * link_coef::decode(c);
        acc.value += t;
        acc.add_link(t, c.slope(), m_r - mid[e], curved);
    };
    let n4 = emitter.len() / 4 * 4;
    for (i, (w, c)) in emitter.chunks_exact(4).zip(coef.chunks_exact(4)).enumerate() {
        if i % 2 == 0 {
            link_coef::prefetch_links(emitter, coef, 4 * i);
        }
        for k in 0..4 {
            term(&mut acc[k], w[k], c[k]);
        }
    }
    for (k, (&w, &c)) in emitter[n4..].iter().zip(&coef[n4..]).enumerate() {
        term(&mut acc[k], w, c);
    }
    let [mut sum, a1, a2, a3] = acc;
    sum.add(&a1);
    sum.add(&a2);
    sum.add(&a3);
    sum
}

/// The sums of one channel set, reduced: `value[c]`, `grad[c][j]`, `diag[c][j]` (without
/// the isotropic part), `iso[c]` and `off[c][j]`, assembled into a [`Linear`].
fn assemble(
    value: [f32; 3],
    grad: [[f32; 3]; 3],
    diag: [[f32; 3]; 3],
    iso: [f32; 3],
    off: [[f32; 3]; 3],
) -> Linear {
    let v = |a: [f32; 3]| Vec3A::from_array(a);
    Linear {
        value: v(value),
        grad: grad.map(v),
        hess: Hess { diag: std::array::from_fn(|c| v(diag[c]) + Vec3A::splat(iso[c])), off: off.map(v) },
    }
}

#[cfg(target_arch = "x86_64")]
mod wide {
    use super::{FF_BIT, Linear, LinkCoef, assemble, curvature_along, link_coef};
    use crate::solver::oracle::FALLOFF_POWER;
    use glam::Vec3A;
    use std::arch::x86_64::*;

    /// Whether the node arrays are small enough for the gathers' 32-bit offsets (`4 e + c`).
    pub(super) fn fits(e_node: &[Vec3A], mid: &[Vec3A]) -> bool {
        e_node.len().max(mid.len()) < 1 << 29
    }

    /// [`super::sum_linear`] sixteen links a step; `CURVED` adds the Hessian.
    ///
    /// # Safety
    /// The CPU must have AVX-512 F and VL, and [`fits`] must hold.
    #[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
    pub(super) unsafe fn sum_avx512<const CURVED: bool>(
        e_node: &[Vec3A],
        mid: &[Vec3A],
        emitter: &[u32],
        coef: &[LinkCoef],
        m_r: Vec3A,
    ) -> Linear {
        let n = emitter.len().min(coef.len());
        let len = _mm512_set1_epi32(e_node.len().min(mid.len()) as i32);
        let zero = _mm512_setzero_ps();
        let m = [m_r.x, m_r.y, m_r.z].map(|v| _mm512_set1_ps(v));
        // Sums: value, gradient, Hessian's diagonal, isotropic part and off-diagonal.
        let mut value = [zero; 3];
        let mut grad = [[zero; 3]; 3];
        let mut diag = [[zero; 3]; 3];
        let mut iso = [zero; 3];
        let mut off = [[zero; 3]; 3];
        // Pairs of 32-bit words of sixteen 64-bit coefficients: (x | y << 16) and (z | s << 16).
        let even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
        let odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
        let mut k = 0;
        while k < n {
            // Sixteen links are two cache lines of coefficients.
            link_coef::prefetch_links(emitter, coef, k);
            link_coef::prefetch_links(emitter, coef, k + 8);
            let left = n - k;
            let lanes: __mmask16 = if left >= 16 { !0 } else { (1u16 << left) - 1 };
            // SAFETY: masked loads touch only the lanes of `lanes`, which lie inside
            // `emitter[k..n]` and `coef[k..n]` (sixteen words, sixteen 64-bit coefficients).
            let (words, lo, hi) = unsafe {
                let c = coef.as_ptr().add(k).cast::<i64>();
                (
                    _mm512_maskz_loadu_epi32(lanes, emitter.as_ptr().add(k).cast()),
                    _mm512_maskz_loadu_epi64(lanes as u8, c),
                    _mm512_maskz_loadu_epi64((lanes >> 8) as u8, c.add(8)),
                )
            };
            let e = _mm512_and_si512(words, _mm512_set1_epi32(!FF_BIT as i32));
            // Every emitter must be a node: an index past the arrays would gather outside them.
            assert_eq!(
                _mm512_mask_cmpge_epu32_mask(lanes, e, len),
                0,
                "link to a cluster past the hierarchy"
            );
            let base = _mm512_slli_epi32::<2>(e);
            let at = |c: i32| _mm512_add_epi32(base, _mm512_set1_epi32(c));
            // SAFETY: every gathered lane reads float `4 e + c` (c < 3) of a node `e` below
            // both arrays' length (checked above), and `fits` keeps `4 e + c` within `i32`.
            let (en, md) = unsafe {
                let g = |p: *const Vec3A, c: i32| _mm512_mask_i32gather_ps::<4>(zero, lanes, at(c), p.cast());
                ([0, 1, 2].map(|c| g(e_node.as_ptr(), c)), [0, 1, 2].map(|c| g(mid.as_ptr(), c)))
            };
            let xy = _mm512_permutex2var_epi32(lo, even, hi);
            let zs = _mm512_permutex2var_epi32(lo, odd, hi);
            let f = [half_lo(xy), half_hi(xy), half_lo(zs)];
            let s = half_hi(zs);
            let t = [0, 1, 2].map(|c| _mm512_mul_ps(en[c], f[c]));
            let d = [0, 1, 2].map(|j| _mm512_sub_ps(m[j], md[j]));
            let d2 = _mm512_fmadd_ps(d[0], d[0], _mm512_fmadd_ps(d[1], d[1], _mm512_mul_ps(d[2], d[2])));
            // 1 / |δ|²: a 14-bit estimate and a Newton step (about 1 ulp), not the divider.
            let d2 = _mm512_max_ps(d2, _mm512_set1_ps(f32::MIN_POSITIVE));
            let y = _mm512_rcp14_ps(d2);
            let inv = _mm512_fmadd_ps(y, _mm512_fnmadd_ps(d2, y, _mm512_set1_ps(1.0)), y);
            let kk = _mm512_mul_ps(_mm512_sub_ps(zero, s), inv);
            for c in 0..3 {
                value[c] = _mm512_add_ps(value[c], t[c]);
                let tk = _mm512_mul_ps(t[c], kk);
                for j in 0..3 {
                    grad[c][j] = _mm512_fmadd_ps(d[j], tk, grad[c][j]);
                }
                if CURVED {
                    iso[c] = _mm512_add_ps(iso[c], tk);
                }
            }
            if CURVED {
                // w = (s² + s + a) / |δ|⁴ where s > 0, else 0.
                let q =
                    _mm512_fmadd_ps(s, _mm512_add_ps(s, _mm512_set1_ps(1.0)), _mm512_set1_ps(FALLOFF_POWER));
                debug_assert_eq!(curvature_along(2.0), 2.0 * 2.0 + 2.0 + FALLOFF_POWER);
                let steep = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(s, zero);
                let w = _mm512_maskz_mul_ps(steep, q, _mm512_mul_ps(inv, inv));
                let dd = [0, 1, 2].map(|j| _mm512_mul_ps(d[j], d[j]));
                let dx = [(1, 2), (0, 2), (0, 1)].map(|(a, b)| _mm512_mul_ps(d[a], d[b]));
                for c in 0..3 {
                    let tw = _mm512_mul_ps(t[c], w);
                    for j in 0..3 {
                        diag[c][j] = _mm512_fmadd_ps(dd[j], tw, diag[c][j]);
                        off[c][j] = _mm512_fmadd_ps(dx[j], tw, off[c][j]);
                    }
                }
            }
            k += 16;
        }
        finish::<CURVED>(value, grad, diag, iso, off)
    }

    /// The expansion from [`sum_avx512`]'s per-lane sums of the value, the gradient and the
    /// Hessian's diagonal, isotropic part and off-diagonal: their lanes added up, sixteen
    /// registers at a time (the Hessian's only if `CURVED`).
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn finish<const CURVED: bool>(
        value: [__m512; 3],
        grad: [[__m512; 3]; 3],
        diag: [[__m512; 3]; 3],
        iso: [__m512; 3],
        off: [[__m512; 3]; 3],
    ) -> Linear {
        let mut all = [_mm512_setzero_ps(); 48];
        all[..3].copy_from_slice(&value);
        all[21..24].copy_from_slice(&iso);
        for c in 0..3 {
            all[3 + 3 * c..6 + 3 * c].copy_from_slice(&grad[c]);
            all[12 + 3 * c..15 + 3 * c].copy_from_slice(&diag[c]);
            all[24 + 3 * c..27 + 3 * c].copy_from_slice(&off[c]);
        }
        let groups = if CURVED { 3 } else { 1 };
        let mut t = [0.0f32; 48];
        for g in 0..groups {
            add_lanes(&all[16 * g..16 * g + 16], &mut t[16 * g..16 * g + 16]);
        }
        let three = |k: usize| [t[k], t[k + 1], t[k + 2]];
        let nine = |k: usize| [three(k), three(k + 3), three(k + 6)];
        assemble(three(0), nine(3), nine(12), three(21), nine(24))
    }

    /// `out[i]` = the sum of `v[i]`'s lanes (sixteen registers): 45 shuffles and adds where
    /// sixteen horizontal sums take about 130. Each step adds halves of two registers into
    /// one, so the last holds every sum.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn add_lanes(v: &[__m512], out: &mut [f32]) {
        assert!(v.len() == 16 && out.len() == 16);
        // Quarters of 128 bits: [a0, a1, b0, b1] + [a2, a3, b2, b3]: w[i] holds halves of
        // v[2 i] and v[2 i + 1].
        let mut w = [_mm512_setzero_ps(); 8];
        for i in 0..8 {
            let (a, b) = (v[2 * i], v[2 * i + 1]);
            w[i] = _mm512_add_ps(_mm512_shuffle_f32x4::<0x44>(a, b), _mm512_shuffle_f32x4::<0xee>(a, b));
        }
        // Quarter k of x[i]: four partial sums of v[4 i + k].
        let mut x = [_mm512_setzero_ps(); 4];
        for i in 0..4 {
            let (a, b) = (w[2 * i], w[2 * i + 1]);
            x[i] = _mm512_add_ps(_mm512_shuffle_f32x4::<0x88>(a, b), _mm512_shuffle_f32x4::<0xdd>(a, b));
        }
        // Within quarters: quarter k of y[i] holds two partial sums each of v[8 i + k] and
        // v[8 i + k + 4].
        let mut y = [_mm512_setzero_ps(); 2];
        for i in 0..2 {
            let (a, b) = (x[2 * i], x[2 * i + 1]);
            y[i] = _mm512_add_ps(_mm512_shuffle_ps::<0x44>(a, b), _mm512_shuffle_ps::<0xee>(a, b));
        }
        // Lane 4 k + m: the sum of v[k + 4 m].
        let z = _mm512_add_ps(_mm512_shuffle_ps::<0x88>(y[0], y[1]), _mm512_shuffle_ps::<0xdd>(y[0], y[1]));
        let mut lanes = [0.0f32; 16];
        // SAFETY: `lanes` holds sixteen floats; the store is unaligned.
        unsafe { _mm512_storeu_ps(lanes.as_mut_ptr(), z) };
        for (i, o) in out.iter_mut().enumerate() {
            *o = lanes[4 * (i % 4) + i / 4];
        }
    }

    /// The half floats in the low 16 bits of each lane, as floats (exact, subnormals
    /// included): the bits moved into an `f32`'s and rescaled by `2^112`.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn half_lo(v: __m512i) -> __m512 {
        let bits = _mm512_slli_epi32::<13>(_mm512_and_si512(v, _mm512_set1_epi32(0xffff)));
        _mm512_mul_ps(_mm512_castsi512_ps(bits), _mm512_set1_ps(crate::solver::link_coef::HALF_RESCALE))
    }

    /// [`half_lo`] of the high 16 bits of each lane.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn half_hi(v: __m512i) -> __m512 {
        half_lo(_mm512_srli_epi32::<16>(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random links of one receiver, some steep, some not, some flagged as form factors.
    fn links(n: usize, nodes: usize, seed: u64) -> (Vec<Vec3A>, Vec<Vec3A>, Vec<u32>, Vec<LinkCoef>) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
        let mut v = || Vec3A::new(rng.random(), rng.random(), rng.random());
        let e_node: Vec<Vec3A> = (0..nodes).map(|_| v()).collect();
        let mid: Vec<Vec3A> = (0..nodes).map(|_| v() * 4.0).collect();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed + 1);
        let emitter =
            (0..n).map(|i| rng.random_range(0..nodes as u32) | if i % 5 == 0 { FF_BIT } else { 0 }).collect();
        let scale = link_coef::receiver_scale(1.0);
        let coef = (0..n)
            .map(|i| {
                let f = Vec3A::new(rng.random(), rng.random(), rng.random());
                let slope = if i % 3 == 0 { 0.0 } else { rng.random_range(0.0..12.0f32) };
                LinkCoef::pack_with_slope(f, scale, slope)
            })
            .collect();
        (e_node, mid, emitter, coef)
    }

    fn close(a: Vec3A, b: Vec3A, scale: f32) -> bool {
        (a - b).abs().max_element() <= 2e-6 * scale
    }

    #[test]
    fn vector_path_matches_the_portable_path() {
        if !Isa::Avx512.is_available() {
            eprintln!("no AVX-512 here: only the portable path runs");
            return;
        }
        for (n, seed) in [(0, 1), (1, 2), (15, 3), (16, 4), (17, 5), (100, 6), (333, 7)] {
            let (e_node, mid, emitter, coef) = links(n, 257, seed);
            let m_r = mid[3] + Vec3A::new(0.1, -0.2, 0.05);
            for curved in [false, true] {
                let a = sum_linear(Isa::Scalar, &e_node, &mid, &emitter, &coef, m_r, curved);
                let b = sum_linear(Isa::Avx512, &e_node, &mid, &emitter, &coef, m_r, curved);
                // Sums of up to 333 terms in another order: relative to their magnitude.
                let size = |l: &Linear| {
                    let all = [l.value].into_iter().chain(l.grad).chain(l.hess.diag).chain(l.hess.off);
                    all.map(|v| v.abs().max_element()).fold(1e-30, f32::max)
                };
                let s = size(&a);
                assert!(close(a.value, b.value, s), "n {n} curved {curved}: {:?} vs {:?}", a.value, b.value);
                for c in 0..3 {
                    assert!(
                        close(a.grad[c], b.grad[c], s),
                        "n {n}: grad {c} {:?} vs {:?}",
                        a.grad[c],
                        b.grad[c]
                    );
                    assert!(close(a.hess.diag[c], b.hess.diag[c], s), "n {n}: diag {c}");
                    assert!(close(a.hess.off[c], b.hess.off[c], s), "n {n}: off {c}");
                }
                if !curved {
                    assert_eq!(b.hess.diag, [Vec3A::ZERO; 3]);
                }
            }
        }
    }
}
