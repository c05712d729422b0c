//! Loading: every format against known geometry, polygon triangulation, rejections with the
//! file named, the validation report, and no panics on truncated or garbage bytes.

use glam::Vec3;
use lucent_core::mesh::generate;
use lucent_core::mesh::io::{MeshFormat, parse_mesh};
use lucent_core::mesh::{Mesh, MeshError, load_gltf_volume_params, load_mesh, load_mesh_with_report};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// A fresh directory for files a test writes.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lucent-mesh-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The 8 corners of [-1,1]^3 in a canonical order.
fn cube_corners() -> Vec<[i32; 3]> {
    let mut c: Vec<[i32; 3]> =
        (0..8).map(|i| [(i & 1) * 2 - 1, ((i >> 1) & 1) * 2 - 1, ((i >> 2) & 1) * 2 - 1]).collect();
    c.sort();
    c
}

/// Checks a mesh is the closed cube [-1,1]^3 triangulated: its 8 corners, 12 triangles, area
/// 24 and volume 8 (closed forms), outward faces, every edge shared by two faces.
fn assert_unit_cube(mesh: &Mesh) {
    let mut p: Vec<[i32; 3]> = mesh.positions.iter().map(|v| v.to_array().map(|x| x as i32)).collect();
    p.sort();
    assert_eq!(p, cube_corners());
    assert_eq!(mesh.triangles.len(), 12);
    assert!((mesh.area() - 24.0).abs() < 1e-9, "area {}", mesh.area());
    assert!((mesh.signed_volume() - 8.0).abs() < 1e-9);
    let t = mesh.topology();
    assert!(t.is_closed_manifold(), "{t}");
    assert_eq!(t.components, 1);
    assert_eq!(t.euler_characteristic, 2);
}

#[test]
fn obj_quads_with_split_normals_load_as_welded_cube() {
    let (mesh, report) = load_mesh_with_report(&data("cube_quads.obj")).unwrap();
    assert_unit_cube(&mesh);
    assert_eq!(report.degenerate_faces, 0);
    assert!(report.is_clean(), "{report}");
}

#[test]
fn ascii_ply_quads_load_as_cube() {
    assert_unit_cube(&load_mesh(&data("cube_quads.ply")).unwrap());
}

#[test]
fn off_quads_with_comments_and_colours_load_as_cube() {
    assert_unit_cube(&load_mesh(&data("cube_quads.off")).unwrap());
}

#[test]
fn extension_is_case_insensitive() {
    let dir = scratch("case");
    let p = dir.join("CUBE.Off");
    std::fs::copy(data("cube_quads.off"), &p).unwrap();
    assert_unit_cube(&load_mesh(&p).unwrap());
}

#[test]
fn hexagon_faces_are_triangulated() {
    let mesh = load_mesh(&data("hexprism.off")).unwrap();
    // 2 hexagons -> 4 triangles each, 6 quads -> 2 each.
    assert_eq!(mesh.triangles.len(), 2 * 4 + 6 * 2);
    // Closed form: regular hexagon of circumradius 1 has area 3*sqrt(3)/2; height 1.
    let hex = 1.5 * 3f64.sqrt();
    assert!((mesh.signed_volume() - hex).abs() < 1e-5);
    assert!((mesh.area() - (2.0 * hex + 6.0)).abs() < 1e-5);
    assert!(mesh.topology().is_closed_manifold());
}

// ---- writers for the round trips (test-side, minimal) ----

fn obj_text(m: &Mesh) -> String {
    let mut s = String::from("# written by the test\n");
    for p in &m.positions {
        s += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in &m.triangles {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

fn off_text(m: &Mesh) -> String {
    let mut s = format!("OFF\n{} {} 0\n", m.positions.len(), m.triangles.len());
    for p in &m.positions {
        s += &format!("{} {} {}\n", p.x, p.y, p.z);
    }
    for t in &m.triangles {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    s
}

/// Binary little-endian PLY with double coordinates and `vertex_index` as a `uchar ushort`
/// list (the less common types and name), plus an ignored extra vertex property.
fn ply_binary(m: &Mesh) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nelement face {}\nproperty list uchar ushort vertex_index\nend_header\n",
        m.positions.len(),
        m.triangles.len()
    )
    .into_bytes();
    for p in &m.positions {
        for c in p.to_array() {
            b.extend((c as f64).to_le_bytes());
        }
        b.push(200);
    }
    for t in &m.triangles {
        b.push(3);
        for &i in t {
            b.extend((i as u16).to_le_bytes());
        }
    }
    b
}

/// Binary big-endian PLY with float coordinates and `uint` indices in a `uint` list.
fn ply_binary_be(m: &Mesh) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_big_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uint uint vertex_indices\nend_header\n",
        m.positions.len(),
        m.triangles.len()
    )
    .into_bytes();
    for p in &m.positions {
        for c in p.to_array() {
            b.extend(c.to_be_bytes());
        }
    }
    for t in &m.triangles {
        b.extend(3u32.to_be_bytes());
        for &i in t {
            b.extend(i.to_be_bytes());
        }
    }
    b
}

