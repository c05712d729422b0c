//! Radial tables that make tabulated profiles (photon beam diffusion, single scattering) as
//! cheap to evaluate as the dipole: `r R(r)` for the one-point estimates and the tail integral
//! `Q(r)` for the form factor (Mertens §4), per channel, calibrated to the exact half-space
//! albedo ([`super::halfspace`]).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Samples per channel of a [`RadialTable`] (the grid is `r_k = r_max (k/N)²`, `k = 0..=N`,
/// dense near 0 where profiles peak).
pub const TABLE_SIZE: usize = 1024;

/// Tails below this fraction of `Q(0)` are cut: `r_max` is where the tail falls below it.
const TAIL_CUT: f64 = 1e-8;

/// One channel's radial profile tabulated in mesh units: `r R(r)` for the one-point estimates
/// (in `f32`, linear in `x = √(r / r_max)`) and the tail `Q(r)` for the form factor (`f64`).
/// Beyond `r_max` both are 0.
#[derive(Clone, Debug, PartialEq)]
pub struct RadialTable {
    /// Largest tabulated distance (mesh units); the profile is 0 beyond it.
    pub r_max: f64,
    /// `r R(r)` at the grid points (per mesh unit).
    pub r_radial: Vec<f32>,
    /// `Q(r) = ∫_r^∞ R(t) t dt` at the grid points (unitless), non-increasing, last entry 0.
    pub tail: Vec<f64>,
    /// Smallest distance at which `R = r R / r` is evaluated (mesh units): `R` may grow like
    /// `1/r` at 0 (single scattering), and the area below it holds a negligible share.
    pub r_floor: f64,
}

/// Cell index and fraction of grid position `x` (`√(r / r_max)` times [`TABLE_SIZE`]), or
/// `None` beyond the grid.
#[inline]
fn cell_at(x: f64) -> Option<(usize, f64)> {
    (x < TABLE_SIZE as f64).then(|| {
        let i = x as usize;
        (i, x - i as f64)
    })
}

