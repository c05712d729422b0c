//! Nine-coefficient spherical-harmonic irradiance (Ramamoorthi & Hanrahan 2001, "An Efficient
//! Representation for Irradiance Environment Maps"), as Mertens et al. 2003 §5.3 uses it to
//! sample environment light at the leaves.
//!
//! The cosine lobe is a zonal kernel, so by the Funk–Hecke theorem irradiance is the radiance's
//! SH expansion with band `l` scaled by `A_l = 2π ∫_0^1 μ P_l(μ) dμ` (`π, 2π/3, π/4`). Bands 0..2
//! keep all but a few percent of the irradiance of real maps, because `A_l` falls off fast.
//!
//! The Fresnel-transmitted irradiance `E_t(n) = ∫ L(ω) F_t(eta, n·ω) max(0, n·ω) dω` has a zonal
//! kernel too, so it is *also* separable per band: `A_l^t = 2π ∫_0^1 F_t(eta, μ) μ P_l(μ) dμ`
//! ([`BandWeights::fresnel_cosine`]). This is exact for the band-limited part of the radiance; the
//! only approximation is the same 9-coefficient truncation as for plain irradiance.
//!
//! Frame: world `x, y, z` (lucent is +Y up) plug straight into the real SH basis below; the R&H
//! formula does not care which axis is "up" as long as projection and evaluation use the same
//! basis.

use crate::Rgb;
use crate::bssrdf::{fresnel_transmittance, zonal_band_weights};
use glam::Vec3;

/// Number of coefficients per colour channel (bands l = 0, 1, 2).
pub const SH_COUNT: usize = 9;

/// Irradiance constants of Ramamoorthi & Hanrahan 2001, eq. 13: `c1..c5`.
pub const C1: f32 = 0.429_043;
/// See [`C1`].
pub const C2: f32 = 0.511_664;
/// See [`C1`].
pub const C3: f32 = 0.743_125;
/// See [`C1`].
pub const C4: f32 = 0.886_227;
/// See [`C1`].
pub const C5: f32 = 0.247_708;

/// The nine real SH basis functions at the unit direction `d`, in the order
/// `[Y00, Y1-1, Y10, Y11, Y2-2, Y2-1, Y20, Y21, Y22]` (index `l(l+1)+m`), with
/// `Y1-1 ∝ y, Y10 ∝ z, Y11 ∝ x, Y2-2 ∝ xy, Y2-1 ∝ yz, Y20 ∝ 3z²-1, Y21 ∝ xz, Y22 ∝ x²-y²`
/// (R&H 2001 eq. 3).
#[inline]
pub fn sh_basis(d: Vec3) -> [f32; SH_COUNT] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        0.282_095,
        0.488_603 * y,
        0.488_603 * z,
        0.488_603 * x,
        1.092_548 * x * y,
        1.092_548 * y * z,
        0.315_392 * (3.0 * z * z - 1.0),
        1.092_548 * x * z,
        0.546_274 * (x * x - y * y),
    ]
}

/// The band (`l`) of each coefficient index.
pub const SH_BAND: [usize; SH_COUNT] = [0, 1, 1, 1, 2, 2, 2, 2, 2];

/// Nine SH coefficients `L_lm` per RGB channel of a radiance function (same units as the
/// radiance, e.g. W m^-2 sr^-1), in the order of [`sh_basis`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sh9 {
    /// `L_lm` per channel.
    pub coeffs: [Rgb; SH_COUNT],
}

impl Sh9 {
    /// All-zero coefficients.
    pub const ZERO: Sh9 = Sh9 { coeffs: [Rgb::ZERO; SH_COUNT] };

    /// From plain arrays (`[[r, g, b]; 9]`, the order of [`sh_basis`]).
    pub fn from_array(a: [[f32; 3]; SH_COUNT]) -> Self {
        Sh9 { coeffs: a.map(Rgb::from_array) }
    }

    /// As plain arrays (for upload to the GPU or serialisation).
    pub fn to_array(&self) -> [[f32; 3]; SH_COUNT] {
        self.coeffs.map(|c| c.to_array())
    }

