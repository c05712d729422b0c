//! The mesh pass's highlight honours a spot light's cone (the same falloff as the subsurface
//! irradiance, `lucent_core::irradiance::spot_falloff`): inside the inner cone a spot is the
//! point light it sits at, pointed away it gives nothing, and a narrow cone lights less.

mod common;

use glam::Vec3;
use lucent_core::camera::OrbitCamera;
use lucent_core::irradiance::Light;
use lucent_gpu::GpuContext;
use lucent_gpu::mesh_pass::{GpuMesh, Shading};
use lucent_gpu::offscreen::OffscreenRenderer;
use lucent_gpu::test_support::adapter_or_skip;
use lucent_gpu::tonemap::ToneMap;

/// Sum of the HDR highlight over the image of a unit sphere with no subsurface radiance.
fn highlight(ctx: &GpuContext, light: Light) -> f32 {
    let (pos, tris) = common::icosphere(4);
    let mesh = GpuMesh::new(ctx, &pos, &pos, &vec![Vec3::ZERO; pos.len()], &tris).unwrap();
    let r = OffscreenRenderer::new(ctx, 128, 128).unwrap();
    let camera = r.camera_view(&mesh, &OrbitCamera::default());
    let shading = Shading { eta: 1.4, lights: vec![light], shininess: 16.0, ..Default::default() };
    r.render(ctx, &mesh, &camera, &shading, &ToneMap::default()).unwrap();
    r.read_hdr(ctx).unwrap().iter().map(|p| p[0] + p[1] + p[2]).sum()
}

#[test]
fn spot_cone_limits_the_highlight() {
    let Some(ctx) = adapter_or_skip() else { return };
    // Beside the camera (which sits on +z), 3 radii from the centre: the sphere subtends
    // asin(1/3) = 19.5 degrees, inside a 30-degree cone's inner 24 degrees.
    let position = Vec3::new(0.5, 0.5, 3.0);
    let intensity = Vec3::splat(9.0);
    let spot = |direction: Vec3, cone_deg: f32| Light::Spot {
        position,
        direction,
        intensity,
        cone_angle: cone_deg.to_radians(),
        soft_edge: 0.2,
    };
    let point = highlight(&ctx, Light::Point { position, intensity });
    let inside = highlight(&ctx, spot(-position, 30.0));
    let away = highlight(&ctx, spot(position, 30.0));
    let narrow = highlight(&ctx, spot(-position, 4.0));
    eprintln!("point {point}, spot {inside}, away {away}, narrow {narrow}");
    assert!(point > 1.0, "the point light makes a highlight");
    assert!((inside - point).abs() < 1e-4 * point, "inside the inner cone a spot is a point light");
    assert_eq!(away, 0.0, "pointed away, the spot lights nothing");
    assert!(narrow > 0.0 && narrow < 0.9 * point, "a 4-degree cone lights part of the sphere");
}
