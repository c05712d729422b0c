//! Golden images of the offscreen renderer, compared with NVIDIA's FLIP metric (mean and a high
//! percentile, as wgpu's own example tests do), tolerant of the small differences between
//! Mesa's lavapipe (Vulkan) and llvmpipe (GL) rasterisers.
//!
//! `LUCENT_UPDATE_GOLDEN=1 cargo test --release -p lucent-gpu --test golden` rewrites the
//! images under `tests/golden/`. Without an adapter the tests skip with a note (under CI they fail:
//! see `lucent_gpu::test_support`).

mod common;

use glam::Vec3;
use lucent_core::camera::OrbitCamera;
use lucent_core::irradiance::Light;
use lucent_gpu::mesh_pass::{GpuMesh, Shading};
use lucent_gpu::offscreen::{RenderSettings, render_image};
use lucent_gpu::test_support::adapter_or_skip;
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
    let Some(ctx) = adapter_or_skip() else { return };
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
    let Some(ctx) = adapter_or_skip() else { return };
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
            background: 0.0,
            exit_lobe: Default::default(),
            linear_single: false,
        },
        tone: ToneMap { exposure: 1.5, operator: ToneOperator::AcesFilmic, ..Default::default() },
    };
    let image = render_image(&ctx, &mesh, &settings).unwrap();
    check_golden("torus_filmic", &image);
}

// ---- Solved scenes: irradiance (shadows, SH environment) and the exact solve from lucent-core,
// so these goldens cover the whole Mertens path; each also asserts what the physics requires,
// so that a golden is never just a snapshot of whatever the code did.

mod solved {
    use super::check_golden;
    use glam::Vec3;
    use lucent_core::Rgb;
    use lucent_core::bssrdf::{Material, Profile};
    use lucent_core::camera::{CameraView, OrbitCamera};
    use lucent_core::formfactor::FormFactorOptions;
    use lucent_core::irradiance::{
        BandWeights, EnvMap, Environment, Light, SceneLight, ShadowCaster, face_irradiance_shadowed,
    };
    use lucent_core::mesh::{Mesh, generate};
    use lucent_core::{shading, solver};
    use lucent_gpu::GpuContext;
    use lucent_gpu::mesh_pass::{EnvironmentMap, GpuMesh, Shading};
    use lucent_gpu::offscreen::OffscreenRenderer;
    use lucent_gpu::test_support::adapter_or_skip;
    use lucent_gpu::tonemap::ToneMap;

    const SIZE: u32 = 256;

    /// `mesh` moved by `offset` after scaling by `scale` per axis.
    fn placed(mesh: Mesh, scale: Vec3, offset: Vec3) -> Mesh {
        Mesh::new(mesh.positions.iter().map(|p| *p * scale + offset).collect(), mesh.triangles)
    }

    /// Two meshes as one (two components).
    fn union(a: Mesh, b: Mesh) -> Mesh {
        let n = a.positions.len() as u32;
        let mut positions = a.positions;
        positions.extend(b.positions);
        let mut triangles = a.triangles;
        triangles.extend(b.triangles.iter().map(|t| t.map(|i| i + n)));
        Mesh::new(positions, triangles)
    }

    /// Per-vertex `B / pi` of the exact solve.
    fn solve(mesh: &Mesh, profile: &Profile, e: &[Rgb]) -> Vec<Rgb> {
        let b = solver::exact::solve(mesh, profile, e, &FormFactorOptions::default());
        shading::diffuse_radiance(&mesh.face_to_vertex(&b), profile)
    }

    struct Shot {
        image: image::RgbaImage,
        hdr: Vec<[f32; 4]>,
        camera: CameraView,
    }

    fn shoot(
        ctx: &GpuContext,
        mesh: &Mesh,
        radiance: &[Rgb],
        camera: &OrbitCamera,
        shading: &Shading,
        env: Option<&EnvironmentMap>,
        tone: &ToneMap,
    ) -> Shot {
        let gpu =
            GpuMesh::new(ctx, &mesh.positions, &mesh.vertex_normals(), radiance, &mesh.triangles).unwrap();
        let mut r = OffscreenRenderer::new(ctx, SIZE, SIZE).unwrap();
        if let Some(env) = env {
            r.mesh_pass_mut().set_environment(ctx, env);
        }
        let camera = r.camera_view(&gpu, camera);
        r.render(ctx, &gpu, &camera, shading, tone).unwrap();
        Shot { image: r.read_image(ctx).unwrap(), hdr: r.read_hdr(ctx).unwrap(), camera }
    }

    /// The pixel `p` projects to.
    fn pixel(camera: &CameraView, p: Vec3) -> (u32, u32) {
        let c = camera.view_proj * p.extend(1.0);
        let ndc = c.truncate() / c.w;
        let x = ((ndc.x * 0.5 + 0.5) * SIZE as f32) as u32;
        let y = ((0.5 - ndc.y * 0.5) * SIZE as f32) as u32;
        (x, y)
    }

