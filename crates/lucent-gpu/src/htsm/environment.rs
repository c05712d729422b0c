//! Environment light for HTSM. Shopf 2007 §5.4: "because all reference images are rendered from
//! the light's viewpoint, the algorithm only supports point and distant lights, not environment
//! lighting". This module makes a distant SH environment (Mertens 2003 §5.3's nine coefficients,
//! [`Environment`]) into what HTSM can render, in two parts:
//!
//! * **Subsurface transport**: [`environment_lights`], eight distant lights from the corners of
//!   a cube, each rendered through the ordinary reference-image and camera passes. Light `k`
//!   from direction `u_k` has irradiance `w_k = (4 pi / 8) L_01(u_k)`, where `L_01` is the
//!   environment's radiance truncated to SH bands 0 and 1. The cube's corners form a spherical
//!   3-design, so this quadrature reproduces the radiance's band-0 and band-1 coefficients
//!   exactly, and with them (Funk-Hecke) the band-0 and band-1 parts of the irradiance on every
//!   surface orientation: the total light entering the object and its dominant direction are
//!   right. What is approximated: band 2 of the radiance is dropped from the transport, and
//!   eight cosine lobes are lumpier than the smooth irradiance they stand for (for a uniform
//!   environment they give between 0.82 and 1.15 times the true irradiance depending on the
//!   normal, exact on average; the transport's sampling kernel blurs this further). Where
//!   `L_01` dips below zero (a strongly one-sided environment) the weight is clamped at zero,
//!   which adds light: the band-1 match then no longer holds exactly.
//! * **Lit-side surface terms**, added once per frame: the diffuse term with the full nine-
//!   coefficient irradiance transmitted through Schlick's Fresnel (instead of one light's
//!   `E cos`), and a glossy reflection, the band-limited radiance in the mirror direction times
//!   Schlick's Fresnel at the view angle (the specular lobe is narrow next to what nine
//!   coefficients resolve). The environment's own lights add neither term, so that the surface
//!   terms are not counted twice. Neither term is shadowed: like the transport, they assume a
//!   convex object (§5.4).
//!
//! Cost: up to eight more light passes per frame (a direction whose clamped weight is zero in
//! every channel is skipped), plus two SH evaluations per pixel.

use super::pipeline::FrameUniforms;
use glam::{Quat, Vec3};
use lucent_core::bssrdf::zonal_band_weights;
use lucent_core::irradiance::sh::{SH_BAND, sh_basis};
use lucent_core::irradiance::{Environment, Light};

/// How many distant lights stand in for an environment: one per corner of a cube.
pub const ENVIRONMENT_LIGHTS: usize = 8;

/// Unit directions towards the cube's corners, in the environment map's frame.
fn corner_directions() -> [Vec3; ENVIRONMENT_LIGHTS] {
    std::array::from_fn(|k| {
        let s = |bit: usize| if k & (1 << bit) == 0 { 1.0 } else { -1.0 };
        Vec3::new(s(0), s(1), s(2)) / 3f32.sqrt()
    })
}

/// The eight distant lights that carry `env`'s subsurface transport (module docs): light `k`
/// shines from the world direction of cube corner `u_k` (the map's frame turned by
/// `env.rotation_deg` about +y) with irradiance `(4 pi / 8) max(0, L_01(u_k)) env.intensity` per
/// channel (radiance units times sr). Lights whose irradiance is zero in every channel are left
/// out, so the result may hold fewer than eight.
pub fn environment_lights(env: &Environment) -> Vec<Light> {
    let to_world = Quat::from_rotation_y(env.rotation_deg.to_radians());
    let solid_angle = 4.0 * std::f32::consts::PI / ENVIRONMENT_LIGHTS as f32;
    corner_directions()
        .into_iter()
        .filter_map(|u| {
            let y = sh_basis(u);
            let l01: Vec3 = (0..4).map(|i| env.sh.coeffs[i] * y[i]).sum();
            let irradiance = (l01 * solid_angle * env.intensity).max(Vec3::ZERO);
            (irradiance.max_element() > 0.0)
                .then(|| Light::Directional { direction: -(to_world * u), irradiance })
        })
        .collect()
}

/// Band weights `A_l` (l = 0, 1, 2, sr) of Schlick's transmitted cosine `(1 - F(mu)) max(0, mu)`,
/// `F` Schlick's reflectance with normal-incidence value `f0`.
fn schlick_transmitted_bands(f0: f32) -> [f32; 3] {
    let f0 = f0 as f64;
    zonal_band_weights(|mu| (1.0 - (f0 + (1.0 - f0) * (1.0 - mu).powi(5))) * mu)
}

