//! `lucent render` of textured meshes (issue 18): a checker texture shows its colours, a white
//! texture changes nothing, and a missing or corrupt texture is one error line naming the file.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::lucent;

fn scratch(name: &str) -> PathBuf {
    common::scratch("cli_texture", name)
}

fn png(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
    let img = image::RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).unwrap();
    bytes
}

/// A cube, each face subdivided `n x n` and mapping the whole texture, written as `name.obj`
/// with a `name.mtl` naming `texture` (none when `None`).
fn write_cube(dir: &Path, name: &str, texture: Option<&str>, n: usize) -> PathBuf {
    let mut obj = String::new();
    if let Some(t) = texture {
        obj += &format!("mtllib {name}.mtl\nusemtl mat\n");
        std::fs::write(dir.join(format!("{name}.mtl")), format!("newmtl mat\nKd 1 1 1\nmap_Kd {t}\n"))
            .unwrap();
    }
    let (mut nv, mut nt) = (0, 0);
    // Each face: origin o, axes a and b (a x b points out).
    let faces: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
        ([-1.0, -1.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([1.0, -1.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([1.0, -1.0, 1.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
        ([-1.0, -1.0, -1.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([-1.0, 1.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]),
        ([-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ];
    for (o, a, b) in faces {
        for j in 0..=n {
            for i in 0..=n {
                let (s, t) = (i as f32 / n as f32, j as f32 / n as f32);
                let p: Vec<f32> = (0..3).map(|k| o[k] + 2.0 * (s * a[k] + t * b[k])).collect();
                obj += &format!("v {} {} {}\nvt {s} {t}\n", p[0], p[1], p[2]);
            }
        }
        for j in 0..n {
            for i in 0..n {
                let v = |i: usize, j: usize| nv + j * (n + 1) + i + 1;
                let (c0, c1, c2, c3) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
                obj += &format!("f {c0}/{c0} {c1}/{c1} {c2}/{c2} {c3}/{c3}\n");
                nt += 2;
            }
        }
        nv += (n + 1) * (n + 1);
    }
    assert_eq!(nt, 12 * n * n);
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, obj).unwrap();
    path
}

fn render(mesh: &Path, out: &Path) -> Output {
    let args =
        ["render", "--width", "160", "--height", "120", "--exposure", "2", "--mesh", mesh.to_str().unwrap()];
    lucent(&[&args[..], &["--out", out.to_str().unwrap()]].concat())
}

#[test]
fn checker_texture_shows_its_colours_and_white_changes_nothing() {
    if !common::gpu_or_skip() {
        return;
    }
    let dir = scratch("checker");
    std::fs::write(
        dir.join("checker.png"),
        png(4, 4, |x, y| if (x + y) % 2 == 0 { [255, 0, 0] } else { [0, 255, 0] }),
    )
    .unwrap();
    std::fs::write(dir.join("white.png"), png(1, 1, |_, _| [255, 255, 255])).unwrap();
    let mut images = Vec::new();
    for (name, texture) in [("plain", None), ("white", Some("white.png")), ("checker", Some("checker.png"))] {
        let out = dir.join(format!("{name}.png"));
        let run = render(&write_cube(&dir, name, texture, 8), &out);
        assert!(run.status.success(), "{name}: {}", String::from_utf8_lossy(&run.stderr));
        images.push(image::open(&out).unwrap().to_rgba8());
    }
    // sqrt(1) at entry and exit: a white texture leaves every byte as it was.
    assert!(images[0] == images[1], "a white texture changed the image");
    let count = |f: fn(i32, i32) -> bool| images[2].pixels().filter(|p| f(p[0] as i32, p[1] as i32)).count();
    // Red or green squares: one channel clearly above the other (tone mapping desaturates).
    let red = count(|r, g| r > g + 30);
    let green = count(|r, g| g > r + 30);
    assert!(red > 200 && green > 200, "red {red}, green {green} pixels");
    // Untextured skim milk is never green; it reddens a little where its light travelled far
    // (red's mean free path is 2.7 times blue's): on the top face, seen at grazing, once the
    // 6 mm faces are split for the solve (`--refine auto`), about 40 pixels, not squares.
    let plain = |f: fn(i32, i32) -> bool| images[0].pixels().filter(|p| f(p[0] as i32, p[1] as i32)).count();
    assert_eq!(plain(|r, g| g > r + 20), 0, "the untextured cube has green pixels");
    let plain_red = plain(|r, g| r > g + 20);
    assert!(plain_red * 5 < red, "the untextured cube has {plain_red} red pixels, the checker {red}");
}

#[test]
fn missing_or_corrupt_texture_is_one_error_line_naming_the_file() {
    let dir = scratch("bad");
    std::fs::write(dir.join("corrupt.png"), b"\x89PNG\r\n\x1a\nbroken").unwrap();
    for name in ["missing.png", "corrupt.png"] {
        let out = dir.join("never.png");
        let run = render(&write_cube(&dir, "cube", Some(name), 1), &out);
        let stderr = String::from_utf8_lossy(&run.stderr);
        let errors: Vec<_> = stderr.lines().filter(|l| l.starts_with("lucent: error:")).collect();
        assert_eq!(run.status.code(), Some(1), "{stderr}");
        assert_eq!(errors.len(), 1, "{stderr}");
        assert!(errors[0].contains(name), "{}", errors[0]);
        assert!(!out.exists());
    }
}
