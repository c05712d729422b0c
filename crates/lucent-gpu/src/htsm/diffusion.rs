//! The `diffusion` transport model's constants (issue 55 item 2): what HTSM's hierarchical
//! samples (Shopf 2007 §4.3.1, fig. 4.3) weigh, derived from the medium's coefficients rather
//! than the thesis's equal weights `1/n`, and what light crossing the body keeps.
//!
//! # The quadrature
//!
//! The exitance at a visible point is `M(x_o) = integral E(x_i) K(x_i -> x_o) dA_i` over the lit
//! surface; HTSM samples `E` at the centre and on rings at 1, 2 and 4 times the kernel radius
//! `r_1`. Each sample stands for the part of the plane nearer its ring than any other: the
//! centre for the disc `r < r_1 / 2`, ring 1 for `r_1 / 2 .. 1.5 r_1`, ring 2 for
//! `1.5 r_1 .. 3 r_1`, ring 3 for `3 r_1 .. 6 r_1`, and the outermost ring present for
//! everything beyond (so the weights of a uniformly lit plane sum to the kernel's total). A
//! sample's weight is the kernel integrated over its annulus, divided among the ring's samples.
//!
//! The kernel's lateral shape is the dipole's (Jensen et al. 2001, eq. 4 without the albedo): a
//! source at depth `z` below the exit plane and its image at `z + 2 z_b`. The annulus integral
//! has a closed form: `integral_{b_0}^{b_1} z (1 + s d) e^{-s d} / d^3 2 pi r dr` (with
//! `d = sqrt(r^2 + z^2)`, `s = sigma_tr`) is `2 pi e^{-s z} (F(b_0) - F(b_1))` with
//! `F(b) = z / d(b) e^{-s (d(b) - z)}`, `F(0) = 1`, `F(inf) = 0`: [`kernel_share`].
//!
//! # The kernel's medium and total
//!
//! The kernel is that of the medium along the sample's ray: its mean density (for `sigma_t'`,
//! hence `z_r` and `z_b`, and the albedo) and its mean `sigma_tr` (the ray cast's optical depth
//! over its length, [`super::medium`]), so that in a uniform body it is the medium's exactly and
//! through a heterogeneous one its attenuation is the ray cast's.
//!
//! * **A visible point the light reaches** (the shadow test of the lit side): light enters and
//!   leaves the same face; the kernel's source is at `z_r = 1 / sigma_t'`; the total is the half-space's albedo for the light's incidence
//!   cosine, exact transport (Chandrasekhar's H function, `lucent_core::bssrdf::halfspace`),
//!   single scattering included ([`DiffusionUniforms::albedo`]).
//! * **A point the light does not reach**: its samples' light crossed the body. The kernel's
//!   source is at the depth `h` the sample lies below the visible point's tangent plane; the
//!   total is the multiple-scattering transmittance of a slab from lucent-core's exact
//!   one-dimensional transport (`lucent_core::bssrdf::slab::SlabTable`, normal incidence;
//!   [`DiffusionUniforms::slab`]), in place of the straight ray's `exp(-sigma_tr D)`, as thick
//!   as the ray extends along the light (times the ray cast's mean `sigma_tr`): the rest of the
//!   ray is the sample's offset in the light view, whose attenuation the annulus share already
//!   carries, so a laterally uniform slab lit along its normal gets its `T` exactly. The light
//!   leaves by diffusion's exit lobe at an index-matched boundary, `(1 + 1.5 mu_o) / 2` of a
//!   Lambertian exit's radiance. The table leaves single scattering out (lucent gives it to the
//!   view ray); the camera pass adds the view ray's own (`view_single_scattering` in
//!   `htsm_render.wgsl`, docs/htsm.md).
//!
//! Both tables are made at [`DENSITY_LEVELS`] densities and interpolated.

use super::medium::HtsmCoefficients;
use bytemuck::{Pod, Zeroable};
use lucent_core::bssrdf::halfspace::HalfSpace;
use lucent_core::bssrdf::slab::SlabTable;
use lucent_core::bssrdf::{boundary_a, refracted_cosine};

/// Entries of the albedo table per density: incidence cosines `k / (ALBEDO_ENTRIES - 1)`.
pub const ALBEDO_ENTRIES: usize = 9;
/// Entries of the slab table per density: diffusion optical depths `(k * SLAB_STEP)^2`.
pub const SLAB_ENTRIES: usize = 33;
/// Spacing of the slab table in the square root of the diffusion optical depth `sigma_tr h`
/// (dimensionless; the table reaches `sigma_tr h = 16`). Even steps in the root are fine where a
/// thin slab's transmittance rises steeply from zero (at low absorption `sigma_tr h = 0.5` is
/// several mean free paths) and coarse where `T e^x` has flattened.
pub const SLAB_STEP: f32 = 0.125;
/// Densities the tables are made at: `k / (DENSITY_LEVELS - 1)`, interpolated linearly between.
pub const DENSITY_LEVELS: usize = 9;

