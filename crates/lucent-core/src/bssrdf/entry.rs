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
//! separate by `2(z + z_b)`; `z_b` is photon beam diffusion's extrapolation distance): far from
//! the entry an oblique beam carries `(μ_t + σ_t z_b) / (1 + σ_t z_b)` of a normal beam's light,
//! 0.4 at grazing incidence for albedo near 1 at `η = 1`. Near it, a shallow source returns
//! more. The ratio of the two profiles falls slowly between (marble, `μ_t = 0.4`: 0.92 at 1 mm,
//! 0.78 at 2 mm, 0.66 at 8 mm), so the entry term splits in two:
//!
//! * the *carried* part `F_t g(μ_t)`, which the profile spreads (its normal-incidence shape),
//!   where `g` makes the light returned beyond one mean free path of the entry right (photon
//!   beam diffusion's sources at depth `μ_t t`, integrated past that distance in closed form);
//! * the *local* part `F_t (A(μ_t)/A(1) - g(μ_t))`, the rest, returned within a mean free path
//!   where a radial profile resolves nothing, given back at the entry face (`B += A(1) E_local`).
//!
//! Without the split, light entering near a terminator spreads into the shadow as if it had
//! entered head-on: 3.6x the path tracer's radiance on the dim side of a 10 cm marble sphere.
//! With the far-field share carried everywhere, the few millimetres past the terminator of a
//! 2 cm marble sphere were a third too dark (worst 8x8 block 33% beyond noise, 17% with `g`).
//!
//! Both parts are tabulated over the outside cosine `μ_i` (33 points, linear; they are smooth),
//! and their zonal band weights serve the SH environment.

use super::beam_diffusion::PointSource;
use super::fresnel::{fresnel_transmittance, refracted_cosine};
use super::halfspace::HalfSpace;
use crate::Rgb;
use std::f64::consts::PI;

/// Samples of the entry term over `μ_i = k / SAMPLES`, `k = 0..=SAMPLES`.
pub(super) const SAMPLES: usize = 32;

/// Which parts of the half-space entry term [`Entry::half_space_parts`] keeps: both in
/// lucent's default ([`EntryParts::ALL`]); the validation's ablation drops one at a time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EntryParts {
    /// The albedo ratio `A(μ_t) / A(1)`; without it the profile carries Fresnel's `F_t` alone
    /// (Mertens §5.3) and nothing returns locally (the single-scattered part is kept).
    pub ratio: bool,
    /// The split into a carried and a local part; without it the profile carries all of
    /// `F_t A(μ_t) / A(1)` with its normal-incidence shape.
    pub local: bool,
}

impl EntryParts {
    /// Every part: lucent's entry term.
    pub const ALL: EntryParts = EntryParts { ratio: true, local: true };
}

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
    /// The light scattered once that leaves directly at the entry face, at the same cosines, per
    /// channel (unitless, 0..~0.5): none where the profile carries it; where it does not, the
    /// eye sees it along the view ray, and a bounce between parts sends it on.
    single: Vec<[f32; 3]>,
    /// Zonal band weights (l = 0, 1, 2, in sr) of `K(μ) = carried(μ) max(0, μ)` per channel,
    /// for the environment.
    bands: [[f32; 3]; 3],
    /// The same for the local part.
    local_bands: [[f32; 3]; 3],
    /// The same for the single-scattered part.
    single_bands: [[f32; 3]; 3],
}

impl Entry {
    /// Fresnel's transmittance alone (Mertens §5.3, Jensen et al. 2001): no dependence on
    /// direction beyond the boundary's.
    pub fn fresnel(eta: f64) -> Self {
        Self::from_fn(eta, |mu_i| [[fresnel_transmittance(mu_i, eta); 3], [0.0; 3], [0.0; 3]])
    }

    /// Fresnel's transmittance times the half-space albedo ratio for reduced albedos `rho` per
    /// channel (0..=1) at relative index `eta`, split into the carried part `F_t g(μ_t)` and
    /// the local rest (module docs). About a millisecond per channel. `with_single`: whether
    /// the albedo counts single scattering; without it (the profile has none, or it is computed
    /// along the view ray, which has its own dependence on the angle) the ratio is of the
    /// albedos less their direct single scattering, most of what rises at grazing incidence,
    /// and that single scattering is the third part (Hanrahan & Krueger's, through the boundary).
    pub fn half_space(rho: &[f64; 3], eta: f64, with_single: bool) -> Self {
        Self::half_space_parts(rho, eta, with_single, EntryParts::ALL)
    }

