//! Branch-free exponentials `e^x` for `x ≤ 0`, for the hot loops of the solver (one-point
//! estimates) and the form factor (the I1 and I2 terms of Mertens eqs. 10-13). Both use the
//! textbook scheme: `x = k ln 2 + r` with `|r| ≤ ln 2 / 2`, a Taylor polynomial for `e^r`,
//! and `2^k` written into the exponent bits. Unlike the C library's `exp` they inline, and
//! the compiler vectorises loops over them.

use crate::simd::{Madd, Separate};

/// `e^x` for `x ≤ 0` to about 2e-7 relative (`x < -87` gives `e^-87`): range reduction by
/// `ln 2` and a degree-6 Taylor polynomial on `|r| ≤ ln 2 / 2`, branch free so that it
/// vectorises.
#[inline(always)]
pub fn exp_neg(x: f32) -> f32 {
    exp_neg_with::<Separate>(x)
}

/// [`exp_neg`] with its multiply-adds fused or not (`M`), for the kernels compiled per
/// instruction set ([`crate::simd`]).
#[inline(always)]
pub fn exp_neg_with<M: Madd>(x: f32) -> f32 {
    let (p, k) = reduced::<M>(x.clamp(-87.0, 0.0));
    // 2^k has exponent field `k + 127`.
    p * f32::from_bits(k.wrapping_add(127) << 23)
}

/// `e^y = 2^k e^r` for `y` within `f32`'s exponent range: `(e^r, k)`, `k = round(y / ln 2)`
/// (as the bits of a two's-complement integer), `r = y - k ln 2` in two parts and `e^r` by a
/// degree-6 Taylor polynomial. Shared by [`exp_neg_with`] and [`exp_m1_with`], which scale
/// by `2^k` each within its own range.
#[inline(always)]
fn reduced<M: Madd>(y: f32) -> (f32, u32) {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    // Adding and subtracting 1.5 · 2^23 rounds to the nearest integer in f32.
    const ROUND: f32 = 12_582_912.0;
    let shifted = M::madd(y, LOG2E, ROUND);
    let k = shifted - ROUND;
    let r = M::madd(-k, LN2_LO, M::madd(-k, LN2_HI, y));
    let mut p = 1.0 / 720.0;
    for c in [1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0] {
        p = M::madd(p, r, c);
    }
    // `k` as an integer from the bits of `shifted` (an `as i32` cast saturates, which does
    // not vectorise).
    (p, shifted.to_bits().wrapping_sub(ROUND.to_bits()))
}

/// `e^x - 1` for any `x` to about 5e-7 relative (`+∞` above `ln f32::MAX`, as the C library's;
/// `x < -86` gives `e^-86 - 1`, which rounds to -1): the Taylor polynomial of degree 9 where
/// `|x| ≤ 1/2` (no cancellation near 0, where `e^x - 1` loses the relative accuracy that the
/// chord factor `1 - e^{-σ_t T}` of a thin part needs), else [`exp_neg_with`]'s scheme
/// extended to positive `x`, minus one. Branch free, so that it vectorises.
#[inline(always)]
pub fn exp_m1_with<M: Madd>(x: f32) -> f32 {
    // `ln f32::MAX`: beyond it `e^x` overflows.
    const OVERFLOW: f32 = 88.722_83;
    let big = {
        let (p, k) = reduced::<M>(x.clamp(-86.0, OVERFLOW));
        // 2^k as 2^(k-1) times 2: k reaches 128 near the overflow, whose 2^k has no `f32`
        // (k ≥ -124 here, so 2^(k-1) is normal).
        let e = p * f32::from_bits(k.wrapping_add(126) << 23) * 2.0;
        if x > OVERFLOW { f32::INFINITY } else { e - 1.0 }
    };
    // x (1 + x/2! + ... + x^8/9!): the next term is below 1.4e-8 of the value at |x| = 1/2.
    let mut p = 1.0 / 362_880.0;
    for c in [1.0 / 40_320.0, 1.0 / 5_040.0, 1.0 / 720.0, 1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0] {
        p = M::madd(p, x, c);
    }
    let small = p * x;
    if x.abs() <= 0.5 { small } else { big }
}

