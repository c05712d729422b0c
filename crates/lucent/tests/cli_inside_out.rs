//! `lucent render` on a closed mesh wound inside out (issue 50, item 4): the loader flips it,
//! prints one `lucent: warning:` line naming the file, and the image is the right mesh's.
//! (`lucent view` resolves its scene through the same loader, `scene::load_textured_mesh_file`.)

mod common;

use lucent_core::mesh::{Mesh, embedded};
use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    common::scratch("cli_inside_out", name)
}

/// OFF keeps the vertex order as written, so the flipped mesh is the right one face for face.
fn write_off(path: &Path, m: &Mesh, inside_out: bool) {
    let mut s = format!("OFF\n{} {} 0\n", m.positions.len(), m.triangles.len());
    for p in &m.positions {
        s += &format!("{} {} {}\n", p.x, p.y, p.z);
    }
    for t in &m.triangles {
        let [a, b, c] = if inside_out { [t[0], t[2], t[1]] } else { *t };
        s += &format!("3 {a} {b} {c}\n");
    }
    std::fs::write(path, s).unwrap();
}

/// Renders `mesh` to a PNG; returns the image and the stderr lines.
fn render(mesh: &Path, out: &Path) -> (image::RgbaImage, Vec<String>) {
    let run = Command::new(env!("CARGO_BIN_EXE_lucent"))
        .args(["render", "--mesh"])
        .arg(mesh)
        .args(["--material", "skimmilk", "--scale", "0.05", "--width", "96", "--height", "72", "--out"])
        .arg(out)
        .output()
        .expect("run lucent");
    let lines: Vec<String> = String::from_utf8_lossy(&run.stderr).lines().map(str::to_string).collect();
    assert!(run.status.success(), "stderr: {lines:?}");
    (image::open(out).unwrap().to_rgba8(), lines)
}

#[test]
fn inside_out_bunny_renders_as_the_right_one_with_one_warning() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("bunny");
    let bunny = embedded::bunny();
    let (right, wrong) = (dir.join("right.off"), dir.join("inside_out.off"));
    write_off(&right, &bunny, false);
    write_off(&wrong, &bunny, true);
    let (want, right_lines) = render(&right, &dir.join("right.png"));
    let (got, wrong_lines) = render(&wrong, &dir.join("inside_out.png"));
    let flips =
        |lines: &[String]| lines.iter().filter(|l| l.contains("inside out")).cloned().collect::<Vec<_>>();
    assert!(flips(&right_lines).is_empty(), "{right_lines:?}");
    let warned = flips(&wrong_lines);
    assert_eq!(warned.len(), 1, "one warning line: {wrong_lines:?}");
    assert!(warned[0].starts_with("lucent: warning:"), "{}", warned[0]);
    assert!(warned[0].contains("inside_out.off"), "the line names the file: {}", warned[0]);
    // The same mesh after the flip: the same image, to the rounding of 8-bit output.
    let worst =
        want.pixels().zip(got.pixels()).flat_map(|(a, b)| (0..4).map(move |k| a[k].abs_diff(b[k]))).max();
    assert!(worst <= Some(1), "largest channel difference {worst:?}");
    // And the object is there (not the near-black render an inside-out mesh gave).
    let lit = got.pixels().filter(|p| p[0] as u32 + p[1] as u32 + p[2] as u32 > 150).count();
    assert!(lit > 200, "only {lit} bright pixels");
}