impl RadialTable {
    /// Tabulates a profile given in *optical* units (`σ_t = 1`) for a medium with extinction
    /// `sigma_t` (per mesh unit): `R(r) = σ_t² R_opt(σ_t r)`, `Q(r) = Q_opt(σ_t r)`.
    /// `tail_opt` must be non-increasing and reach 0 (or `TAIL_CUT` of its start) by
    /// optical radius `r_opt_max`.
    pub fn from_optical(
        sigma_t: f64,
        r_opt_max: f64,
        radial_opt: impl Fn(f64) -> f64,
        tail_opt: impl Fn(f64) -> f64,
    ) -> Self {
        let q0 = tail_opt(0.0);
        // Shrink the range to where the tail is negligible, by bisection on the grid variable.
        let (mut lo, mut hi) = (0.0f64, r_opt_max);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if tail_opt(mid) > TAIL_CUT * q0 { lo = mid } else { hi = mid }
        }
        let r_opt_max = hi.max(1e-6);
        let r_max = r_opt_max / sigma_t;
        let mut r_radial = Vec::with_capacity(TABLE_SIZE + 1);
        let mut tail = Vec::with_capacity(TABLE_SIZE + 1);
        for k in 0..=TABLE_SIZE {
            let x = k as f64 / TABLE_SIZE as f64;
            let r_opt = r_opt_max * x * x;
            let last = k == TABLE_SIZE;
            r_radial.push(if last { 0.0 } else { (sigma_t * r_opt * radial_opt(r_opt)) as f32 });
            tail.push(if last { 0.0 } else { tail_opt(r_opt).max(0.0) });
        }
        // Round-off must not make the tail grow outwards.
        for k in (0..TABLE_SIZE).rev() {
            tail[k] = tail[k].max(tail[k + 1]);
        }
        RadialTable { r_max, r_radial, tail, r_floor: 1e-3 / sigma_t }
    }

    /// Tabulates a profile given in optical units by `R_opt` alone, up to optical radius
    /// `r_opt_max`: the tail `Q` is integrated on the grid (trapezoid rule in `x`, from the
    /// outside in). `R_opt` is evaluated at the 1,024 inner grid points, in parallel.
    pub fn from_radial(sigma_t: f64, r_opt_max: f64, radial_opt: impl Fn(f64) -> f64 + Sync) -> Self {
        use rayon::prelude::*;
        let n = TABLE_SIZE;
        // `r R(r)` in optical units at x_k; the integrand of Q in x is `r R(r) · 2 r_max x`.
        let w: Vec<f64> = (0..=n)
            .into_par_iter()
            .map(|k| {
                let x = k as f64 / n as f64;
                let r = r_opt_max * x * x;
                if k == n { 0.0 } else { r * radial_opt(r) }
            })
            .collect();
        let mut tail = vec![0.0; n + 1];
        for k in (0..n).rev() {
            let (x0, x1) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
            let g = |x: f64, w: f64| w * 2.0 * r_opt_max * x;
            tail[k] = tail[k + 1] + 0.5 * (x1 - x0) * (g(x0, w[k]) + g(x1, w[k + 1]));
        }
        RadialTable {
            r_max: r_opt_max / sigma_t,
            r_radial: w.iter().map(|&v| (sigma_t * v) as f32).collect(),
            tail,
            r_floor: 1e-3 / sigma_t,
        }
    }

    /// `wa · self + wb · other`, for two tables on the same grid (same `σ_t` and range).
    pub fn weighted_sum(&self, wa: f64, other: &RadialTable, wb: f64) -> RadialTable {
        debug_assert!(self.r_max == other.r_max && self.r_floor == other.r_floor);
        let zip_f32 = |a: &[f32], b: &[f32]| {
            a.iter().zip(b).map(|(x, y)| (wa * *x as f64 + wb * *y as f64) as f32).collect()
        };
        RadialTable {
            r_max: self.r_max,
            r_radial: zip_f32(&self.r_radial, &other.r_radial),
            tail: self.tail.iter().zip(&other.tail).map(|(x, y)| wa * x + wb * y).collect(),
            r_floor: self.r_floor,
        }
    }

    /// Grid position of distance `r`: cell index and fraction, or `None` beyond `r_max`.
    #[inline]
    fn cell(&self, r: f64) -> Option<(usize, f64)> {
        cell_at((r.max(0.0) / self.r_max).sqrt() * TABLE_SIZE as f64)
    }

    /// `R(r)` (per mesh unit²) at distance `r` (mesh units).
    #[inline]
    pub fn radial(&self, r: f64) -> f64 {
        self.cell(r).map_or(0.0, |(i, t)| {
            let w = self.r_radial[i] as f64 * (1.0 - t) + self.r_radial[i + 1] as f64 * t;
            w / r.max(self.r_floor)
        })
    }

    /// `Q(r)` (unitless) at distance `r` (mesh units).
    #[inline]
    pub fn tail(&self, r: f64) -> f64 {
        self.cell(r).map_or(0.0, |(i, t)| self.tail_in(i, t))
    }

    /// `Q` at fraction `t` of cell `i`.
    #[inline]
    fn tail_in(&self, i: usize, t: f64) -> f64 {
        self.tail[i] * (1.0 - t) + self.tail[i + 1] * t
    }

    /// `TABLE_SIZE / √r_max`: the grid position of distance `r` is `√r` times this, so tables of
    /// several channels can share the square root ([`RadialTable::tail_at_root`]).
    #[inline]
    pub fn root_scale(&self) -> f64 {
        TABLE_SIZE as f64 / self.r_max.sqrt()
    }

    /// [`RadialTable::tail`] at the distance whose square root is `root_r`, given this table's
    /// [`RadialTable::root_scale`] `scale`.
    #[inline]
    pub fn tail_at_root(&self, root_r: f64, scale: f64) -> f64 {
        cell_at(root_r * scale).map_or(0.0, |(i, t)| self.tail_in(i, t))
    }

    /// `∫ R dA` over the plane, `2π Q(0)` (unitless).
    pub fn total(&self) -> f64 {
        std::f64::consts::TAU * self.tail[0]
    }
}

