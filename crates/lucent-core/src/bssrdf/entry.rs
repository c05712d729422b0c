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
//! face lit from the side returns the energy radiative transfer gives it.
//!
//! *Where* that light returns depends on the angle too. Oblique light scatters first at a
//! shallower depth `t μ_t` along its refracted path, and the light a source at depth `z`
//! sends far along the surface grows like `z + z_b` (the dipole's real and image sources
//! separate by `2(z + z_b)`; `z_b` is photon beam diffusion's extrapolation distance). Averaged
//! over the first-interaction density `σ_t e^{-σ_t t}`, the far field of a beam with refracted
//! cosine `μ_t` is `g(μ_t) = (μ_t + σ_t z_b) / (1 + σ_t z_b)` times the normal beam's: 0.4 at
//! grazing incidence for albedo near 1 at `η = 1`. So the entry term splits in two:
//!
//! * the *carried* part `F_t g(μ_t)`, which the profile spreads (its normal-incidence shape);
//! * the *local* part `F_t (A(μ_t)/A(1) - g(μ_t))`, the extra light an oblique beam returns
//!   close to where it entered, given back at the entry face (`B += A(1) E_local`).
//!
//! Without the split, light entering near a terminator spreads into the shadow as if it had
//! entered head-on: 3.6x the path tracer's radiance on the dim side of a 10 cm marble sphere.
//!
//! Both parts are tabulated over the outside cosine `μ_i` (33 points, linear; they are smooth),
//! and their zonal band weights serve the SH environment.

use super::fresnel::{fresnel_moment1, fresnel_moment2, fresnel_transmittance};
use super::halfspace::HalfSpace;
use crate::Rgb;

/// Samples of the entry term over `μ_i = k / SAMPLES`, `k = 0..=SAMPLES`.
const SAMPLES: usize = 32;

/// The entry term `F_t(η, μ_i) A(μ_t) / A(1)` per channel, over the cosine `μ_i` between the
/// surface normal and the direction to the light (outside the material), split into the part
/// the profile carries and the part returned locally (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Relative index of refraction (unitless, >= 1 for the half-space ratio; Fresnel alone below).
    pub eta: f64,
    /// The carried part at `μ_i = k / SAMPLES`, per channel (unitless, 0..1).
    samples: Vec<[f32; 3]>,
    /// The local part at the same cosines, per channel (unitless, 0..~1).
    local: Vec<[f32; 3]>,
    /// Zonal band weights (l = 0, 1, 2, in sr) of `K(μ) = carried(μ) max(0, μ)` per channel,
    /// for the environment.
    bands: [[f32; 3]; 3],
    /// The same for the local part.
    local_bands: [[f32; 3]; 3],
}

impl Entry {
    /// Fresnel's transmittance alone (Mertens §5.3, Jensen et al. 2001): no dependence on
    /// direction beyond the boundary's.
    pub fn fresnel(eta: f64) -> Self {
        Self::from_fn(eta, |mu_i| ([fresnel_transmittance(mu_i, eta); 3], [0.0; 3]))
    }

    /// Fresnel's transmittance times the half-space albedo ratio for reduced albedos `rho` per
    /// channel (0..=1) at relative index `eta`, split into the carried part `F_t g(μ_t)` and
    /// the local rest (module docs). About a millisecond per channel. `with_single`: whether
    /// the albedo counts single scattering; without it (the profile has none, or it is computed
    /// along the view ray, which has its own dependence on the angle) the ratio is of the
    /// albedos less their direct single scattering, most of what rises at grazing incidence.
    pub fn half_space(rho: &[f64; 3], eta: f64, with_single: bool) -> Self {
        let spaces: [(HalfSpace, f64, f64); 3] = std::array::from_fn(|c| {
            let hs = HalfSpace::new(rho[c], eta);
            let normal = albedo_of(&hs, 1.0, with_single);
            (hs, normal, optical_extrapolation_distance(rho[c], eta))
        });
        Self::from_fn(eta, |mu_i| {
            // Snell: the refracted cosine inside.
            let mu_t = (1.0 - (1.0 - mu_i * mu_i) / (eta * eta)).max(0.0).sqrt();
            let f_t = fresnel_transmittance(mu_i, eta);
            let mut carried = [0.0; 3];
            let mut local = [0.0; 3];
            for (c, (hs, normal, z_b)) in spaces.iter().enumerate() {
                let ratio = if *normal > 1e-12 { albedo_of(hs, mu_t, with_single) / normal } else { 1.0 };
                let g = ((mu_t + z_b) / (1.0 + z_b)).min(ratio);
                carried[c] = f_t * g;
                local[c] = f_t * (ratio - g);
            }
            (carried, local)
        })
    }

