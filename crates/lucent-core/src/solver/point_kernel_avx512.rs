//! The one-point estimate kernel of [`super::point_kernel`] written out for AVX-512: the same
//! sixteen lanes (four points × three channels, lane `4 c + j`, four padding lanes), one
//! `zmm` register per quantity, but without the divider. The portable path's two square roots
//! and division per pole become one `vrsqrt14ps` and a Newton step (`s` and `1 / s³` from it),
//! its exponential a fitted `2^t` scaled by `vscalefps`, and PBD's table is read as 64-bit
//! pairs `(t[i], t[i + 1])`: two gathers of eight (the second masked to the four used lanes)
//! instead of two of sixteen. Results differ from the portable path by a few ulp (the Newton
//! step's rounding, amplified by `σ_tr s` in the exponential; tested to 2e-5 relative, about
//! 8e-6 measured); lanes do not interact, so a single estimate, a batch of four points and a
//! batch of four receivers agree bit for bit, as the oracle needs.

use super::point_kernel::{Lanes, ProfileLanes, TABLE_LEN, WIDTH};
use super::point_sample::ReceiverSources;
use crate::bssrdf::tables::TABLE_SIZE;
use glam::Vec3;
use std::arch::x86_64::*;

/// Sixteen floats as a vector.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn load(a: &[f32; WIDTH]) -> __m512 {
    // SAFETY: `a` holds sixteen floats; the load is unaligned.
    unsafe { _mm512_loadu_ps(a.as_ptr()) }
}

/// Sixteen 32-bit integers as a vector.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn load_i(a: &[u32; WIDTH]) -> __m512i {
    // SAFETY: `a` holds sixteen 32-bit integers; the load is unaligned.
    unsafe { _mm512_loadu_epi32(a.as_ptr().cast()) }
}

/// `(1 / √x, √x c)` for `x > 0`: the 14-bit estimate `y` and one Newton step, `y (1 + g)` with
/// `g = (1 - x y²) / 2`, applied to `x y c` as well, so that `√x c` does not wait for `1 / √x`
/// (about 2 ulp each).
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn rsqrt_sqrt(x: __m512, c: __m512) -> (__m512, __m512) {
    let y = _mm512_rsqrt14_ps(x);
    let xy = _mm512_mul_ps(x, y);
    let g = _mm512_fnmadd_ps(xy, _mm512_mul_ps(y, _mm512_set1_ps(0.5)), _mm512_set1_ps(0.5));
    let xyc = _mm512_mul_ps(xy, c);
    (_mm512_fmadd_ps(y, g, y), _mm512_fmadd_ps(xyc, g, xyc))
}

/// `2^t` for `t ≤ 0`: `t = k + f`, `|f| ≤ 1/2`, a degree-5 polynomial fitted to `2^f` (relative
/// error 1.5e-7 in `f32`; [`crate::fastexp::exp_neg`]'s Taylor polynomial needs degree 6 and
/// a reduction by `ln 2` for the same), `2^k` by `vscalefps`, which underflows to 0 below
/// `2^-149` where the portable path clamps at `e^-87`.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn exp2_neg(t: __m512) -> __m512 {
    const C: [f32; 6] =
        [1.000_000_1, 0.693_146_94, 0.240_221_2, 0.055_507_13, 0.009_675_542, 0.001_327_647_1];
    let k = _mm512_roundscale_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(t);
    let f = _mm512_sub_ps(t, k);
    // Estrin's scheme: three multiply-adds deep instead of five (the estimate is latency bound).
    let c = [C[0], C[1], C[2], C[3], C[4], C[5]];
    let c = [0, 1, 2, 3, 4, 5].map(|i| _mm512_set1_ps(c[i]));
    let f2 = _mm512_mul_ps(f, f);
    let (p01, p23, p45) =
        (_mm512_fmadd_ps(c[1], f, c[0]), _mm512_fmadd_ps(c[3], f, c[2]), _mm512_fmadd_ps(c[5], f, c[4]));
    let p = _mm512_fmadd_ps(_mm512_fmadd_ps(p45, f2, p23), f2, p01);
    _mm512_scalef_ps(p, k)
}

/// One source's term times `k`, `k z (1 + σ s) e^{-σ s} / s³ = (k z / s + k z σ) e^{-σ s} / s²`,
/// from the squared distance `s2 > 0` (`kz`, `kzs` = `k z`, `k z σ`; `e2` = `-σ log2 e`).
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn pole(kz: __m512, kzs: __m512, e2: __m512, s2: __m512) -> __m512 {
    let (inv_s, t) = rsqrt_sqrt(s2, e2);
    let e = exp2_neg(t);
    let front = _mm512_mul_ps(_mm512_fmadd_ps(kz, inv_s, kzs), _mm512_mul_ps(inv_s, inv_s));
    _mm512_mul_ps(front, e)
}

