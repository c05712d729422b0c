//! A sphere's multiple-scattering transmittance `T(R, θ)` over albedo, walked once and
//! committed with the source (`sphere_table.bin`): what the curved cross-body term reads
//! (issues 50 and 51), so no process walks a table when its first image is made.
//!
//! `T` is [`super::sphere_walk::transmitted`]'s quantity (index-matched sphere `R` mean free
//! paths in radius, isotropic scattering of albedo `ρ`, lit head-on over one hemisphere by
//! irradiance 1; the multiple-scattering exit flux density at `θ` from the antipode of the lit
//! pole). The grid:
//!
//! * radius: [`RADIUS_STEPS`] log-spaced from [`MIN_RADIUS`] to [`WALK_R`] mean free paths;
//! * angle: [`THETA_DEG`] from the antipode (one walk scores them all);
//! * albedo: `ρ = 1`, then the albedos whose slowest decay rate `κ(ρ)`
//!   ([`super::slab::asymptotic_decay`]) is `KAPPA_FIRST · KAPPA_RATIO^j` up to
//!   [`KAPPA_LAST`] (dense near `ρ = 1`: the presets' reduced albedos are 0.9-0.99997), then
//!   [`LOW_ALBEDOS`], where `κ` saturates near 1;
//! * photons per point: [`grid_paths`].
//!
//! Between the points it interpolates linearly in `(v, ln R, θ)` the smooth quantity
//! `g = ln(T / ρ²) + 2 κ R`: at large `R` light crosses the diameter in the slowest mode, so
//! `ln T ≈ c - 2 κ R` (linear in `κ`, and `g` flat in `R`); the `ρ²` (every scored path
//! scatters at least twice) keeps `g` finite as `ρ → 0`. The albedo variable `v` is `κ(ρ)` down
//! to [`ALBEDO_SWITCH`] and continues linearly in `ρ` below it (where `κ` saturates). Below the
//! smallest radius `T` goes as `R³` (the first two collisions' chance in a small sphere); beyond
//! the largest it falls as the slab's slowest mode over the diameter, `e^{-2 κ R}`.
//!
//! Made by `cargo run --release -p lucent-core --example sphere_table` (docs/transmission.md
//! says how long it took and how the table meets fresh walks). A second table on the same grid,
//! `sphere_table_eta1.3.bin` (`--eta 1.3`), holds the same quantities for a smooth dielectric
//! boundary of the presets' index, walked forward ([`super::sphere_forward`]); both are read by
//! [`SphereTable::for_material`].

use super::slab::asymptotic_decay;
pub use super::sphere_walk::WALK_R;
use std::sync::OnceLock;

/// Radii of the table, log-spaced from [`MIN_RADIUS`] to [`WALK_R`].
pub const RADIUS_STEPS: usize = 24;
/// Smallest radius of the table (mean free paths).
pub const MIN_RADIUS: f64 = 0.25;
/// Exit angles of the table, degrees from the antipode of the lit pole.
pub const THETA_DEG: [f64; 10] = [0.0, 15.0, 30.0, 45.0, 55.0, 65.0, 72.0, 78.0, 83.0, 87.0];
/// Smallest nonzero decay rate `κ` of the albedo grid (per mean free path; `ρ ≈ 1 - 3e-6`).
const KAPPA_FIRST: f64 = 0.003;
/// Ratio of successive decay rates of the albedo grid.
const KAPPA_RATIO: f64 = 1.2;
/// Largest decay rate of the geometric part of the albedo grid (`ρ ≈ 0.8`).
pub const KAPPA_LAST: f64 = 0.75;
/// Below this albedo the interpolation variable is `ρ` itself, not `κ(ρ)` (which saturates
/// near 1). It is a grid albedo.
pub const ALBEDO_SWITCH: f64 = 0.7;
/// Albedos of the grid below the geometric part (descending; the first is [`ALBEDO_SWITCH`],
/// the last is where `T / ρ²` is taken as constant below).
pub const LOW_ALBEDOS: [f64; 8] = [0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1, 0.01];
/// Photons per point up to 4 mean free paths; in proportion to the radius beyond, up to
/// [`MAX_PATHS`].
pub const PATHS: usize = 32_768;
/// Most photons per point.
pub const MAX_PATHS: usize = 131_072;
/// Seed of the first walk of the table; point `(a, r)` uses `SEED + 64 a + r`.
pub const SEED: u64 = 0x7ab1_e000;
/// First bytes of the file (format version 2: with the exit's tilt).
const MAGIC: &[u8; 8] = b"LSPHT002";