    fn from_fn(eta: f64, f: impl Fn(f64) -> ([f64; 3], [f64; 3])) -> Self {
        let both: Vec<_> = (0..=SAMPLES).map(|k| f(k as f64 / SAMPLES as f64)).collect();
        let samples: Vec<[f32; 3]> = both.iter().map(|(a, _)| a.map(|v| v as f32)).collect();
        let local: Vec<[f32; 3]> = both.iter().map(|(_, b)| b.map(|v| v as f32)).collect();
        let bands = |table: &[[f32; 3]]| -> [[f32; 3]; 3] {
            std::array::from_fn(|c| zonal_band_weights(|mu| interpolate(table, mu as f32)[c] as f64 * mu))
        };
        Entry { eta, bands: bands(&samples), local_bands: bands(&local), samples, local }
    }

    /// The carried part at cosine `cos_i` (clamped to 0..1) per channel: what the profile
    /// spreads.
    #[inline]
    pub fn at(&self, cos_i: f32) -> Rgb {
        Rgb::from_array(interpolate(&self.samples, cos_i))
    }

    /// The local part at cosine `cos_i` per channel: what returns at the entry face itself.
    #[inline]
    pub fn local_at(&self, cos_i: f32) -> Rgb {
        Rgb::from_array(interpolate(&self.local, cos_i))
    }

    /// Whether any light is returned locally (not for Fresnel's entry).
    pub fn has_local(&self) -> bool {
        self.local.iter().any(|v| v.iter().any(|&x| x > 0.0))
    }

    /// Zonal band weights `A_l` (l = 0, 1, 2, in sr) of `carried(μ) max(0, μ)` for channel `c`
    /// (0..3), as [`crate::irradiance::BandWeights`] takes them.
    pub fn band_weights(&self, c: usize) -> [f32; 3] {
        self.bands[c]
    }

    /// The same for the local part.
    pub fn local_band_weights(&self, c: usize) -> [f32; 3] {
        self.local_bands[c]
    }
}

/// The half-space albedo at refracted cosine `mu_t`, with or without its direct single
/// scattering.
fn albedo_of(hs: &HalfSpace, mu_t: f64, with_single: bool) -> f64 {
    if with_single { hs.albedo(mu_t) } else { hs.albedo(mu_t) - hs.single_albedo(mu_t) }
}

/// A table over `μ = k / SAMPLES` at `mu` (clamped to 0..1), linearly.
#[inline]
fn interpolate(table: &[[f32; 3]], mu: f32) -> [f32; 3] {
    let x = mu.clamp(0.0, 1.0) * SAMPLES as f32;
    let k = (x as usize).min(SAMPLES - 1);
    let t = x - k as f32;
    let (a, b) = (table[k], table[k + 1]);
    std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t)
}

/// Photon beam diffusion's extrapolation distance `z_b = 2D (1 + 3 FM_2) / (1 - 2 FM_1)` in
/// optical units (`σ_t = 1`, so `D = (2 - ρ) / 3`, Grosjean's) for reduced albedo `rho` at
/// relative index `eta` (unitless; 2/3 at albedo 1 and `η = 1`).
pub fn optical_extrapolation_distance(rho: f64, eta: f64) -> f64 {
    let d = (2.0 - rho.clamp(0.0, 1.0)) / 3.0;
    2.0 * d * (1.0 + 3.0 * fresnel_moment2(eta)) / (1.0 - 2.0 * fresnel_moment1(eta))
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
        let e = Entry::half_space(&[0.3, 0.9, 0.99], 1.0, true);
        let normal = e.at(1.0) + e.local_at(1.0);
        assert!((normal - Rgb::ONE).abs().max_element() < 1e-5);
        assert!(e.local_at(1.0).max_element() < 1e-6, "a normal beam is all carried");
        let oblique = e.at(0.6) + e.local_at(0.6);
        // Chandrasekhar: (1 - H(0.6)√(1-ω)) / (1 - H(1)√(1-ω)), with the random walk's figures.
        assert!(oblique.x > 1.25 && oblique.z > 1.05 && oblique.z < 1.09, "{oblique}");
    }

    /// The carried part follows the first-interaction depth: `(μ_t + z_b) / (1 + z_b)`, with
    /// `z_b = 2/3` at albedo 1 and `η = 1` (0.4 at grazing, where Fresnel leaves nothing); the rest is local, and the two
    /// add up to the half-space ratio.
    #[test]
    fn oblique_light_is_carried_by_its_depth_and_the_rest_returns_locally() {
        assert!((optical_extrapolation_distance(1.0, 1.0) - 2.0 / 3.0).abs() < 1e-12);
        let e = Entry::half_space(&[0.999; 3], 1.0, true);
        let z_b = optical_extrapolation_distance(0.999, 1.0);
        for mu in [0.0625f32, 0.25, 0.5, 0.75] {
            let want = (mu as f64 + z_b) / (1.0 + z_b);
            assert!((e.at(mu).x as f64 - want).abs() < 1e-4, "carried at {mu}");
            assert!(e.local_at(mu).x > 0.0, "local at {mu}");
        }
        let band = |l: usize| e.band_weights(0)[l] + e.local_band_weights(0)[l];
        let total = zonal_band_weights(|mu| (e.at(mu as f32).x + e.local_at(mu as f32).x) as f64 * mu);
        assert!((band(0) - total[0]).abs() < 2e-3 * total[0]);
        assert!(!Entry::fresnel(1.3).has_local() && e.has_local());
    }
}