    /// The band-limited radiance `Σ L_lm Y_lm(d)` at unit direction `d`.
    pub fn radiance(&self, d: Vec3) -> Rgb {
        self.coeffs.iter().zip(sh_basis(d)).map(|(c, y)| *c * y).sum()
    }

    /// Irradiance `E(n) = ∫ L(ω) max(0, n·ω) dω` at unit normal `n` by Ramamoorthi & Hanrahan's
    /// quadratic form (eq. 13). Note the `L22` term takes `c1`, not `c3` (a typo in some copies).
    pub fn irradiance(&self, n: Vec3) -> Rgb {
        let l = &self.coeffs;
        let (x, y, z) = (n.x, n.y, n.z);
        // Index map: 0 L00, 1 L1-1, 2 L10, 3 L11, 4 L2-2, 5 L2-1, 6 L20, 7 L21, 8 L22.
        l[8] * (C1 * (x * x - y * y)) + l[6] * (C3 * z * z) + l[0] * C4 - l[6] * C5
            + (l[4] * (x * y) + l[7] * (x * z) + l[5] * (y * z)) * (2.0 * C1)
            + (l[3] * x + l[1] * y + l[2] * z) * (2.0 * C2)
    }

    /// `Σ_l w_l Σ_m L_lm Y_lm(n)`: the convolution of the radiance with a zonal kernel whose band
    /// weights are `w` (see [`BandWeights`]). With [`BandWeights::COSINE`] this equals
    /// [`Sh9::irradiance`].
    pub fn convolve(&self, n: Vec3, w: &BandWeights) -> Rgb {
        self.coeffs.iter().zip(sh_basis(n)).zip(SH_BAND).map(|((c, y), l)| *c * (y * w.0[l])).sum()
    }
}

/// Per-band weights `A_l` (l = 0, 1, 2) of a zonal kernel `K(n·ω)`:
/// `A_l = 2π ∫_{-1}^{1} K(μ) P_l(μ) dμ`, in sr.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandWeights(pub [f32; 3]);

impl BandWeights {
    /// The clamped cosine `max(0, μ)`: `A = (π, 2π/3, π/4)` (R&H 2001 eq. 8).
    pub const COSINE: BandWeights =
        BandWeights([std::f32::consts::PI, 2.0 * std::f32::consts::PI / 3.0, std::f32::consts::PI / 4.0]);

    /// The Fresnel-transmitted clamped cosine `F_t(eta, μ) max(0, μ)` for a smooth dielectric
    /// of relative index `eta` (light entering from air). `A_0 / π` is the cosine-weighted
    /// hemispherical average of `F_t`, `1 − F_dr,ext` (about 0.93 at eta 1.3; note that the
    /// dipole's `F_dr` fit is the *internal* one, `1 − F_dr,int = (1 − F_dr,ext) / eta²`).
    /// Computed by composite Simpson quadrature in `f64` (1024 intervals; `F_t` is smooth for
    /// `eta >= 1`, so the error is far below `f32` precision).
    pub fn fresnel_cosine(eta: f64) -> BandWeights {
        BandWeights(zonal_band_weights(|mu| fresnel_transmittance(mu, eta) * mu))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rh_constants_follow_from_band_weights_and_basis() {
        // R&H eq. 12-13: each c_i is a band weight A_l times a basis normalisation.
        let a = BandWeights::COSINE.0;
        assert!((C1 - a[2] * 0.546_274).abs() < 2e-6);
        // The linear and xy/yz/xz terms appear as 2 c2 and 2 c1 in eq. 13.
        assert!((2.0 * C2 - a[1] * 0.488_603).abs() < 2e-6);
        assert!((2.0 * C1 - a[2] * 1.092_548).abs() < 2e-6);
        assert!((C3 - a[2] * 0.315_392 * 3.0).abs() < 2e-6);
        assert!((C4 - a[0] * 0.282_095).abs() < 2e-6);
        assert!((C5 - a[2] * 0.315_392).abs() < 2e-6);
    }

    #[test]
    fn fresnel_weights_tend_to_cosine_at_eta_one() {
        let w = BandWeights::fresnel_cosine(1.0);
        for (a, b) in w.0.iter().zip(BandWeights::COSINE.0) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
    }
}
