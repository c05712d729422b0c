//! The mesh pass multiplies diffuse radiance, not single scattering, by the exit lobe
//! `T(μ_o)` it is given, at each pixel's own exit cosine: a flat square with diffuse radiance 1
//! and single scattering 0.5 everywhere, seen head-on and obliquely at `eta = 1` (no Fresnel
//! loss), shows `T(μ_o) + 0.5` per channel, and with the flat lobe `1.5`.

mod common;

use glam::{Vec2, Vec3};
use lucent_core::bssrdf::ExitLobe;
use lucent_core::camera::OrbitCamera;
use lucent_gpu::mesh_pass::{GpuMesh, Shading};
use lucent_gpu::offscreen::OffscreenRenderer;
use lucent_gpu::test_support::adapter_or_skip;
use lucent_gpu::tonemap::ToneMap;

const SINGLE: f32 = 0.5;

/// `(μ_o, radiance)` at the pixels wholly inside the square, seen from `yaw_deg`.
fn exit_radiance(lobe: &ExitLobe, yaw_deg: f32) -> Option<Vec<(f32, [f32; 3])>> {
    let ctx = adapter_or_skip()?;
    let (pos, nrm, tris) = common::square();
    let mesh = GpuMesh::new(&ctx, &pos, &nrm, &[Vec3::ONE; 4], &tris).unwrap();
    mesh.update_radiance(&ctx, &[Vec3::ONE; 4], &[Vec3::splat(SINGLE); 4]).unwrap();
    let size = 96u32;
    let r = OffscreenRenderer::new(&ctx, size, size).unwrap();
    let camera = r.camera_view(&mesh, &OrbitCamera { yaw_deg, pitch_deg: 0.0, ..Default::default() });
    let shading = Shading { eta: 1.0, specular: 0.0, exit_lobe: lobe.clone(), ..Default::default() };
    r.render(&ctx, &mesh, &camera, &shading, &ToneMap::default()).unwrap();
    let hdr = r.read_hdr(&ctx).unwrap();
    let mut seen = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let (origin, dir) =
                camera.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::splat(size as f32));
            let hit = origin + dir * (-origin.z / dir.z);
            let p = hdr[(y * size + x) as usize];
            if hit.x.abs() < 0.95 && hit.y.abs() < 0.95 && p[3] == 1.0 {
                seen.push(((camera.eye - hit).normalize().z, [p[0], p[1], p[2]]));
            }
        }
    }
    assert!(seen.len() > 200, "{} pixels on the square", seen.len());
    Some(seen)
}

#[test]
fn diffuse_radiance_leaves_along_the_exit_lobe() {
    // Limb-darkened in red, peaked in between in blue (ExitLobe's docs).
    let lobe = ExitLobe::half_space(&[0.999, 0.75, 0.05], 1.0, false);
    let mut range = (1.0f32, 0.0f32);
    for yaw in [0.0, 50.0, 75.0] {
        let Some(seen) = exit_radiance(&lobe, yaw) else { return };
        for (mu_o, got) in seen {
            range = (range.0.min(mu_o), range.1.max(mu_o));
            let t = lobe.at(mu_o);
            for c in 0..3 {
                let want = t[c] + SINGLE;
                assert!((got[c] / want - 1.0).abs() < 0.01, "mu_o {mu_o} channel {c}: {} vs {want}", got[c]);
            }
        }
    }
    assert!(range.0 < 0.35 && range.1 > 0.99, "exit cosines seen: {range:?}");
}

#[test]
fn the_flat_lobe_changes_nothing() {
    let Some(seen) = exit_radiance(&ExitLobe::flat(), 60.0) else { return };
    for (mu_o, got) in seen {
        for v in got {
            assert!((v / (1.0 + SINGLE) - 1.0).abs() < 2e-3, "mu_o {mu_o}: {v}");
        }
    }
}
