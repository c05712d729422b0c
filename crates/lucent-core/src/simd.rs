//! Run-time choice of the instruction set for the solver's two hot kernels: the one-point
//! estimates of Mertens et al. 2003, §4.2 (`solver::point_kernel`) and render mode's gather of
//! §5.5 (`solver::link_coef`).
//!
//! The x86-64 baseline has neither fused multiply-add nor vectors wider than 128 bits, so a
//! binary built for it detects AVX2 + FMA and AVX-512 once and calls `#[target_feature]`
//! copies of the kernels; any other target, or a CPU without them, takes the portable path.
//! `LUCENT_SIMD=scalar|avx2|avx512` picks a path by hand (one the CPU lacks falls back to the
//! best it has), to compare them on one binary.
//!
//! Arithmetic: the vector paths fuse multiply-adds ([`Fused`]), the portable one does not
//! ([`Separate`]), so they differ by a few ulp (about 1e-7 relative, tested). The AVX-512
//! one-point kernel is written out by hand (reciprocal square root and a Newton step instead
//! of square roots and divisions), so it differs from the AVX2 one by a few ulp as well.

use std::sync::OnceLock;

/// An instruction set a hot kernel can run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    /// Portable Rust, no fused multiply-add (any target).
    Scalar,
    /// x86-64 with AVX2, FMA and F16C (256-bit vectors).
    Avx2,
    /// x86-64 with AVX-512 F and VL besides (512-bit vectors).
    Avx512,
}

impl Isa {
    /// Every path, slowest first.
    pub const ALL: [Isa; 3] = [Isa::Scalar, Isa::Avx2, Isa::Avx512];

    /// The name `LUCENT_SIMD` and the benches use.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }

    /// Whether this CPU runs the path.
    pub fn is_available(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            let avx2 = has!("avx2") && has!("fma") && has!("f16c");
            match self {
                Isa::Scalar => true,
                Isa::Avx2 => avx2,
                Isa::Avx512 => avx2 && has!("avx512f") && has!("avx512vl"),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self == Isa::Scalar
        }
    }

    /// The paths this CPU runs, slowest first.
    pub fn available() -> Vec<Isa> {
        Isa::ALL.into_iter().filter(|i| i.is_available()).collect()
    }

    /// The path the solver takes: the widest available, or `LUCENT_SIMD`'s if available
    /// (detected once).
    pub fn best() -> Isa {
        static BEST: OnceLock<Isa> = OnceLock::new();
        *BEST.get_or_init(|| {
            let widest = *Isa::available().last().expect("scalar is always available");
            let asked = std::env::var("LUCENT_SIMD").ok();
            Isa::ALL
                .into_iter()
                .find(|i| asked.as_deref().map(str::trim) == Some(i.name()) && i.is_available())
                .unwrap_or(widest)
        })
    }
}

/// `a b + c` in `f32`, fused or not: the kernels are written once over this and compiled per
/// instruction set.
pub trait Madd {
    /// `a b + c`.
    fn madd(a: f32, b: f32, c: f32) -> f32;
}

/// Two roundings (the portable path: `mul_add` without hardware FMA is a library call).
pub struct Separate;

/// One rounding (`vfmadd` inside the AVX2 and AVX-512 kernels).
pub struct Fused;

impl Madd for Separate {
    #[inline(always)]
    fn madd(a: f32, b: f32, c: f32) -> f32 {
        a * b + c
    }
}

impl Madd for Fused {
    #[inline(always)]
    fn madd(a: f32, b: f32, c: f32) -> f32 {
        a.mul_add(b, c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn best_is_available() {
        assert!(Isa::best().is_available());
        assert_eq!(Isa::available()[0], Isa::Scalar);
        assert_eq!(Fused::madd(2.0, 3.0, 1.0), Separate::madd(2.0, 3.0, 1.0));
    }
}