/// Minimal base64 (standard alphabet, padded) for glTF data URIs.
fn base64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A glTF document with one mesh of one indexed triangle primitive, instanced by two nodes:
/// node 0 translated by `shift`, node 1 (its child) additionally translated by 5 along x and
/// scaled by -1 in x (a mirror, which must flip the winding to stay outward), plus a points primitive that must be
/// ignored. Returns (JSON with `uri` or without, binary buffer).
fn gltf_parts(m: &Mesh, shift: Vec3, uri: Option<&str>, volume: bool) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    for p in &m.positions {
        for c in p.to_array() {
            bin.extend(c.to_le_bytes());
        }
    }
    let pos_len = bin.len();
    for t in &m.triangles {
        for &i in t {
            bin.extend(i.to_le_bytes());
        }
    }
    let idx_len = bin.len() - pos_len;
    let (lo, hi) = m.bounds();
    let uri_field = uri.map(|u| format!(r#""uri":"{u}","#)).unwrap_or_default();
    let material = if volume {
        r#","materials":[{"extensions":{"KHR_materials_volume":{"thicknessFactor":1.0,"attenuationColor":[0.9,0.5,0.25],"attenuationDistance":0.125}}}],"extensionsUsed":["KHR_materials_volume"]"#
    } else {
        ""
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[{},{},{}],"children":[1]}},{{"mesh":0,"translation":[5,0,0],"scale":[-1,1,1]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}},{{"attributes":{{"POSITION":0}},"mode":0}}]}}],
"buffers":[{{{uri_field}"byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},{{"buffer":0,"byteOffset":{pos_len},"byteLength":{idx_len}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},
{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}]{material}}}"#,
        shift.x,
        shift.y,
        shift.z,
        bin.len(),
        m.positions.len(),
        lo.x,
        lo.y,
        lo.z,
        hi.x,
        hi.y,
        hi.z,
        m.triangles.len() * 3
    );
    (json, bin)
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(b);
    out
}

/// The mesh the glTF scene above describes: `m` shifted, then `m` mirrored and shifted.
fn gltf_expected(m: &Mesh, shift: Vec3) -> (Vec<Vec3>, f64) {
    let mut p: Vec<Vec3> = m.positions.iter().map(|&p| p + shift).collect();
    // glTF node matrix = T * R * S, composed parent * child.
    p.extend(m.positions.iter().map(|&p| Vec3::new(5.0 - p.x, p.y, p.z) + shift));
    (p, 2.0 * m.signed_volume())
}

/// Same positions (bitwise) and triangles, up to a relabelling of the vertices.
fn assert_same_mesh(got: &Mesh, want: &Mesh) {
    let bits = |p: &Vec3| p.to_array().map(f32::to_bits);
    let index: std::collections::HashMap<[u32; 3], u32> =
        want.positions.iter().enumerate().map(|(i, p)| (bits(p), i as u32)).collect();
    assert_eq!(got.positions.len(), want.positions.len());
    let relabel: Vec<u32> = got.positions.iter().map(|p| index[&bits(p)]).collect();
    let tris: Vec<[u32; 3]> = got.triangles.iter().map(|t| t.map(|i| relabel[i as usize])).collect();
    assert_eq!(tris, want.triangles);
}

#[test]
fn round_trip_obj_ply_off() {
    let m = generate::icosphere(1);
    let dir = scratch("roundtrip");
    let files = [
        ("m.obj", obj_text(&m).into_bytes()),
        ("m.off", off_text(&m).into_bytes()),
        ("m_le.ply", ply_binary(&m)),
        ("m_be.ply", ply_binary_be(&m)),
    ];
    for (name, bytes) in files {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        let (got, report) = load_mesh_with_report(&p).unwrap();
        // Display of f32 is exact (shortest round-trip form), so positions must match bitwise;
        // OBJ orders vertices by first use, hence the comparison up to relabelling.
        assert_same_mesh(&got, &m);
        assert!(report.is_clean(), "{name}: {report}");
    }
}

