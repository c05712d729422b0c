//! Multiple scattering through a slab, by random walk: what light crossing a thin part of the
//! body carries (issue 50; the transmission that Donner & Jensen 2005's multipole models in
//! diffusion theory, here in transport).
//!
//! A slab `τ` mean free paths thick (isotropic scattering, albedo `ρ`, a smooth boundary of
//! relative index `η` on both faces) is lit on one face by a collimated beam at refracted cosine
//! `μ` inside. What leaves is split as lucent splits it ([`super::walk`]): unscattered light
//! and direct single scattering (one scattering, no internal reflection) are the view ray's;
//! the rest is multiple scattering, the part a diffusion profile carries. This module gives
//! that multiple scattering's total transmittance `T(τ)` (out of the far face) and reflectance
//! `R(τ)` (out of the lit face), per unit flux entering.
//!
//! At `η = 1` (an index-matched boundary, the validation suite's) the answer is deterministic:
//! the collision density `ψ(z)` obeys the one-dimensional transport equation in integral form,
//! `ψ(z) = q₀(z) + ρ ∫₀^τ ½E₁(|z - z'|) ψ(z') dz'` with the first collisions
//! `q₀(z) = e^{-z/μ}/μ`, and what a collision at depth `z` sends out of the far face before
//! colliding again is `ρ ½E₂(τ - z)` (Chandrasekhar 1950, ch. I; Case & Zweifel 1967). lucent
//! solves it with the density constant over cells of at most [`CELL_TAU`] mean free paths and
//! the kernel integrated exactly over each cell (product integration, which takes `E₁`'s
//! logarithmic peak); multiple scattering is what `ψ - q₀` sends out. With a reflecting
//! boundary (`η ≠ 1`) photons are walked and scored where they leave. Beyond [`WALK_TAU`] mean
//! free paths `T` falls as the transport equation's slowest mode: the ratio of
//! `sinh(κ (τ + 2 z₀))`, with `κ` the root of `ρ atanh(κ) = κ` (Case's discrete eigenvalue)
//! and `z₀ = 0.7104` Milne's extrapolation length, scaled to meet the last solved point.
//! `validation/slab_walk.py` is an independent numpy walk of the same quantities.

use super::fresnel::fresnel_dielectric;
use super::halfspace::HalfSpace;
use super::tables::{TableCache, cached_table};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

/// Photons below this weight play Russian roulette (survivors double).
const ROULETTE: f64 = 0.05;
/// Largest cell (mean free paths) of [`multiple_return_exact`]'s collision density.
pub const CELL_TAU: f64 = 0.15;
/// Most cells of one solve (thicker slabs get wider cells).
const MAX_CELLS: usize = 1000;
/// Milne's extrapolation length for isotropic scattering (mean free paths).
pub const MILNE_Z0: f64 = 0.710_446;
/// No path is followed further (reached only at albedo 1 in very thick slabs).
const MAX_STEPS: usize = 1 << 20;
/// Thickest slab walked (mean free paths); beyond it `T` falls as the slowest mode.
pub const WALK_TAU: f64 = 24.0;

/// Multiple-scattering transmittance and reflectance of a slab.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SlabReturn {
    /// Through the far face, per unit flux entering (unitless, 0..1).
    pub transmitted: f64,
    /// Back out of the lit face (unitless, 0..1).
    pub reflected: f64,
}

/// `E₁(x)` for `x > 0`: the series below 1, the continued fraction above (relative error
/// under 1e-12).
fn exp_integral_e1(x: f64) -> f64 {
    if x <= 0.0 {
        return f64::INFINITY;
    }
    if x < 1.0 {
        // -γ - ln x - Σ (-x)^k / (k k!)
        let mut sum = 0.0;
        let mut term = 1.0;
        for k in 1..40 {
            term *= -x / k as f64;
            sum += term / k as f64;
        }
        -0.577_215_664_901_532_9 - x.ln() - sum
    } else {
        // Lentz's continued fraction for e^x E₁(x).
        let (mut b, mut c, mut d) = (x + 1.0, 1e300, 1.0 / (x + 1.0));
        let mut h = d;
        for i in 1..200 {
            let a = -((i * i) as f64);
            b += 2.0;
            d = 1.0 / (a * d + b);
            c = b + a / c;
            let del = c * d;
            h *= del;
            if (del - 1.0).abs() < 1e-14 {
                break;
            }
        }
        h * (-x).exp()
    }
}

