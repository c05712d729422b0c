//! Final shading (Mertens §5.4): exitant radiance `L = F_t(eta, w_o) B / pi`.
//!
//! The view-dependent `F_t(eta, w_o)` is applied per pixel on the GPU; this module gives the
//! per-vertex diffuse part `B / pi` and the CPU form of the full expression for tests.

use crate::Rgb;
use crate::bssrdf::fresnel_transmittance;

/// `B / pi` per vertex: the radiance leaving the surface before the exit Fresnel factor.
pub fn diffuse_radiance(b: &[Rgb]) -> Vec<Rgb> {
    b.iter().map(|v| *v / std::f32::consts::PI).collect()
}

/// `L = F_t(eta, w_o) B / pi` for a view direction at `cos_o` to the normal.
pub fn exitant_radiance(b: Rgb, cos_o: f32, eta: f64) -> Rgb {
    b * (fresnel_transmittance(cos_o as f64, eta) as f32 / std::f32::consts::PI)
}
