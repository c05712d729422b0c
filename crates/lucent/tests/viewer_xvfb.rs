//! The viewer end to end: `lucent view` in a real window under Xvfb (Mesa's lavapipe or
//! llvmpipe draws it), driven by a script that dents the mesh and moves a light, with a
//! screenshot before and after. Needs `xvfb-run` (Debian: `apt-get install xvfb xauth`) and a
//! GPU adapter; without them the tests skip with a note, except under CI (see `common`).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

/// Background of the 3D view in the PNG: `viewer::draw::BACKGROUND` (0.055, 0.06, 0.07)
/// written as 8-bit display values.
const BACKGROUND: [u8; 3] = [14, 15, 18];

/// The 3D viewport `(x, y, width, height)` that the viewer reports for a saved screenshot.
fn viewport_of(stdout: &str, file: &str) -> [u32; 4] {
    let line = stdout
        .lines()
        .find(|l| l.contains("lucent view: saved") && l.contains(file))
        .unwrap_or_else(|| panic!("no 'saved {file}' line in the viewer's output:\n{stdout}"));
    let tail = line.split("3D viewport").nth(1).expect("viewport in the line");
    let v: Vec<u32> = tail
        .trim()
        .trim_end_matches(')')
        .split_whitespace()
        .map(|n| n.parse().expect("viewport numbers"))
        .collect();
    [v[0], v[1], v[2], v[3]]
}

fn load(path: &Path) -> image::RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display())).into_rgb8()
}

fn differs_from_background(p: &image::Rgb<u8>) -> bool {
    p.0.iter().zip(BACKGROUND).any(|(a, b)| a.abs_diff(b) > 8)
}

/// Runs `lucent view` under Xvfb in `dir` with `script`, saving the final frame to `last`;
/// returns the viewer's stdout, or `None` when `xvfb-run` or an adapter is missing (the test
/// is then skipped with a note, or fails under CI: see `common`).
fn run_viewer(dir: &Path, script: &str, last: &str) -> Option<String> {
    run_viewer_with(dir, &[], script, last)
}

/// [`run_viewer`] with more `lucent view` arguments.
fn run_viewer_with(dir: &Path, extra: &[&str], script: &str, last: &str) -> Option<String> {
    let xvfb = common::xvfb_run_or_skip()?;
    if !common::gpu_or_skip() {
        return None;
    }
    std::fs::create_dir_all(dir).unwrap();
    let output = Command::new(xvfb)
        .args(["-a", "-s", "-screen 0 1280x1024x24"])
        .arg(env!("CARGO_BIN_EXE_lucent"))
        .args(["view", "--width", "720", "--height", "480", "--frames", "6"])
        .args(extra)
        .args(["--script", script])
        .args(["--screenshot", last])
        .current_dir(dir)
        // Xvfb is an X server: keep winit from choosing a Wayland compositor of the caller's.
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("running xvfb-run");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "lucent view failed ({}):\nstdout:\n{stdout}\nstderr:\n{stderr}",
        output.status
    );
    Some(stdout)
}

/// Checks that the object shows in both screenshots' 3D view and that the view changed between
/// them; returns the changed fraction of the view.
fn check_object_and_change(dir: &Path, stdout: &str, first: &str, second: &str) -> f64 {
    let before = load(&dir.join(first));
    let after = load(&dir.join(second));
    assert_eq!(before.dimensions(), after.dimensions());
    let [x, y, w, h] = viewport_of(stdout, second);
    assert_eq!([x, y, w, h], viewport_of(stdout, first));
    assert!(w > 100 && h > 100, "3D viewport too small: {w}x{h}");

    // The object is visible: the viewport's centre is not background, its corner is.
    let (cx, cy) = (x + w / 2, y + h / 2);
    for img in [&before, &after] {
        let centre_lit = (0..5)
            .flat_map(|dy| (0..5).map(move |dx| (cx - 2 + dx, cy - 2 + dy)))
            .filter(|&(px, py)| differs_from_background(img.get_pixel(px, py)))
            .count();
        assert!(centre_lit >= 20, "centre of the 3D view looks like background");
        assert!(!differs_from_background(img.get_pixel(x + w - 3, y + 3)));
    }

    let changed = (y..y + h)
        .flat_map(|py| (x..x + w).map(move |px| (px, py)))
        .filter(|&(px, py)| {
            let (a, b) = (before.get_pixel(px, py), after.get_pixel(px, py));
            a.0.iter().zip(b.0).any(|(p, q)| p.abs_diff(q) > 8)
        })
        .count();
    changed as f64 / (w * h) as f64
}

fn fresh_dir(name: &str, files: &[&str]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    for f in files {
        let _ = std::fs::remove_file(dir.join(f));
    }
    dir
}

#[test]
fn scripted_dent_and_light_move_change_the_image() {
    let dir = fresh_dir("viewer_xvfb", &["before.png", "after.png"]);
    let Some(stdout) = run_viewer(&dir, "shot:before.png;dent:0.1,0.15,0.5;light:0,1,-2", "after.png") else {
        return;
    };
    // The dent and the light move changed the 3D view.
    let fraction = check_object_and_change(&dir, &stdout, "before.png", "after.png");
    assert!(fraction > 0.01, "only {:.3}% of the 3D view changed", 100.0 * fraction);
}