/// `E₂(x) = e^{-x} - x E₁(x)` for `x >= 0` (`E₂(0) = 1`).
pub fn exp_integral_e2(x: f64) -> f64 {
    if x <= 0.0 { 1.0 } else { (-x).exp() - x * exp_integral_e1(x) }
}

/// The slowest decay rate `κ` (per mean free path) of light in an infinite medium of albedo
/// `rho` under isotropic scattering: the root of `ρ atanh(κ) = κ` in `0..1` (0 at `ρ = 1`).
pub fn asymptotic_decay(rho: f64) -> f64 {
    if rho >= 1.0 {
        return 0.0;
    }
    if rho <= 0.0 {
        return 1.0;
    }
    // f(κ) = ρ atanh(κ) - κ is positive just below 1 and negative just above 0.
    let (mut lo, mut hi) = (0.0f64, 1.0 - 1e-15);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if rho * mid.atanh() - mid > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `E₃(x) = (e^{-x} - x E₂(x)) / 2` for `x >= 0` (`E₃(0) = 1/2`).
fn exp_integral_e3(x: f64) -> f64 {
    if x <= 0.0 { 0.5 } else { 0.5 * ((-x).exp() - x * exp_integral_e2(x)) }
}

/// Multiple-scattering return of a slab `tau` mean free paths thick (index-matched faces,
/// isotropic scattering of albedo `rho`, 0..=1) lit by a collimated beam at cosine `mu`
/// (0..=1]: the integral equation of the module docs on cells of at most [`CELL_TAU`]. Within
/// 0.3% of a converged walk (tests, `validation/slab_walk.py`).
pub fn multiple_return_exact(tau: f64, rho: f64, mu: f64) -> SlabReturn {
    multiple_collisions(tau, rho, mu).map_or_else(SlabReturn::default, |(edges, m)| escaping(tau, &edges, &m))
}

/// What the collisions `multiple` (per cell of `edges`) send out of each face of a slab `tau`
/// thick: `½ ∫_cell E₂(distance) dz` each.
fn escaping(tau: f64, edges: &[f64], multiple: &[f64]) -> SlabReturn {
    let mut out = SlabReturn::default();
    for (j, m) in multiple.iter().enumerate() {
        let (a, b) = (edges[j], edges[j + 1]);
        out.transmitted += m * 0.5 * (exp_integral_e3(tau - b) - exp_integral_e3(tau - a));
        out.reflected += m * 0.5 * (exp_integral_e3(a) - exp_integral_e3(b));
    }
    out
}

/// The radiance of the multiple scattering a slab transmits (as [`multiple_return_exact`],
/// normal incidence) at each exit cosine of `mus` (0..=1), over what a Lambertian exit of the
/// same exitance would have, `π I(μ) / T` (1 everywhere for a Lambertian; empty where
/// nothing is transmitted), with the slab's return.
pub fn transmitted_lobe_exact(tau: f64, rho: f64, mus: &[f64]) -> (Vec<f64>, SlabReturn) {
    let Some((edges, multiple)) = multiple_collisions(tau, rho, 1.0) else {
        return (Vec::new(), SlabReturn::default());
    };
    let ret = escaping(tau, &edges, &multiple);
    if ret.transmitted <= 1e-300 {
        return (Vec::new(), ret);
    }
    let lobe = mus
        .iter()
        .map(|&mu| {
            if mu <= 1e-6 {
                return 0.0;
            }
            // I(μ) = Σ ρ(ψ - q₀)/(4π) ∫_cell e^{-(τ - z)/μ} dz / μ.
            let i: f64 = multiple
                .iter()
                .enumerate()
                .map(|(j, m)| m * ((-(tau - edges[j + 1]) / mu).exp() - (-(tau - edges[j]) / mu).exp()))
                .sum::<f64>()
                / (4.0 * std::f64::consts::PI);
            std::f64::consts::PI * i / ret.transmitted
        })
        .collect();
    (lobe, ret)
}

/// The cell edges of the solve and, per cell, the density of collisions after which light
/// is scattered a second time or more, `ρ (ψ - q₀)` (module docs); `None` for an empty slab.
fn multiple_collisions(tau: f64, rho: f64, mu: f64) -> Option<(Vec<f64>, Vec<f64>)> {
    multiple_collisions_many(tau, rho, &[mu]).map(|(edges, mut m)| (edges, m.swap_remove(0)))
}

/// Multiple-scattering return of a slab (as [`multiple_return_exact`]) for beams at each
/// cosine of `mus`: one system, a right-hand side per cosine.
pub fn multiple_return_exact_many(tau: f64, rho: f64, mus: &[f64]) -> Vec<SlabReturn> {
    match multiple_collisions_many(tau, rho, mus) {
        Some((edges, m)) => m.iter().map(|m| escaping(tau, &edges, m)).collect(),
        None => vec![SlabReturn::default(); mus.len()],
    }
}

/// [`multiple_collisions`] for beams at each cosine of `mus` (one solve of the system).
fn multiple_collisions_many(tau: f64, rho: f64, mus: &[f64]) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    if tau <= 0.0 || rho <= 0.0 || mus.is_empty() {
        return None;
    }
    let edges = cell_edges(tau);
    let n = edges.len() - 1;
    let edge = |j: usize| edges[j];
    // The system (I - ρK) ψ = q₀, K_ij = ½ ∫_cell j E₁(|c_i - z'|) dz' at cell i's centre.
    let mut a = vec![0.0; n * n];
    let mut q0 = vec![vec![0.0; n]; mus.len()];
    for i in 0..n {
        let c = 0.5 * (edge(i) + edge(i + 1));
        for j in 0..n {
            let k = if j == i {
                1.0 - 0.5 * exp_integral_e2(c - edge(i)) - 0.5 * exp_integral_e2(edge(i + 1) - c)
            } else if j > i {
                0.5 * (exp_integral_e2(edge(j) - c) - exp_integral_e2(edge(j + 1) - c))
            } else {
                0.5 * (exp_integral_e2(c - edge(j + 1)) - exp_integral_e2(c - edge(j)))
            };
            a[i * n + j] = if i == j { 1.0 } else { 0.0 } - rho * k;
        }
        // The cell's mean first-collision density.
        for (q, &mu) in q0.iter_mut().zip(mus) {
            let mu = mu.clamp(1e-3, 1.0);
            q[i] = ((-edge(i) / mu).exp() - (-edge(i + 1) / mu).exp()) / (edge(i + 1) - edge(i));
        }
    }
    let psi = solve_dense(&mut a, q0.clone(), n);
    let multiple = psi.iter().zip(&q0).map(|(p, q)| (0..n).map(|j| rho * (p[j] - q[j])).collect()).collect();
    Some((edges, multiple))
}

