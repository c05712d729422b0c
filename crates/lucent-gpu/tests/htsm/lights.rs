//! Several lights, spot lights and the SH environment (`lucent_gpu::htsm::environment`).

use super::*;
use lucent_core::irradiance::{Environment, Sh9};
use lucent_gpu::htsm::HtsmError;
use std::f32::consts::PI;

/// `Y_00` and `Y_11 / x` of the real SH basis.
const Y00: f32 = 0.282_095;
const Y1: f32 = 0.488_603;

/// The HDR image of `mesh` with the default vein volume.
fn hdr(ctx: &GpuContext, mesh: &Mesh, view: &HtsmView, params: &HtsmParams) -> Vec<[f32; 4]> {
    hdr_in(ctx, mesh, &VolumeSpec::default().build([32, 22, 16]).unwrap(), view, params)
}

fn hdr_in(
    ctx: &GpuContext,
    mesh: &Mesh,
    volume: &DensityVolume,
    view: &HtsmView,
    params: &HtsmParams,
) -> Vec<[f32; 4]> {
    let mut r = HtsmRenderer::new(ctx, mesh, volume, 128).unwrap_or_else(|e| panic!("{e}"));
    r.render_hdr(ctx, view, params).unwrap_or_else(|e| panic!("{e}"))
}

/// An environment of radiance `1 + gradient * x` (mesh frame before rotation).
fn environment(gradient: f32, rotation_deg: f32) -> Environment {
    let mut sh = Sh9::ZERO;
    sh.coeffs[0] = Vec3::splat(1.0 / Y00);
    sh.coeffs[3] = Vec3::new(1.0, 0.8, 0.6) * (gradient / Y1);
    Environment { sh, rotation_deg, intensity: 1.0 }
}

fn with(mesh: &Mesh, size: u32, lights: Vec<Light>, environment: Option<Environment>) -> HtsmView {
    HtsmView { lights, environment, ..view(mesh, size) }
}

#[test]
fn lights_and_the_environment_add_up() {
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let params = HtsmParams::default();
    let distant = view(&mesh, 64).lights[0];
    let point = Light::Point { position: Vec3::new(1.5, 2.0, 2.5), intensity: Vec3::new(6.0, 5.0, 4.0) };
    let env = Some(environment(0.5, 30.0));
    let parts = [
        hdr(&ctx, &mesh, &with(&mesh, 64, vec![distant], None), &params),
        hdr(&ctx, &mesh, &with(&mesh, 64, vec![point], None), &params),
        hdr(&ctx, &mesh, &with(&mesh, 64, vec![], env), &params),
    ];
    let all = hdr(&ctx, &mesh, &with(&mesh, 64, vec![distant, point], env), &params);
    let mut covered = 0;
    for (i, p) in all.iter().enumerate() {
        assert_eq!(p[3], parts[0][i][3], "pixel {i}: coverage differs");
        covered += (p[3] > 0.5) as usize;
        for c in 0..3 {
            let sum: f32 = parts.iter().map(|q| q[i][c]).sum();
            // Each pass is rounded to the f16 target, then added.
            assert!((p[c] - sum).abs() <= 3e-3 * sum + 1e-5, "pixel {i} channel {c}: {} vs {sum}", p[c]);
        }
    }
    assert!(covered > 500, "the object covers {covered} pixels");
}

#[test]
fn a_spot_light_is_a_point_light_inside_its_cone_and_nothing_outside() {
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let params = HtsmParams::default();
    let position = Vec3::new(0.5, 0.8, -3.0);
    let intensity = Vec3::new(20.0, 18.0, 15.0);
    let spot = |direction: Vec3, cone_angle: f32, soft_edge: f32| {
        let light = Light::Spot { position, direction, intensity, cone_angle, soft_edge };
        hdr(&ctx, &mesh, &with(&mesh, 64, vec![light], None), &params)
    };
    let point = hdr(&ctx, &mesh, &with(&mesh, 64, vec![Light::Point { position, intensity }], None), &params);
    let total = |img: &[[f32; 4]]| img.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>();
    assert!(total(&point) > 0.0);

    // A cone of half-angle pi covers every direction: exactly the point light.
    assert_eq!(spot(-position, PI, 0.0), point);

    // Turned away: no light at all, but the object is still there.
    let away = spot(position, 0.3, 0.2);
    assert!(away.iter().all(|p| p[0] == 0.0 && p[1] == 0.0 && p[2] == 0.0));
    assert_eq!(away.iter().filter(|p| p[3] > 0.5).count(), point.iter().filter(|p| p[3] > 0.5).count());

    // Narrower than the object (about 0.33 rad from here), soft-edged: part of the light, and
    // never more than the point light anywhere.
    let narrow = spot(-position, 0.15, 0.5);
    let ratio = total(&narrow) / total(&point);
    assert!(ratio > 0.02 && ratio < 0.6, "narrow spot / point light = {ratio}");
    for (s, p) in narrow.iter().zip(&point) {
        for c in 0..3 {
            assert!(s[c] <= p[c] * 1.002 + 1e-6, "{s:?} > {p:?}");
        }
    }
}