/// The panel's method switch: the same bunny drawn by HTSM (Shopf 2007) with its default vein
/// volume instead of the Mertens solve.
#[test]
fn switching_to_htsm_draws_the_object_differently() {
    let dir = fresh_dir("viewer_xvfb_htsm", &["mertens.png", "htsm.png"]);
    let Some(stdout) = run_viewer(&dir, "light:0.2,0.6,-1.5;shot:mertens.png;method:htsm", "htsm.png") else {
        return;
    };
    let fraction = check_object_and_change(&dir, &stdout, "mertens.png", "htsm.png");
    assert!(fraction > 0.05, "only {:.3}% of the 3D view changed", 100.0 * fraction);
}

/// HTSM's medium follows a later preset (issue 55): after `material:ketchup` the HTSM view
/// shows the red sauce instead of skim milk's near white (its diffusion tables made on their
/// own thread; the script waits for them).
#[test]
fn htsm_follows_the_material_preset() {
    let dir = fresh_dir("viewer_xvfb_htsm_preset", &["skim.png", "ketchup.png"]);
    let script = "light:0.2,0.6,-1.5;method:htsm;shot:skim.png;material:ketchup";
    let Some(stdout) = run_viewer(&dir, script, "ketchup.png") else {
        return;
    };
    let fraction = check_object_and_change(&dir, &stdout, "skim.png", "ketchup.png");
    assert!(fraction > 0.05, "only {:.3}% of the HTSM view changed", 100.0 * fraction);
    // Redder: the view's mean red over green grows.
    let [x, y, w, h] = viewport_of(&stdout, "ketchup.png");
    let red_over_green = |file: &str| {
        let img = load(&dir.join(file));
        let (mut r, mut g) = (0u64, 0u64);
        for py in y..y + h {
            for px in x..x + w {
                let p = img.get_pixel(px, py).0;
                r += p[0] as u64;
                g += p[1] as u64;
            }
        }
        r as f64 / g as f64
    };
    let (skim, ketchup) = (red_over_green("skim.png"), red_over_green("ketchup.png"));
    assert!(ketchup > 1.2 * skim, "red/green {skim:.3} (skim milk) -> {ketchup:.3} (ketchup)");
}

/// The panel's "save material" as the script's `save:`: the scene file it writes reads back
/// (as `lucent render --scene` reads it) to the material the viewer had.
#[test]
fn saved_material_reads_back_as_a_scene() {
    let dir = fresh_dir("viewer_xvfb_save", &["saved.toml", "last.png"]);
    if run_viewer(&dir, "albedo:0.7,0.5,0.3,2,1,0.5;scale:0.08;save:saved.toml", "last.png").is_none() {
        return;
    }
    let overrides = lucent::scene::Overrides { scene: Some(dir.join("saved.toml")), ..Default::default() };
    let scene = lucent::scene::Scene::resolve(&overrides).unwrap();
    let albedo = [0.7f32, 0.5, 0.3].map(f64::from);
    let want =
        lucent_core::bssrdf::Material::from_albedo_mfp("colour", albedo, [2.0, 1.0, 0.5], 1.3).unwrap();
    assert_eq!(scene.material(), &want);
    assert_eq!(scene.scale(), 0.08);
    // The splits and bounces the viewer had are written too (the default bunny is not split).
    let text = std::fs::read_to_string(dir.join("saved.toml")).unwrap();
    assert!(text.contains("refine = 0") && text.contains("bounces = 3"), "{text}");
    assert_eq!((scene.refine_levels, scene.settings.bounces), (0, 3));
}

/// A textured glTF (Khronos' BoxTextured, in `assets/`) is drawn with its texture: the Cesium
/// logo's blue and green show in the 3D view, which the untextured skim milk (near white) and
/// the background (grey) do not have.
#[test]
fn viewer_draws_a_glb_texture() {
    let dir = fresh_dir("viewer_xvfb_texture", &["box.png"]);
    let mesh = format!("{}/../../assets/BoxTextured/BoxTextured.gltf", env!("CARGO_MANIFEST_DIR"));
    let Some(stdout) = run_viewer_with(&dir, &["--mesh", &mesh], "camera:25,20,2.6", "box.png") else {
        return;
    };
    let img = load(&dir.join("box.png"));
    let [x, y, w, h] = viewport_of(&stdout, "box.png");
    let pixels = || (y..y + h).flat_map(|py| (x..x + w).map(move |px| (px, py)));
    let count = |f: &dyn Fn([i32; 3]) -> bool| {
        pixels().filter(|&(px, py)| f(img.get_pixel(px, py).0.map(i32::from))).count() as f64 / (w * h) as f64
    };
    // Lit, the logo's blue is about (67, 82, 89) and its green (46, 58, 32); the untextured
    // bunny in docs/viewer.png has no pixel of either kind.
    let blue = count(&|[r, g, b]| b > r + 15 && b > g);
    let green = count(&|[r, g, b]| g > b + 15 && g > r + 8);
    assert!(blue > 0.01 && green > 0.01, "blue {blue:.4}, green {green:.4} of the 3D view");
}