/// Cell edges over `0..tau` for [`multiple_return_exact`]: fine at both faces, where the
/// first collisions and the escape chances change over a fraction of a mean free path, and
/// growing by 15% per cell into the slab up to [`CELL_TAU`] (about 200 cells at 24 mean
/// free paths).
fn cell_edges(tau: f64) -> Vec<f64> {
    let first = (0.004f64).min(tau / 16.0);
    // One half from the lit face, mirrored for the other.
    let mut half = vec![0.0];
    let mut h = first;
    while half[half.len() - 1] + h < 0.5 * tau {
        half.push(half[half.len() - 1] + h);
        h = (h * 1.15).min(CELL_TAU);
    }
    let mut edges = half.clone();
    edges.push(0.5 * tau);
    edges.extend(half.iter().rev().map(|z| tau - z));
    edges.truncate(MAX_CELLS + 1);
    edges
}

/// Solves the dense `n`×`n` system `a x = b` (row-major, diagonally dominant: `I - ρK` with
/// `ρ ‖K‖ < 1`) for each right-hand side of `bs` by Gaussian elimination without pivoting.
fn solve_dense(a: &mut [f64], mut bs: Vec<Vec<f64>>, n: usize) -> Vec<Vec<f64>> {
    for k in 0..n {
        let pivot = a[k * n + k];
        for i in k + 1..n {
            let f = a[i * n + k] / pivot;
            if f == 0.0 {
                continue;
            }
            for j in k..n {
                a[i * n + j] -= f * a[k * n + j];
            }
            bs.iter_mut().for_each(|b| b[i] -= f * b[k]);
        }
    }
    for b in &mut bs {
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| a[k * n + j] * b[j]).sum();
            b[k] = (b[k] - s) / a[k * n + k];
        }
    }
    bs
}

/// A unit direction's cosine with the slab's normal, uniformly over the sphere.
#[inline]
fn isotropic_cosine(rng: &mut Pcg64Mcg) -> f64 {
    1.0 - 2.0 * rng.random::<f64>()
}

