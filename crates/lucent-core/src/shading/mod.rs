//! Final shading (Mertens §5.4): exitant radiance `L = F_t(eta, w_o) B / (c pi)`.
//!
//! `c = 1 - 2 FM_1(1/eta)` normalises the exit lobe `F_t(eta, w_o) / (c pi)` so that it
//! integrates to 1 over the hemisphere (the separable BSSRDF of pbrt-v3): then all of `B`, the
//! radiant exitance the profile delivers, leaves the surface, and none is lost at `eta != 1`.
//! Mertens (and Jensen et al. 2001) write `F_t B / pi`, which loses `1 - c` (6% at eta = 1.3);
//! the `mertens` profile keeps that form to reproduce the paper ([`Profile::exit_normalization`]).
//!
//! The view-dependent `F_t(eta, w_o)` is applied per pixel on the GPU, and to the diffuse part
//! also the exit lobe `T(mu_o)` of the profile (`bssrdf::ExitLobe`, flat for `mertens`), which
//! keeps the lobe's integral at 1; this module gives the per-vertex diffuse part `B / (c pi)`,
//! and [`single_scattering`] the per-vertex radiance scattered once along the refracted view
//! ray, to which the GPU applies `F_t` alone.

use crate::Rgb;
use crate::bssrdf::Profile;

/// `B / (c pi)` per vertex: the radiance leaving the surface before the exit Fresnel factor,
/// for the profile `dipole` (which sets `1/c`).
pub fn diffuse_radiance(b: &[Rgb], profile: &Profile) -> Vec<Rgb> {
    let k = (profile.exit_normalization() / std::f64::consts::PI) as f32;
    b.iter().map(|v| *v * k).collect()
}

pub mod exit_chord;
pub mod single_scattering;
pub mod transmitted_exit;
pub use single_scattering::{SingleScattering, UnknownSingleScattering};
pub mod view_basis;
