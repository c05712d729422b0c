//! The plugin's image against `lucent render`'s: Bevy runs headless (no window: the camera
//! renders into an `Rgba32Float` image read back to the CPU, on Mesa's lavapipe without a GPU),
//! draws the embedded bunny in marble at 10 cm under one directional light of 1 lux with the
//! camera `lucent render` frames by default, and the linear radiance of every pixel the object
//! fully covers is compared with `lucent render --format exr` of the same mesh, material,
//! light and camera. Target (issue 53): the median relative difference over the object within
//! 5%.
//!
//! Then the `Translucent` component's material is changed to skim milk, and the image must match
//! `lucent render --material skimmilk` by the same criterion, solved in the same session (its
//! material path, refit mode), not a new one. Then the mesh asset's positions are edited, and
//! the plugin must solve the new pose in the same session (its deformation path).
//!
//! A second test presses the bunny example's `M` key (its key handling, without a window) and
//! checks that the component's material follows the example's list.
//!
//! `LUCENT_BEVY_DEBUG=1` prints what each frame read back; `LUCENT_BEVY_LIMIT_S` changes the
//! 300 s limit on reaching a stable frame.
//!
//! Needs the `lucent` binary of the same build (`cargo test --release --workspace` builds it)
//! and a Vulkan or GL driver; without them the test says SKIPPED and what to do (under CI, a
//! failure).

use bevy::prelude::*;
use common::{HEIGHT, LIGHT, Latest, Pixels, WIDTH, decode, headless_app, lucent_view, scene};
use lucent_bevy::{LucentPlugin, SolveStatus, Translucent, TranslucentMaterial};
use std::path::PathBuf;
use std::time::{Duration, Instant};

mod common;
#[path = "../examples/bunny/keys.rs"]
mod keys;

/// How to get a driver on Debian without a GPU (lucent-gpu's `test_support::INSTALL_ADAPTER`).
const INSTALL_ADAPTER: &str = "apt-get install mesa-vulkan-drivers libegl1 libgl1-mesa-dri";

/// lucent-gpu's `test_support::skip` rule (not a dependency here: it would pull wgpu 30 beside
/// Bevy's wgpu 29): a note on a developer's machine, a failure under CI.
fn skip(missing: &str, install: &str) {
    let text = format!("{missing}; install it with `{install}` (.ci/run installs everything)");
    assert!(std::env::var_os("CI").is_none(), "{text}. CI is set, so this test may not be skipped");
    eprintln!("SKIPPED the_bevy_image_matches_lucent_render: {text}");
}

/// The `lucent` binary next to this test's build (target/release/lucent).
fn lucent_binary() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    let bin = exe.parent()?.parent()?.join(format!("lucent{}", std::env::consts::EXE_SUFFIX));
    bin.is_file().then_some(bin)
}

/// `lucent render` of the scene in `material` as linear radiance, or `None` after saying why it
/// cannot run.
fn lucent_render(out: &std::path::Path, material: &str) -> Option<Pixels> {
    let Some(bin) = lucent_binary() else {
        skip("no lucent binary beside the tests", "cargo build --release -p lucent");
        return None;
    };
    let light = format!("dir:{},{},{}", LIGHT[0], LIGHT[1], LIGHT[2]);
    let size = [WIDTH.to_string(), HEIGHT.to_string()];
    let run = std::process::Command::new(bin)
        .args(["render", "--material", material, "--scale", "0.1", "--refine", "0", "--mode", "refit"])
        .args(["--light", &light, "--width", &size[0], "--height", &size[1], "--format", "exr", "--out"])
        .arg(out)
        .output()
        .expect("the lucent binary runs");
    if !run.status.success() {
        let err = String::from_utf8_lossy(&run.stderr);
        if err.contains("adapter") || err.contains("driver") {
            skip("no GPU adapter for lucent render", INSTALL_ADAPTER);
            return None;
        }
        panic!("lucent render failed: {err}");
    }
    let image = exr::prelude::read_first_rgba_layer_from_file(
        out,
        |res, _| vec![[0.0f32; 4]; res.width() * res.height()],
        |px: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * WIDTH as usize + pos.x()] = [r, g, b, a]
        },
    )
    .expect("lucent's EXR reads");
    Some(image.layer_data.channel_data.pixels)
}

