//! Deformation (`HtsmRenderer::set_positions`): the density follows the mesh, `D_i` is the
//! deformed length.

use super::*;
use lucent_core::camera::CameraView;

fn hdr_of(
    ctx: &GpuContext,
    renderer: &mut HtsmRenderer,
    camera: CameraView,
    light: Light,
    params: &HtsmParams,
) -> Vec<[f32; 4]> {
    let view = HtsmView { camera, lights: vec![light], environment: None, width: 96, height: 96 };
    renderer.render_hdr(ctx, &view, params).unwrap_or_else(|e| panic!("{e}"))
}

fn camera_for(positions: &[Vec3], orbit: OrbitCamera) -> CameraView {
    let (centre, radius) = bounding_sphere(positions);
    orbit.frame(centre, radius, 1.0)
}

/// Largest and mean absolute difference over pixels covered in both, relative to the mean.
fn compare(a: &[[f32; 4]], b: &[[f32; 4]]) -> (f32, f32) {
    let (mut max, mut sum, mut total, mut n) = (0.0f32, 0.0, 0.0, 0);
    for (p, q) in a.iter().zip(b) {
        if p[3] > 0.5 && q[3] > 0.5 {
            for c in 0..3 {
                max = max.max((p[c] - q[c]).abs());
                sum += (p[c] - q[c]).abs();
                total += p[c];
            }
            n += 1;
        }
    }
    assert!(n > 1000, "{n} pixels covered in both");
    let mean = total / (3 * n) as f32;
    (max / mean, sum / (3 * n) as f32 / mean)
}

#[test]
fn a_moved_and_scaled_object_looks_like_the_rest_object_seen_from_a_moved_camera() {
    // p -> s p + t moves every length by s: paths through the object are s times longer, which
    // the rest object shows with s times the extinction (T_c^s at the same T_d, density scale
    // times s) and a kernel 1/s as large in object units (the same size in the moved images).
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let volume = VolumeSpec::default().build([32, 22, 16]).unwrap();
    let light = Light::Directional { direction: Vec3::new(0.15, -0.2, 1.0), irradiance: Vec3::splat(3.0) };
    let orbit = OrbitCamera { yaw_deg: 20.0, pitch_deg: 10.0, ..Default::default() };
    let base = HtsmParams::default();
    let mut rest = HtsmRenderer::new(&ctx, &mesh, &volume, 128).unwrap();
    let mut moved = HtsmRenderer::new(&ctx, &mesh, &volume, 128).unwrap();
    for s in [1.0f32, 1.6] {
        let t = Vec3::new(0.3, -0.2, 0.5);
        let positions: Vec<Vec3> = mesh.positions.iter().map(|p| *p * s + t).collect();
        moved.set_positions(&ctx, &positions).unwrap();
        let a = hdr_of(&ctx, &mut moved, camera_for(&positions, orbit), light, &base);
        let equivalent = HtsmParams {
            transport_colour: base.transport_colour.powf(s),
            density_scale: base.density_scale * s,
            kernel_radius: base.kernel_radius / s,
            ..base
        };
        let b = hdr_of(&ctx, &mut rest, camera_for(&mesh.positions, orbit), light, &equivalent);
        let (max, mean) = compare(&a, &b);
        assert!(mean < 2e-3 && max < 0.05, "scale {s}: differences max {max}, mean {mean} (of the mean)");
        if s != 1.0 {
            // Not vacuous: the same material at the larger size is darker.
            let c = hdr_of(&ctx, &mut rest, camera_for(&mesh.positions, orbit), light, &base);
            assert!(compare(&a, &c).1 > 0.05, "scaling by {s} changed nothing");
        }
    }
}

#[test]
fn the_density_turns_with_the_mesh() {
    // The ellipsoid is symmetric under a half turn about the view axis z, and so are camera and
    // light (both on z): only the density can tell the turned mesh from the rest one. If it
    // follows the mesh, the image is the rest image turned by 180 degrees.
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let volume = VolumeSpec::default().build([32, 22, 16]).unwrap();
    let light = Light::Directional { direction: Vec3::Z, irradiance: Vec3::splat(3.0) };
    let camera = camera_for(&mesh.positions, OrbitCamera { pitch_deg: 0.0, ..Default::default() });
    let params = HtsmParams::default();
    let mut r = HtsmRenderer::new(&ctx, &mesh, &volume, 128).unwrap();
    let rest = hdr_of(&ctx, &mut r, camera, light, &params);
    let turned_positions: Vec<Vec3> = mesh.positions.iter().map(|p| Vec3::new(-p.x, -p.y, p.z)).collect();
    r.set_positions(&ctx, &turned_positions).unwrap();
    let turned = hdr_of(&ctx, &mut r, camera, light, &params);
    let rest_turned: Vec<[f32; 4]> = rest.iter().rev().copied().collect();
    let (_, follows) = compare(&turned, &rest_turned);
    let (_, stays) = compare(&turned, &rest);
    assert!(follows < 0.01 && stays > 0.1, "against the turned rest image {follows}, the rest image {stays}");
}

#[test]
fn a_twist_changes_the_image_and_keeps_it_finite_and_lit() {
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let volume = VolumeSpec::default().build([32, 22, 16]).unwrap();
    let light = Light::Directional { direction: Vec3::new(0.15, -0.2, 1.0), irradiance: Vec3::splat(3.0) };
    let camera = camera_for(&mesh.positions, OrbitCamera { pitch_deg: 0.0, ..Default::default() });
    let params = HtsmParams::default();
    let mut r = HtsmRenderer::new(&ctx, &mesh, &volume, 128).unwrap();
    let rest = hdr_of(&ctx, &mut r, camera, light, &params);
    // About y, 1.2 rad per mesh unit of height.
    let twisted: Vec<Vec3> = mesh
        .positions
        .iter()
        .map(|p| {
            let (s, c) = (1.2 * p.y).sin_cos();
            Vec3::new(c * p.x + s * p.z, p.y, -s * p.x + c * p.z)
        })
        .collect();
    r.set_positions(&ctx, &twisted).unwrap();
    let img = hdr_of(&ctx, &mut r, camera, light, &params);
    assert!(img.iter().flatten().all(|v| v.is_finite()));
    let lit = img.iter().filter(|p| p[3] > 0.5 && p[0] + p[1] + p[2] > 1e-3).count();
    assert!(lit > 1000, "{lit} lit pixels");
    let (_, mean) = compare(&img, &rest);
    assert!(mean > 0.05, "the twist changed the image by {mean} of its mean");
    // Wrong vertex counts are refused.
    assert!(r.set_positions(&ctx, &twisted[1..]).is_err());
}
