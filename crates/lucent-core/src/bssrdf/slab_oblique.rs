//! A slab's transmittance for light arriving obliquely (issue 50): what
//! `solver::transmission` scales its head-on slab term by where the far side is lit at a
//! slant.
//!
//! The same one-dimensional transport [`super::slab`] solves, with the collimated source of a
//! beam at refracted cosine `μ`, first collisions `q₀(z) = e^{-z/μ}/μ` (Chandrasekhar 1950,
//! ch. I): light entering at a slant collides nearer the lit face, so less of it crosses
//! (on 3 mm of marble `T(μ = 0.25)` is 0.53 of `T(1)`, `validation/slab_walk.py material
//! --mu0 0.25`). Tabulated per albedo as `T(τ, μ) / T(τ, 1)` over optical thickness and
//! cosine at an index-matched boundary (`η = 1`), where the solve is exact; beyond the
//! thickest row the ratio is the thickest row's (the slowest mode's share of a slanted
//! source no longer changes with depth).

use super::slab::{WALK_TAU, multiple_return_exact_many};
use super::tables::{TableCache, cached_table};
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

/// Cosines of a row, `0.05` then `0.1, 0.2, ..., 1`.
const MUS: [f64; 11] = [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0];
/// Thicknesses, log-spaced from [`TAU_MIN`] to [`WALK_TAU`].
const THICKNESSES: usize = 24;
const TAU_MIN: f64 = 0.02;

/// `T(τ, μ) / T(τ, 1)` of one albedo at `η = 1`.
#[derive(Debug)]
pub struct ObliqueTable {
    /// `ln τ` of the rows.
    ln_tau: Vec<f64>,
    /// Per row, the ratio at each of [`MUS`] (1 at `μ = 1`).
    ratio: Vec<[f64; MUS.len()]>,
}

impl ObliqueTable {
    /// The table for albedo `rho` (0..=1) at `η = 1`, made once per process (one solve per
    /// thickness for every cosine).
    pub fn cached(rho: f64) -> Arc<Self> {
        static CACHE: TableCache<ObliqueTable> = OnceLock::new();
        cached_table(&CACHE, rho, 1.0, || Self::new(rho))
    }

    fn new(rho: f64) -> Self {
        let tau: Vec<f64> = (0..THICKNESSES)
            .map(|k| TAU_MIN * (WALK_TAU / TAU_MIN).powf(k as f64 / (THICKNESSES - 1) as f64))
            .collect();
        let ratio = tau
            .par_iter()
            .map(|&t| {
                let r = multiple_return_exact_many(t, rho.clamp(0.0, 1.0), &MUS);
                let head_on = r[MUS.len() - 1].transmitted;
                std::array::from_fn(|m| if head_on > 0.0 { r[m].transmitted / head_on } else { 1.0 })
            })
            .collect();
        ObliqueTable { ln_tau: tau.iter().map(|t| t.ln()).collect(), ratio }
    }

    /// `T(τ, μ) / T(τ, 1)` for a slab `tau` mean free paths thick lit at cosine `mu`
    /// (linear in `ln τ` and `μ` between the table's; its nearest beyond them; 1 at `μ = 1`).
    pub fn ratio(&self, tau: f64, mu: f64) -> f64 {
        if tau.is_nan() || mu.is_nan() {
            return 1.0;
        }
        let x = (tau.max(TAU_MIN).ln() - self.ln_tau[0]) / (self.ln_tau[1] - self.ln_tau[0]);
        let x = x.clamp(0.0, (THICKNESSES - 1) as f64);
        let k = (x as usize).min(THICKNESSES - 2);
        let f = x - k as f64;
        let mu = mu.clamp(MUS[0], 1.0);
        let m = MUS.partition_point(|&v| v <= mu).clamp(1, MUS.len() - 1) - 1;
        let g = (mu - MUS[m]) / (MUS[m + 1] - MUS[m]);
        let at = |row: &[f64; MUS.len()]| row[m] + (row[m + 1] - row[m]) * g;
        at(&self.ratio[k]) * (1.0 - f) + at(&self.ratio[k + 1]) * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against validation/slab_walk.py (its own numpy walk; 100,000 photons, seed 3, standard
    /// error about 1%): 3 mm of marble, `material --name marble --mm 3 --mu0 MU`, red
    /// (albedo 0.99904, τ = 6.58): T 0.2010 at μ = 1, 0.1390 at 0.5, 0.1067 at 0.25.
    #[test]
    fn slanted_light_crosses_less_as_the_independent_walk_says() {
        let t = ObliqueTable::new(2.19 / 2.1921);
        let tau = 2.1921 * 3.0;
        for (mu, want) in [(0.5, 0.1390 / 0.2010), (0.25, 0.1067 / 0.2010)] {
            let got = t.ratio(tau, mu);
            assert!((got / want - 1.0).abs() < 0.04, "mu {mu}: {got} vs {want}");
        }
        assert!((t.ratio(tau, 1.0) - 1.0).abs() < 1e-12);
    }
}