    /// Mean HDR luminance of the 5 x 5 pixels around `(x, y)`, all of which must be covered.
    fn patch_luminance(hdr: &[[f32; 4]], (x, y): (u32, u32)) -> f32 {
        let mut sum = 0.0;
        for j in y - 2..=y + 2 {
            for i in x - 2..=x + 2 {
                let p = hdr[(j * SIZE + i) as usize];
                assert_eq!(p[3], 1.0, "pixel ({i}, {j}) should show the mesh");
                sum += 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            }
        }
        sum / 25.0
    }

    /// A cube floating over a slab, lit by a point light above and to the side: the cube's
    /// shadow on the slab comes from the BVH ray casts (Mertens §5.3), is where the geometry puts
    /// it, and is darker than the lit slab by far more than the subsurface light that bleeds in.
    #[test]
    fn point_light_cast_shadow() {
        let Some(ctx) = adapter_or_skip() else { return };
        let slab = placed(generate::cube(12), Vec3::new(2.0, 0.15, 2.0), Vec3::new(0.0, -1.0, 0.0));
        let block = placed(generate::cube(6), Vec3::splat(0.4), Vec3::new(0.0, 0.2, 0.0));
        let mesh = union(slab, block);
        let light_pos = Vec3::new(1.2, 2.6, 0.6);
        // Irradiance 1 at the slab's top centre.
        let top = Vec3::new(0.0, -0.85, 0.0);
        let light =
            Light::Point { position: light_pos, intensity: Vec3::splat(light_pos.distance_squared(top)) };
        let lights = [SceneLight { light, shadows: true }];
        // Marble, slab 4 units = 40 cm: the diffusion length (under 1 cm) is far below the
        // shadow's size, so the umbra stays dark.
        let material = Material::by_name("marble").unwrap();
        let profile = Profile::for_model_scale(&material, mesh.extent() as f64, 0.4);
        let caster = ShadowCaster::new(&mesh);
        let e = face_irradiance_shadowed(&mesh, &lights, None, &profile.entry, Some(&caster));
        let e_open = face_irradiance_shadowed(&mesh, &lights, None, &profile.entry, None);

        // The shadow is where a ray to the light meets the block (slab tops only; a closed-form
        // box test, independent of the BVH).
        let (lo, hi) = (Vec3::new(-0.4, -0.2, -0.4), Vec3::new(0.4, 0.6, 0.4));
        let hits_block = |p: Vec3| {
            let d = light_pos - p;
            let (t0, t1) = ((lo - p) / d, (hi - p) / d);
            let (near, far) = (t0.min(t1).max_element(), t0.max(t1).min_element());
            near <= far && far > 0.0 && near < 1.0
        };
        let mut shadowed = 0;
        for f in 0..mesh.triangles.len() {
            let (c, n) = (mesh.face_centroid(f), mesh.face_normal(f));
            if n.y < 0.99 || (c.y - (-0.85)).abs() > 1e-4 {
                continue;
            }
            if hits_block(c) {
                shadowed += 1;
                assert_eq!(e[f], Vec3::ZERO, "face {f} at {c} is behind the block");
                assert!(e_open[f].min_element() > 0.0);
            } else {
                assert_eq!(e[f], e_open[f], "face {f} at {c} sees the light");
            }
        }
        assert!(shadowed > 20, "the block shadows {shadowed} slab faces");

        let camera = OrbitCamera { yaw_deg: -20.0, pitch_deg: 35.0, ..Default::default() };
        let shading = Shading { eta: material.eta as f32, lights: vec![light], ..Default::default() };
        let tone = ToneMap { exposure: 1.5, ..Default::default() };
        let shot = shoot(&ctx, &mesh, &solve(&mesh, &profile, &e), &camera, &shading, None, &tone);
        let open = shoot(&ctx, &mesh, &solve(&mesh, &profile, &e_open), &camera, &shading, None, &tone);

        // The umbra's centre: the block's centre projected from the light onto the slab top;
        // a lit point as far from the block on the other side.
        let through = Vec3::new(0.0, 0.2, 0.0);
        let t = (light_pos.y - (-0.85)) / (light_pos.y - through.y);
        let umbra = light_pos + (through - light_pos) * t;
        let lit = Vec3::new(-umbra.x, -0.85, -umbra.z) * 0.9 + Vec3::new(0.0, 0.0, 0.9);
        assert!(hits_block(umbra) && !hits_block(lit));
        let (dark, bright) = (
            patch_luminance(&shot.hdr, pixel(&shot.camera, umbra)),
            patch_luminance(&shot.hdr, pixel(&shot.camera, lit)),
        );
        let dark_open = patch_luminance(&open.hdr, pixel(&open.camera, umbra));
        eprintln!("shadow: umbra {dark:.4}, lit {bright:.4}, umbra without shadows {dark_open:.4}");
        assert!(dark < 0.2 * bright, "umbra {dark} should be far darker than the lit slab {bright}");
        assert!(dark < 0.2 * dark_open, "without shadows the same spot is lit: {dark_open}");
        check_golden("point_shadow", &shot.image);
    }

