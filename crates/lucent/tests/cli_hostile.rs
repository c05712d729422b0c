//! Hostile input through the command line (issue "Hostile input"): every refusal is one line
//! naming the value or file, with a non-zero exit, no panic text and no output file; what lucent
//! repairs is one warning line with a count; nothing outside a model's or scene's folder is read.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{lucent, stderr_lines as lines};

fn scratch(name: &str) -> PathBuf {
    common::scratch("cli_hostile", name)
}

/// Exit `code`, exactly one stderr line, containing every needle, no panic, and no `out` file.
fn refused(out: &Output, code: i32, needles: &[&str], not_written: &Path) {
    let l = lines(out);
    assert_eq!(out.status.code(), Some(code), "{l:?}");
    assert_eq!(l.len(), 1, "want one line, got {l:?}");
    for n in needles {
        assert!(l[0].contains(n), "{:?} should contain {n:?}", l[0]);
    }
    assert!(!l[0].contains("panicked"));
    assert!(!not_written.exists(), "{} written on error", not_written.display());
}

#[test]
fn numbers_out_of_range_are_one_line_usage_errors() {
    let dir = scratch("ranges");
    let out = dir.join("x.png");
    let o = out.to_str().unwrap();
    for (flag, value) in [
        ("--scale", "-1"),
        ("--scale", "1e6"),
        ("--width", "0"),
        ("--frames", "0"),
        ("--pitch", "100"),
        ("--exposure", "nan"),
        ("--phase-g", "1"),
    ] {
        let run = lucent(&["render", flag, value, "--out", o]);
        refused(&run, 2, &[flag, value], &out);
    }
    // Values that parse but are absurd: refused with the range, not run for minutes.
    let run = lucent(&["render", "--deform", "noise:1e30,1e30", "--out", o]);
    refused(&run, 1, &["noise amplitude", "outside"], &out);
    let run = lucent(&["render", "--deform", "twist:1e6", "--out", o]);
    refused(&run, 1, &["twist angle", "-1080..=1080"], &out);
    let run = lucent(&["render", "--light", "point:1e30,0,0", "--out", o]);
    refused(&run, 1, &["--light", "within"], &out);
}

