//! Photon beam diffusion (Habel, Christensen & Jarosz 2013, "Photon Beam Diffusion: A Hybrid
//! Monte Carlo Method for Subsurface Scattering"), the radial profile of the `pbd` diffusion
//! profile and the single-scattering term, with the isotropic phase function of lucent's
//! similarity-reduced materials (`σ_s = σ_s'`, `g = 0`).
//!
//! A beam entering at normal incidence is a line of point sources, one per depth `z` with the
//! density `σ_t e^{-σ_t z}` of first interactions:
//!
//! * multiple scattering: each source is a dipole with Grosjean's diffusion coefficient
//!   `D = (2σ_a + σ_s) / (3σ_t²)`, the extrapolated boundary `z_e = -2D (1 + 3 FM_2) / (1 -
//!   2 FM_1)` and the exitance `c_φ φ + c_E E·n` (`c_φ = (1 - 2FM_1)/4`, `c_E = (1 - 3FM_2)/2`),
//!   weighted by `ρ²` and by `κ = 1 - e^{-2σ_t (d_r + z)}`, which removes what a source too close
//!   to the exit point cannot have scattered (Habel et al. §4);
//! * single scattering: the beam scatters once at depth `t` towards the exit point, attenuated
//!   along both legs and transmitted by the exit Fresnel term; below the critical depth
//!   `r √(η² - 1)` the exit direction is totally reflected.
//!
//! pbrt-v3 estimates both integrals with 100 stratified exponential samples and tabulates the
//! result over albedo and radius. lucent evaluates them per channel at material set-up on the
//! 1,025-point radial grid of [`super::RadialTable`] instead (about 10 ms for three channels):
//! there is no interpolation across albedo, and the depth integrals use composite
//! Gauss-Legendre on geometric panels, which resolves the `1/r` peak of single scattering near
//! the entry point that 100 exponential samples miss.
//!
//! Photon beam diffusion's multiple scattering is then calibrated to the exact half-space albedo
//! ([`super::halfspace`], [`super::tables::channel_tables`]); [`EffectiveAlbedo`] tabulates
//! the calibrated total over albedo, for materials given by colour.

use super::fresnel::{fresnel_dielectric, fresnel_moment1, fresnel_moment2};
use std::f64::consts::PI;

/// The two parts of a profile value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Split {
    /// Multiple scattering.
    pub multiple: f64,
    /// Single scattering.
    pub single: f64,
}

impl Split {
    /// `multiple + single`.
    pub fn total(&self) -> f64 {
        self.multiple + self.single
    }
}

/// 8-point Gauss-Legendre nodes on `[-1, 1]` (positive half) and weights.
const GL8_X: [f64; 4] =
    [0.183_434_642_495_649_8, 0.525_532_409_916_329, 0.796_666_477_413_626_7, 0.960_289_856_497_536_3];
const GL8_W: [f64; 4] =
    [0.362_683_783_378_362, 0.313_706_645_877_887_3, 0.222_381_034_453_374_5, 0.101_228_536_290_376_3];

/// `∫_a^b f` on geometric panels from `a > 0` (each `ratio` times the last) up to `b`, 8-point
/// Gauss-Legendre per panel, plus one panel on `[0, a]` when `from_zero`.
pub(crate) fn integrate_geometric(
    a: f64,
    b: f64,
    ratio: f64,
    from_zero: bool,
    f: impl Fn(f64) -> f64,
) -> f64 {
    let panel = |lo: f64, hi: f64| {
        let (m, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        (0..4).map(|k| GL8_W[k] * (f(m - h * GL8_X[k]) + f(m + h * GL8_X[k]))).sum::<f64>() * h
    };
    let mut sum = if from_zero { panel(0.0, a) } else { 0.0 };
    let mut lo = a;
    while lo < b {
        let hi = (lo * ratio).min(b);
        sum += panel(lo, hi);
        lo = hi;
    }
    sum
}

/// Photon beam diffusion's dipole for one point source (Habel et al. 2013, as pbrt-v3): Grosjean's
/// diffusion coefficient, the extrapolated boundary, and the exitance's fluence and flux weights.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointSource {
    /// Grosjean's diffusion coefficient `D = (2σ_a + σ_s) / (3σ_t²)` (length).
    pub d_g: f64,
    /// `σ_tr = sqrt(σ_a / D)` (1/length).
    pub sigma_tr: f64,
    /// The extrapolated boundary's height `z_e` (length, negative: above the surface).
    pub z_e: f64,
    /// Weights of the fluence and of the normal flux in the exitance (unitless).
    pub c_phi: f64,
    pub c_e: f64,
}

