//! `lucent render` end to end: the default scene renders to a PNG of the requested size with
//! the object in it; bad input gives exit code 1, a one-line message naming the culprit, and no
//! output file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lucent(args: &[&str], envs: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lucent"));
    cmd.args(args);
    for (k, v) in envs {
        cmd.env(k, v);
    }
    cmd.output().expect("run lucent")
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_render").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// stderr without the lines Mesa's drivers print on headless machines.
fn stderr_lines(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| !l.contains("XDG_RUNTIME_DIR"))
        .map(str::to_string)
        .collect()
}

/// Checks a failed run: exit 1, exactly one `lucent: error:` line containing `needle`, no
/// panic, no file at `output_file` and no temporary file beside it.
fn assert_clean_failure(out: &Output, needle: &str, output_file: &Path) {
    let lines = stderr_lines(out);
    assert_eq!(out.status.code(), Some(1), "stderr: {lines:?}");
    let errors: Vec<_> = lines.iter().filter(|l| l.starts_with("lucent: error:")).collect();
    assert_eq!(errors.len(), 1, "want one error line, got {lines:?}");
    assert!(errors[0].contains(needle), "error line {:?} should name {needle:?}", errors[0]);
    assert!(!lines.iter().any(|l| l.contains("panicked")), "{lines:?}");
    assert!(!output_file.exists(), "{} must not be created on error", output_file.display());
    if let Ok(entries) = std::fs::read_dir(output_file.parent().unwrap()) {
        let leftovers: Vec<_> = entries
            .map(|e| e.unwrap().file_name())
            .filter(|n| n.to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty(), "temporary files left behind: {leftovers:?}");
    }
}

fn luminance(p: &image::Rgba<u8>) -> f32 {
    0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32
}

#[test]
fn default_scene_renders_an_object_of_the_requested_size() {
    let dir = scratch("default");
    let out = dir.join("default.png");
    let run = lucent(&["render", "--width", "160", "--height", "120", "--out", out.to_str().unwrap()], &[]);
    assert!(run.status.success(), "stderr: {:?}", stderr_lines(&run));
    let summary = String::from_utf8_lossy(&run.stdout);
    assert!(summary.contains("default.png"), "summary should name the output: {summary}");
    let img = image::open(&out).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (160, 120));
    // The corners show the background: exactly the tone mapper's background colour.
    let bg = lucent_gpu::tonemap::ToneMap::default().background.map(|c| (c * 255.0).round() as u8);
    for (x, y) in [(0, 0), (159, 0), (0, 119), (159, 119)] {
        assert_eq!(img.get_pixel(x, y).0[..3], bg, "corner ({x}, {y})");
    }
    // The centre third holds the object: many pixels clearly brighter than the background.
    let bg_lum = luminance(&image::Rgba([bg[0], bg[1], bg[2], 255]));
    let brighter = (53..107)
        .flat_map(|x| (40..80).map(move |y| (x, y)))
        .filter(|&(x, y)| luminance(img.get_pixel(x, y)) > bg_lum + 10.0)
        .count();
    assert!(brighter > 100, "only {brighter} centre pixels brighter than the background");
}

#[test]
fn missing_mesh_file_is_one_clean_error() {
    let dir = scratch("missing");
    let out = dir.join("never.png");
    let mesh = dir.join("no-such-mesh.obj");
    let run = lucent(&["render", "--mesh", mesh.to_str().unwrap(), "--out", out.to_str().unwrap()], &[]);
    assert_clean_failure(&run, "no-such-mesh.obj", &out);
}

#[test]
fn corrupt_mesh_file_is_one_clean_error() {
    let dir = scratch("corrupt");
    let out = dir.join("never.png");
    let mesh = dir.join("corrupt.obj");
    std::fs::write(&mesh, b"v 0 0 0\nv 1 0\xff\xfe\nf 1 2 99\n").unwrap();
    let run = lucent(&["render", "--mesh", mesh.to_str().unwrap(), "--out", out.to_str().unwrap()], &[]);
    assert_clean_failure(&run, "corrupt.obj", &out);
}

#[test]
fn bad_light_is_one_clean_error() {
    let dir = scratch("light");
    let out = dir.join("never.png");
    let run = lucent(&["render", "--light", "spot:1,2,3", "--out", out.to_str().unwrap()], &[]);
    assert_clean_failure(&run, "spot:1,2,3", &out);
}

#[test]
fn missing_output_directory_is_one_clean_error() {
    let dir = scratch("outdir");
    let out = dir.join("no-such-dir").join("x.png");
    let run = lucent(&["render", "--out", out.to_str().unwrap()], &[]);
    assert_clean_failure(&run, "no-such-dir", &out);
}

#[test]
fn unusable_backend_says_what_to_install() {
    let dir = scratch("backend");
    let out = dir.join("never.png");
    // No valid backend name: nothing to search.
    let run = lucent(&["render", "--out", out.to_str().unwrap()], &[("WGPU_BACKEND", "none")]);
    assert_clean_failure(&run, "WGPU_BACKEND", &out);
    // A backend that exists, but not on this platform (Metal off macOS, DX12 on macOS).
    let absent = if cfg!(target_os = "macos") { "dx12" } else { "metal" };
    let run = lucent(&["render", "--out", out.to_str().unwrap()], &[("WGPU_BACKEND", absent)]);
    assert_clean_failure(&run, "mesa-vulkan-drivers", &out);
}
