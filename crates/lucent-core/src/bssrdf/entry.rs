//! How much of the light arriving from one direction a profile carries: the entry term.
//!
//! Every profile is a response to light entering at *normal* incidence. Light that arrives
//! obliquely refracts to a shallower path and more of it finds its way back out: in a half-space
//! of albedo 0.99 at `eta = 1`, 3% more at refracted cosine 0.8, 7% more at 0.6, 20% more at
//! grazing incidence; at albedo 0.3, where single scattering dominates, 32% more at 0.6.
//! Mertens §5.3 (like Jensen et al. 2001) takes only Fresnel's transmittance `F_t(η, μ_i)`.
//!
//! The entry term multiplies it by the ratio of the exact half-space albedos at the refracted
//! cosine and at normal incidence, `A(μ_t) / A(1)` ([`super::halfspace`]), per channel, so a
//! face lit from the side carries the energy radiative transfer gives it; the profile's shape
//! stays the normal-incidence one. It is tabulated over the outside cosine `μ_i` (33 points,
//! linear; the ratio is smooth), and its zonal band weights serve the SH environment.

use super::fresnel::fresnel_transmittance;
use super::halfspace::HalfSpace;
use crate::Rgb;

/// Samples of the entry term over `μ_i = k / SAMPLES`, `k = 0..=SAMPLES`.
const SAMPLES: usize = 32;

/// The entry term `F_t(η, μ_i) A(μ_t) / A(1)` per channel, over the cosine `μ_i` between the
/// surface normal and the direction to the light (outside the material).
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Relative index of refraction (unitless, >= 1 for the half-space ratio; Fresnel alone below).
    pub eta: f64,
    /// The term at `μ_i = k / SAMPLES`, per channel (unitless, 0..~1.3).
    samples: Vec<[f32; 3]>,
    /// Zonal band weights (l = 0, 1, 2, in sr) of `K(μ) = entry(μ) max(0, μ)` per channel, for
    /// the environment.
    bands: [[f32; 3]; 3],
}

impl Entry {
    /// Fresnel's transmittance alone (Mertens §5.3, Jensen et al. 2001): no dependence on
    /// direction beyond the boundary's.
    pub fn fresnel(eta: f64) -> Self {
        Self::from_fn(eta, |mu_i| [fresnel_transmittance(mu_i, eta); 3])
    }

    /// Fresnel's transmittance times the half-space albedo ratio for reduced albedos `rho` per
    /// channel (0..=1) at relative index `eta`. About a millisecond per channel.
    pub fn half_space(rho: &[f64; 3], eta: f64) -> Self {
        let spaces: [(HalfSpace, f64); 3] = std::array::from_fn(|c| {
            let hs = HalfSpace::new(rho[c], eta);
            let normal = hs.albedo(1.0);
            (hs, normal)
        });
        Self::from_fn(eta, |mu_i| {
            // Snell: the refracted cosine inside.
            let mu_t = (1.0 - (1.0 - mu_i * mu_i) / (eta * eta)).max(0.0).sqrt();
            let f_t = fresnel_transmittance(mu_i, eta);
            std::array::from_fn(|c| {
                let (hs, normal) = &spaces[c];
                if *normal > 1e-12 { f_t * hs.albedo(mu_t) / normal } else { f_t }
            })
        })
    }

    fn from_fn(eta: f64, f: impl Fn(f64) -> [f64; 3]) -> Self {
        let samples: Vec<[f32; 3]> =
            (0..=SAMPLES).map(|k| f(k as f64 / SAMPLES as f64).map(|v| v as f32)).collect();
        let bands = std::array::from_fn(|c| {
            zonal_band_weights(|mu| {
                let x = mu * SAMPLES as f64;
                let k = (x as usize).min(SAMPLES - 1);
                let t = x - k as f64;
                (samples[k][c] as f64 * (1.0 - t) + samples[k + 1][c] as f64 * t) * mu
            })
        });
        Entry { eta, samples, bands }
    }

    /// The term at cosine `cos_i` (clamped to 0..1) per channel.
    #[inline]
    pub fn at(&self, cos_i: f32) -> Rgb {
        let x = cos_i.clamp(0.0, 1.0) * SAMPLES as f32;
        let k = (x as usize).min(SAMPLES - 1);
        let t = x - k as f32;
        let (a, b) = (self.samples[k], self.samples[k + 1]);
        Rgb::new(a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t)
    }

    /// Zonal band weights `A_l` (l = 0, 1, 2, in sr) of `entry(μ) max(0, μ)` for channel `c`
    /// (0..3), as [`crate::irradiance::BandWeights`] takes them.
    pub fn band_weights(&self, c: usize) -> [f32; 3] {
        self.bands[c]
    }
}

/// Band weights `A_l = 2π ∫_0^1 K(μ) P_l(μ) dμ` (l = 0, 1, 2, in sr) of a zonal kernel `K`
/// that vanishes below the horizon, by composite Simpson quadrature in `f64` (1024 intervals).
pub fn zonal_band_weights(kernel: impl Fn(f64) -> f64) -> [f32; 3] {
    const N: usize = 1024;
    let mut a = [0.0f64; 3];
    for i in 0..=N {
        let mu = i as f64 / N as f64;
        let s = match i {
            0 => 1.0,
            _ if i == N => 1.0,
            _ if i % 2 == 1 => 4.0,
            _ => 2.0,
        };
        let k = kernel(mu) * s;
        a[0] += k;
        a[1] += k * mu;
        a[2] += k * 0.5 * (3.0 * mu * mu - 1.0);
    }
    let h = 1.0 / N as f64;
    a.map(|v| (2.0 * std::f64::consts::PI * v * h / 3.0) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_entry_is_the_fresnel_cosine_kernel() {
        // The tabulated kernel against Fresnel's, integrated exactly.
        let e = Entry::fresnel(1.3);
        let want = zonal_band_weights(|mu| fresnel_transmittance(mu, 1.3) * mu);
        for l in 0..3 {
            assert!((e.band_weights(0)[l] - want[l]).abs() < 2e-3 * want[0], "band {l}");
        }
        assert!((e.at(1.0).x as f64 - fresnel_transmittance(1.0, 1.3)).abs() < 1e-6);
    }

    #[test]
    fn oblique_light_returns_more_and_normal_light_is_unchanged() {
        let e = Entry::half_space(&[0.3, 0.9, 0.99], 1.0);
        let normal = e.at(1.0);
        assert!((normal - Rgb::ONE).abs().max_element() < 1e-5);
        let oblique = e.at(0.6);
        // Chandrasekhar: (1 - H(0.6)√(1-ω)) / (1 - H(1)√(1-ω)), with the random walk's figures.
        assert!(oblique.x > 1.25 && oblique.z > 1.05 && oblique.z < 1.09, "{oblique}");
    }
}