/// The diffusion model's part of the frame uniforms; mirrors the fields of `Frame` in
/// `htsm_common.wgsl` from `rings` on. Lengths in object units.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct DiffusionUniforms {
    /// x, y, z: the annuli's boundaries `r_1 / 2`, `1.5 r_1`, `3 r_1`; w: the index of the
    /// outermost ring present (0 for n = 1, 3 for n = 13), whose annulus reaches infinity.
    pub rings: [f32; 4],
    /// x: the boundary's `A` (Jensen et al. 2001; 1 at eta = 1), which sets the extrapolation
    /// distance `z_b = 2 A / (3 sigma_t')`; y, z, w unused.
    pub boundary: [f32; 4],
    /// rgb at density `d / 8` and incidence cosine `k / 8` (entry `d * 9 + k`): the
    /// half-space's total albedo per unit flux entering.
    pub albedo: [[f32; 4]; DENSITY_LEVELS * ALBEDO_ENTRIES],
    /// rgb at density `d / 8` and diffusion optical depth `x = (k SLAB_STEP)^2` (entry `d * 33 +
    /// k`): the slab's multiple-scattering transmittance times `e^x` (smooth, so linear
    /// interpolation in `sqrt(x)` holds); the last entry holds beyond the table.
    pub slab: [[f32; 4]; DENSITY_LEVELS * SLAB_ENTRIES],
}

/// What [`DiffusionUniforms::new`] depends on: the medium, the index and the pattern.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffusionKey {
    /// The medium per object unit.
    pub coefficients: HtsmCoefficients,
    /// Relative index of refraction.
    pub eta: f32,
    /// Ring-1 radius, object units.
    pub kernel_radius: f32,
    /// Samples per pixel (1, 5, 9, 13).
    pub samples: u32,
}

impl DiffusionKey {
    /// The key of the tables `params` render with: `None` unless the model is
    /// [`super::TransportModel::Diffusion`] with a medium.
    pub fn of(params: &super::HtsmParams) -> Option<DiffusionKey> {
        let coefficients = params.medium.filter(|_| params.model == super::TransportModel::Diffusion)?;
        Some(DiffusionKey {
            coefficients,
            eta: params.eta,
            kernel_radius: params.kernel_radius,
            samples: params.samples,
        })
    }
}

/// `F(b)` of the module docs: the share of a dipole term with source depth `z` lying beyond
/// lateral distance `b` (`None`: infinity, share 0), for transport coefficient `s`.
pub fn kernel_share(b: Option<f64>, z: f64, s: f64) -> f64 {
    match b {
        None => 0.0,
        Some(b) => {
            let d = (b * b + z * z).sqrt();
            if d <= 0.0 { 1.0 } else { z / d * (-s * (d - z)).exp() }
        }
    }
}

/// Per channel at density `rho`: `(sigma_tr, sigma_t', albedo sigma_s' / sigma_t')`.
fn channels(c: &HtsmCoefficients, rho: f32) -> [(f64, f64, f64); 3] {
    let tr = c.sigma_tr(rho);
    std::array::from_fn(|k| {
        let a = (c.sigma_a[k] + rho * c.density_sigma_a[k]) as f64;
        let s = c.sigma_s_prime[k] as f64;
        let t = (a + s).max(1e-12);
        // A medium without absorption has sigma_tr 0; the floor keeps the slab table's depth
        // conversion finite (such a medium transmits as the thinnest depth the floor allows).
        ((tr[k] as f64).max(1e-4 * t), t, s / t)
    })
}