/// The tabulated part of a profile, one table per colour channel (PBD's multiple plus single
/// scattering, or only the single-scattering term added to an analytic dipole).
#[derive(Clone, Debug, PartialEq)]
pub struct ProfileTables {
    /// One table per channel.
    pub channels: [RadialTable; 3],
}

/// Shared, immutable tables (cloning a [`super::Profile`] shares them).
pub type SharedTables = Arc<ProfileTables>;

/// Per-channel tables of photon beam diffusion for reduced albedos `rho` and extinctions
/// `sigma_t` (per mesh unit) at relative index `eta`: its multiple-scattering part, its
/// single-scattering part, or both, evaluated on each channel's grid (no albedo interpolation).
///
/// The multiple-scattering part is *calibrated*: scaled so that, with the single-scattering
/// part (exact for a half-space at normal incidence), the profile integrates to the exact
/// half-space albedo ([`super::halfspace`]). Uncalibrated, diffusion returns 4-15% too much
/// light near albedo 1 and up to 40% too much multiple scattering at albedo 0.3 (the factors
/// are in `tests/beam_diffusion.rs`). The scale is taken on the tables' own integrals, so a flat
/// slab renders the exact albedo; the profile's shape is photon beam diffusion's.
pub fn channel_tables(
    rho: &[f64; 3],
    sigma_t: &[f64; 3],
    eta: f64,
    multiple: bool,
    single: bool,
) -> SharedTables {
    use super::beam_diffusion::{beam_diffusion_multiple, beam_diffusion_single};
    let channels = std::array::from_fn(|c| {
        let rho = rho[c].clamp(0.0, 1.0 - 1e-9);
        // Both parts decay at least as fast as e^{-σ_tr r}, σ_tr = √(3(1-ρ)/(2-ρ)) (Grosjean).
        let sigma_tr = (3.0 * (1.0 - rho) / (2.0 - rho)).sqrt();
        let r_opt_max = (20.0 / sigma_tr + 30.0).min(400.0);
        let ss = RadialTable::from_radial(sigma_t[c], r_opt_max, |r| {
            beam_diffusion_single(rho, 1.0 - rho, eta, r)
        });
        if !multiple {
            return ss;
        }
        let ms = RadialTable::from_radial(sigma_t[c], r_opt_max, |r| {
            beam_diffusion_multiple(rho, 1.0 - rho, eta, r)
        });
        let scale = multiple_scattering_scale(rho, eta, ms.total(), ss.total());
        ms.weighted_sum(scale, &ss, if single { 1.0 } else { 0.0 })
    });
    Arc::new(ProfileTables { channels })
}

/// The factor on photon beam diffusion's multiple scattering (total `ms_total`) that makes it,
/// plus single scattering (`ss_total`), the exact albedo of a half-space at normal incidence.
pub fn multiple_scattering_scale(rho: f64, eta: f64, ms_total: f64, ss_total: f64) -> f64 {
    let exact = super::halfspace::HalfSpace::new(rho, eta).albedo(1.0);
    if ms_total > 1e-12 { ((exact - ss_total) / ms_total).max(0.0) } else { 1.0 }
}

/// Tables made once per process for each (albedo, index) pair: the slab's transport and the
/// finite body's gain, which every face of a material shares.
pub type TableCache<T> = OnceLock<Mutex<HashMap<(u64, u64), Arc<T>>>>;

/// The table in `cache` for albedo `rho` and index `eta`, made by `make` on the first ask.
pub fn cached_table<T>(
    cache: &'static TableCache<T>,
    rho: f64,
    eta: f64,
    make: impl FnOnce() -> T,
) -> Arc<T> {
    let key = (rho.to_bits(), eta.to_bits());
    let cache = cache.get_or_init(Default::default);
    if let Some(hit) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return hit.clone();
    }
    let made = Arc::new(make());
    cache.lock().unwrap_or_else(|e| e.into_inner()).insert(key, made.clone());
    made
}