#[test]
fn round_trip_gltf_and_glb_with_node_transforms() {
    let m = generate::cube(2);
    let shift = Vec3::new(3.0, -1.0, 0.5);
    let (want_pos, want_vol) = gltf_expected(&m, shift);
    let dir = scratch("gltf");

    let (json_ext, bin) = gltf_parts(&m, shift, Some("m.bin"), false);
    std::fs::write(dir.join("m.bin"), &bin).unwrap();
    std::fs::write(dir.join("external.gltf"), &json_ext).unwrap();
    let data_uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let (json_emb, _) = gltf_parts(&m, shift, Some(&data_uri), false);
    std::fs::write(dir.join("embedded.GLTF"), &json_emb).unwrap();
    let (json_glb, _) = gltf_parts(&m, shift, None, false);
    std::fs::write(dir.join("m.glb"), glb(&json_glb, &bin)).unwrap();

    for name in ["external.gltf", "embedded.GLTF", "m.glb"] {
        let (got, report) = load_mesh_with_report(&dir.join(name)).unwrap();
        // Two instances of the cube, each welded within itself; they do not touch.
        let mut g: Vec<[u32; 3]> = got.positions.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
        let mut w: Vec<[u32; 3]> = want_pos.iter().map(|p| p.to_array().map(f32::to_bits)).collect();
        g.sort();
        w.sort();
        assert_eq!(g, w, "{name}");
        assert_eq!(got.triangles.len(), 2 * m.triangles.len());
        // The mirrored instance keeps outward faces only if its winding was flipped.
        assert!((got.signed_volume() - want_vol).abs() < 1e-4, "{name}: {}", got.signed_volume());
        assert!(report.is_closed_manifold(), "{name}: {report}");
        assert_eq!(report.components, 2);
    }
}

#[test]
fn gltf_volume_params() {
    let m = generate::cube_base();
    let dir = scratch("volume");
    let (json, bin) = gltf_parts(&m, Vec3::ZERO, None, true);
    let with = dir.join("vol.glb");
    std::fs::write(&with, glb(&json, &bin)).unwrap();
    assert_eq!(load_gltf_volume_params(&with).unwrap(), Some(([0.9, 0.5, 0.25], 0.125)));
    let (json, bin) = gltf_parts(&m, Vec3::ZERO, None, false);
    let without = dir.join("novol.glb");
    std::fs::write(&without, glb(&json, &bin)).unwrap();
    assert_eq!(load_gltf_volume_params(&without).unwrap(), None);
    let err = load_gltf_volume_params(&dir.join("missing.glb")).unwrap_err();
    assert!(err.to_string().contains("missing.glb"), "{err}");
}

// ---- rejections ----

fn load_err(name: &str, content: &[u8]) -> MeshError {
    let dir = scratch("reject");
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap();
    let err = load_mesh(&p).expect_err(name);
    let msg = err.to_string();
    assert!(msg.starts_with(&p.display().to_string()), "message must name the file: {msg}");
    assert!(!msg.contains('\n'), "one line: {msg}");
    err
}

#[test]
fn rejects_empty_meshes() {
    assert!(load_err("novert.off", b"OFF\n0 0 0\n").reason().contains("no vertices"));
    assert!(load_err("noface.off", b"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n").reason().contains("no triangles"));
    assert!(load_err("empty.obj", b"").reason().contains("no vertices"));
    // tobj returns no object for vertices without faces.
    assert!(load_err("points.obj", b"v 0 0 0\nv 1 0 0\n").reason().contains("empty mesh"));
    let ply = b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
    assert!(load_err("empty.ply", ply).reason().contains("no vertices"));
}

#[test]
fn rejects_out_of_range_indices() {
    let off = b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n";
    assert!(load_err("range.off", off).reason().contains("out of range"));
    let ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
    assert!(load_err("range.ply", ply).reason().contains("out of range"));
    let neg = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n";
    assert!(load_err("negative.ply", neg).reason().contains("invalid vertex index"));
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
    load_err("range.obj", obj);
}