/// Multiple-scattering return of a slab `tau` mean free paths thick, albedo `rho` (0..=1),
/// relative index `eta` (>= 1), lit by a collimated beam at refracted cosine `mu` (0..=1]
/// inside, from `paths` photons seeded by `seed` (the same arguments give the same value on any
/// machine). At `eta = 1` [`multiple_return_exact`] gives the same without noise.
pub fn multiple_return_walked(tau: f64, rho: f64, eta: f64, mu: f64, paths: usize, seed: u64) -> SlabReturn {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mu = mu.clamp(1e-3, 1.0);
    let mut sum = SlabReturn::default();
    for k in 0..paths {
        // Stratified first flight: the depth of the first collision.
        let u = (k as f64 + rng.random::<f64>()) / paths as f64;
        let z = -(1.0 - u).ln() * mu;
        if z >= tau {
            continue;
        }
        let r = walk_out(tau, rho, eta, z, &mut rng);
        sum.transmitted += r.transmitted;
        sum.reflected += r.reflected;
    }
    let n = paths as f64;
    SlabReturn { transmitted: sum.transmitted / n, reflected: sum.reflected / n }
}

/// One photon after its first collision at depth `z`, walked out through Fresnel-reflecting
/// faces and scored where it leaves.
fn walk_out(tau: f64, rho: f64, eta: f64, mut z: f64, rng: &mut Pcg64Mcg) -> SlabReturn {
    let mut weight = rho;
    let (mut scatters, mut reflected) = (1u32, false);
    let mut cos = isotropic_cosine(rng);
    for _ in 0..MAX_STEPS {
        let step = -(1.0 - rng.random::<f64>()).ln();
        let z_next = z + step * cos;
        if z_next <= 0.0 || z_next >= tau {
            z = if z_next <= 0.0 { 0.0 } else { tau };
            if rng.random::<f64>() < fresnel_dielectric(cos.abs(), 1.0 / eta) {
                cos = -cos;
                reflected = true;
                continue;
            }
            let counted = scatters >= 2 || reflected;
            let w = if counted { weight } else { 0.0 };
            return if z == tau {
                SlabReturn { transmitted: w, reflected: 0.0 }
            } else {
                SlabReturn { transmitted: 0.0, reflected: w }
            };
        }
        z = z_next;
        weight *= rho;
        scatters += 1;
        cos = isotropic_cosine(rng);
        if weight < ROULETTE {
            if rng.random::<f64>() < 0.5 {
                return SlabReturn::default();
            }
            weight *= 2.0;
        }
    }
    SlabReturn::default()
}

/// Thinnest slab of a [`SlabTable`] (mean free paths); below it `T` and `R` go to 0 in
/// proportion to the thickness.
const TABLE_MIN_TAU: f64 = 0.02;
/// Thicknesses of a [`SlabTable`], log-spaced from [`TABLE_MIN_TAU`] to [`WALK_TAU`].
const TABLE_STEPS: usize = 24;
/// Photons per thickness where the boundary reflects (`η ≠ 1`): a standard error of about
/// 1% of `T` at 20 mean free paths.
const WALK_PATHS: usize = 16_384;
/// Exit cosines of a [`SlabTable`]'s transmitted lobe, `0, 1/16, ..., 1`.
pub const LOBE_MU: usize = 17;

/// A thickness's place among a [`SlabTable`]'s lobes: the thinner row `k` and the share `f`
/// (0..=1) of the next, interpolated in `ln τ`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LobeRow {
    k: u32,
    f: f32,
}

/// A slab's multiple-scattering transmittance and reflectance over optical thickness for one
/// albedo and index, at normal incidence: what [`crate::solver::transmission`] reads.
#[derive(Debug)]
pub struct SlabTable {
    /// Optical thicknesses (mean free paths), log-spaced.
    tau: Vec<f64>,
    /// [`SlabReturn`] at each.
    at: Vec<SlabReturn>,
    /// At each, the transmitted light's radiance over a Lambertian exit's at exit cosines
    /// `k / (LOBE_MU - 1)` ([`transmitted_lobe_exact`]); empty where `η ≠ 1` (not modelled).
    lobe: Vec<[f32; LOBE_MU]>,
    /// The slowest mode's decay rate per mean free path ([`asymptotic_decay`]).
    kappa: f64,
    /// The half-space's multiple-scattering albedo at normal incidence: `R` of an infinitely
    /// thick slab.
    half_space: f64,
}