#[test]
fn scene_errors_are_one_line_with_line_and_column() {
    let dir = scratch("toml");
    let out = dir.join("x.png");
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, "mesh = \"bunny\"\nscale = [1\n").unwrap();
    let run = lucent(&["render", "--scene", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    refused(&run, 1, &["bad.toml", "line 2, column"], &out);
    std::fs::write(&scene, "material = { sigma_s_prime = [1, 1, 1], sigma_a = [1e300, 1, 1] }\n").unwrap();
    let run = lucent(&["render", "--scene", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    refused(&run, 1, &["sigma_a", "10000"], &out);
}

#[test]
fn files_outside_the_model_or_scene_folder_are_never_read() {
    let dir = scratch("escape");
    let out = dir.join("x.png");
    let o = out.to_str().unwrap();
    for uri in ["/etc/passwd", "../../../etc/passwd", "/dev/zero", "file:///etc/passwd"] {
        let gltf = dir.join("m.gltf");
        std::fs::write(
            &gltf,
            format!(
                r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":"{uri}","byteLength":36}}],"bufferViews":[{{"buffer":0,"byteLength":36}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}]}}"#
            ),
        )
        .unwrap();
        let run = lucent(&["render", "--mesh", gltf.to_str().unwrap(), "--out", o]);
        refused(&run, 1, &["m.gltf", uri, "not a relative path inside"], &out);
    }
    let scene = dir.join("s.toml");
    std::fs::write(&scene, "mesh = \"../../../../etc/passwd.obj\"\n").unwrap();
    let run = lucent(&["render", "--scene", scene.to_str().unwrap(), "--out", o]);
    refused(&run, 1, &["s.toml", "not a relative path inside"], &out);
}

#[test]
#[cfg(unix)]
fn devices_are_not_read() {
    let dir = scratch("devices");
    let out = dir.join("x.png");
    let link = dir.join("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    let run = lucent(&["render", "--mesh", link.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    refused(&run, 1, &["zero.obj", "not a regular file"], &out);
    let link = dir.join("zero.exr");
    std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
    let run = lucent(&["render", "--env", link.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    refused(&run, 1, &["zero.exr", "not a regular file"], &out);
}

/// The EXR whose header made lucent ask for 333 GB and abort: one line, at once.
#[test]
fn corrupt_exr_header_is_refused_before_allocating() {
    let dir = scratch("exr");
    let out = dir.join("x.png");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../lucent-fuzz/regressions/exr/huge-data-window");
    let env = dir.join("bad.exr");
    std::fs::copy(src, &env).unwrap();
    let run = lucent(&["render", "--env", env.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    refused(&run, 1, &["bad.exr"], &out);
}

#[test]
fn repairs_are_one_warning_line_each_with_a_count() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("repairs");
    let out = dir.join("x.png");
    // A tetrahedron with one degenerate face (a repeated vertex), cut mid-line at the end.
    let obj = dir.join("cut.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\nf 1 1 2")
        .unwrap();
    let run = lucent(&[
        "render",
        "--mesh",
        obj.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        out.to_str().unwrap(),
    ]);
    let l = lines(&run);
    assert!(run.status.success(), "{l:?}");
    let warnings: Vec<_> = l.iter().filter(|l| l.starts_with("lucent: warning: ")).collect();
    assert!(warnings.iter().any(|w| w.contains("cut.obj") && w.contains("cut short")), "{l:?}");
    assert!(warnings.iter().any(|w| w.contains("removed 1 degenerate faces")), "{l:?}");
    assert!(out.exists());
}

/// Colour-and-distance materials: one flag without the other is a usage error; values outside
/// their ranges are one line naming the value and the range; a scene's `{ albedo, mfp }` renders.
#[test]
fn albedo_and_mfp_materials() {
    let dir = scratch("albedo");
    let out = dir.join("x.png");
    let o = out.to_str().unwrap();
    refused(&lucent(&["render", "--albedo", "0.8,0.6,0.4", "--out", o]), 2, &["--mfp"], &out);
    refused(
        &lucent(&["render", "--albedo", "0.8,0.6", "--mfp", "1,1,1", "--out", o]),
        2,
        &["--albedo", "R,G,B"],
        &out,
    );
    refused(&lucent(&["render", "--mfp", "1,1,1", "--out", o]), 2, &["--albedo"], &out);
    // Out of range: a usage error (exit 2) naming the value and the accepted range.
    for (albedo, mfp, needles) in [
        ("1.2,0.6,0.4", "1,1,1", ["--albedo 1.2", "0.001..=0.999"]),
        ("0.8,0,0.4", "1,1,1", ["--albedo 0 ", "0.001..=0.999"]),
        ("0.8,0.6,0.4", "1,0,1", ["--mfp 0 ", "0.0001..=1000"]),
        ("0.8,0.6,0.4", "1,1,1e12", ["--mfp 1000000000000", "0.0001..=1000"]),
        ("0.8,0.6,0.4", "1,inf,1", ["--mfp", "finite"]),
    ] {
        let run = lucent(&["render", "--albedo", albedo, "--mfp", mfp, "--out", o]);
        refused(&run, 2, &needles, &out);
    }
    let scene = dir.join("a.toml");
    std::fs::write(&scene, "material = { albedo = [0.8, 0.6, 0.4] }\n").unwrap();
    let run = lucent(&["render", "--scene", scene.to_str().unwrap(), "--out", o]);
    refused(&run, 1, &["a.toml", "albedo and mfp"], &out);
    std::fs::write(&scene, "material = { albedo = [0.8, 1.5, 0.4], mfp = [1, 1, 1] }\n").unwrap();
    let run = lucent(&["render", "--scene", scene.to_str().unwrap(), "--out", o]);
    refused(&run, 1, &["a.toml", "albedo 1.5 is outside the accepted range 0.001..=0.999"], &out);
    // The rest renders, which needs an adapter.
    if !common::gpu_or_skip() {
        return;
    }
    std::fs::write(&scene, "material = { albedo = [0.8, 0.6, 0.4], mfp = [1.0, 0.5, 0.25] }\n").unwrap();
    let run = lucent(&[
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        o,
    ]);
    assert!(run.status.success(), "{:?}", lines(&run));
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("material: albedo 0.800,0.600,0.400 mfp 1,0.5,0.25 mm -> sigma_s'"), "{stdout}");
    std::fs::remove_file(&out).unwrap();
    // The flags print what they chose.
    let run = lucent(&[
        "render",
        "--albedo",
        "0.8,0.6,0.4",
        "--mfp",
        "1,0.5,0.25",
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        o,
    ]);
    assert!(run.status.success(), "{:?}", lines(&run));
    let stdout = String::from_utf8_lossy(&run.stdout);
    let said: Vec<&str> = stdout.lines().filter(|l| l.contains("material: albedo")).collect();
    assert_eq!(said.len(), 1, "{stdout}");
    assert!(
        said[0].contains("mfp 1,0.5,0.25 mm -> sigma_s' ") && said[0].contains(" sigma_a "),
        "{}",
        said[0]
    );
}