#[test]
fn rejects_non_finite_coordinates() {
    for (name, v) in [("nan.off", "nan"), ("inf.off", "inf")] {
        let off = format!("OFF\n3 1 0\n0 0 0\n1 {v} 0\n0 1 0\n3 0 1 2\n");
        assert!(load_err(name, off.as_bytes()).reason().contains("vertex 1 has a non-finite"));
    }
    let mut m = generate::cube_base();
    m.positions[5].z = f32::NAN;
    assert!(load_err("nan.ply", &ply_binary_be(&m)).reason().contains("vertex 5 has a non-finite"));
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n";
    assert!(load_err("inf.obj", obj).reason().contains("non-finite"));
}

#[test]
fn rejects_all_degenerate() {
    let off = b"OFF\n3 2 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n3 0 0 1\n";
    assert!(load_err("flat.off", off).reason().contains("degenerate"));
}

#[test]
fn rejects_unknown_extension_and_missing_file() {
    let e = load_err("cube.stl", b"solid x\nendsolid x\n");
    assert!(e.reason().contains(".stl") && e.reason().contains(".obj"), "{e}");
    let e = load_err("noextension", b"OFF\n");
    assert!(e.reason().contains("extension"), "{e}");
    let missing = Path::new("/nonexistent/dir/bunny.ply");
    let e = load_mesh(missing).unwrap_err();
    assert!(e.to_string().starts_with("/nonexistent/dir/bunny.ply: cannot open"), "{e}");
}

#[test]
fn rejects_garbage_and_truncation_with_the_file_named() {
    load_err("garbage.off", b"OFF\n8 6 0\n1 2 banana\n");
    load_err("truncated.off", &std::fs::read(data("cube_quads.off")).unwrap()[..120]);
    let ply = std::fs::read(data("cube_quads.ply")).unwrap();
    load_err("truncated.ply", &ply[..ply.len() - 20]);
    load_err(
        "garbage.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\nhello\n",
    );
    load_err("binary.obj", &[0xff, 0xfe, 0x00, 0x13, 0x37, b'\n', b'f', b' ', b'1']);
    load_err("garbage.glb", b"glTF\x02\x00\x00\x00\xff\xff\xff\xff garbage");
    load_err("garbage.gltf", b"{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [{");
}

#[test]
fn report_counts_degenerate_and_nonmanifold() {
    let (mesh, r) = load_mesh_with_report(&data("cube_fin_degenerate.off")).unwrap();
    // See the fixture's comment for where each count comes from.
    assert_eq!(r.degenerate_faces, 2, "{r}");
    assert_eq!(mesh.triangles.len(), 13);
    assert_eq!(r.triangles, 13);
    assert_eq!(r.nonmanifold_edges, 1, "{r}");
    assert_eq!(r.boundary_edges, 2, "{r}");
    assert_eq!(r.unreferenced_vertices, 1, "{r}");
    assert_eq!(r.components, 1);
    assert!(!r.is_closed_manifold());
    let line = r.to_string();
    assert!(line.contains("removed 2 degenerate faces") && line.contains("1 non-manifold edges"), "{line}");
}

#[test]
fn report_counts_components_and_inconsistent_orientation() {
    // Two separate cubes, the second with one face flipped.
    let a = generate::cube_base();
    let mut positions = a.positions.clone();
    positions.extend(a.positions.iter().map(|p| *p + Vec3::X * 5.0));
    let mut triangles = a.triangles.clone();
    triangles.extend(a.triangles.iter().map(|t| t.map(|i| i + 8)));
    let last = triangles.len() - 1;
    triangles[last].swap(1, 2);
    let (_, r) = lucent_core::mesh::validate::validate(Mesh::new(positions, triangles), "two cubes").unwrap();
    assert_eq!(r.components, 2);
    assert_eq!(r.inconsistent_edges, 3);
    assert_eq!(r.boundary_edges, 0);
    assert_eq!(r.euler_characteristic, 4);
}

#[test]
fn repeated_faces_are_removed_keeping_the_winding_that_agrees_with_the_neighbours() {
    // A closed cube, then: its first face again (same winding), its second face reversed and
    // stored *before* the original (a back-to-back pair, as the vrip dragon has hundreds),
    // and a face over three vertices no other face shares (a repeat-free fin is not touched).
    let cube = generate::cube_base();
    let mut triangles = vec![{
        let mut t = cube.triangles[1];
        t.swap(1, 2);
        t
    }];
    triangles.extend(cube.triangles.iter().copied());
    triangles.push(cube.triangles[0]);
    let (mesh, r) =
        lucent_core::mesh::validate::validate(Mesh::new(cube.positions.clone(), triangles), "cube").unwrap();
    assert_eq!(r.repeated_faces, 2, "{r}");
    assert_eq!(mesh.triangles, cube.triangles, "the outward copies stay, in order");
    assert!(r.is_closed_manifold() && !r.is_clean(), "{r}");
    assert!(r.to_string().contains("removed 2 repeated faces"), "{r}");
    assert!(r.warnings().iter().any(|w| w.contains("2 repeated faces")), "{:?}", r.warnings());
    assert!(mesh.signed_volume() > 0.0);
}