impl DiffusionUniforms {
    /// The tables of the module docs for `key`: a few hundred milliseconds the first time a
    /// medium is seen (the slab tables, made once per albedo and index per process).
    pub fn new(key: &DiffusionKey) -> Self {
        let r1 = key.kernel_radius;
        let last = match key.samples {
            1 => 0.0,
            5 => 1.0,
            9 => 2.0,
            _ => 3.0,
        };
        let eta = key.eta as f64;
        let mut u = DiffusionUniforms {
            rings: [0.5 * r1, 1.5 * r1, 3.0 * r1, last],
            boundary: [boundary_a(eta) as f32, 0.0, 0.0, 0.0],
            ..Zeroable::zeroed()
        };
        for d in 0..DENSITY_LEVELS {
            let rho = d as f32 / (DENSITY_LEVELS - 1) as f32;
            for (k, (sigma_tr, sigma_t, albedo)) in channels(&key.coefficients, rho).into_iter().enumerate() {
                let half_space = HalfSpace::new(albedo, eta);
                for (i, row) in u.albedo[d * ALBEDO_ENTRIES..][..ALBEDO_ENTRIES].iter_mut().enumerate() {
                    let cos = i as f64 / (ALBEDO_ENTRIES - 1) as f64;
                    row[k] = half_space.albedo(refracted_cosine(cos, eta)) as f32;
                }
                let slab = SlabTable::cached(albedo, eta);
                for (i, row) in u.slab[d * SLAB_ENTRIES..][..SLAB_ENTRIES].iter_mut().enumerate() {
                    let x = (i as f64 * SLAB_STEP as f64).powi(2);
                    row[k] = (slab.at(x * sigma_t / sigma_tr).transmitted * x.exp()) as f32;
                }
            }
        }
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn skim_milk_5cm() -> DiffusionKey {
        let mm = 50.0;
        DiffusionKey {
            coefficients: HtsmCoefficients {
                sigma_a: Vec3::new(0.0014, 0.0025, 0.0142) * mm,
                sigma_s_prime: Vec3::new(0.70, 1.22, 1.90) * mm,
                density_sigma_a: Vec3::splat(0.5 * mm),
            },
            eta: 1.0,
            kernel_radius: 0.04,
            samples: 9,
        }
    }

    #[test]
    fn the_annulus_share_is_the_dipole_term_integrated() {
        // Midpoint rule on the radial integral of z (1 + s d) e^{-s d} / d^3 r dr against the
        // closed form e^{-s z} (F(b0) - F(b1)).
        let (z, s, b0, b1) = (0.02f64, 6.0, 0.01, 0.07);
        let n = 200_000;
        let h = (b1 - b0) / n as f64;
        let sum: f64 = (0..n)
            .map(|i| {
                let r = b0 + (i as f64 + 0.5) * h;
                let d = (r * r + z * z).sqrt();
                z * (1.0 + s * d) * (-s * d).exp() / d.powi(3) * r * h
            })
            .sum();
        let closed = (-s * z).exp() * (kernel_share(Some(b0), z, s) - kernel_share(Some(b1), z, s));
        assert!((sum / closed - 1.0).abs() < 1e-6, "{sum} vs {closed}");
        assert_eq!(kernel_share(Some(0.0), z, s), 1.0);
        assert_eq!(kernel_share(None, z, s), 0.0);
    }

    #[test]
    fn a_thin_slab_at_low_absorption_is_tabulated_finely() {
        // Density 0 of skim milk, red: sigma_tr h = 0.1 is 1.3 mean free paths. The shader's
        // lookup (linear in sqrt(x) between entries) against the slab itself: 19%, 7%, 3%, 1%
        // at x = 0.02, 0.05, 0.1, 0.27; even steps of 0.5 in x gave 63-73% too little there.
        let key = skim_milk_5cm();
        let u = DiffusionUniforms::new(&key);
        let (sigma_tr, sigma_t, albedo) = channels(&key.coefficients, 0.0)[0];
        let slab = SlabTable::cached(albedo, 1.0);
        for (x, within) in [(0.02f64, 0.2), (0.05, 0.08), (0.1, 0.04), (0.27, 0.02), (0.6, 0.02), (4.0, 0.01)]
        {
            let at = x.sqrt() / SLAB_STEP as f64;
            let (i, f) = (at as usize, at.fract());
            let tabulated = (u.slab[i][0] as f64 * (1.0 - f) + u.slab[i + 1][0] as f64 * f) * (-x).exp();
            let exact = slab.at(x * sigma_t / sigma_tr).transmitted;
            assert!((tabulated / exact - 1.0).abs() < within, "x {x}: {tabulated} vs {exact}");
        }
    }

    #[test]
    fn the_tables_are_the_half_space_and_the_slab() {
        let key = skim_milk_5cm();
        let u = DiffusionUniforms::new(&key);
        for k in 0..3 {
            // A low-absorption half-space returns most of the light, more at grazing incidence.
            let (normal, grazing) = (u.albedo[ALBEDO_ENTRIES - 1][k], u.albedo[1][k]);
            // More absorption (density 1), less albedo.
            assert!(u.albedo[(DENSITY_LEVELS - 1) * ALBEDO_ENTRIES + ALBEDO_ENTRIES - 1][k] < normal);
            assert!(normal > 0.6 && normal < 1.0 && grazing > normal, "channel {k}: {normal} {grazing}");
            // No slab, no multiple scattering through it; a thick one falls as e^{-sigma_tr h}
            // times a factor of order sigma_tr / sigma_t' (the slab factor docs/htsm.md derived).
            assert_eq!(u.slab[0][k], 0.0);
            let far = u.slab[SLAB_ENTRIES - 1][k];
            assert!(far > 0.05 && far < 2.0, "channel {k}: {far}");
        }
    }
}