/// Smallest squared distance evaluated: a point on a pole gets `R` there (a huge or infinite
/// dipole term, the table's first entry over `r_floor`), not `0 · ∞`.
const S2_MIN: f32 = 1e-30;

/// The tabulated `R(r)` from the squared distance `s2` (0 beyond `r_max`): as the portable
/// `radial`, but `1 / max(r, r_floor)` as `min(1 / r, 1 / r_floor)` from the reciprocal
/// square root, and both cell ends in one 64-bit gather per lane.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn radial(t: &[f32; TABLE_LEN], l: &Lanes<WIDTH>, s2: __m512, upper: __mmask8) -> __m512 {
    // At `s2 = 0`, `r = 0` (the first cell) and `1 / r` is capped below.
    let (inv_r, r_scaled) = rsqrt_sqrt(_mm512_max_ps(s2, _mm512_set1_ps(S2_MIN)), load(&l.x_scale));
    let r_scaled = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(s2, _mm512_setzero_ps()), r_scaled);
    // A true square root for the grid variable: its rounding moves the cell fraction.
    radial_at(t, l, _mm512_sqrt_ps(r_scaled), inv_r, upper)
}

/// [`radial`] from the grid variable `x = √(r N² / r_max)` and `1 / r` (`r = 0`: `x = 0`).
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn radial_at(t: &[f32; TABLE_LEN], l: &Lanes<WIDTH>, x: __m512, inv_r: __m512, upper: __mmask8) -> __m512 {
    const N: f32 = TABLE_SIZE as f32;
    let inside = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(x, _mm512_set1_ps(N));
    let x = _mm512_maskz_mov_ps(inside, x);
    let cell = _mm512_cvttps_epi32(x);
    let f = _mm512_sub_ps(x, _mm512_cvtepi32_ps(cell));
    // `x < N` so `cell ≤ N - 1` and `at + 1` is in the channel's samples.
    let at = _mm512_add_epi32(load_i(&l.table_start), cell);
    let base: *const i64 = t.as_ptr().cast();
    // SAFETY: every index is below `TABLE_LEN - 1`, so both floats of each pair are in `t`;
    // the upper eight lanes are gathered where `upper` says (a batch's lanes 12..16 pad).
    let (lo8, hi8) = unsafe {
        (
            _mm512_i32gather_epi64::<4>(_mm512_castsi512_si256(at), base),
            _mm512_mask_i32gather_epi64::<4>(
                _mm512_setzero_si512(),
                upper,
                _mm512_extracti64x4_epi64::<1>(at),
                base,
            ),
        )
    };
    let (lo8, hi8) = (_mm512_castsi512_ps(lo8), _mm512_castsi512_ps(hi8));
    let even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    let odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
    let (t0, t1) = (_mm512_permutex2var_ps(lo8, even, hi8), _mm512_permutex2var_ps(lo8, odd, hi8));
    let w = _mm512_fmadd_ps(t0, _mm512_sub_ps(_mm512_set1_ps(1.0), f), _mm512_mul_ps(t1, f));
    _mm512_maskz_mul_ps(inside, w, _mm512_min_ps(inv_r, load(&l.inv_r_floor)))
}

/// `area R` over the lanes of `l` from the squared distances to the real and virtual poles;
/// the table is read for lanes 8..16 where `upper` says.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn lanes(
    k: &ProfileLanes,
    l: &Lanes<WIDTH>,
    s2_r: __m512,
    s2_v: __m512,
    area: __m512,
    upper: __mmask8,
) -> __m512 {
    let s2_min = _mm512_set1_ps(S2_MIN);
    let mut out = _mm512_setzero_ps();
    if k.analytic {
        let e2 = load(&l.exp2_scale);
        let s2_r = _mm512_max_ps(_mm512_add_ps(s2_r, load(&l.off_r)), s2_min);
        let s2_v = _mm512_max_ps(_mm512_add_ps(s2_v, load(&l.off_v)), s2_min);
        let r = pole(load(&l.kz_r), load(&l.kzs_r), e2, s2_r);
        out = _mm512_add_ps(r, pole(load(&l.kz_v), load(&l.kzs_v), e2, s2_v));
    }
    if let Some(t) = &k.table {
        out = _mm512_add_ps(out, radial(t, l, s2_r, upper));
    }
    _mm512_mul_ps(out, area)
}

/// `area R` over the batch lanes (four points × three channels, lanes 12..16 padding).
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn estimate(k: &ProfileLanes, s2_r: __m512, s2_v: __m512, area: __m512) -> __m512 {
    lanes(k, &k.batch, s2_r, s2_v, area, 0x0f)
}