/// The committed table, as the generator wrote it.
static COMMITTED: &[u8] = include_bytes!("sphere_table.bin");

/// The relative index of the second committed table, walked forward with a dielectric
/// boundary (`super::sphere_forward`): the presets'.
pub const DIELECTRIC_ETA: f64 = 1.3;

/// The second committed table (index [`DIELECTRIC_ETA`]).
static COMMITTED_DIELECTRIC: &[u8] = include_bytes!("sphere_table_eta1.3.bin");

/// How many times [`grid_paths`] the forward walk takes: its estimate at the antipode (a band
/// of 10 degrees) has about twice the reciprocal walk's error per photon.
pub const FORWARD_PATHS: f64 = 2.0;

/// `ln T` stored where the forward walk scored nothing (its relative error then 1): far below
/// what any image shows.
pub const UNSCORED_LN_T: f32 = -69.0;

/// The radii of the grid (mean free paths), ascending.
pub fn grid_radii() -> Vec<f64> {
    (0..RADIUS_STEPS)
        .map(|k| MIN_RADIUS * (WALK_R / MIN_RADIUS).powf(k as f64 / (RADIUS_STEPS - 1) as f64))
        .collect()
}

/// The albedos of the grid, descending from 1 (module docs).
pub fn grid_albedos() -> Vec<f64> {
    let mut rho = vec![1.0];
    let mut kappa = KAPPA_FIRST;
    while kappa <= KAPPA_LAST {
        rho.push(kappa / kappa.atanh());
        kappa *= KAPPA_RATIO;
    }
    rho.extend(LOW_ALBEDOS);
    rho
}

/// Photons walked at `radius` mean free paths ([`PATHS`], [`MAX_PATHS`]).
pub fn grid_paths(radius: f64) -> usize {
    ((PATHS as f64 * (radius / 4.0).max(1.0)) as usize).min(MAX_PATHS)
}

/// The variable in which the table interpolates over albedo `rho` (0..=1): `κ(ρ)` down to
/// [`ALBEDO_SWITCH`], then continuing linearly in `ρ` (increasing as `ρ` falls).
pub fn albedo_variable(rho: f64) -> f64 {
    let rho = rho.clamp(0.0, 1.0);
    if rho >= ALBEDO_SWITCH {
        asymptotic_decay(rho)
    } else {
        asymptotic_decay(ALBEDO_SWITCH) + (ALBEDO_SWITCH - rho)
    }
}

/// A walked table: `ln T` and its relative standard error at every (albedo, radius, angle).
#[derive(Clone, Debug, PartialEq)]
pub struct Walked {
    /// Albedos, descending (unitless, 0..=1).
    pub albedo: Vec<f64>,
    /// Radii, ascending (mean free paths).
    pub radius: Vec<f64>,
    /// Exit angles, ascending (degrees from the antipode).
    pub theta_deg: Vec<f64>,
    /// Photons walked per (albedo, radius), albedo-major.
    pub paths: Vec<u32>,
    /// `ln T` per (albedo, radius, angle), albedo-major then radius (`T` per unit incident
    /// irradiance, unitless).
    pub ln_t: Vec<f32>,
    /// The standard error of `T` over `T` at each (unitless).
    pub rel_se: Vec<f32>,
    /// The exit's tilt at each: the flux-weighted mean of `ω_o · t`, `t` the tangent away from
    /// the lit pole ([`super::sphere_walk::Exits::tilt`]; unitless).
    pub tilt: Vec<f32>,
    /// The exit's mean cosine with the normal at each ([`super::sphere_walk::Exits::normal`]).
    pub normal: Vec<f32>,
}

impl Walked {
    /// Index of (albedo `a`, radius `r`, angle `t`) in [`Walked::ln_t`].
    pub fn index(&self, a: usize, r: usize, t: usize) -> usize {
        (a * self.radius.len() + r) * self.theta_deg.len() + t
    }