// ---- robustness: no input may panic a parser ----

/// Deterministic xorshift so the corrupted inputs are reproducible.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

fn assert_no_parser_panic(bytes: &[u8], format: MeshFormat, what: &str) {
    // parse_mesh turns parser panics into errors; the test requires that none happened.
    if let Err(e) = parse_mesh(bytes, format, what) {
        assert!(!e.reason().contains("parser failed"), "{what}: {e}");
        assert!(e.to_string().starts_with(what));
    }
}

#[test]
fn truncated_and_corrupted_bytes_never_panic() {
    let m = generate::icosphere(0);
    let (json, bin) = gltf_parts(&m, Vec3::ZERO, None, true);
    let data_uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let (json_emb, _) = gltf_parts(&m, Vec3::ZERO, Some(&data_uri), true);
    let samples: Vec<(MeshFormat, Vec<u8>)> = vec![
        (MeshFormat::Obj, std::fs::read(data("cube_quads.obj")).unwrap()),
        (MeshFormat::Ply, std::fs::read(data("cube_quads.ply")).unwrap()),
        (MeshFormat::Ply, ply_binary(&m)),
        (MeshFormat::Ply, ply_binary_be(&m)),
        (MeshFormat::Off, std::fs::read(data("cube_quads.off")).unwrap()),
        (MeshFormat::Gltf, glb(&json, &bin)),
        (MeshFormat::Gltf, json_emb.into_bytes()),
    ];
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for (k, (format, bytes)) in samples.iter().enumerate() {
        // Every prefix.
        for len in 0..bytes.len() {
            assert_no_parser_panic(&bytes[..len], *format, &format!("sample{k}[..{len}]"));
        }
        // Random byte corruptions, including digits and separators that keep text parseable.
        for trial in 0..300 {
            let mut b = bytes.clone();
            for _ in 0..1 + rng.next() % 4 {
                let i = (rng.next() % b.len() as u64) as usize;
                b[i] = match rng.next() % 4 {
                    0 => (rng.next() & 0xff) as u8,
                    1 => b"0123456789"[(rng.next() % 10) as usize],
                    2 => b"-9 \n"[(rng.next() % 4) as usize],
                    _ => 0xff,
                };
            }
            assert_no_parser_panic(&b, *format, &format!("sample{k} trial {trial}"));
        }
    }
    // Pure garbage.
    for format in [MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Off, MeshFormat::Gltf] {
        for n in [1, 7, 64, 1000] {
            let b: Vec<u8> = (0..n).map(|_| (rng.next() & 0xff) as u8).collect();
            assert_no_parser_panic(&b, format, "garbage");
        }
    }
}

#[test]
fn ply_other_elements_are_skipped_and_missing_coordinates_rejected() {
    // A leading unrelated element, an edge element after the faces, extra vertex properties
    // before and after the coordinates, and a char-typed index list.
    let ply = b"ply\nformat ascii 1.0\nelement material 1\nproperty uchar red\nelement vertex 4\nproperty int id\nproperty double x\nproperty double y\nproperty double z\nproperty list uchar float extra\nelement face 4\nproperty uchar flags\nproperty list uchar char vertex_index\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n7\n0 0 0 0 2 1.5 2.5\n1 1 0 0 0\n2 0 1 0 1 9\n3 0 0 1 0\n0 3 0 2 1\n0 3 0 1 3\n0 3 0 3 2\n0 3 1 2 3\n0 1\n";
    let (m, r) = parse_mesh(ply, MeshFormat::Ply, "tetra.ply").unwrap();
    assert_eq!(m.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]);
    assert_eq!(m.triangles, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
    assert!(r.is_clean(), "{r}");
    // Unit right tetrahedron: volume 1/6.
    assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-12);

    let no_z = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0\n1 0\n0 1\n3 0 1 2\n";
    let e = load_err("noz.ply", no_z);
    assert!(e.reason().contains("no 'z' property"), "{e}");
    let no_face = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
    assert!(load_err("noface.ply", no_face).reason().contains("no 'face' element"));
}
