//! Textures (issue 18): UVs survive the OBJ (+ MTL `map_Kd`), glTF (`baseColorTexture`) and
//! PLY (`s`, `t`, `comment TextureFile`) loaders per triangle corner, seams split for drawing,
//! images decode to linear RGB, entry factors are `sqrt(texture)`, and a missing, corrupt or
//! oversized image is one error line naming the image file.

use glam::{Vec2, Vec3};
use lucent_core::mesh::texture::{MAX_TEXTURE_SIDE, TextureSource, UvSplit};
use lucent_core::mesh::{load_mesh, load_textured_mesh};
use std::path::{Path, PathBuf};

/// A fresh directory for files a test writes.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lucent-tex-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Encodes an 8-bit sRGB PNG of `w x h` texels from `f(x, y)`.
fn png(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
    let img = image::RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).unwrap();
    bytes
}

/// A 2x2 red/green checker: red at top-left and bottom-right.
fn checker() -> Vec<u8> {
    png(2, 2, |x, y| if (x + y) % 2 == 0 { [255, 0, 0] } else { [0, 255, 0] })
}

/// A unit quad in z = 0 with full-texture UVs (OBJ's bottom-left origin), material `mat`.
const QUAD_OBJ: &str = "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
    vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl mat\nf 1/1 2/2 3/3 4/4\n";

fn write_quad(dir: &Path, texture: &str) -> PathBuf {
    std::fs::write(dir.join("quad.obj"), QUAD_OBJ).unwrap();
    std::fs::write(dir.join("quad.mtl"), format!("newmtl mat\nKd 1 1 1\nmap_Kd {texture}\n")).unwrap();
    dir.join("quad.obj")
}

#[test]
fn obj_keeps_uvs_and_names_the_map_kd_image() {
    let dir = scratch("obj");
    std::fs::write(dir.join("checker.png"), checker()).unwrap();
    let path = write_quad(&dir, "checker.png");
    let (mesh, _, texture) = load_textured_mesh(&path).unwrap();
    let texture = texture.expect("the quad has UVs");
    assert_eq!(mesh.triangles.len(), 2);
    assert_eq!(texture.corner_uvs.len(), 2);
    // v flipped to the image's top-left origin: vertex k's UV follows its position (x, 1 - y).
    for (t, uvs) in mesh.triangles.iter().zip(&texture.corner_uvs) {
        for (v, uv) in t.iter().zip(uvs) {
            let p = mesh.positions[*v as usize];
            assert_eq!(*uv, Vec2::new(p.x, 1.0 - p.y), "vertex {v}");
        }
    }
    assert_eq!(texture.image, Some(TextureSource::File(dir.join("checker.png"))));
    let loaded = texture.load().unwrap().unwrap();
    assert_eq!((loaded.image.width, loaded.image.height), (2, 2));
    // sRGB 255 is linear 1; texel centres sample exactly.
    assert_eq!(loaded.image.sample(Vec2::new(0.25, 0.25)), Vec3::X);
    assert_eq!(loaded.image.sample(Vec2::new(0.75, 0.25)), Vec3::Y);
    // The plain loader reads no .mtl and returns the same geometry.
    assert_eq!(load_mesh(&path).unwrap(), mesh);
}

#[test]
fn obj_seams_stay_sharp_while_positions_weld() {
    // A cube whose six faces each map the whole texture: every corner is on a seam.
    let dir = scratch("seams");
    let mut obj =
        String::from("v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n");
    for (k, f) in ["1 4 3 2", "5 6 7 8", "1 2 6 5", "2 3 7 6", "3 4 8 7", "4 1 5 8"].iter().enumerate() {
        // Face k maps the texture shifted by 2k (it repeats): four UVs no other face has.
        let (u0, u1) = (2 * k, 2 * k + 1);
        obj += &format!("vt {u0} 0\nvt {u1} 0\nvt {u1} 1\nvt {u0} 1\n");
        let idx: Vec<&str> = f.split(' ').collect();
        let t = 4 * k;
        obj += &format!(
            "f {}/{} {}/{} {}/{} {}/{}\n",
            idx[0],
            t + 1,
            idx[1],
            t + 2,
            idx[2],
            t + 3,
            idx[3],
            t + 4
        );
    }
    std::fs::write(dir.join("cube.obj"), obj).unwrap();
    let (mesh, report, texture) = load_textured_mesh(&dir.join("cube.obj")).unwrap();
    assert!(report.is_clean(), "{report}");
    assert_eq!(mesh.positions.len(), 8);
    let texture = texture.unwrap();
    assert_eq!(texture.image, None, "no material, no image");
    let split = UvSplit::new(&mesh, &texture.corner_uvs);
    assert_eq!(split.source.len(), 24, "each face's four corners have their own UVs");
    assert_eq!(split.triangles.len(), 12);
    for (t, st) in mesh.triangles.iter().zip(&split.triangles) {
        assert_eq!(*t, st.map(|k| split.source[k as usize]));
    }
    assert_eq!(split.gather(&mesh.positions).len(), 24);
}