impl PointSource {
    /// For scattering `sigma_s`, absorption `sigma_a` (any common length unit) and relative
    /// index `eta`.
    pub fn new(sigma_s: f64, sigma_a: f64, eta: f64) -> Self {
        let sigma_t = sigma_s + sigma_a;
        let d_g = (2.0 * sigma_a + sigma_s) / (3.0 * sigma_t * sigma_t);
        let (fm1, fm2) = (fresnel_moment1(eta), fresnel_moment2(eta));
        PointSource {
            d_g,
            sigma_tr: (sigma_a / d_g).sqrt(),
            z_e: -2.0 * d_g * (1.0 + 3.0 * fm2) / (1.0 - 2.0 * fm1),
            c_phi: 0.25 * (1.0 - 2.0 * fm1),
            c_e: 0.5 * (1.0 - 3.0 * fm2),
        }
    }

    /// Depth of the virtual source mirroring a real one at depth `z_r` (negative: above).
    pub fn virtual_depth(&self, z_r: f64) -> f64 {
        -z_r + 2.0 * self.z_e
    }

    /// Exitance per unit source of a real source at depth `z_r` and its virtual one at `z_v`,
    /// at distances `d_r` and `d_v` from the exit point (before PBD's near-source `κ`).
    pub fn exitance(&self, z_r: f64, z_v: f64, d_r: f64, d_v: f64) -> f64 {
        let sigma_tr = self.sigma_tr;
        let (e_r, e_v) = ((-sigma_tr * d_r).exp(), (-sigma_tr * d_v).exp());
        let phi = (e_r / d_r - e_v / d_v) / (4.0 * PI * self.d_g);
        let e_n = (z_r * (1.0 + sigma_tr * d_r) * e_r / (d_r * d_r * d_r)
            - z_v * (1.0 + sigma_tr * d_v) * e_v / (d_v * d_v * d_v))
            / (4.0 * PI);
        self.c_phi * phi + self.c_e * e_n
    }
}

/// Multiple-scattering radial profile `R(r)` (per unit area, length^-2 in the units of
/// `1/σ`) of photon beam diffusion for scattering `sigma_s`, absorption `sigma_a` (any common
/// length unit, `σ_s + σ_a > 0`) and relative index `eta`, at distance `r ≥ 0`.
pub fn beam_diffusion_multiple(sigma_s: f64, sigma_a: f64, eta: f64, r: f64) -> f64 {
    let sigma_t = sigma_s + sigma_a;
    let rho = sigma_s / sigma_t;
    let source = PointSource::new(sigma_s, sigma_a, eta);
    let exitance = |z_r: f64| {
        let z_v = source.virtual_depth(z_r);
        let d_r = (r * r + z_r * z_r).sqrt();
        let d_v = (r * r + z_v * z_v).sqrt();
        let kappa = 1.0 - (-2.0 * sigma_t * (d_r + z_r)).exp();
        sigma_t * (-sigma_t * z_r).exp() * rho * rho * kappa * source.exitance(z_r, z_v, d_r, d_v)
    };
    let first = 1e-4 / sigma_t;
    integrate_geometric(first, 60.0 / sigma_t, 1.5, true, exitance).max(0.0)
}

/// Single-scattering radial profile `R(r)` (per unit area) for the same parameters as
/// [`beam_diffusion_multiple`], with the exit Fresnel transmittance and total internal
/// reflection below the critical depth.
pub fn beam_diffusion_single(sigma_s: f64, sigma_a: f64, eta: f64, r: f64) -> f64 {
    let sigma_t = sigma_s + sigma_a;
    let t_crit = r * (eta * eta - 1.0).max(0.0).sqrt();
    // Scattered at depth t (beyond the critical depth), towards the exit point at distance d.
    let integrand = |u: f64| {
        let t = t_crit + u;
        let d = (r * r + t * t).sqrt();
        if d <= 0.0 {
            return 0.0;
        }
        let cos_o = t / d;
        let transmit = 1.0 - fresnel_dielectric(cos_o, 1.0 / eta);
        sigma_s * (-sigma_t * (t + d)).exp() / (d * d) * transmit * cos_o / (4.0 * PI)
    };
    // The integrand peaks within `r` of the critical depth: panels start at a fraction of it.
    let first = (1e-3 * r).max(1e-7 / sigma_t);
    integrate_geometric(first, t_crit + 60.0 / sigma_t, 1.4, true, integrand).max(0.0)
}