/// A point's coordinates per lane.
type Xyz = [__m512; 3];

/// `|a - b|²` per lane, in the portable path's order.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn dist2(a: &Xyz, b: &Xyz) -> __m512 {
    let (dx, dy, dz) = (_mm512_sub_ps(a[0], b[0]), _mm512_sub_ps(a[1], b[1]), _mm512_sub_ps(a[2], b[2]));
    _mm512_fmadd_ps(dz, dz, _mm512_fmadd_ps(dy, dy, _mm512_mul_ps(dx, dx)))
}

/// `n` packed floats (at most sixteen) from `p`.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn load_packed<T>(p: &T, n: u32) -> __m512 {
    debug_assert!(n as usize * 4 <= size_of::<T>() && n <= 16);
    // SAFETY: the mask reads the first `n` floats of `*p`, which holds at least that many.
    unsafe { _mm512_maskz_loadu_ps(((1u32 << n) - 1) as u16, (p as *const T).cast()) }
}

/// Lane `4 c + j` ← float `3 c + a` (`[Vec3; 3]` element `c`, axis `a`; padding repeats
/// channel 2).
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn channel_index(a: i32) -> __m512i {
    let (c0, c1, c2) = (a, 3 + a, 6 + a);
    _mm512_setr_epi32(c0, c0, c0, c0, c1, c1, c1, c1, c2, c2, c2, c2, c2, c2, c2, c2)
}

/// Lane `4 c + j` ← float `3 j + a` (`[Vec3; 4]` element `j`, axis `a`).
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn point_index(a: i32) -> __m512i {
    let (j0, j1, j2, j3) = (a, 3 + a, 6 + a, 9 + a);
    _mm512_setr_epi32(j0, j1, j2, j3, j0, j1, j2, j3, j0, j1, j2, j3, j0, j1, j2, j3)
}

/// The channels' poles of one receiver per lane.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn poles(x: &[Vec3; 3]) -> Xyz {
    let v = load_packed(x, 9);
    [
        _mm512_permutexvar_ps(channel_index(0), v),
        _mm512_permutexvar_ps(channel_index(1), v),
        _mm512_permutexvar_ps(channel_index(2), v),
    ]
}

/// A point per lane, broadcast.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn splat(p: Vec3) -> Xyz {
    [_mm512_set1_ps(p.x), _mm512_set1_ps(p.y), _mm512_set1_ps(p.z)]
}

/// Lane `i` from `out[i]` to `[[f32; 3]; 4]` (`out[j][c]` is lane `4 c + j`).
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn unpack(v: __m512) -> [[f32; 3]; 4] {
    let idx = _mm512_setr_epi32(0, 4, 8, 1, 5, 9, 2, 6, 10, 3, 7, 11, 0, 0, 0, 0);
    let v = _mm512_permutexvar_ps(idx, v);
    let mut out = [[0.0f32; 3]; 4];
    // Eight and four floats rather than a masked store, which loads cannot forward from.
    let o: *mut f32 = out.as_mut_ptr().cast();
    // SAFETY: `out` holds twelve contiguous floats: eight from `o`, four from `o + 8`.
    unsafe {
        _mm256_storeu_ps(o, _mm512_castps512_ps256(v));
        _mm_storeu_ps(o.add(8), _mm512_extractf32x4_ps::<2>(v));
    }
    out
}

/// `A R` from one receiver's poles to four points (areas 0 pad).
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
pub(super) fn to_points(
    k: &ProfileLanes,
    src: &ReceiverSources,
    p: &[Vec3; 4],
    area: &[f32; 4],
) -> [[f32; 3]; 4] {
    let pv = load_packed(p, 12);
    let pt = [
        _mm512_permutexvar_ps(point_index(0), pv),
        _mm512_permutexvar_ps(point_index(1), pv),
        _mm512_permutexvar_ps(point_index(2), pv),
    ];
    // SAFETY: `area` holds four floats.
    let a = _mm512_broadcast_f32x4(unsafe { _mm_loadu_ps(area.as_ptr()) });
    let s2_r = dist2(&poles(&src.x_r), &pt);
    let s2_v = if k.analytic { dist2(&poles(&src.x_v), &pt) } else { s2_r };
    unpack(estimate(k, s2_r, s2_v, a))
}

/// Lane `4 c + j` from receiver `j`'s poles.
#[inline]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
fn poles4(x: [&[Vec3; 3]; 4]) -> Xyz {
    let mut out = [_mm512_setzero_ps(); 3];
    for (j, x) in x.into_iter().enumerate() {
        let v = load_packed(x, 9);
        // Lanes `4 c + j`, padding included.
        let lanes = 0x1111u16 << j;
        for (a, o) in out.iter_mut().enumerate() {
            *o = _mm512_mask_permutexvar_ps(*o, lanes, channel_index(a as i32), v);
        }
    }
    out
}