    /// The little-endian bytes of the file: `LSPHT002`, the three counts (u32), the albedos,
    /// radii and angles (f64), the photon counts (u32), `ln T`, the relative errors, the
    /// tilts and the normal cosines (f32).
    pub fn encode(&self) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        for n in [self.albedo.len(), self.radius.len(), self.theta_deg.len()] {
            out.extend((n as u32).to_le_bytes());
        }
        for v in self.albedo.iter().chain(&self.radius).chain(&self.theta_deg) {
            out.extend(v.to_le_bytes());
        }
        self.paths.iter().for_each(|p| out.extend(p.to_le_bytes()));
        self.ln_t
            .iter()
            .chain(&self.rel_se)
            .chain(&self.tilt)
            .chain(&self.normal)
            .for_each(|v| out.extend(v.to_le_bytes()));
        out
    }

    /// Reads what [`Walked::encode`] wrote; `None` if it is not such a file.
    pub fn decode(bytes: &[u8]) -> Option<Walked> {
        let mut at = bytes.strip_prefix(MAGIC.as_slice())?;
        let mut take = |n: usize| -> Option<&[u8]> {
            let (head, rest) = at.split_at_checked(n)?;
            at = rest;
            Some(head)
        };
        let mut count = || -> Option<usize> { Some(u32::from_le_bytes(take(4)?.try_into().ok()?) as usize) };
        let (na, nr, nt) = (count()?, count()?, count()?);
        let f64s = |b: &[u8]| -> Vec<f64> {
            b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect()
        };
        let f32s = |b: &[u8]| -> Vec<f32> {
            b.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect()
        };
        let albedo = f64s(take(8 * na)?);
        let radius = f64s(take(8 * nr)?);
        let theta_deg = f64s(take(8 * nt)?);
        let paths =
            take(4 * na * nr)?.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap())).collect();
        let ln_t = f32s(take(4 * na * nr * nt)?);
        let rel_se = f32s(take(4 * na * nr * nt)?);
        let tilt = f32s(take(4 * na * nr * nt)?);
        let normal = f32s(take(4 * na * nr * nt)?);
        (at.is_empty() && na >= 2 && nr >= 2 && nt >= 1).then_some(Walked {
            albedo,
            radius,
            theta_deg,
            paths,
            ln_t,
            rel_se,
            tilt,
            normal,
        })
    }

    /// The table committed with the source.
    pub fn committed() -> &'static Walked {
        static TABLE: OnceLock<Walked> = OnceLock::new();
        TABLE.get_or_init(|| Walked::decode(COMMITTED).expect("sphere_table.bin is a walked table"))
    }

    /// The table committed for the dielectric boundary of index [`DIELECTRIC_ETA`].
    pub fn committed_dielectric() -> &'static Walked {
        static TABLE: OnceLock<Walked> = OnceLock::new();
        TABLE.get_or_init(|| {
            Walked::decode(COMMITTED_DIELECTRIC).expect("sphere_table_eta1.3.bin is a walked table")
        })
    }
}

/// `T(R, θ)` of a sphere for one albedo and index, from the committed tables: what
/// [`crate::solver::transmission`] reads for curved parts.
#[derive(Clone, Debug)]
pub struct SphereTable {
    /// Radii (mean free paths), ascending.
    radius: Vec<f64>,
    /// Exit angles (radians from the antipode), ascending.
    theta: Vec<f64>,
    /// `g = ln(T / ρ²) + 2 κ R` per (radius, angle), radius-major (module docs).
    g: Vec<f64>,
    /// The relative standard error of the walk behind each `g` (the larger of the two albedos').
    rel_se: Vec<f64>,
    /// The exit's tilt per (radius, angle), radius-major ([`Walked::tilt`]).
    tilt: Vec<f64>,
    /// The exit's mean normal cosine likewise ([`Walked::normal`]).
    normal: Vec<f64>,
    /// The albedo (0..=1).
    rho: f64,
    /// The slab's slowest mode's decay rate per mean free path ([`asymptotic_decay`]).
    kappa: f64,
}

