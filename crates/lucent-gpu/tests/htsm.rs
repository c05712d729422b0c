//! Heterogeneous Translucent Shadow Maps (Shopf 2007) on whatever adapter exists (Mesa lavapipe
//! or llvmpipe suffice): a golden image, the equivalence of a uniform volume with a homogeneous
//! material, monotonic absorption, the smoothing of more sample rays (fig. 5.7) and the
//! coverage-normalised mips of the reference images.
//!
//! The scene is self-contained: an ellipsoid (a subdivided icosahedron, 2 x 1.4 x 1 mesh units)
//! lit from behind by a distant light, seen from the front.
//! `LUCENT_UPDATE_GOLDEN=1 cargo test --release -p lucent-gpu --test htsm` rewrites the golden.
//!
//! More in the submodules: several lights, spots and the environment ([`lights`]), deformation
//! ([`deformation`]) and drawing into a caller's texture ([`target`]).

#[path = "htsm/deformation.rs"]
mod deformation;
#[path = "htsm/lights.rs"]
mod lights;
#[path = "htsm/target.rs"]
mod target;

use glam::Vec3;
use lucent_core::camera::{OrbitCamera, bounding_sphere};
use lucent_core::irradiance::Light;
use lucent_core::mesh::Mesh;
use lucent_core::volume::{DensityVolume, VolumeSpec};
use lucent_gpu::GpuContext;
use lucent_gpu::htsm::{HtsmMedium, HtsmParams, HtsmRenderer, HtsmView, TransportModel};
use lucent_gpu::readback::read_texture;
use lucent_gpu::test_support::adapter_or_skip;
use std::path::PathBuf;

/// The test object: an ellipsoid with semi-axes `(1, 0.7, half_depth)` mesh units.
fn ellipsoid(half_depth: f32) -> Mesh {
    let mut m = lucent_core::mesh::generate::icosphere(4);
    for p in &mut m.positions {
        *p *= Vec3::new(1.0, 0.7, half_depth);
    }
    m
}

/// Seen from +z, lit from behind (the light travels towards the camera, slightly downwards).
fn view(mesh: &Mesh, size: u32) -> HtsmView {
    HtsmView {
        camera: {
            let (centre, radius) = bounding_sphere(&mesh.positions);
            OrbitCamera { pitch_deg: 0.0, ..Default::default() }.frame(centre, radius, 1.0)
        },
        lights: vec![Light::Directional {
            direction: Vec3::new(0.15, -0.2, 1.0),
            irradiance: Vec3::splat(3.0),
        }],
        environment: None,
        width: size,
        height: size,
    }
}

fn render(ctx: &GpuContext, mesh: &Mesh, volume: &DensityVolume, params: &HtsmParams) -> image::RgbaImage {
    let mut r = HtsmRenderer::new(ctx, mesh, volume, 128).unwrap_or_else(|e| panic!("{e}"));
    r.render(ctx, &view(mesh, 128), params).unwrap_or_else(|e| panic!("{e}"))
}

/// Relative luminance of an sRGB-encoded pixel, linearised (Rec. 709 weights).
fn luminance(p: &image::Rgba<u8>) -> f32 {
    let lin = |c: u8| {
        let c = c as f32 / 255.0;
        if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
    };
    0.2126 * lin(p[0]) + 0.7152 * lin(p[1]) + 0.0722 * lin(p[2])
}

/// Pixels covered by the object: those that differ from the background (the corner pixel).
fn object_mask(img: &image::RgbaImage) -> Vec<bool> {
    let bg = *img.get_pixel(0, 0);
    img.pixels().map(|p| *p != bg).collect()
}

/// Mean luminance over `mask`.
fn mean_luminance(img: &image::RgbaImage, mask: &[bool]) -> f32 {
    let (sum, n) = img
        .pixels()
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0.0, 0), |(s, n), (p, _)| (s + luminance(p), n + 1));
    assert!(n > 100, "the object covers only {n} pixels");
    sum / n as f32
}

fn golden_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden/htsm_default.png")
}