/// `A R` from four receivers' poles to one point.
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
pub(super) fn from_point(k: &ProfileLanes, src: &[ReceiverSources; 4], p: Vec3, area: f32) -> [[f32; 3]; 4] {
    let pt = splat(p);
    let s2_r = dist2(&poles4(src.each_ref().map(|s| &s.x_r)), &pt);
    let s2_v = if k.analytic { dist2(&poles4(src.each_ref().map(|s| &s.x_v)), &pt) } else { s2_r };
    unpack(estimate(k, s2_r, s2_v, _mm512_set1_ps(area)))
}

/// `A R` from one receiver's poles to one point (lanes `4 c` of a batch of four equal points).
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
pub(super) fn to_point(k: &ProfileLanes, src: &ReceiverSources, p: Vec3, area: f32) -> [f32; 3] {
    let pt = splat(p);
    let s2_r = dist2(&poles(&src.x_r), &pt);
    let s2_v = if k.analytic { dist2(&poles(&src.x_v), &pt) } else { s2_r };
    unpack(estimate(k, s2_r, s2_v, _mm512_set1_ps(area)))[0]
}

/// `Σ_i w_i R(p_i)` per channel from one receiver's poles, over points given as coordinate
/// arrays `x`, `y`, `z` and weights `w` of one length, a multiple of sixteen (pad with weight
/// 0: padding lanes are masked off the sums). Sixteen points a channel per register, three
/// channels: the kernel's lanes all used, where a batch of four points leaves a quarter idle.
#[target_feature(enable = "avx512f,avx512vl,avx2,fma,f16c")]
pub(super) fn weighted_sum(
    k: &ProfileLanes,
    src: &ReceiverSources,
    x: &[f32],
    y: &[f32],
    z: &[f32],
    w: &[f32],
) -> [f32; 3] {
    assert!(x.len().is_multiple_of(WIDTH) && y.len() == x.len() && z.len() == x.len() && w.len() == x.len());
    let mut acc = [_mm512_setzero_ps(); 3];
    let at = |a: &[f32], i: usize| load(a[i..i + WIDTH].try_into().expect("sixteen floats"));
    // The distance form: every pole at the receiver point, one squared distance a point.
    let one_pole = src.x_r.iter().chain(&src.x_v).all(|&x| x == src.x_r[0]);
    if let Some(t) = k.table.as_deref().filter(|_| !k.analytic && one_pole) {
        // A profile of tables alone whose poles are all at the receiver point (the distance
        // form): one distance, reciprocal root and grid root `r^¼` serve the three channels,
        // whose grid variables `√(r s_c) = r^¼ √s_c` differ by a factor only.
        let grid: [__m512; 3] = std::array::from_fn(|c| _mm512_sqrt_ps(load(&k.channel[c].x_scale)));
        for i in (0..x.len()).step_by(WIDTH) {
            let (p, wt) = ([at(x, i), at(y, i), at(z, i)], at(w, i));
            let used = _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(wt, _mm512_setzero_ps());
            let s2 = dist2(&splat(src.x_r[0]), &p);
            let (inv_r, r) = rsqrt_sqrt(_mm512_max_ps(s2, _mm512_set1_ps(S2_MIN)), _mm512_set1_ps(1.0));
            let r = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(s2, _mm512_setzero_ps()), r);
            let quarter = _mm512_sqrt_ps(r);
            for (c, acc) in acc.iter_mut().enumerate() {
                let l = &k.channel[c];
                let v = _mm512_mul_ps(radial_at(t, l, _mm512_mul_ps(quarter, grid[c]), inv_r, 0xff), wt);
                *acc = _mm512_mask_add_ps(*acc, used, *acc, v);
            }
        }
        return acc.map(|a| _mm512_reduce_add_ps(a));
    }
    for i in (0..x.len()).step_by(WIDTH) {
        let (p, wt) = ([at(x, i), at(y, i), at(z, i)], at(w, i));
        let used = _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(wt, _mm512_setzero_ps());
        let s2 = one_pole.then(|| dist2(&splat(src.x_r[0]), &p));
        for (c, acc) in acc.iter_mut().enumerate() {
            let s2_r = s2.unwrap_or_else(|| dist2(&splat(src.x_r[c]), &p));
            let s2_v = match s2 {
                Some(s2) => s2,
                None if k.analytic => dist2(&splat(src.x_v[c]), &p),
                None => s2_r,
            };
            let v = lanes(k, &k.channel[c], s2_r, s2_v, wt, 0xff);
            *acc = _mm512_mask_add_ps(*acc, used, *acc, v);
        }
    }
    acc.map(|a| _mm512_reduce_add_ps(a))
}
