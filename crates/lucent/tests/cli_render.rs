//! `lucent render` end to end: the default scene, the example scene files and animations render
//! to PNGs of the requested size with the object in it; bad input gives exit code 1, a one-line
//! message naming the culprit, and no output file or directory.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{lucent_env as lucent, stderr_lines};

fn scratch(name: &str) -> PathBuf {
    common::scratch("cli_render", name)
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
    if !common::gpu_or_skip() {
        return;
    }
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

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes")
}

/// Mean luminance of the pixels that differ from the background.
fn object_luminance(img: &image::RgbaImage) -> f32 {
    let bg = lucent_gpu::tonemap::ToneMap::default().background.map(|c| (c * 255.0).round() as u8);
    let lums: Vec<f32> = img.pixels().filter(|p| p.0[..3] != bg).map(luminance).collect();
    assert!(lums.len() > 100, "the object covers only {} pixels", lums.len());
    lums.iter().sum::<f32>() / lums.len() as f32
}

#[test]
fn example_scenes_render() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("scenes");
    for name in ["candle", "bunny_courtyard", "bunny_spot"] {
        let out = dir.join(format!("{name}.png"));
        let scene = examples().join(format!("{name}.toml"));
        let (s, o) = (scene.to_str().unwrap(), out.to_str().unwrap());
        let run = lucent(&["render", "--scene", s, "--width", "96", "--height", "72", "--out", o], &[]);
        assert!(run.status.success(), "{name}: {:?}", stderr_lines(&run));
        let img = image::open(&out).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (96, 72));
        assert!(object_luminance(&img) > 20.0, "{name}: the object is lit");
    }
}

/// A flag given on the command line wins over the scene file: a quarter of the exposure gives a
/// darker image of the same scene.
#[test]
fn flags_override_the_scene() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("override");
    let scene = examples().join("candle.toml");
    let mut lum = Vec::new();
    for exposure in [None, Some("0.25")] {
        let out = dir.join(format!("c{}.png", lum.len()));
        let mut a = vec!["render", "--scene", scene.to_str().unwrap(), "--width", "64", "--height", "64"];
        a.extend(["--out", out.to_str().unwrap()]);
        if let Some(e) = exposure {
            a.extend(["--exposure", e]);
        }
        let run = lucent(&a, &[]);
        assert!(run.status.success(), "{:?}", stderr_lines(&run));
        lum.push(object_luminance(&image::open(&out).unwrap().to_rgba8()));
    }
    assert!(lum[1] < 0.8 * lum[0], "--exposure 0.25 should darken the scene's image: {lum:?}");
}

#[test]
fn missing_scene_file_is_one_clean_error() {
    let dir = scratch("scene_missing");
    let out = dir.join("never.png");
    let scene = dir.join("no-such-scene.toml");
    let run = lucent(&["render", "--scene", scene.to_str().unwrap(), "--out", out.to_str().unwrap()], &[]);
    assert_clean_failure(&run, "no-such-scene.toml", &out);
}

#[test]
fn bad_scene_field_is_one_clean_error_naming_file_and_field() {
    let dir = scratch("scene_bad");
    let out = dir.join("never.png");
    let scene = dir.join("bad.toml");
    std::fs::write(
        &scene,
        "mesh = \"sphere\"\n[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\nbrightness = 3\n",
    )
    .unwrap();
    let run = lucent(&["render", "--scene", scene.to_str().unwrap(), "--out", out.to_str().unwrap()], &[]);
    assert_clean_failure(&run, "bad.toml", &out);
    assert!(stderr_lines(&run).iter().any(|l| l.contains("brightness")), "{:?}", stderr_lines(&run));
    // A missing environment map named inside the file: both names in the one line.
    std::fs::write(&scene, "mesh = \"sphere\"\n[environment]\npath = \"gone.exr\"\n").unwrap();
    let run = lucent(&["render", "--scene", scene.to_str().unwrap(), "--out", out.to_str().unwrap()], &[]);
    assert_clean_failure(&run, "gone.exr", &out);
    assert!(stderr_lines(&run).iter().any(|l| l.contains("bad.toml")), "{:?}", stderr_lines(&run));
}

/// An animation: numbered frames for video tools, nothing else in the directory, timings on
/// stdout, and the deformation visible as frames that differ.
#[test]
fn frames_write_a_numbered_sequence() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("frames");
    let out = dir.join("anim");
    let run = lucent(
        &[
            "render",
            "--frames",
            "3",
            "--deform",
            "twist:90",
            "--width",
            "64",
            "--height",
            "48",
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
    );
    assert!(run.status.success(), "{:?}", stderr_lines(&run));
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("median"), "timings should be printed: {stdout}");
    let mut names: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into()).collect();
    names.sort();
    assert_eq!(names, ["frame_0001.png", "frame_0002.png", "frame_0003.png"]);
    let first = image::open(out.join("frame_0001.png")).unwrap().to_rgba8();
    let last = image::open(out.join("frame_0003.png")).unwrap().to_rgba8();
    assert_eq!(first.dimensions(), (64, 48));
    assert_ne!(first, last, "the twist ramps from the rest pose to full");
}