#[test]
fn golden_image_of_the_default_heterogeneous_scene() {
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let volume = VolumeSpec::default().build([32, 22, 16]).unwrap();
    let img = render(&ctx, &mesh, &volume, &HtsmParams::default());
    let path = golden_path();
    if std::env::var_os("LUCENT_UPDATE_GOLDEN").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        img.save(&path).unwrap();
        return;
    }
    let golden = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (LUCENT_UPDATE_GOLDEN=1 writes it)", path.display()))
        .to_rgba8();
    assert_eq!(golden.dimensions(), img.dimensions());
    let rgb = |i: &image::RgbaImage| -> Vec<u8> { i.pixels().flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let (w, h) = img.dimensions();
    let error = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, &rgb(&golden)),
        nv_flip::FlipImageRgb8::with_data(w, h, &rgb(&img)),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let mut pool = nv_flip::FlipPool::from_image(&error);
    let (mean, p99) = (pool.mean(), pool.get_percentile(0.99, true));
    // Thresholds in the style of wgpu's own image tests: software rasterisers differ in
    // rounding, not in content. A wrong pass shows up as mean FLIP errors of 0.1 and more.
    if mean > 0.01 || p99 > 0.1 {
        let out = std::env::temp_dir().join("htsm_default_actual.png");
        img.save(&out).unwrap();
        panic!(
            "FLIP mean {mean}, 99th percentile {p99} against {}; actual in {}",
            path.display(),
            out.display()
        );
    }
}

#[test]
fn uniform_density_equals_a_homogeneous_material_with_the_density_folded_in() {
    // A uniform density d adds density_scale * d to the extinction (eq. 4.1), so it must equal
    // a clear (density 0) body whose base material absorbs that much more:
    // * Beer-Lambert: sigma' = sigma + s d, i.e. T_c' = exp(-sigma' T_d);
    // * thesis: (2 T_d - D (1 + s d)) / T_d = (2 T_d' - D) / T_d' with T_d' = T_d / (1 + s d).
    // d = 0.4 is exact in the 8-bit density texture (102 / 255), and the midpoint rule
    // integrates a constant exactly, so only float rounding separates the images.
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let dims = [16, 12, 8];
    let d = 0.4;
    let dense = DensityVolume::uniform(dims, d).unwrap();
    let clear = DensityVolume::uniform(dims, 0.0).unwrap();
    for model in [TransportModel::BeerLambert, TransportModel::Thesis] {
        let base = HtsmParams { model, density_scale: 2.0, ..Default::default() };
        let s_d = base.density_scale * d;
        let folded = match model {
            TransportModel::BeerLambert => HtsmParams {
                transport_colour: (-(base.sigma() + s_d) * base.transport_distance).exp(),
                ..base
            },
            TransportModel::Thesis => {
                HtsmParams { transport_distance: base.transport_distance / (1.0 + s_d), ..base }
            }
            TransportModel::Diffusion => unreachable!("not in this loop"),
        };
        let a = render(&ctx, &mesh, &dense, &base);
        let b = render(&ctx, &mesh, &clear, &folded);
        let unfolded = render(&ctx, &mesh, &clear, &base);
        let max_diff = |x: &image::RgbaImage, y: &image::RgbaImage| {
            x.as_raw().iter().zip(y.as_raw()).map(|(p, q)| p.abs_diff(*q)).max().unwrap()
        };
        assert!(max_diff(&a, &b) <= 2, "{model:?}: uniform vs folded differ by {}", max_diff(&a, &b));
        // Not vacuous: the density does change the image.
        assert!(max_diff(&a, &unfolded) >= 20, "{model:?}: density had no visible effect");
    }
}

#[test]
fn more_density_or_a_longer_path_transmits_less_light() {
    let Some(ctx) = adapter_or_skip() else { return };
    // The diffusion model needs a medium: skim milk at 1 cm, whose density adds 0.2 mm^-1.
    let milk = HtsmMedium {
        sigma_s_prime: Vec3::new(0.70, 1.22, 1.90),
        sigma_a: Vec3::new(0.0014, 0.0025, 0.0142),
        density_sigma_a: Vec3::splat(0.2),
        scale_m: 0.01,
    };
    for model in [TransportModel::BeerLambert, TransportModel::Thesis, TransportModel::Diffusion] {
        // No surface shading: the front is unlit anyway, this keeps rims out of the mean.
        let params = HtsmParams { model, diffuse: 0.0, specular: 0.0, ..Default::default() };
        let params = if model == TransportModel::Diffusion { milk.apply(params) } else { params };
        let mesh = ellipsoid(0.5);
        let mut previous = f32::INFINITY;
        for d in [0.0, 0.1, 0.25, 0.5] {
            let img = render(&ctx, &mesh, &DensityVolume::uniform([8, 8, 8], d).unwrap(), &params);
            let l = mean_luminance(&img, &object_mask(&img));
            assert!(l < previous, "{model:?}: density {d} gives mean luminance {l} >= {previous}");
            previous = l;
        }
        // Thicker along the light (and view) axis: same silhouette, longer paths.
        let volume = DensityVolume::uniform([8, 8, 8], 0.1).unwrap();
        let mut previous = f32::INFINITY;
        for half_depth in [0.3, 0.5, 0.7] {
            let img = render(&ctx, &ellipsoid(half_depth), &volume, &params);
            let l = mean_luminance(&img, &object_mask(&img));
            assert!(l < previous, "{model:?}: depth {half_depth} gives mean luminance {l} >= {previous}");
            previous = l;
        }
    }
}