impl SphereTable {
    /// The table for albedo `rho` (0..=1; clamped) at index 1, interpolated over the committed
    /// albedos (microseconds; nothing is walked).
    pub fn for_albedo(rho: f64) -> Self {
        Self::from_walked(Walked::committed(), rho)
    }

    /// The table for albedo `rho` (0..=1) and relative index `eta` (1..=3): the index-1 table,
    /// the dielectric one at [`DIELECTRIC_ETA`], linear in `η` between them (in the
    /// interpolated quantities, so geometric in `T`); above it the dielectric table's, which
    /// under-reads: a higher index traps more light inside and sends more to the far side.
    pub fn for_material(rho: f64, eta: f64) -> Self {
        let w = ((eta - 1.0) / (DIELECTRIC_ETA - 1.0)).clamp(0.0, 1.0);
        if w <= 0.0 || eta.is_nan() {
            return Self::for_albedo(rho);
        }
        let dielectric = Self::from_walked(Walked::committed_dielectric(), rho);
        if w >= 1.0 {
            return dielectric;
        }
        let mut table = Self::for_albedo(rho);
        let blend = |a: &mut Vec<f64>, b: &[f64]| a.iter_mut().zip(b).for_each(|(x, y)| *x += w * (y - *x));
        blend(&mut table.g, &dielectric.g);
        blend(&mut table.tilt, &dielectric.tilt);
        blend(&mut table.normal, &dielectric.normal);
        table.rel_se.iter_mut().zip(&dielectric.rel_se).for_each(|(x, y)| *x = x.max(*y));
        table
    }

    /// The table for albedo `rho` (0..=1; clamped) from `walked`.
    pub fn from_walked(walked: &Walked, rho: f64) -> Self {
        let rho = rho.clamp(0.0, 1.0);
        let kappa = asymptotic_decay(rho);
        let v = albedo_variable(rho);
        let nodes: Vec<f64> = walked.albedo.iter().map(|&a| albedo_variable(a)).collect();
        // Bracketing albedos and the weight of the second; constant below the last.
        let (a, w) = match nodes.partition_point(|&n| n <= v) {
            0 => (0, 0.0),
            k if k >= nodes.len() => (nodes.len() - 2, 1.0),
            k => (k - 1, (v - nodes[k - 1]) / (nodes[k] - nodes[k - 1])),
        };
        let (nr, nt) = (walked.radius.len(), walked.theta_deg.len());
        let mut g = Vec::with_capacity(nr * nt);
        let mut rel_se = Vec::with_capacity(nr * nt);
        let mut tilt = Vec::with_capacity(nr * nt);
        let mut normal = Vec::with_capacity(nr * nt);
        for (r, &radius) in walked.radius.iter().enumerate() {
            for t in 0..nt {
                let q = |a: usize| walked.ln_t[walked.index(a, r, t)] as f64 - 2.0 * walked.albedo[a].ln();
                g.push((1.0 - w) * q(a) + w * q(a + 1) + 2.0 * kappa * radius);
                let se = |a: usize| walked.rel_se[walked.index(a, r, t)] as f64;
                rel_se.push(se(a).max(se(a + 1)));
                let m = |a: usize| walked.tilt[walked.index(a, r, t)] as f64;
                tilt.push((1.0 - w) * m(a) + w * m(a + 1));
                let m = |a: usize| walked.normal[walked.index(a, r, t)] as f64;
                normal.push((1.0 - w) * m(a) + w * m(a + 1));
            }
        }
        let theta = walked.theta_deg.iter().map(|d| d.to_radians()).collect();
        SphereTable { radius: walked.radius.clone(), theta, g, rel_se, tilt, normal, rho, kappa }
    }

    /// `T(0)` of a sphere `radius` mean free paths in radius, at the antipode of the lit pole
    /// (unitless, per unit incident irradiance).
    pub fn at(&self, radius: f64) -> f64 {
        self.at_angle(radius, 0.0)
    }