/// Runs `app` until the plugin has shown `solves` solves and two read-backs agree (the
/// pipelines compile asynchronously; read-backs of frames before the solve was shown are let
/// pass), at most `limit`.
fn render(app: &mut App, latest: &Latest, solves: u64, limit: Duration) -> Pixels {
    /// Frames after the solve is shown before a read-back counts (read-backs lag a few frames).
    const SETTLE: u32 = 8;
    let started = Instant::now();
    let mut previous: Option<Pixels> = None;
    let mut since_shown = 0;
    loop {
        assert!(started.elapsed() < limit, "no stable Bevy frame with solve {solves} within {limit:?}");
        app.update();
        let status = status(app);
        if let Some(err) = status.error {
            panic!("the plugin could not solve the bunny: {err}");
        }
        let shown = status.solves >= solves && !status.solving;
        since_shown = if shown { since_shown + 1 } else { 0 };
        let got = latest.lock().unwrap().take();
        if std::env::var_os("LUCENT_BEVY_DEBUG").is_some() {
            let covered = got.as_ref().map(|b| decode(b).iter().filter(|p| p[3] > 0.999).count());
            let lit = got.as_ref().map(|b| decode(b).iter().filter(|p| p[0] + p[1] + p[2] > 0.0).count());
            eprintln!(
                "t {:.1}s solves {} read back {:?} covered {covered:?} lit {lit:?}",
                started.elapsed().as_secs_f32(),
                status.solves,
                got.as_ref().map(Vec::len)
            );
        }
        let Some(bytes) = got else { continue };
        if since_shown < SETTLE {
            std::thread::sleep(Duration::from_millis(20));
            continue;
        }
        let pixels = decode(&bytes);
        let covered = pixels.iter().filter(|p| p[3] > 0.999 && p[0] + p[1] + p[2] > 0.0).count();
        if covered > 0 && previous.as_ref() == Some(&pixels) {
            return pixels;
        }
        previous = Some(pixels);
    }
}

/// The one body's [`SolveStatus`].
fn status(app: &mut App) -> SolveStatus {
    let world = app.world_mut();
    world.query::<&SolveStatus>().single(world).expect("one body").clone()
}

/// Whether pixel `i` and its four neighbours are fully covered in `image`.
fn interior(image: &Pixels, i: usize) -> bool {
    let (w, x, y) = (WIDTH as usize, i % WIDTH as usize, i / WIDTH as usize);
    if x == 0 || y == 0 || x + 1 == w || y + 1 == HEIGHT as usize {
        return false;
    }
    [i, i - 1, i + 1, i - w, i + w].iter().all(|&j| image[j][3] > 0.999)
}