/// Total variation of the luminance over pixels whose 5x5 neighbourhood is inside the object
/// (so that the silhouette, which does not depend on n, is left out).
fn interior_total_variation(img: &image::RgbaImage) -> f32 {
    let mask = object_mask(img);
    let (w, h) = img.dimensions();
    let inside = |x: i64, y: i64| {
        (-2..=2).all(|dy| {
            (-2..=2).all(|dx| {
                let (u, v) = (x + dx, y + dy);
                u >= 0 && v >= 0 && u < w as i64 && v < h as i64 && mask[(v * w as i64 + u) as usize]
            })
        })
    };
    let mut tv = 0.0;
    for y in 0..h as i64 - 1 {
        for x in 0..w as i64 - 1 {
            if inside(x, y) {
                let l = luminance(img.get_pixel(x as u32, y as u32));
                tv += (luminance(img.get_pixel(x as u32 + 1, y as u32)) - l).abs()
                    + (luminance(img.get_pixel(x as u32, y as u32 + 1)) - l).abs();
            }
        }
    }
    tv
}

#[test]
fn more_sample_rays_give_a_smoother_image() {
    // Shopf fig. 5.7: 1, 5, 9, 13 rays progressively smooth the light shining through.
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let volume = VolumeSpec::default().build([32, 22, 16]).unwrap();
    let tv: Vec<f32> = [1, 5, 9, 13]
        .iter()
        .map(|&samples| {
            interior_total_variation(&render(
                &ctx,
                &mesh,
                &volume,
                &HtsmParams { samples, ..Default::default() },
            ))
        })
        .collect();
    for pair in tv.windows(2) {
        assert!(pair[1] < pair[0] * 1.02, "total variation {tv:?} does not decrease with n");
    }
    assert!(tv[3] < 0.8 * tv[0], "13 rays are not clearly smoother than 1: {tv:?}");
}

#[test]
fn reference_mips_average_texture_coordinates_over_covered_texels_only() {
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let volume = DensityVolume::uniform([4, 4, 4], 0.0).unwrap();
    let mut r = HtsmRenderer::new(&ctx, &mesh, &volume, 64).unwrap();
    r.render(&ctx, &view(&mesh, 32), &HtsmParams::default()).unwrap();
    let texcoord = &r.reference_textures()[1];
    let level0 = read_texture(&ctx, texcoord, 0).unwrap().to_rgba_f32().unwrap();
    for level in [1u32, 3] {
        let data = read_texture(&ctx, texcoord, level).unwrap();
        let texels = data.to_rgba_f32().unwrap();
        let f = 1usize << level;
        let mut partial = 0;
        for y in 0..data.height as usize {
            for x in 0..data.width as usize {
                // CPU reference: mean texture coordinate of the covered level-0 texels below.
                let (mut sum, mut covered) = (Vec3::ZERO, 0.0f32);
                for v in y * f..(y + 1) * f {
                    for u in x * f..(x + 1) * f {
                        let t = level0[v * 64 + u];
                        if t[3] > 0.5 {
                            sum += Vec3::new(t[0], t[1], t[2]);
                            covered += 1.0;
                        }
                    }
                }
                let t = texels[y * data.width as usize + x];
                let coverage = covered / (f * f) as f32;
                assert!(
                    (t[3] - coverage).abs() < 2e-3,
                    "level {level} ({x},{y}): alpha {} vs {coverage}",
                    t[3]
                );
                if covered > 0.0 {
                    let gpu = Vec3::new(t[0], t[1], t[2]) / t[3];
                    let cpu = sum / covered;
                    assert!(
                        (gpu - cpu).abs().max_element() < 4e-3,
                        "level {level} ({x},{y}): {gpu} vs {cpu}"
                    );
                    if covered < (f * f) as f32 {
                        partial += 1;
                    }
                }
            }
        }
        assert!(partial > 0, "level {level} has no partly covered texel to test");
    }
}
