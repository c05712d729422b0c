//! Stored transport coefficients, 16 bits per channel.
//!
//! Render mode (Mertens et al. 2003, §5.5) is a gather over millions of stored links, every
//! frame. The sum `Σ E_e F_re` has non-negative terms, so a relative rounding error per link
//! bounds the same relative error of `B`: [`LinkCoef`] keeps 10 mantissa bits (relative error
//! at most `2^-11` ≈ 4.9e-4, twenty times below the solver's 1% accuracy target) and a 6-bit
//! exponent covering `[2^-39, 2^24)`. The range is wide on purpose: `F` usually stays below
//! `R_d_total` < 1, but where a receiver's dipole source lies just under an emitter on the far
//! side of a thin part, the (exact) form factor reaches into the thousands.
//!
//! Decoding is a shift and a multiply (it puts the 16 bits into the low exponent and high
//! mantissa bits of an `f32` and rescales), for all three channels at once in one SSE2
//! register ([`LinkCoef::unpack_a`]): the gather is bound by instructions per link, and this
//! takes a third off render mode at 131K triangles against three scalar `f32` (IEEE half
//! floats would need `f16c`, which is not in the x86-64 baseline, and have too little range).

use glam::Vec3A;

/// Bits below the packed value in the `f32` it decodes to.
const SHIFT: u32 = 13;

/// Exponent offset (in `f32` exponent-field units) between an `f32` and its packed form.
const EXP_OFFSET: u32 = 87 << 23;

/// `2^87`: rescales the decoded `f32`, whose exponent field holds the 6-bit exponent `e`
/// (`2^(e - 127)`), to `2^(e - 40)`.
const SCALE: f32 = f32::from_bits(EXP_OFFSET + (127 << 23));

/// Smallest non-zero packed value, `2^-39`.
pub const MIN_POSITIVE: f32 = f32::from_bits(EXP_OFFSET + (1 << 23));

/// Largest packed value, just below `2^24`.
pub const MAX: f32 = f32::from_bits(EXP_OFFSET + (0xffff << SHIFT));

/// Largest relative rounding error of a packed value in `[MIN_POSITIVE, MAX]`.
pub const MAX_REL_ERROR: f32 = 1.0 / 2048.0;

/// A link's transport coefficient per channel (unitless, `F(E, x_R)` of Mertens eq. 6) in
/// 16 bits each (see the module documentation); the fourth lane is 0, so that eight aligned
/// bytes load into one register.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C, align(8))]
pub struct LinkCoef([u16; 4]);

impl LinkCoef {
    /// Packs `f`, rounding to nearest; negative and NaN values (numerical noise of a form
    /// factor that is 0) become 0, values above [`MAX`] saturate.
    #[inline]
    pub fn pack(f: [f32; 3]) -> Self {
        LinkCoef([pack_one(f[0]), pack_one(f[1]), pack_one(f[2]), 0])
    }

    /// The coefficient per channel.
    #[inline]
    pub fn unpack(self) -> [f32; 3] {
        std::array::from_fn(|c| f32::from_bits((self.0[c] as u32) << SHIFT) * SCALE)
    }

    /// The coefficient per channel as a SIMD vector (its fourth lane 0).
    #[inline]
    pub fn unpack_a(self) -> Vec3A {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::*;
            let bits = u64::from_le_bytes(bytemuck::cast(self.0));
            // Zero-extend the four lanes to 32 bits, move them into the exponent field and
            // rescale.
            // SAFETY: these are SSE2 register operations (no memory access), and SSE2 is part
            // of the x86-64 baseline.
            let f = unsafe {
                let x = _mm_unpacklo_epi16(_mm_cvtsi64_si128(bits as i64), _mm_setzero_si128());
                _mm_mul_ps(_mm_castsi128_ps(_mm_slli_epi32::<{ SHIFT as i32 }>(x)), _mm_set1_ps(SCALE))
            };
            Vec3A::from(f)
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            Vec3A::from_array(self.unpack())
        }
    }
}

#[inline]
fn pack_one(x: f32) -> u16 {
    if x.is_nan() || x < MIN_POSITIVE * 0.5 {
        return 0;
    }
    if x >= MAX {
        return u16::MAX;
    }
    // Values in [MIN/2, MIN) round up to MIN: their bits fall below the offset.
    let bits = x.max(MIN_POSITIVE).to_bits() - EXP_OFFSET;
    ((bits + (1 << (SHIFT - 1))) >> SHIFT).min(u16::MAX as u32) as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_within_the_stated_relative_error() {
        let mut x = MIN_POSITIVE;
        while x < MAX {
            for t in [1.0f32, 1.000_1, 1.3, 1.499_9, 1.5, 1.77, 1.999_9] {
                let v = (x * t).min(MAX);
                let p = LinkCoef::pack([v, 0.5 * v, 0.25 * v]);
                assert_eq!(Vec3A::from_array(p.unpack()), p.unpack_a());
                let got = p.unpack()[0];
                assert!(((got - v) / v).abs() <= MAX_REL_ERROR, "{v:e} -> {got:e}");
            }
            x *= 2.0;
        }
    }

    #[test]
    fn edge_values() {
        assert_eq!(LinkCoef::pack([0.0, -1.0, f32::NAN]).unpack(), [0.0; 3]);
        assert_eq!(LinkCoef::pack([MIN_POSITIVE * 0.4, 0.0, 0.0]).unpack()[0], 0.0);
        assert_eq!(LinkCoef::pack([MIN_POSITIVE * 0.6, 0.0, 0.0]).unpack()[0], MIN_POSITIVE);
        assert_eq!(
            LinkCoef::pack([MAX, 1e9, f32::INFINITY]).unpack(),
            [LinkCoef::pack([MAX; 3]).unpack()[0]; 3]
        );
        // Exactly representable values survive unchanged, so re-packing is lossless.
        for v in [1.0f32, 0.5, 0.75, MIN_POSITIVE, 3.0 / 1024.0] {
            let p = LinkCoef::pack([v; 3]);
            assert_eq!(p.unpack(), [v; 3]);
            assert_eq!(p.unpack_a(), Vec3A::splat(v));
            assert_eq!(LinkCoef::pack(p.unpack()), p);
        }
    }
}
