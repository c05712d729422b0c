//! The mesh pass blends single-scattered radiance geometrically across a face (it falls off
//! exponentially past the terminator) and diffuse radiance linearly: on a square whose left
//! edge has 1 and right edge 1/100, the middle shows 1/10 of single scattering and about 1/2
//! of diffuse radiance.

mod common;

use glam::{Vec2, Vec3};
use lucent_core::camera::OrbitCamera;
use lucent_gpu::mesh_pass::{GpuMesh, Shading};
use lucent_gpu::offscreen::OffscreenRenderer;
use lucent_gpu::test_support::adapter_or_skip;
use lucent_gpu::tonemap::ToneMap;

const RIGHT_EDGE: f32 = 1e-2;

/// Radiance along the square's horizontal midline, as `(x in -1..1, radiance)`, with the given
/// per-vertex diffuse and single-scattered values.
fn midline(diffuse: [f32; 2], single: [f32; 2]) -> Option<Vec<(f32, f32)>> {
    let ctx = adapter_or_skip()?;
    let (pos, nrm, tris) = common::square();
    let side = |v: [f32; 2]| [0, 1, 1, 0].map(|k| Vec3::splat(v[k])).to_vec();
    let mesh = GpuMesh::new(&ctx, &pos, &nrm, &side(diffuse), &tris).unwrap();
    mesh.update_radiance(&ctx, &side(diffuse), &side(single)).unwrap();
    let size = 128u32;
    let r = OffscreenRenderer::new(&ctx, size, size).unwrap();
    let camera = r.camera_view(&mesh, &OrbitCamera { pitch_deg: 0.0, ..Default::default() });
    // eta = 1: no Fresnel loss on the way out, the radiance is what was uploaded.
    let shading = Shading { eta: 1.0, specular: 0.0, ..Default::default() };
    r.render(&ctx, &mesh, &camera, &shading, &ToneMap::default()).unwrap();
    let hdr = r.read_hdr(&ctx).unwrap();
    let y = size / 2;
    let mut line = Vec::new();
    for x in 0..size {
        let (origin, dir) = camera.ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::splat(size as f32));
        let hit = origin + dir * (-origin.z / dir.z);
        let p = hdr[(y * size + x) as usize];
        // Whole pixels inside the square, off its diagonal's row of half-covered samples.
        if hit.x.abs() < 0.95 && p[3] == 1.0 {
            line.push((hit.x, p[0]));
        }
    }
    assert!(line.len() > 40, "{} pixels on the square", line.len());
    Some(line)
}

#[test]
fn single_scattering_blends_geometrically() {
    let Some(line) = midline([0.0, 0.0], [1.0, RIGHT_EDGE]) else { return };
    for (x, got) in line {
        let want = RIGHT_EDGE.powf((x + 1.0) / 2.0);
        assert!((got / want - 1.0).abs() < 0.03, "x = {x}: {got} against {want}");
    }
}

#[test]
fn diffuse_radiance_blends_linearly() {
    let Some(line) = midline([1.0, RIGHT_EDGE], [0.0, 0.0]) else { return };
    for (x, got) in line {
        let want = 1.0 + (RIGHT_EDGE - 1.0) * (x + 1.0) / 2.0;
        assert!((got - want).abs() < 0.01, "x = {x}: {got} against {want}");
    }
}