/// `e^x` for `x ≤ 0` to about 1e-14 relative (`x < -708` gives `e^-708`): `x = (64 m + j)
/// ln 2 / 64 + r` with `|r| ≤ ln 2 / 128`, `e^x = 2^m 2^{j/64} e^r`, a table of the 64
/// values `2^{j/64}` and a degree-5 Taylor polynomial for `e^r` (next term below 2e-16).
#[inline(always)]
pub fn exp_neg_f64(x: f64) -> f64 {
    const SCALE: f64 = 64.0 * std::f64::consts::LOG2_E;
    const LN2_64_HI: f64 = 6.931_471_803_691_238e-1 / 64.0;
    const LN2_64_LO: f64 = 1.908_214_929_270_587_7e-10 / 64.0;
    const ROUND: f64 = 6_755_399_441_055_744.0; // 1.5 · 2^52
    let x = x.clamp(-708.0, 0.0);
    let shifted = x * SCALE + ROUND;
    let k = shifted - ROUND;
    let r = x - k * LN2_64_HI - k * LN2_64_LO;
    let p = 1.0 + r * (1.0 + r * (0.5 + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0)))));
    let k_int = shifted.to_bits().wrapping_sub(ROUND.to_bits()) as i64;
    let (m, j) = (k_int >> 6, (k_int & 63) as usize);
    p * EXP2_64[j] * f64::from_bits(((m + 1023) as u64) << 52)
}

/// `2^{j/64}` for `j = 0..64`.
static EXP2_64: [f64; 64] = {
    // e^{j ln2/64} by its Taylor series at compile time (converges fast: the argument < 0.7).
    let mut t = [0.0; 64];
    let mut j = 0;
    while j < 64 {
        let y = j as f64 * std::f64::consts::LN_2 / 64.0;
        let (mut sum, mut term, mut n) = (1.0, 1.0, 1);
        while n < 30 {
            term = term * y / n as f64;
            sum += term;
            n += 1;
        }
        t[j] = sum;
        j += 1;
    }
    t
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_matches_libm() {
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let x = (-87.0 * i as f64 / 200_000.0) as f32;
            // Compare at the f32 argument: rounding x is not exp_neg's error.
            let want = (x as f64).exp();
            worst = worst.max(((exp_neg(x) as f64 - want) / want).abs());
        }
        assert!(worst < 3e-7, "worst relative error {worst:e}");
        assert_eq!(exp_neg(0.0), 1.0);
        let worst_fused = (0..=20_000)
            .map(|i| {
                let x = (-87.0 * i as f64 / 20_000.0) as f32;
                let want = (x as f64).exp();
                ((exp_neg_with::<crate::simd::Fused>(x) as f64 - want) / want).abs()
            })
            .fold(0.0, f64::max);
        assert!(worst_fused < 3e-7, "fused: worst relative error {worst_fused:e}");
        assert!(exp_neg(-1000.0) > 0.0 && exp_neg(-1000.0) < 1e-37);
    }

    #[test]
    fn exp_m1_matches_libm() {
        // Both signs, fine near 0 (where e^x - 1 cancels) and out to the overflow.
        let xs = (0..=400_000).map(|i| {
            let u = (i as f64 / 200_000.0) - 1.0;
            (u.signum() * u.abs().powi(3) * 88.0) as f32
        });
        for fused in [false, true] {
            let mut worst = 0.0f64;
            for x in xs.clone().filter(|x| *x <= 88.7) {
                let got =
                    if fused { exp_m1_with::<crate::simd::Fused>(x) } else { exp_m1_with::<Separate>(x) };
                let want = (x as f64).exp_m1();
                if want != 0.0 {
                    worst = worst.max(((got as f64 - want) / want).abs());
                }
            }
            assert!(worst < 6e-7, "fused {fused}: worst relative error {worst:e}");
        }
        let e = |x: f32| exp_m1_with::<Separate>(x);
        assert_eq!(e(0.0), 0.0);
        assert_eq!(e(89.0), f32::INFINITY);
        assert_eq!(e(88.8), 88.8f32.exp_m1(), "overflows where the C library's does");
        assert!(e(88.72).is_finite());
        assert_eq!(e(-1000.0), -1.0);
    }

    #[test]
    fn exp_neg_f64_matches_libm() {
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let x = -708.0 * i as f64 / 200_000.0;
            let want = x.exp();
            worst = worst.max(((exp_neg_f64(x) - want) / want).abs());
        }
        assert!(worst < 1e-14, "worst relative error {worst:e}");
        assert_eq!(exp_neg_f64(0.0), 1.0);
        assert!(exp_neg_f64(-1e4) > 0.0 && exp_neg_f64(-1e4) < 1e-300);
    }
}
