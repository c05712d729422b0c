//! The environment drawn behind the mesh (`Shading::background`) shows, at each background
//! pixel, the map's radiance along that pixel's view ray; the mesh covers it.

mod common;

use glam::Vec3;
use lucent_core::camera::OrbitCamera;
use lucent_core::irradiance::{EnvMap, equirect_uv};
use lucent_gpu::mesh_pass::{EnvironmentMap, GpuMesh, Shading};
use lucent_gpu::offscreen::OffscreenRenderer;
use lucent_gpu::test_support::adapter_or_skip;
use lucent_gpu::tonemap::ToneMap;

#[test]
fn background_shows_the_map_along_view_rays() {
    let Some(ctx) = adapter_or_skip() else { return };
    // Radiance that encodes its direction, (d + 1) / 2: smooth, so bilinear filtering of the
    // 256 x 128 texels reproduces it to a fraction of a percent.
    let map = EnvMap::from_fn(256, 128, |d| (d + Vec3::ONE) * 0.5);
    let texels: Vec<[f32; 4]> = map.texels.iter().map(|t| t.extend(1.0).to_array()).collect();
    let env = EnvironmentMap::from_rgba_f32(&ctx, 256, 128, &texels).unwrap();
    let (pos, tris) = common::icosphere(3);
    let mesh = GpuMesh::new(&ctx, &pos, &pos, &vec![Vec3::ZERO; pos.len()], &tris).unwrap();
    let size = 96;
    let mut r = OffscreenRenderer::new(&ctx, size, size).unwrap();
    r.mesh_pass_mut().set_environment(&ctx, &env);
    let camera = r.camera_view(&mesh, &OrbitCamera { yaw_deg: 30.0, pitch_deg: 20.0, ..Default::default() });
    let shading = Shading { specular: 0.0, background: 1.0, ..Default::default() };
    r.render(&ctx, &mesh, &camera, &shading, &ToneMap::default()).unwrap();
    let hdr = r.read_hdr(&ctx).unwrap();

    let inv = camera.view_proj.inverse();
    let mut checked = 0;
    for (k, p) in hdr.iter().enumerate() {
        let (x, y) = ((k as u32 % size) as f32 + 0.5, (k as u32 / size) as f32 + 0.5);
        let ndc = glam::Vec2::new(x / size as f32 * 2.0 - 1.0, 1.0 - y / size as f32 * 2.0);
        let (near, far) = (inv.project_point3(ndc.extend(0.0)), inv.project_point3(ndc.extend(1.0)));
        let d = (far - near).normalize();
        let on_sphere = {
            // The ray from the eye meets the unit sphere, or passes within about a pixel of it
            // (edge pixels mix mesh and background samples)?
            let b = camera.eye.dot(d);
            b * b - (camera.eye.length_squared() - 1.05f32.powi(2)) > 0.0
        };
        assert_eq!(p[3], 1.0, "every pixel is covered (mesh or background)");
        if on_sphere {
            // The mesh (zero radiance, no highlight) hides the background.
            continue;
        }
        let (u, _) = equirect_uv(d);
        if !(0.02..0.98).contains(&u) {
            continue; // the seam, where filtering wraps
        }
        let want = (d + Vec3::ONE) * 0.5;
        let got = Vec3::new(p[0], p[1], p[2]);
        assert!((got - want).abs().max_element() < 0.01, "pixel ({x}, {y}): {got} vs {want}");
        checked += 1;
    }
    assert!(checked > (size * size / 4) as usize, "{checked} background pixels checked");
}