#[test]
fn uniform_texture_entry_factor_is_its_square_root() {
    let dir = scratch("uniform");
    std::fs::write(dir.join("flat.png"), png(3, 2, |_, _| [188, 64, 255])).unwrap();
    let (_, _, texture) = load_textured_mesh(&write_quad(&dir, "flat.png")).unwrap();
    let texture = texture.unwrap().load().unwrap().unwrap();
    let srgb = |c: f32| ((c / 255.0 + 0.055) / 1.055).powf(2.4);
    let want = Vec3::new(srgb(188.0), srgb(64.0), 1.0);
    for f in texture.entry_factors() {
        assert!((f * f - want).abs().max_element() < 1e-4, "{f} squared is not {want}");
    }
}

#[test]
fn gltf_with_embedded_buffer_and_image_keeps_uvs() {
    let dir = scratch("gltf");
    let positions: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let uvs: [[f32; 2]; 3] = [[0.0, 1.0], [1.0, 1.0], [0.0, 0.0]];
    let mut buffer: Vec<u8> = bytemuck_free(&positions.concat());
    buffer.extend(bytemuck_free(&uvs.concat()));
    let image = base64::encode(checker());
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
        "textures":[{{"source":0}}],"images":[{{"uri":"data:image/png;base64,{image}"}}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
          {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
        "buffers":[{{"byteLength":60,"uri":"data:application/octet-stream;base64,{}"}}]}}"#,
        base64::encode(&buffer)
    );
    std::fs::write(dir.join("tri.gltf"), json).unwrap();
    let (mesh, _, texture) = load_textured_mesh(&dir.join("tri.gltf")).unwrap();
    let texture = texture.unwrap();
    assert_eq!(mesh.triangles.len(), 1);
    assert_eq!(texture.corner_uvs[0], uvs.map(Vec2::from_array), "glTF UVs are taken as given");
    assert!(matches!(&texture.image, Some(TextureSource::Embedded { .. })));
    let loaded = texture.load().unwrap().unwrap();
    assert_eq!(loaded.image.sample(Vec2::new(0.75, 0.75)), Vec3::X);
}

/// Little-endian bytes of `f32`s.
fn bytemuck_free(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn ply_keeps_s_t_and_names_the_texture_file() {
    let dir = scratch("ply");
    std::fs::write(dir.join("checker.png"), checker()).unwrap();
    let ply = "ply\nformat ascii 1.0\ncomment TextureFile checker.png\nelement vertex 3\n\
        property float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\n\
        element face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n";
    std::fs::write(dir.join("tri.ply"), ply).unwrap();
    let (_, _, texture) = load_textured_mesh(&dir.join("tri.ply")).unwrap();
    let texture = texture.unwrap();
    assert_eq!(texture.corner_uvs[0], [Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 0.0)]);
    assert_eq!(texture.image, Some(TextureSource::File(dir.join("checker.png"))));
}

#[test]
fn bad_images_are_one_line_errors_naming_the_file() {
    let dir = scratch("bad");
    let cases: [(&str, Option<Vec<u8>>, &str); 3] = [
        ("missing.png", None, "missing.png"),
        ("corrupt.png", Some(b"\x89PNG\r\n\x1a\n not really".to_vec()), "corrupt.png"),
        ("huge.png", Some(png(MAX_TEXTURE_SIDE + 1, 1, |_, _| [9, 9, 9])), "4097x1"),
    ];
    for (name, bytes, needle) in cases {
        if let Some(b) = bytes {
            std::fs::write(dir.join(name), b).unwrap();
        }
        // A missing file is refused where the .mtl names it, the others where they are decoded.
        let loaded = load_textured_mesh(&write_quad(&dir, name)).and_then(|(_, _, t)| t.unwrap().load());
        let message = loaded.unwrap_err().to_string();
        assert!(!message.contains('\n'), "{message}");
        assert!(message.contains(name) && message.contains(needle), "{name}: {message}");
    }
    // A texture path leading out of the model's folder is refused at load.
    let path = write_quad(&dir, "../outside.png");
    let message = load_textured_mesh(&path).unwrap_err().to_string();
    assert!(message.contains("quad.obj") && message.contains("map_Kd"), "{message}");
}