impl SlabTable {
    /// The table for albedo `rho` (0..=1) and index `eta` (>= 1), made once per process for
    /// each pair (tens of milliseconds).
    pub fn cached(rho: f64, eta: f64) -> Arc<Self> {
        static CACHE: TableCache<SlabTable> = OnceLock::new();
        cached_table(&CACHE, rho, eta, || Self::new(rho, eta))
    }

    fn new(rho: f64, eta: f64) -> Self {
        let rho = rho.clamp(0.0, 1.0);
        let tau: Vec<f64> = (0..TABLE_STEPS)
            .map(|k| TABLE_MIN_TAU * (WALK_TAU / TABLE_MIN_TAU).powf(k as f64 / (TABLE_STEPS - 1) as f64))
            .collect();
        let mus: Vec<f64> = (0..LOBE_MU).map(|k| k as f64 / (LOBE_MU - 1) as f64).collect();
        let rows: Vec<(SlabReturn, [f32; LOBE_MU])> = tau
            .par_iter()
            .enumerate()
            .map(|(k, &t)| {
                if eta == 1.0 {
                    let (l, ret) = transmitted_lobe_exact(t, rho, &mus);
                    (ret, std::array::from_fn(|k| l.get(k).map_or(1.0, |&v| v as f32)))
                } else {
                    (multiple_return_walked(t, rho, eta, 1.0, WALK_PATHS, k as u64), [1.0; LOBE_MU])
                }
            })
            .collect();
        let at = rows.iter().map(|r| r.0).collect();
        let lobe = if eta == 1.0 { rows.iter().map(|r| r.1).collect() } else { Vec::new() };
        let hs = HalfSpace::new(rho, eta);
        let half_space = (hs.albedo(1.0) - hs.single_albedo(1.0)).max(0.0);
        SlabTable { tau, at, lobe, kappa: asymptotic_decay(rho), half_space }
    }

    /// Where a slab `tau` mean free paths thick reads the transmitted lobe ([`SlabTable::lobe_at`]):
    /// between the table's nearest thicknesses (its thinnest and thickest beyond them), or
    /// `None` where the table has no lobe (`η ≠ 1`). It does not depend on the exit direction,
    /// so a caller that reads many directions finds it once.
    pub fn lobe_row(&self, tau: f64) -> Option<LobeRow> {
        if self.lobe.is_empty() || tau.is_nan() || tau <= 0.0 {
            return None;
        }
        let n = self.tau.len();
        let (k, f) = if tau <= self.tau[0] {
            (0, 0.0)
        } else if tau >= self.tau[n - 1] {
            (n - 2, 1.0)
        } else {
            let k = self.tau.partition_point(|&v| v <= tau) - 1;
            (k, ((tau / self.tau[k]).ln() / (self.tau[k + 1] / self.tau[k]).ln()) as f32)
        };
        Some(LobeRow { k: k as u32, f })
    }