/// Effective albedo `∫ 2π r R(r) dr` of one channel in optical units, by parts.
pub fn effective_albedo(rho: f64, eta: f64) -> Split {
    let part = |f: &dyn Fn(f64) -> f64| integrate_geometric(1e-5, 400.0, 1.25, true, |r| 2.0 * PI * r * f(r));
    Split {
        multiple: part(&|r| beam_diffusion_multiple(rho, 1.0 - rho, eta, r)),
        single: part(&|r| beam_diffusion_single(rho, 1.0 - rho, eta, r)),
    }
}

/// The albedo of the calibrated `pbd` profile, which is the exact half-space albedo at normal
/// incidence ([`super::halfspace`]; see [`super::tables::channel_tables`]), of one channel
/// with reduced albedo `rho` (0..=1) at relative index `eta`.
pub fn calibrated_albedo(rho: f64, eta: f64) -> f64 {
    super::halfspace::HalfSpace::new(rho.min(1.0 - 1e-9), eta).albedo(1.0)
}

/// The calibrated profile's effective albedo over albedo at one `eta`, on pbrt-v3's grid `ρ_i = (1 - e^{-8i/99}) /
/// (1 - e^{-8})`, `i = 0..100` (dense near 1, where translucent materials live), for finding the
/// albedo that gives a colour.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectiveAlbedo {
    /// Relative index of refraction the table is for.
    pub eta: f64,
    /// Albedos of the rows (0..=1, increasing).
    pub rho: Vec<f64>,
    /// Total (multiple + single) effective albedo of the calibrated profile per row
    /// ([`calibrated_albedo`], 0..1, increasing).
    pub rho_eff: Vec<f64>,
}

impl EffectiveAlbedo {
    /// Rows of the table.
    pub const ROWS: usize = 100;

    /// The table for `eta` (100 half-space albedos, in parallel: about 50 ms on two cores).
    pub fn new(eta: f64) -> Self {
        use rayon::prelude::*;
        let rho: Vec<f64> = (0..Self::ROWS)
            .map(|i| (1.0 - (-8.0 * i as f64 / (Self::ROWS - 1) as f64).exp()) / (1.0 - (-8.0f64).exp()))
            .collect();
        let rho_eff =
            rho.par_iter().map(|&r| if r > 0.0 { calibrated_albedo(r, eta) } else { 0.0 }).collect();
        EffectiveAlbedo { eta, rho, rho_eff }
    }

    /// The albedo whose total effective albedo is `target` (linear between rows), or `None`
    /// outside the table's range.
    pub fn invert(&self, target: f64) -> Option<f64> {
        let k = self.bracket(target)?;
        let (a, b) = (self.rho_eff[k], self.rho_eff[k + 1]);
        let t = if b > a { (target - a) / (b - a) } else { 0.0 };
        Some(self.rho[k] + t * (self.rho[k + 1] - self.rho[k]))
    }

    /// Like [`EffectiveAlbedo::invert`], then refined on [`calibrated_albedo`] itself (Illinois
    /// false position between the bracketing rows) to a relative 1e-6: linear interpolation
    /// alone is 1% off at albedos near 0.02, where rows are sparse.
    pub fn invert_exact(&self, target: f64) -> Option<f64> {
        let k = self.bracket(target)?;
        let f = |rho: f64| calibrated_albedo(rho, self.eta) - target;
        let (mut a, mut b) = (self.rho[k], self.rho[k + 1]);
        let (mut fa, mut fb) = (self.rho_eff[k] - target, self.rho_eff[k + 1] - target);
        let mut x = self.invert(target)?;
        for _ in 0..40 {
            if fb == fa || (b - a).abs() < 1e-12 {
                break;
            }
            x = b - fb * (b - a) / (fb - fa);
            let fx = f(x);
            if fx.abs() <= 1e-6 * target {
                break;
            }
            if (fx > 0.0) == (fb > 0.0) {
                // Same side as b: x replaces b, and the kept end's value is halved (Illinois).
                fa *= 0.5;
            } else {
                (a, fa) = (b, fb);
            }
            (b, fb) = (x, fx);
        }
        Some(x)
    }

    /// The row `k` with `rho_eff[k] <= target <= rho_eff[k + 1]`.
    fn bracket(&self, target: f64) -> Option<usize> {
        self.rho_eff.windows(2).position(|w| w[0] <= target && target <= w[1])
    }
}
