//! Golden images of the offscreen renderer, compared with NVIDIA's FLIP metric (mean and a high
//! percentile, as wgpu's own example tests do), tolerant of the small differences between
//! Mesa's lavapipe (Vulkan) and llvmpipe (GL) rasterisers.
//!
//! `LUCENT_UPDATE_GOLDEN=1 cargo test --release -p lucent-gpu --test golden` rewrites the
//! images under `tests/golden/`. Without an adapter the tests fail (they never skip).

mod common;

use glam::Vec3;
use lucent_core::irradiance::Light;
use lucent_gpu::camera::OrbitCamera;
use lucent_gpu::mesh_pass::{GpuMesh, Shading};
use lucent_gpu::offscreen::{RenderSettings, render_image};
use lucent_gpu::tonemap::{ToneMap, ToneOperator};
use std::path::PathBuf;

/// Mean FLIP error allowed over the image.
const MEAN_FLIP: f32 = 0.01;
/// FLIP error allowed at the 99th percentile (edge pixels may differ between rasterisers).
const P99_FLIP: f32 = 0.15;

fn check_golden(name: &str, image: &image::RgbaImage) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let path = dir.join(format!("{name}.png"));
    if std::env::var_os("LUCENT_UPDATE_GOLDEN").is_some_and(|v| v == "1") {
        std::fs::create_dir_all(&dir).unwrap();
        image.save(&path).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let golden = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}; run with LUCENT_UPDATE_GOLDEN=1 to create it", path.display()))
        .to_rgb8();
    assert_eq!(golden.dimensions(), image.dimensions(), "{name}: size differs from the golden");
    let (w, h) = image.dimensions();
    let actual = image::DynamicImage::ImageRgba8(image.clone()).to_rgb8();
    let error_map = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, golden.as_raw()),
        nv_flip::FlipImageRgb8::with_data(w, h, actual.as_raw()),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let mut pool = nv_flip::FlipPool::from_image(&error_map);
    let mean = pool.mean();
    let p99 = pool.get_percentile(0.99, false);
    eprintln!("{name}: FLIP mean {mean:.5}, p99 {p99:.5}");
    if mean > MEAN_FLIP || p99 > P99_FLIP {
        let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
        let actual_path = out.join(format!("{name}.actual.png"));
        let flip_path = out.join(format!("{name}.flip.png"));
        image.save(&actual_path).unwrap();
        let flip_rgb = error_map.apply_color_lut(&nv_flip::magma_lut());
        image::RgbImage::from_raw(w, h, flip_rgb.to_vec()).unwrap().save(&flip_path).unwrap();
        panic!(
            "{name}: FLIP mean {mean:.5} (limit {MEAN_FLIP}), p99 {p99:.5} (limit {P99_FLIP}); \
             see {} and {}",
            actual_path.display(),
            flip_path.display()
        );
    }
}

/// A unit sphere glowing as if lit from the upper left behind: per-vertex `B / pi` falls off
/// exponentially (per channel, red travelling farthest, like skim milk) with distance from a
/// point outside the sphere. A frontal point light adds a Fresnel-weighted highlight.
#[test]
fn sphere_translucent_glow() {
    let ctx = common::ctx();
    let (pos, tris) = common::icosphere(4);
    let source = Vec3::new(-1.2, 0.9, -0.8);
    let sigma = Vec3::new(1.2, 2.4, 3.6);
    let radiance: Vec<Vec3> = pos
        .iter()
        .map(|p| {
            let d = p.distance(source);
            Vec3::new((-sigma.x * d).exp(), (-sigma.y * d).exp(), (-sigma.z * d).exp()) * 4.0
        })
        .collect();
    let mesh = GpuMesh::new(&ctx, &pos, &pos, &radiance, &tris).unwrap();
    let settings = RenderSettings {
        width: 256,
        height: 256,
        camera: OrbitCamera::default(),
        shading: Shading {
            eta: 1.3,
            lights: vec![Light::Point { position: Vec3::new(2.0, 3.0, 4.0), intensity: Vec3::splat(30.0) }],
            ..Default::default()
        },
        tone: ToneMap::default(),
    };
    let image = render_image(&ctx, &mesh, &settings).unwrap();
    check_golden("sphere_glow", &image);
}

/// A torus seen from above at an angle (self-occlusion needs the depth test), radiance from its
/// normals, tone mapped with the ACES fit at a high exposure.
#[test]
fn torus_filmic() {
    let ctx = common::ctx();
    let (pos, nrm, tris) = common::torus(1.0, 0.4, 64, 32);
    let radiance: Vec<Vec3> = nrm.iter().map(|n| (*n * 0.5 + Vec3::splat(0.5)) * 0.5).collect();
    let mesh = GpuMesh::new(&ctx, &pos, &nrm, &radiance, &tris).unwrap();
    let settings = RenderSettings {
        width: 256,
        height: 256,
        camera: OrbitCamera { yaw_deg: 30.0, pitch_deg: 40.0, ..Default::default() },
        shading: Shading {
            eta: 1.5,
            lights: vec![Light::Directional {
                direction: Vec3::new(-0.3, -1.0, -0.5),
                irradiance: Vec3::splat(2.0),
            }],
            specular: 1.0,
            shininess: 32.0,
            environment: 0.0,
        },
        tone: ToneMap { exposure: 1.5, operator: ToneOperator::AcesFilmic, ..Default::default() },
    };
    let image = render_image(&ctx, &mesh, &settings).unwrap();
    check_golden("torus_filmic", &image);
}