#[test]
fn orbit_light_frames_differ() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("orbit");
    let out = dir.join("orbit");
    let o = out.to_str().unwrap();
    let run = lucent(
        &["render", "--frames", "2", "--orbit-light", "--width", "48", "--height", "48", "--out", o],
        &[],
    );
    assert!(run.status.success(), "{:?}", stderr_lines(&run));
    let a = image::open(out.join("frame_0001.png")).unwrap().to_rgba8();
    let b = image::open(out.join("frame_0002.png")).unwrap().to_rgba8();
    assert_ne!(a, b, "the light moved half a turn");
}

#[test]
fn bad_animations_are_clean_errors_without_output() {
    let dir = scratch("frames_bad");
    // --out is a file.
    let file = dir.join("taken.png");
    std::fs::write(&file, b"x").unwrap();
    let run =
        lucent(&["render", "--frames", "2", "--deform", "twist:10", "--out", file.to_str().unwrap()], &[]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr_lines(&run).iter().any(|l| l.starts_with("lucent: error:") && l.contains("taken.png")));
    // Nothing to animate; a bad deformation: no directory is created (zero frames is a usage
    // error, tests/cli_hostile.rs).
    let out = dir.join("never");
    for extra in [&["--frames", "2"][..], &["--frames", "2", "--deform", "twist"]] {
        let mut a = vec!["render", "--out", out.to_str().unwrap()];
        a.extend_from_slice(extra);
        let run = lucent(&a, &[]);
        assert_eq!(run.status.code(), Some(1), "{extra:?}");
        let errors: Vec<_> =
            stderr_lines(&run).into_iter().filter(|l| l.starts_with("lucent: error:")).collect();
        assert_eq!(errors.len(), 1, "{extra:?}: {errors:?}");
        assert!(!out.exists(), "{extra:?}: no output directory on error");
    }
}

/// `--env courtyard` lights the object by itself (no default light is added) and colours it after
/// the map (warmer than it is blue), and draws the map behind it unless --no-env-background; a
/// missing map is a clean error naming it.
#[test]
fn environment_flag_lights_the_object() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("env");
    let out = dir.join("env.png");
    let o = out.to_str().unwrap();
    let size = ["--width", "64", "--height", "64"];
    let run = lucent(
        &[&["render", "--env", "courtyard", "--no-env-background", "--out", o][..], &size].concat(),
        &[],
    );
    assert!(run.status.success(), "{:?}", stderr_lines(&run));
    let img = image::open(&out).unwrap().to_rgba8();
    assert!(object_luminance(&img) > 60.0, "the environment lights the bunny");
    let centre = img.get_pixel(32, 36);
    assert!(centre[0] > centre[2], "the courtyard's light is warm: {centre:?}");
    let bg = lucent_gpu::tonemap::ToneMap::default().background.map(|c| (c * 255.0).round() as u8);
    assert_eq!(img.get_pixel(0, 0).0[..3], bg, "flat background");

    let run = lucent(&[&["render", "--env", "courtyard", "--out", o][..], &size].concat(), &[]);
    assert!(run.status.success(), "{:?}", stderr_lines(&run));
    let img = image::open(&out).unwrap().to_rgba8();
    let corners = [(0, 0), (63, 0), (0, 63), (63, 63)];
    assert!(corners.iter().all(|&(x, y)| img.get_pixel(x, y).0[..3] != bg), "the map is drawn behind");

    let never = dir.join("never.png");
    let run = lucent(&["render", "--env", "no-such-map.exr", "--out", never.to_str().unwrap()], &[]);
    assert_clean_failure(&run, "no-such-map.exr", &never);
}

#[test]
fn shrink_wrap_hierarchy_renders_the_wrapped_mesh() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("shrink_wrap");
    let out = dir.join("wrapped.png");
    let run = lucent(
        &[
            "render",
            "--hierarchy",
            "shrink-wrap:3",
            "--width",
            "160",
            "--height",
            "120",
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
    );
    assert!(run.status.success(), "stderr: {:?}", stderr_lines(&run));
    let summary = String::from_utf8_lossy(&run.stdout);
    // 20 x 4^3 triangles are solved and rendered, and the note says how far they are from the input.
    assert!(summary.contains("to 1280 triangles"), "{summary}");
    assert!(summary.contains("max distance to the input"), "{summary}");
    assert!(summary.contains(": 1280 triangles"), "{summary}");
    let img = image::open(&out).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (160, 120));
    assert!(object_luminance(&img) > 0.0);

    // A bad value is a usage error (clap, exit 2) naming the expected forms.
    for bad in ["shrink-wrap:x", "shrink-wrap:12", "octree"] {
        let run = lucent(&["render", "--hierarchy", bad, "--out", out.to_str().unwrap()], &[]);
        assert_eq!(run.status.code(), Some(2), "{bad}");
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains("--hierarchy") && err.contains(bad), "{bad}: {err}");
    }

    // An open mesh cannot be wrapped: one clean error, no image.
    let open = dir.join("open.obj");
    std::fs::write(&open, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n").unwrap();
    let never = dir.join("never.png");
    let run = lucent(
        &[
            "render",
            "--mesh",
            open.to_str().unwrap(),
            "--hierarchy",
            "shrink-wrap:2",
            "--out",
            never.to_str().unwrap(),
        ],
        &[],
    );
    assert_clean_failure(&run, "not closed", &never);
}