    /// [`Entry::half_space`] with only the `parts` asked for: what the validation's ablation
    /// (`lucent render --ablate`, docs/corrections.md) measures each part by.
    pub fn half_space_parts(rho: &[f64; 3], eta: f64, with_single: bool, parts: EntryParts) -> Self {
        let spaces: [(HalfSpace, f64, BeyondOneMfp); 3] = std::array::from_fn(|c| {
            let hs = HalfSpace::new(rho[c], eta);
            let normal = albedo_of(&hs, 1.0, with_single);
            (hs, normal, BeyondOneMfp::new(rho[c], eta))
        });
        Self::from_fn(eta, |mu_i| {
            // Snell: the refracted cosine inside.
            let mu_t = refracted_cosine(mu_i, eta);
            let f_t = fresnel_transmittance(mu_i, eta);
            let mut carried = [0.0; 3];
            let mut local = [0.0; 3];
            let mut single = [0.0; 3];
            for (c, (hs, normal, far)) in spaces.iter().enumerate() {
                let ratio = if !parts.ratio {
                    1.0
                } else if *normal > 1e-12 {
                    albedo_of(hs, mu_t, with_single) / normal
                } else {
                    1.0
                };
                let g = if parts.ratio && parts.local { far.share(mu_t).min(ratio) } else { ratio };
                carried[c] = f_t * g;
                local[c] = f_t * (ratio - g);
                if !with_single {
                    single[c] = f_t * hs.single_albedo(mu_t);
                }
            }
            [carried, local, single]
        })
    }

    fn from_fn(eta: f64, f: impl Fn(f64) -> [[f64; 3]; 3]) -> Self {
        let parts: Vec<_> = (0..=SAMPLES).map(|k| f(k as f64 / SAMPLES as f64)).collect();
        let table = |i: usize| -> Vec<[f32; 3]> { parts.iter().map(|p| p[i].map(|v| v as f32)).collect() };
        let (samples, local, single) = (table(0), table(1), table(2));
        let bands = |table: &[[f32; 3]]| -> [[f32; 3]; 3] {
            std::array::from_fn(|c| zonal_band_weights(|mu| interpolate(table, mu as f32)[c] as f64 * mu))
        };
        Entry {
            eta,
            bands: bands(&samples),
            local_bands: bands(&local),
            single_bands: bands(&single),
            samples,
            local,
            single,
        }
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

    /// The single-scattered part at cosine `cos_i` per channel: what leaves the entry face after
    /// one scattering, when the profile does not carry it.
    #[inline]
    pub fn single_at(&self, cos_i: f32) -> Rgb {
        Rgb::from_array(interpolate(&self.single, cos_i))
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

    /// The same for the single-scattered part.
    pub fn single_band_weights(&self, c: usize) -> [f32; 3] {
        self.single_bands[c]
    }
}

/// The half-space albedo at refracted cosine `mu_t`, with or without its direct single
/// scattering.
fn albedo_of(hs: &HalfSpace, mu_t: f64, with_single: bool) -> f64 {
    if with_single { hs.albedo(mu_t) } else { hs.albedo(mu_t) - hs.single_albedo(mu_t) }
}

/// A table over `μ = k / SAMPLES` at `mu` (clamped to 0..1), linearly.
#[inline]
pub(super) fn interpolate(table: &[[f32; 3]], mu: f32) -> [f32; 3] {
    let (k, t) = interpolation_point(mu);
    let (a, b) = (table[k], table[k + 1]);
    std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t)
}

/// Where [`interpolate`] reads `mu`: the lower sample `k` and the share `t` of the next.
#[inline(always)]
pub(super) fn interpolation_point(mu: f32) -> (usize, f32) {
    let x = mu.clamp(0.0, 1.0) * SAMPLES as f32;
    let k = (x as usize).min(SAMPLES - 1);
    (k, x - k as f32)
}

/// The light an oblique beam carries past one mean free path of its entry point, over a normal
/// beam's: `M(μ_t) / M(1)`, where `M(μ_t)` integrates photon beam diffusion's exitance beyond
/// distance 1 (optical units) for point sources at depth `μ_t t` weighted by the beam's
/// scattering density `ρ e^{-t}` (the refracted beam's sideways drift left out).
///
/// Far from the entry this tends to `(μ_t + z_b) / (1 + z_b)` (the dipole's far field grows as
/// the source's depth plus `z_b`), but only slowly: for marble at `μ_t = 0.4` the oblique
/// beam's profile over the normal one is 0.92 at 1 mm, 0.78 at 2 mm and 0.66 only at 8 mm, so
/// carrying the far-field share everywhere starved the few millimetres past a terminator.
/// Within one mean free path a radial diffusion profile resolves nothing (the near-field rise
/// of a shallow source is there), so that is what the local part returns at the entry face.
#[derive(Clone, Copy, Debug)]
struct BeyondOneMfp {
    rho: f64,
    /// PBD's dipole in optical units (`σ_t = 1`).
    source: PointSource,
    /// `M(1)`.
    normal: f64,
}

impl BeyondOneMfp {
    /// Gauss-Laguerre would do; a fine midpoint rule in `u = 1 - e^{-t}` keeps it plain.
    const STEPS: usize = 128;