    /// A marble sphere under the courtyard probe (SH9 irradiance, Fresnel-transmitted, and the
    /// Fresnel-weighted reflection of the map on the GPU). Energy: over a sphere much larger
    /// than the diffusion length, the area-mean of `B` is `R_d_total` times the mean transmitted
    /// irradiance, which is the DC term `A_0 L_00 Y_00`; the image's mean colour follows it.
    #[test]
    fn courtyard_environment() {
        let Some(ctx) = adapter_or_skip() else { return };
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/courtyard.exr");
        let map = EnvMap::load(&path).unwrap();
        let env = Environment { rotation_deg: 90.0, ..Environment::from_map(&map) };
        let mesh = generate::icosphere(4);
        let material = Material::by_name("marble").unwrap();
        // 20 cm across: radius over 10 diffusion lengths in every channel.
        let profile = Profile::for_model_scale(&material, mesh.extent() as f64, 0.2);
        let e = face_irradiance_shadowed(&mesh, &[], Some(&env), &profile.entry, None);
        let b = solver::exact::solve(&mesh, &profile, &e, &FormFactorOptions::default());

        let area: f32 = (0..mesh.triangles.len()).map(|f| mesh.face_area(f)).sum();
        let mean = |v: &[Rgb]| v.iter().enumerate().map(|(f, x)| *x * mesh.face_area(f)).sum::<Rgb>() / area;
        let l_mean = env.sh.coeffs[0] * 0.282_094_8; // L_00 Y_00: the map's mean radiance
        let a0 = BandWeights::fresnel_cosine(material.eta).0[0];
        let rd = Vec3::from_array(profile.total_diffuse_reflectance().map(|x| x as f32));
        let (e_mean, b_mean) = (mean(&e), mean(&b));
        eprintln!(
            "environment: mean E {e_mean}, A0 L {}, mean B {b_mean}, Rd E {}",
            l_mean * a0,
            rd * e_mean
        );
        for c in 0..3 {
            let rel = |a: f32, b: f32| (a - b).abs() / b;
            assert!(rel(e_mean[c], a0 * l_mean[c]) < 0.02, "channel {c}: mean E is the DC term");
            assert!(rel(b_mean[c], rd[c] * e_mean[c]) < 0.1, "channel {c}: mean B = R_d_total mean E");
        }

        let reflection = map.downsampled(256, 128).rotated(90.0);
        let texels: Vec<[f32; 4]> = reflection.texels.iter().map(|t| t.extend(1.0).to_array()).collect();
        let env_map = EnvironmentMap::from_rgba_f32(&ctx, 256, 128, &texels).unwrap();
        let shading = Shading { eta: material.eta as f32, environment: 1.0, ..Default::default() };
        let tone = ToneMap { exposure: 0.6, ..Default::default() };
        let radiance = shading::diffuse_radiance(&mesh.face_to_vertex(&b), &profile);
        // The image's mean colour over six views along the axes (pitch 89 for the poles): a
        // view's mean is a zonal convolution of the radiance about the view direction, so its
        // first- and second-order SH terms sum to zero over the six, leaving R_d_total times the
        // DC term (the reflection adds a few percent of the map's own mean, perspective and the
        // 1-degree pole offset a little more). Channel ratios within 5%.
        let mut shots = Vec::new();
        let mut img = Vec3::ZERO;
        for (yaw, pitch) in [(0.0, 0.0), (90.0, 0.0), (180.0, 0.0), (270.0, 0.0), (0.0, 89.0), (0.0, -89.0)] {
            let camera = OrbitCamera { yaw_deg: yaw, pitch_deg: pitch, ..Default::default() };
            let shot = shoot(&ctx, &mesh, &radiance, &camera, &shading, Some(&env_map), &tone);
            let covered: Vec<&[f32; 4]> = shot.hdr.iter().filter(|p| p[3] > 0.0).collect();
            img += covered.iter().fold(Vec3::ZERO, |s, p| s + Vec3::new(p[0], p[1], p[2]))
                / covered.len() as f32
                / 6.0;
            shots.push(shot);
        }
        let want = rd * l_mean;
        let (ri, rw) = (img / img.y, want / want.y);
        eprintln!("environment: image mean {img}, ratios {ri} vs R_d L_00 ratios {rw}");
        for c in [0, 2] {
            assert!((ri[c] - rw[c]).abs() < 0.05 * rw[c], "channel {c}: image ratio {ri} vs {rw}");
        }
        let shot = &shots[0];
        check_golden("courtyard_sphere", &shot.image);
    }
}