#[test]
fn oracle_flag_trades_links_for_accuracy() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("oracle");
    let links_of = |oracle: &str| {
        let out = dir.join(format!("{}.png", oracle.replace([':', ','], "_")));
        let run = lucent(
            &[
                "render",
                "--oracle",
                oracle,
                "--width",
                "96",
                "--height",
                "72",
                "--out",
                out.to_str().unwrap(),
            ],
            &[],
        );
        assert!(run.status.success(), "{oracle}: {:?}", stderr_lines(&run));
        assert!(object_luminance(&image::open(&out).unwrap().to_rgba8()) > 0.0, "{oracle}");
        let summary = String::from_utf8_lossy(&run.stdout).to_string();
        let (before, _) = summary.split_once(" links)").unwrap_or_else(|| panic!("{summary}"));
        before.rsplit('(').next().unwrap().parse::<usize>().unwrap()
    };
    let default = links_of("transport");
    let coarse = links_of("transport:0.6,0.3,1e-3");
    let paper = links_of("solid-angle:0.2,0.8");
    assert!(coarse < default && paper < default, "{default} {coarse} {paper}");

    // A bad value is a usage error (clap, exit 2) naming the flag and the value.
    let never = dir.join("never.png");
    let run = lucent(&["render", "--oracle", "solid-angle:0.1", "--out", never.to_str().unwrap()], &[]);
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("--oracle") && err.contains("solid-angle:0.1"), "{err}");
    assert!(!never.exists());
}

/// `--bounces 1` adds the light facing parts send each other (the bunny has crevices), so the
/// object gets brighter and never darker; out of range is a usage error (exit 2).
#[test]
fn bounces_add_light_between_parts() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("bounces");
    let render = |bounces: &str| {
        let out = dir.join(format!("b{bounces}.png"));
        let run = lucent(
            &[
                "render",
                "--material",
                "marble",
                "--scale",
                "0.1",
                "--bounces",
                bounces,
                "--out",
                out.to_str().unwrap(),
            ],
            &[],
        );
        assert!(run.status.success(), "{:?}", stderr_lines(&run));
        image::open(&out).unwrap().to_rgba8()
    };
    let (none, one) = (render("0"), render("1"));
    let brighter = none.pixels().zip(one.pixels()).filter(|(a, b)| luminance(b) > luminance(a) + 0.5).count();
    // Darker by more than one 8-bit step of any channel (green's is 0.72 in luminance): the
    // solve's own error (far below 1%) can tip a channel across a rounding boundary.
    let darker = none.pixels().zip(one.pixels()).filter(|(a, b)| luminance(b) + 1.0 < luminance(a)).count();
    assert!(brighter > 500 && darker == 0, "brighter {brighter}, darker {darker}");
    assert!(object_luminance(&one) > object_luminance(&none));
    let never = dir.join("never.png");
    let run = lucent(&["render", "--bounces", "9", "--out", never.to_str().unwrap()], &[]);
    assert_eq!(run.status.code(), Some(2), "{:?}", stderr_lines(&run));
    assert!(!never.exists());
}

/// HTSM through the same frame session: `--frames` ramps the deformation (the density follows
/// the mesh), and an environment alone lights the object with no light at all.
#[test]
fn htsm_animates_and_takes_the_environment() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("htsm_frames");
    let out = dir.join("anim");
    let small = ["--width", "64", "--height", "48", "--htsm-size", "64"];
    let mut args = vec!["render", "--method", "htsm", "--frames", "2", "--deform", "twist:90"];
    args.extend(small);
    args.extend(["--out", out.to_str().unwrap()]);
    let run = lucent(&args, &[]);
    assert!(run.status.success(), "{:?}", stderr_lines(&run));
    let first = image::open(out.join("frame_0001.png")).unwrap().to_rgba8();
    let last = image::open(out.join("frame_0002.png")).unwrap().to_rgba8();
    assert_ne!(first, last, "the twist ramps from the rest pose to full");

    let env = dir.join("env.png");
    let mut args = vec!["render", "--method", "htsm", "--env", "forest"];
    args.extend(small);
    args.extend(["--out", env.to_str().unwrap()]);
    let run = lucent(&args, &[]);
    assert!(run.status.success(), "{:?}", stderr_lines(&run));
    let img = image::open(&env).unwrap().to_rgb8();
    // The object (centre pixels) is lit by the environment alone.
    let centre = img.get_pixel(32, 24).0;
    assert!(centre.iter().map(|&c| c as u32).sum::<u32>() > 60, "centre {centre:?}");
}