/// Fills the frame uniforms' environment fields (`htsm_common.wgsl`'s `Frame`); zeros and the
/// "none" flag without an environment.
pub(super) fn write_uniforms(env: Option<&Environment>, f0: f32, u: &mut FrameUniforms) {
    let Some(env) = env else {
        u.env_frame = [1.0, 0.0, 0.0, 0.0];
        u.env_irradiance = [[0.0; 4]; 9];
        u.env_radiance = [[0.0; 4]; 9];
        return;
    };
    // World -> map frame is a turn by -rotation about +y (Environment::to_map_frame).
    let (sin, cos) = (-env.rotation_deg.to_radians()).sin_cos();
    u.env_frame = [cos, sin, 1.0, 0.0];
    let bands = schlick_transmitted_bands(f0);
    for (i, c) in env.sh.coeffs.iter().enumerate() {
        let radiance = *c * env.intensity;
        u.env_radiance[i] = radiance.extend(0.0).to_array();
        u.env_irradiance[i] = (radiance * bands[SH_BAND[i]]).extend(0.0).to_array();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lucent_core::irradiance::Sh9;

    fn env(sh: Sh9, rotation_deg: f32) -> Environment {
        Environment { sh, rotation_deg, intensity: 1.5 }
    }

    /// The lights' radiance (deltas of weight w_k at the directions they come from), projected on
    /// SH in the map's frame.
    fn projected(env: &Environment, lights: &[Light]) -> [Vec3; 9] {
        let mut c = [Vec3::ZERO; 9];
        for l in lights {
            let Light::Directional { direction, irradiance } = *l else { unreachable!() };
            let y = sh_basis(env.to_map_frame(-direction.normalize()));
            for (c, y) in c.iter_mut().zip(y) {
                *c += irradiance * y;
            }
        }
        c
    }

    #[test]
    fn the_lights_match_the_environment_to_band_one() {
        let mut sh = Sh9::ZERO;
        sh.coeffs[0] = Vec3::new(1.0, 0.8, 0.6);
        sh.coeffs[1] = Vec3::new(0.2, 0.1, -0.1);
        sh.coeffs[2] = Vec3::new(-0.1, 0.05, 0.0);
        sh.coeffs[3] = Vec3::new(0.15, -0.2, 0.1);
        sh.coeffs[6] = Vec3::splat(0.3);
        sh.coeffs[8] = Vec3::splat(-0.2);
        for rotation in [0.0, 37.0, 200.0] {
            let e = env(sh, rotation);
            let lights = environment_lights(&e);
            assert_eq!(lights.len(), ENVIRONMENT_LIGHTS);
            let c = projected(&e, &lights);
            for (i, (got, coeff)) in c.iter().zip(sh.coeffs).take(4).enumerate() {
                let want = coeff * e.intensity;
                assert!(
                    (*got - want).abs().max_element() < 1e-5,
                    "rotation {rotation}, L{i}: {got} vs {want}"
                );
            }
            // So does the irradiance's band 0 and 1 (hence the mean irradiance over normals).
            let mean = |f: &dyn Fn(Vec3) -> Vec3| -> Vec3 {
                let n = 4000;
                (0..n)
                    .map(|i| {
                        // Fibonacci sphere.
                        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                        let phi = i as f32 * 2.399_963;
                        let r = (1.0 - z * z).sqrt();
                        f(Vec3::new(r * phi.cos(), r * phi.sin(), z))
                    })
                    .sum::<Vec3>()
                    / n as f32
            };
            let from_lights = |n: Vec3| -> Vec3 {
                lights
                    .iter()
                    .map(|l| match *l {
                        Light::Directional { direction, irradiance } => {
                            irradiance * n.dot(-direction.normalize()).max(0.0)
                        }
                        _ => unreachable!(),
                    })
                    .sum()
            };
            let (a, b) = (mean(&from_lights), mean(&|n| e.irradiance(n)));
            assert!((a - b).abs().max_element() < 2e-3 * b.max_element(), "mean irradiance {a} vs {b}");
        }
    }

    #[test]
    fn a_uniform_environment_gives_eight_equal_lights_within_a_fifth_of_its_irradiance() {
        let mut sh = Sh9::ZERO;
        sh.coeffs[0] = Vec3::splat(2.0);
        let e = env(sh, 10.0);
        let lights = environment_lights(&e);
        assert_eq!(lights.len(), 8);
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for i in 0..2000 {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 2000.0;
            let (r, phi) = ((1.0 - z * z).sqrt(), i as f32 * 2.399_963);
            let n = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let sum: f32 = lights
                .iter()
                .map(|l| match *l {
                    Light::Directional { direction, irradiance } => {
                        irradiance.x * n.dot(-direction.normalize()).max(0.0)
                    }
                    _ => unreachable!(),
                })
                .sum();
            let ratio = sum / e.irradiance(n).x;
            (lo, hi) = (lo.min(ratio), hi.max(ratio));
        }
        // sum_k max(0, n.u_k) over the cube's corners lies in [2 sqrt(2/3), 4 / sqrt(3)], 2 on
        // average: between 0.816 (towards an edge's midpoint) and 1.155 (towards a face).
        assert!(lo > 0.816 && lo < 0.83 && hi < 1.1548 && hi > 1.14, "ratio in [{lo}, {hi}]");
    }

    #[test]
    fn a_one_sided_environment_drops_the_directions_it_does_not_light() {
        // A band-limited delta from +y: L01 < 0 for directions more than ~110 degrees away.
        let mut sh = Sh9::ZERO;
        for (c, y) in sh.coeffs.iter_mut().zip(lucent_core::irradiance::sh::sh_basis(Vec3::Y)) {
            *c = Vec3::splat(y);
        }
        let lights = environment_lights(&env(sh, 0.0));
        assert_eq!(lights.len(), 4, "{lights:?}");
        for l in lights {
            let Light::Directional { direction, .. } = l else { unreachable!() };
            assert!(direction.y < 0.0, "a light from below: {direction}");
        }
    }

    #[test]
    fn schlick_band_weights_have_their_closed_form() {
        // 1 - F = (1 - f0) (1 - (1 - mu)^5): A_0 = 2 pi (1 - f0) (1/2 - 1/42),
        // A_1 = 2 pi (1 - f0) (1/3 - 1/168) (Beta integrals of (1 - mu)^5 mu^k).
        let f0 = 0.017f32;
        let a = schlick_transmitted_bands(f0);
        let tau = std::f32::consts::TAU;
        assert!((a[0] - tau * (1.0 - f0) * (0.5 - 1.0 / 42.0)).abs() < 1e-5, "{a:?}");
        assert!((a[1] - tau * (1.0 - f0) * (1.0 / 3.0 - 1.0 / 168.0)).abs() < 1e-5, "{a:?}");
    }
}