/// Stretches the body's mesh asset by 10% along y (a system editing the mesh would do the same)
/// and runs `app` until the plugin has solved it; returns the body's solve count then.
fn stretch(app: &mut App, limit: Duration) -> u64 {
    let before = status(app).solves;
    {
        let world = app.world_mut();
        let handle = world.query::<&Mesh3d>().single(world).expect("one body").0.clone();
        let mut meshes = world.resource_mut::<Assets<Mesh>>();
        let mut mesh = meshes.get_mut(&handle).expect("the body's mesh");
        let Some(bevy::mesh::VertexAttributeValues::Float32x3(p)) =
            mesh.attribute_mut(Mesh::ATTRIBUTE_POSITION)
        else {
            panic!("positions")
        };
        p.iter_mut().for_each(|v| v[1] *= 1.1);
    }
    let started = Instant::now();
    loop {
        assert!(started.elapsed() < limit, "no solve of the stretched mesh within {limit:?}");
        app.update();
        let status = status(app);
        if status.solves != before && !status.solving {
            return status.solves;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Sets the body's material to the preset `name`, as a game (or the example's `M` key) would.
fn set_material(app: &mut App, name: &str) {
    let world = app.world_mut();
    let mut body = world.query::<&mut Translucent>().single_mut(world).expect("one body");
    body.material = TranslucentMaterial::Preset(name.into());
}

fn luminance(p: &[f32; 4]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

fn median(mut v: Vec<f32>) -> f32 {
    v.sort_by(f32::total_cmp);
    v[v.len() / 2]
}

/// Compares Bevy's image of `what` with `lucent render`'s over the pixels both fully cover:
/// asserts the 5% median and that the silhouettes agree, and prints the figures.
fn compare(bevy: &Pixels, reference: &Pixels, what: &str) {
    let pairs: Vec<(f32, f32)> = (0..bevy.len())
        .filter(|&i| interior(bevy, i) && interior(reference, i))
        .map(|i| (luminance(&bevy[i]), luminance(&reference[i])))
        .filter(|&(_, l)| l > 0.0)
        .collect();
    let both = pairs.len();
    assert!(both > 2000, "{what}: the object covers only {both} pixels in both images");
    let only_one = (0..bevy.len()).filter(|&i| (bevy[i][3] > 0.999) != (reference[i][3] > 0.999)).count();
    let relative = median(pairs.iter().map(|&(b, l)| (b - l).abs() / l).collect());
    let ratio = median(pairs.iter().map(|&(b, l)| b / l).collect());
    let mut sorted: Vec<f32> = pairs.iter().map(|&(b, l)| (b - l).abs() / l).collect();
    sorted.sort_by(f32::total_cmp);
    let p95 = sorted[sorted.len() * 95 / 100];
    let (bm, lm) = (median(pairs.iter().map(|p| p.0).collect()), median(pairs.iter().map(|p| p.1).collect()));
    println!(
        "{what}: bevy vs lucent render over {both} interior pixels ({only_one} covered in one image \
         only): median |rel diff| {:.3}% (95th percentile {:.3}%), median ratio {ratio:.5}, median \
         luminance {bm:.4e} vs {lm:.4e}",
        relative * 100.0,
        p95 * 100.0
    );
    assert!(
        only_one * 20 < both,
        "{what}: the silhouettes differ: {only_one} pixels covered in one image only"
    );
    assert!(relative < 0.05, "{what}: median relative difference {:.2}% over the object", relative * 100.0);
}

#[test]
fn the_bevy_image_matches_lucent_render_within_5_percent_median_over_the_object() {
    let dir = std::env::temp_dir().join(format!("lucent-bevy-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let Some(marble) = lucent_render(&dir.join("marble.exr"), "marble") else { return };
    let Some(skimmilk) = lucent_render(&dir.join("skimmilk.exr"), "skimmilk") else { return };
    std::fs::remove_dir_all(&dir).ok();
    let limit = Duration::from_secs(
        std::env::var("LUCENT_BEVY_LIMIT_S").ok().and_then(|s| s.parse().ok()).unwrap_or(300),
    );
    let mut app = headless_app(LucentPlugin::default());
    let latest = scene(&mut app, &lucent_view());
    compare(&render(&mut app, &latest, 1, limit), &marble, "marble");
    // A new material is the session's material path (a new session would count from 0 again).
    set_material(&mut app, "skimmilk");
    compare(&render(&mut app, &latest, 2, limit), &skimmilk, "skim milk after marble");
    assert_eq!(status(&mut app).solves, 2, "the material change was not solved in the body's session");
    // Moved vertices are a deformation of the same session.
    assert_eq!(stretch(&mut app, Duration::from_secs(120)), 3, "the stretch was not solved as a deformation");
}

#[test]
fn the_bunny_examples_m_key_sets_the_next_material() {
    let mut app = App::new();
    app.init_resource::<ButtonInput<KeyCode>>()
        .init_resource::<keys::Controls>()
        .add_systems(Update, keys::keys);
    let body = app.world_mut().spawn(Translucent::preset("marble")).id();
    let press = |app: &mut App, key: KeyCode| {
        app.world_mut().resource_mut::<ButtonInput<KeyCode>>().press(key);
        app.update();
        // What Bevy's input system does between frames.
        let mut input = app.world_mut().resource_mut::<ButtonInput<KeyCode>>();
        input.release(key);
        input.clear();
    };
    let all = keys::materials();
    assert_eq!(all[0].1, TranslucentMaterial::Preset("marble".into()), "the example starts in marble");
    for step in 1..=all.len() {
        press(&mut app, KeyCode::KeyM);
        let material = &app.world().get::<Translucent>(body).expect("the body").material;
        assert_eq!(*material, all[step % all.len()].1, "M pressed {step} times");
    }
    // The other keys leave the material alone.
    press(&mut app, KeyCode::KeyD);
    press(&mut app, KeyCode::Space);
    assert_eq!(app.world().get::<Translucent>(body).expect("the body").material, all[0].1);
    let controls = app.world().resource::<keys::Controls>();
    assert!(controls.bulge && controls.paused, "D and Space toggle the bulge and the pause");
}