    fn new(rho: f64, eta: f64) -> Self {
        let rho = rho.clamp(0.0, 1.0);
        let mut b = BeyondOneMfp { rho, source: PointSource::new(rho, 1.0 - rho, eta), normal: 1.0 };
        b.normal = b.beyond(1.0);
        b
    }

    /// Exitance beyond distance 1 of a unit point source at depth `z_r`: the radial integrals
    /// of the fluence and flux terms in closed form, less PBD's near-source correction
    /// `κ = 1 - e^{-2(d_r + z_r)}`, which fades within a few mean free paths, by quadrature.
    fn point(&self, z_r: f64) -> f64 {
        let PointSource { d_g, sigma_tr, c_phi, c_e, .. } = self.source;
        let z_v = self.source.virtual_depth(z_r);
        let (d_r, d_v) = ((1.0 + z_r * z_r).sqrt(), (1.0 + z_v * z_v).sqrt());
        let (e_r, e_v) = ((-sigma_tr * d_r).exp(), (-sigma_tr * d_v).exp());
        // ∫_1^∞ 2πr e^{-σd}/d dr = 2π e^{-σ d_0} / σ; the real and virtual sources' difference
        // has the limit 2π (d_v0 - d_r0) as σ → 0.
        let phi =
            if sigma_tr > 1e-9 { (e_r - e_v) / (2.0 * d_g * sigma_tr) } else { (d_v - d_r) / (2.0 * d_g) };
        // ∫_1^∞ 2πr z(1+σd)e^{-σd}/d³ dr = 2π z e^{-σ d_0} / d_0.
        let e_n = 0.5 * (z_r * e_r / d_r - z_v * e_v / d_v);
        c_phi * phi + c_e * e_n - self.kappa_correction(z_r, z_v, d_r)
    }

    /// `∫_1^∞ 2πr e^{-2(d_r + z_r)} (c_φ φ + c_E E) dr`, over `d_r` (`r dr = d_r dd_r`) by the
    /// midpoint rule across the ten mean free paths where it lives.
    fn kappa_correction(&self, z_r: f64, z_v: f64, d_r0: f64) -> f64 {
        const STEPS: usize = 40;
        let h = 10.0 / STEPS as f64;
        let mut sum = 0.0;
        for k in 0..STEPS {
            let d_r = d_r0 + (k as f64 + 0.5) * h;
            let d_v = (d_r * d_r - z_r * z_r + z_v * z_v).sqrt();
            sum += (-2.0 * (d_r + z_r)).exp() * self.source.exitance(z_r, z_v, d_r, d_v) * 2.0 * PI * d_r;
        }
        sum * h
    }

    /// `M(μ_t)` in units of the source strength, by the midpoint rule in `u = 1 - e^{-t}`.
    fn beyond(&self, mu_t: f64) -> f64 {
        let n = Self::STEPS;
        let sum: f64 = (0..n)
            .map(|k| {
                let u = (k as f64 + 0.5) / n as f64;
                self.point(-mu_t * (1.0 - u).ln())
            })
            .sum();
        self.rho * self.rho * sum / n as f64
    }

    /// `M(μ_t) / M(1)`.
    fn share(&self, mu_t: f64) -> f64 {
        if self.normal > 1e-300 { self.beyond(mu_t) / self.normal } else { 1.0 }
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
        let e = Entry::half_space(&[0.3, 0.9, 0.99], 1.0, true);
        let normal = e.at(1.0) + e.local_at(1.0);
        assert!((normal - Rgb::ONE).abs().max_element() < 1e-5);
        assert!(e.local_at(1.0).max_element() < 1e-6, "a normal beam is all carried");
        let oblique = e.at(0.6) + e.local_at(0.6);
        // Chandrasekhar: (1 - H(0.6)√(1-ω)) / (1 - H(1)√(1-ω)), with the random walk's figures.
        assert!(oblique.x > 1.25 && oblique.z > 1.05 && oblique.z < 1.09, "{oblique}");
    }