    /// `T(θ)` of a sphere `radius` mean free paths in radius at `theta` radians from the
    /// antipode of the lit pole (clamped to the table's angles, 0..87°): bilinear in `ln R` and
    /// `θ` between the table's points, as `R³` below its radii, falling as `e^{-2 κ R}` beyond
    /// (module docs).
    pub fn at_angle(&self, radius: f64, theta: f64) -> f64 {
        if radius.is_nan() || radius <= 0.0 || self.rho <= 0.0 {
            return 0.0;
        }
        let n = self.radius.len();
        let r = radius.clamp(self.radius[0], self.radius[n - 1]);
        let ln_t = self.lerp(&self.g, r, theta) - 2.0 * self.kappa * r + 2.0 * self.rho.ln();
        let beyond = if radius < r { 3.0 * (radius / r).ln() } else { -2.0 * self.kappa * (radius - r) };
        (ln_t + beyond).exp()
    }

    /// The exit's tilt at `theta` radians from the antipode of a sphere `radius` mean free paths
    /// in radius ([`Walked::tilt`]): bilinear as [`SphereTable::at_angle`], the nearest radius
    /// beyond the table's.
    pub fn tilt_at(&self, radius: f64, theta: f64) -> f64 {
        self.exit_moment(&self.tilt, radius, theta).unwrap_or(0.0)
    }

    /// The exit's mean normal cosine at `theta` ([`Walked::normal`]), as [`SphereTable::tilt_at`]
    /// (a Lambertian exit's 2/3 where no light leaves).
    pub fn normal_at(&self, radius: f64, theta: f64) -> f64 {
        self.exit_moment(&self.normal, radius, theta).unwrap_or(2.0 / 3.0)
    }

    /// One of the exit's moments at `theta`, bilinear, the nearest radius beyond the table's;
    /// `None` where no light leaves (no radius, no albedo).
    fn exit_moment(&self, values: &[f64], radius: f64, theta: f64) -> Option<f64> {
        if radius.is_nan() || radius <= 0.0 || self.rho <= 0.0 {
            return None;
        }
        let n = self.radius.len();
        Some(self.lerp(values, radius.clamp(self.radius[0], self.radius[n - 1]), theta))
    }

    /// The relative standard error of the walk behind [`SphereTable::at_angle`] (unitless; its
    /// nearest points' largest, for radii within the table).
    pub fn relative_error(&self, radius: f64, theta: f64) -> f64 {
        let n = self.radius.len();
        let (r, f) = bracket(&self.radius, radius.clamp(self.radius[0], self.radius[n - 1]).ln(), f64::ln);
        let (t, g) = bracket(&self.theta, theta, |x| x);
        let nt = self.theta.len();
        let mut worst = 0.0f64;
        for (dr, wr) in [(0, 1.0 - f), (1, f)] {
            for (dt, wt) in [(0, 1.0 - g), (1, g)] {
                if wr * wt > 0.0 {
                    worst = worst.max(self.rel_se[(r + dr) * nt + (t + dt).min(nt - 1)]);
                }
            }
        }
        worst
    }

    /// Bilinear interpolation of `values` (radius-major) at radius `r` (within the table) and
    /// angle `theta`, linear in `ln R` and `θ`.
    fn lerp(&self, values: &[f64], r: f64, theta: f64) -> f64 {
        let nt = self.theta.len();
        let (k, f) = bracket(&self.radius, r.ln(), f64::ln);
        let (t, g) = bracket(&self.theta, theta, |x| x);
        let at = |k: usize, t: usize| values[k * nt + t.min(nt - 1)];
        let row = |k: usize| at(k, t) + (at(k, t + 1) - at(k, t)) * g;
        row(k) + (row((k + 1).min(self.radius.len() - 1)) - row(k)) * f
    }
}

/// The segment of ascending `nodes` holding `x` (in the variable `map`, clamped to the ends):
/// its first index and the fraction of the way to the next.
fn bracket(nodes: &[f64], x: f64, map: impl Fn(f64) -> f64) -> (usize, f64) {
    let n = nodes.len();
    if n < 2 || x.is_nan() || x <= map(nodes[0]) {
        return (0, 0.0);
    }
    if x >= map(nodes[n - 1]) {
        return (n - 2, 1.0);
    }
    let k = nodes.partition_point(|&v| map(v) <= x) - 1;
    (k, (x - map(nodes[k])) / (map(nodes[k + 1]) - map(nodes[k])))
}

#[cfg(test)]
#[path = "sphere_table_tests.rs"]
mod tests;