    /// The transmitted light's radiance at exit cosine `mu` over a Lambertian exit's, for the
    /// slab `row` stands for ([`SlabTable::lobe_row`]).
    #[inline]
    pub fn lobe_at(&self, row: LobeRow, mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0) * (LOBE_MU - 1) as f32;
        let i = (x as usize).min(LOBE_MU - 2);
        let g = x - i as f32;
        let at = |row: &[f32; LOBE_MU]| row[i] + (row[i + 1] - row[i]) * g;
        let k = row.k as usize;
        at(&self.lobe[k]) * (1.0 - row.f) + at(&self.lobe[k + 1]) * row.f
    }

    /// The slab's multiple-scattering return at optical thickness `tau` (mean free paths):
    /// between the table's thicknesses linear in `ln τ` (`T`'s logarithm), in proportion to `τ` below them, and
    /// beyond them `T` falls and `R` rises to the half-space's as the slowest mode (module
    /// docs).
    pub fn at(&self, tau: f64) -> SlabReturn {
        let n = self.tau.len();
        if tau.is_nan() || tau <= 0.0 {
            return SlabReturn::default();
        }
        if tau <= self.tau[0] {
            let f = tau / self.tau[0];
            return SlabReturn {
                transmitted: self.at[0].transmitted * f,
                reflected: self.at[0].reflected * f,
            };
        }
        if tau >= self.tau[n - 1] {
            let last = self.at[n - 1];
            let mode = |t: f64| {
                let x = self.kappa * (t + 2.0 * MILNE_Z0);
                if x < 1e-9 {
                    t + 2.0 * MILNE_Z0
                } else if x > 600.0 {
                    f64::INFINITY
                } else {
                    x.sinh() / self.kappa
                }
            };
            let ratio = mode(self.tau[n - 1]) / mode(tau);
            let ratio = if ratio.is_finite() { ratio } else { 0.0 };
            return SlabReturn {
                transmitted: last.transmitted * ratio,
                reflected: self.half_space - (self.half_space - last.reflected) * ratio,
            };
        }
        let k = self.tau.partition_point(|&v| v <= tau) - 1;
        let f = (tau / self.tau[k]).ln() / (self.tau[k + 1] / self.tau[k]).ln();
        let (a, b) = (self.at[k], self.at[k + 1]);
        // T falls about exponentially: interpolated in its logarithm where both are positive.
        let transmitted = if a.transmitted > 0.0 && b.transmitted > 0.0 {
            a.transmitted * (b.transmitted / a.transmitted).powf(f)
        } else {
            a.transmitted + (b.transmitted - a.transmitted) * f
        };
        SlabReturn { transmitted, reflected: a.reflected + (b.reflected - a.reflected) * f }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn e2_matches_known_values() {
        // ∫₀¹ e^{-x/μ} dμ by the trapezoid rule on 4M points (numpy).
        for (x, want) in [(0.5, 0.326_643_86), (1.0, 0.148_495_51), (2.0, 0.037_534_26), (5.0, 0.000_996_469)]
        {
            assert!((exp_integral_e2(x) / want - 1.0).abs() < 1e-5, "E2({x}) = {}", exp_integral_e2(x));
        }
    }

    #[test]
    fn decay_is_diffusions_near_albedo_one() {
        // κ² ≈ 3 (1 - ρ) for ρ → 1; κ → 1 for ρ → 0.
        let k = asymptotic_decay(0.999);
        assert!((k / (3.0f64 * 0.001).sqrt() - 1.0).abs() < 0.01, "{k}");
        assert!(asymptotic_decay(1e-6) > 0.999);
    }

    /// The table between and beyond its thicknesses against the solve itself.
    #[test]
    fn table_interpolates_and_extends() {
        let rho = 0.9926;
        let t = SlabTable::cached(rho, 1.0);
        for tau in [0.3, 3.3, 17.0, 40.0] {
            let got = t.at(tau);
            let want = multiple_return_exact(tau, rho, 1.0);
            assert!(
                (got.transmitted / want.transmitted - 1.0).abs() < 0.02,
                "tau {tau}: {got:?} vs {want:?}"
            );
            assert!((got.reflected / want.reflected - 1.0).abs() < 0.02, "tau {tau}: {got:?} vs {want:?}");
        }
    }

    /// Against validation/slab_walk.py's `lobe --tau 6.58 --albedo 0.99904` (400,000 photons;
    /// marble's red): forward-peaked, 0.83 and 0.94 at μ = 0.45 and 0.55, 1.21 at 0.95, where the
    /// half-space's multiple scattering is 1.04-1.07 head-on.
    #[test]
    fn transmitted_lobe_matches_the_independent_walk() {
        // (The walk's bins are 0.1 wide: its first, where the lobe bends, is left out.)
        let (got, _) = transmitted_lobe_exact(6.58, 0.99904, &[0.45, 0.55, 0.95]);
        for (g, want) in got.iter().zip([0.83, 0.936, 1.206]) {
            assert!((g / want - 1.0).abs() < 0.03, "{got:?}");
        }
    }

    /// Against validation/slab_walk.py (its own numpy walk, 400,000 photons): marble's red
    /// (albedo 0.99904) at normal incidence.
    #[test]
    fn marble_red_matches_the_independent_walk() {
        for (tau, t, r) in [(1.0, 0.1839, 0.1976), (5.0, 0.2452, 0.5796), (20.0, 0.0633, 0.7411)] {
            let got = multiple_return_exact(tau, 2.19 / 2.1921, 1.0);
            // The reference's standard error is 0.2-0.5%.
            assert!((got.transmitted / t - 1.0).abs() < 0.015, "tau {tau}: T {} vs {t}", got.transmitted);
            assert!((got.reflected / r - 1.0).abs() < 0.01, "tau {tau}: R {} vs {r}", got.reflected);
        }
    }
}