#[test]
fn no_light_and_no_environment_is_an_error() {
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let volume = DensityVolume::uniform([4, 4, 4], 0.0).unwrap();
    let mut r = HtsmRenderer::new(&ctx, &mesh, &volume, 64).unwrap();
    let err = r.render(&ctx, &with(&mesh, 32, vec![], None), &HtsmParams::default()).unwrap_err();
    assert!(matches!(err, HtsmError::Light(_)), "{err}");
    let inside = Light::Point { position: Vec3::ZERO, intensity: Vec3::ONE };
    let err = r.render(&ctx, &with(&mesh, 32, vec![inside], None), &HtsmParams::default()).unwrap_err();
    assert!(matches!(err, HtsmError::Light(_)), "{err}");
}

/// Mean over the object of `|a - b|` for pixels matched by `map`, relative to the mean of `a`.
fn relative_difference(
    a: &[[f32; 4]],
    b: &[[f32; 4]],
    size: usize,
    map: impl Fn(usize, usize) -> usize,
) -> f32 {
    let (mut diff, mut sum) = (0.0, 0.0);
    for y in 0..size {
        for x in 0..size {
            let (p, q) = (a[y * size + x], b[map(x, y)]);
            if p[3] > 0.5 && q[3] > 0.5 {
                diff += (0..3).map(|c| (p[c] - q[c]).abs()).sum::<f32>();
                sum += p[0] + p[1] + p[2];
            }
        }
    }
    diff / sum
}

/// Mean radiance over the object in the right (`vertical`: bottom) half of the image over that
/// in the other half.
fn half_ratio(img: &[[f32; 4]], size: u32, vertical: bool) -> f32 {
    let s = size as usize;
    let side = |second: bool| -> f32 {
        let px: Vec<f32> = (0..s * s)
            .filter(|&i| ((if vertical { i / s } else { i % s }) >= s / 2) == second && img[i][3] > 0.5)
            .map(|i| img[i][0] + img[i][1] + img[i][2])
            .collect();
        px.iter().sum::<f32>() / px.len() as f32
    };
    side(true) / side(false)
}

#[test]
fn a_uniform_environment_alone_lights_a_sphere_evenly_and_a_turned_gradient_moves() {
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = lucent_core::mesh::generate::icosphere(4);
    let size = 96;
    // Seen from +z with y up: image x is world x; the cube-corner lights are symmetric under
    // x -> -x and y -> -y, and so are the sphere and a uniform density.
    let params = HtsmParams::default();
    let volume = DensityVolume::uniform([8, 8, 8], 0.2).unwrap();
    let env_view =
        |gradient: f32, rotation: f32| with(&mesh, size, vec![], Some(environment(gradient, rotation)));
    let uniform = hdr_in(&ctx, &mesh, &volume, &env_view(0.0, 0.0), &params);
    assert!(uniform.iter().flatten().all(|v| v.is_finite()));
    let covered: Vec<&[f32; 4]> = uniform.iter().filter(|p| p[3] > 0.5).collect();
    assert!(covered.len() > 2000, "{} pixels", covered.len());
    let mean = covered.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / (3 * covered.len()) as f32;
    // Radiance 1 from everywhere: the lit-side diffuse term alone is 0.3 T_c (1 - F) ~ 0.17.
    assert!(mean > 0.1 && mean < 3.0, "mean radiance {mean}");
    // Mirror symmetry, pixel against pixel, with isotropic scattering. With g != 0 the image
    // is only roughly symmetric (a few percent): the lit side's centre sample has D_i ~ 0, and
    // the phase angle of that near-zero ray comes from f16 rounding of texture coordinates,
    // which is coarser above 0.5 than below (a property of the camera pass under any light).
    let isotropic = HtsmParams { phase_g: 0.0, ..params };
    let even = hdr_in(&ctx, &mesh, &volume, &env_view(0.0, 0.0), &isotropic);
    let s = size as usize;
    let mirror_x = relative_difference(&even, &even, s, |x, y| y * s + (s - 1 - x));
    let mirror_y = relative_difference(&even, &even, s, |x, y| (s - 1 - y) * s + x);
    assert!(mirror_x < 0.005 && mirror_y < 0.005, "asymmetry: left-right {mirror_x}, top-bottom {mirror_y}");
    let (lr, bt) = (half_ratio(&uniform, size, false), half_ratio(&uniform, size, true));
    assert!(
        (lr - 1.0).abs() < 0.06 && (bt - 1.0).abs() < 0.06,
        "g = 0.3: right / left {lr}, bottom / top {bt}"
    );
    // The LDR image is not black either.
    let mut r = HtsmRenderer::new(&ctx, &mesh, &volume, 128).unwrap();
    let img = r.render(&ctx, &env_view(0.0, 0.0), &params).unwrap();
    assert!(mean_luminance(&img, &object_mask(&img)) > 0.05);

    // Brighter towards +x; turned by 180 degrees about +y, brighter towards -x.
    let east = hdr_in(&ctx, &mesh, &volume, &env_view(0.8, 0.0), &isotropic);
    let west = hdr_in(&ctx, &mesh, &volume, &env_view(0.8, 180.0), &isotropic);
    let (e, w) = (half_ratio(&east, size, false), half_ratio(&west, size, false));
    assert!(e > 1.2 && w < 1.0 / 1.2, "right / left: {e} unturned, {w} turned");
    assert!((e * w - 1.0).abs() < 0.01, "turning by 180 degrees should mirror: {e} x {w}");
}