    /// The carried part is what an oblique beam returns beyond one mean free path: less than a
    /// normal beam's, more than the far field's `(μ_t + z_b) / (1 + z_b)` (`z_b = 2/3` at albedo
    /// 1 and `η = 1`), falling with the angle; the rest is local, and the two add up to the
    /// half-space ratio.
    #[test]
    fn oblique_light_is_carried_past_one_mean_free_path_and_the_rest_returns_locally() {
        let e = Entry::half_space(&[0.999; 3], 1.0, true);
        let z_b = 2.0 * (2.0 - 0.999) / 3.0;
        let mut last = 1.0;
        for mu in [0.75f32, 0.5, 0.25, 0.0625] {
            let (carried, far) = (e.at(mu).x as f64, (mu as f64 + z_b) / (1.0 + z_b));
            assert!(carried > far + 0.05 && carried < last, "carried {carried} at {mu}: far field {far}");
            assert!(e.local_at(mu).x > 0.0, "local at {mu}");
            last = carried;
        }
        // The closed forms against photon beam diffusion's exitance integrated numerically over
        // distance and depth (the same sources, PBD's κ at each distance rather than at 1).
        for (rho, eta) in [(0.999, 1.0), (0.9, 1.3), (0.5, 1.0)] {
            let b = BeyondOneMfp::new(rho, eta);
            let by_quadrature = |mu: f64| {
                let mut m = 0.0;
                for k in 0..200 {
                    let u = (k as f64 + 0.5) / 200.0;
                    let z_r = -mu * (1.0 - u).ln();
                    // Distances 1..~300 on a geometric grid (midpoints).
                    for i in 0..400 {
                        let (r0, r1) = (1.015f64.powi(i), 1.015f64.powi(i + 1));
                        let r = 0.5 * (r0 + r1);
                        let z_v = b.source.virtual_depth(z_r);
                        let (d_r, d_v) = ((r * r + z_r * z_r).sqrt(), (r * r + z_v * z_v).sqrt());
                        let kappa = 1.0 - (-2.0 * (d_r + z_r)).exp();
                        m += kappa * b.source.exitance(z_r, z_v, d_r, d_v) * 2.0 * PI * r * (r1 - r0) / 200.0;
                    }
                }
                m
            };
            let want = by_quadrature(0.4) / by_quadrature(1.0);
            assert!((b.share(0.4) - want).abs() < 0.01 * want, "rho {rho}: {} vs {want}", b.share(0.4));
        }
        let band = |l: usize| e.band_weights(0)[l] + e.local_band_weights(0)[l];
        let total = zonal_band_weights(|mu| (e.at(mu as f32).x + e.local_at(mu as f32).x) as f64 * mu);
        assert!((band(0) - total[0]).abs() < 2e-3 * total[0]);
        assert!(!Entry::fresnel(1.3).has_local() && e.has_local());
    }

    /// The third part is Hanrahan & Krueger's single scattering leaving a half-space, per unit
    /// irradiance: at eta = 1, `α'/2 (1 - μ_i ln(1 + 1/μ_i))`; none where the profile carries it,
    /// and none for Fresnel's entry.
    #[test]
    fn the_single_part_is_hanrahan_and_krueger_s_exitance() {
        let rho = [0.999, 0.75, 0.2];
        let e = Entry::half_space(&rho, 1.0, false);
        for mu in [1.0f64, 0.5, 0.25] {
            let got = e.single_at(mu as f32);
            for c in 0..3 {
                let want = rho[c] / 2.0 * (1.0 - mu * (1.0 + 1.0 / mu).ln());
                assert!(
                    (got[c] as f64 / want - 1.0).abs() < 0.01,
                    "μ {mu} channel {c}: {} against {want}",
                    got[c]
                );
            }
        }
        assert_eq!(Entry::half_space(&rho, 1.0, true).single_at(0.5), Rgb::ZERO);
        assert_eq!(Entry::fresnel(1.3).single_at(0.5), Rgb::ZERO);
        // Its band weights integrate the same table.
        let want = zonal_band_weights(|mu| e.single_at(mu as f32).y as f64 * mu);
        assert!((e.single_band_weights(1)[0] - want[0]).abs() < 1e-3 * want[0]);
    }
}
