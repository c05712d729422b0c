//! The fuzz targets: one per loader lucent exposes to files, each with the valid seed inputs
//! mutation starts from (generated here, so no binary seeds are committed).

use glam::Vec3;
use lucent_core::irradiance::EnvMap;
use lucent_core::mesh::io::{MeshFormat, parse_mesh};
use lucent_core::mesh::{Mesh, generate};
use lucent_core::volume::{DensityVolume, RawFormat, parse_lvol, parse_raw};
use std::path::Path;

/// A loader under test.
pub struct Target {
    /// Name on the command line and folder name of its regression inputs.
    pub name: &'static str,
    /// Feeds one input to the loader. `Ok` carries a short summary of what loaded, `Err` the
    /// loader's error; both only feed the corpus heuristic. A panic escaping this is a crash.
    pub run: fn(&[u8]) -> Result<String, String>,
    /// Valid inputs to start from.
    pub seeds: fn() -> Vec<Vec<u8>>,
}

/// Every target, in the order `all` runs them.
pub const TARGETS: &[Target] = &[
    Target { name: "obj", run: |b| mesh(b, MeshFormat::Obj), seeds: obj_seeds },
    Target { name: "ply-ascii", run: |b| mesh(b, MeshFormat::Ply), seeds: ply_ascii_seeds },
    Target { name: "ply-binary", run: |b| mesh(b, MeshFormat::Ply), seeds: ply_binary_seeds },
    Target { name: "off", run: |b| mesh(b, MeshFormat::Off), seeds: off_seeds },
    Target { name: "gltf", run: gltf, seeds: gltf_seeds },
    Target { name: "glb", run: gltf, seeds: glb_seeds },
    Target { name: "hdr", run: |b| envmap(b, "hdr"), seeds: hdr_seeds },
    Target { name: "exr", run: |b| envmap(b, "exr"), seeds: exr_seeds },
    Target { name: "scene", run: scene, seeds: scene_seeds },
    Target { name: "lvol", run: lvol, seeds: lvol_seeds },
    Target { name: "raw", run: raw, seeds: raw_seeds },
];

/// The target called `name`.
pub fn target(name: &str) -> Option<&'static Target> {
    TARGETS.iter().find(|t| t.name == name)
}

fn mesh(bytes: &[u8], format: MeshFormat) -> Result<String, String> {
    parse_mesh(bytes, format, "fuzz")
        .map(|(m, r)| format!("{} {}", m.triangles.len(), r))
        .map_err(|e| e.to_string())
}

/// The mesh and the first material's subsurface extensions (`mesh::gltf_material`).
fn gltf(bytes: &[u8]) -> Result<String, String> {
    let material = match lucent_core::mesh::parse_gltf_material(bytes, "fuzz") {
        Ok(m) => format!("material {}", m.map_or(0, |m| m.count)),
        Err(e) => e.to_string(),
    };
    mesh(bytes, MeshFormat::Gltf).map(|m| format!("{m} {material}"))
}

fn envmap(bytes: &[u8], ext: &str) -> Result<String, String> {
    EnvMap::from_bytes(bytes, ext, "fuzz")
        .map(|m| format!("{}x{}", m.width, m.height))
        .map_err(|e| e.to_string())
}

fn scene(bytes: &[u8]) -> Result<String, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "not UTF-8".to_string())?;
    // A folder that does not exist: whatever file a mutated scene names cannot be read.
    let scene = lucent_scene::scene::SceneFile::parse(text, "/nonexistent-fuzz-dir".into())
        .map_err(|e| format!("{e:#}"))?;
    // The environment map itself is the hdr and exr targets' business (and decoding the
    // built-in probes for every input would only slow the run).
    let lights = scene.lights(Vec3::ZERO);
    let _ = scene.camera();
    Ok(format!("{} lights {} deformations", lights.len(), scene.deform.len()))
}

fn lvol(bytes: &[u8]) -> Result<String, String> {
    parse_lvol(bytes, Path::new("fuzz.lvol")).map(|v| format!("{:?}", v.dims)).map_err(|e| e.to_string())
}

/// Raw grids take their size from the command line: here the first four bytes give the three
/// sides (1..=16) and the voxel format, the rest is the data.
fn raw(bytes: &[u8]) -> Result<String, String> {
    let [a, b, c, f, data @ ..] = bytes else { return Err("short".into()) };
    let dims = [a, b, c].map(|&d| u32::from(d % 16) + 1);
    let format = [RawFormat::U8, RawFormat::U16, RawFormat::F32][usize::from(*f % 3)];
    parse_raw(data, dims, format, Path::new("fuzz.raw"))
        .map(|v| format!("{:?}", v.dims))
        .map_err(|e| e.to_string())
}

// ---------------------------------------------------------------------------------------------
// Seeds

fn small_mesh() -> Mesh {
    generate::icosphere(0)
}

fn obj_seeds() -> Vec<Vec<u8>> {
    let m = small_mesh();
    let mut plain = String::from("# icosahedron\no ico\n");
    for p in &m.positions {
        plain += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    let mut full = plain.clone();
    full += "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n";
    for t in &m.triangles {
        plain += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        full += &format!("f {}/1/1 {}/2/1 -{}//1\n", t[0] + 1, t[1] + 1, m.positions.len() as u32 - t[2]);
    }
    full += "usemtl wax\ns off\nf 1 2 3 4\nl 1 2\n";
    vec![plain.into_bytes(), full.into_bytes()]
}

fn ply_header(m: &Mesh, format: &str, extra_vertex: &str) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment fuzz seed\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n{extra_vertex}element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        m.positions.len(),
        m.triangles.len()
    )
}

fn ply_ascii_seeds() -> Vec<Vec<u8>> {
    let m = small_mesh();
    let mut s = ply_header(&m, "ascii", "property uchar red\n");
    for p in &m.positions {
        s += &format!("{} {} {} 200\n", p.x, p.y, p.z);
    }
    for t in &m.triangles {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    vec![s.into_bytes()]
}

fn ply_binary_seeds() -> Vec<Vec<u8>> {
    let m = small_mesh();
    let mut seeds = Vec::new();
    for big in [false, true] {
        let fmt = if big { "binary_big_endian" } else { "binary_little_endian" };
        let mut b = ply_header(&m, fmt, "").into_bytes();
        let f32b = |v: f32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
        let i32b = |v: i32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
        for p in &m.positions {
            for c in p.to_array() {
                b.extend(f32b(c));
            }
        }
        for t in &m.triangles {
            b.push(3);
            for &i in t {
                b.extend(i32b(i as i32));
            }
        }
        seeds.push(b);
    }
    seeds
}

fn off_seeds() -> Vec<Vec<u8>> {
    let m = small_mesh();
    let mut s = format!("OFF\n# seed\n{} {} 0\n", m.positions.len(), m.triangles.len());
    for p in &m.positions {
        s += &format!("{} {} {}\n", p.x, p.y, p.z);
    }
    for t in &m.triangles {
        s += &format!("3 {} {} {} 255 0 0\n", t[0], t[1], t[2]);
    }
    vec![s.into_bytes()]
}

/// The icosahedron as glTF JSON (`uri`: the buffer's URI, or `None` for a GLB chunk) and its
/// binary buffer (positions as float VEC3, then indices as u16).
fn gltf_json(uri: Option<String>) -> (String, Vec<u8>) {
    let m = small_mesh();
    let mut bin = Vec::new();
    for p in &m.positions {
        for c in p.to_array() {
            bin.extend(c.to_le_bytes());
        }
    }
    let positions_len = bin.len();
    for t in &m.triangles {
        for &i in t {
            bin.extend((i as u16).to_le_bytes());
        }
    }
    let (lo, hi) = m.bounds();
    let uri = uri.map(|u| format!(r#""uri":"{u}","#)).unwrap_or_default();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0,"children":[1]}},{{"mesh":0,"translation":[2,0,0],"scale":[1,-1,1]}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":4}}]}}],"buffers":[{{{uri}"byteLength":{}}}],"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{positions_len}}},{{"buffer":0,"byteOffset":{positions_len},"byteLength":{}}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},{{"bufferView":1,"componentType":5123,"count":{},"type":"SCALAR"}}],"materials":[{{"extensions":{{"KHR_materials_volume":{{"attenuationColor":[0.9,0.5,0.3],"attenuationDistance":0.5}},"KHR_materials_diffuse_transmission":{{"diffuseTransmissionFactor":0.5,"diffuseTransmissionColorFactor":[1,0.9,0.8]}},"KHR_materials_volume_scatter":{{"multiscatterColor":[0.5,0.4,0.3],"scatterAnisotropy":0.2}},"KHR_materials_ior":{{"ior":1.4}}}}}}]}}"#,
        bin.len(),
        bin.len() - positions_len,
        m.positions.len(),
        lo.x,
        lo.y,
        lo.z,
        hi.x,
        hi.y,
        hi.z,
        m.triangles.len() * 3,
    );
    (json, bin)
}

fn gltf_seeds() -> Vec<Vec<u8>> {
    let (_, bin) = gltf_json(None);
    let data = format!("data:application/octet-stream;base64,{}", base64::encode(&bin));
    vec![gltf_json(Some(data)).0.into_bytes()]
}

fn glb_seeds() -> Vec<Vec<u8>> {
    let (mut json, mut bin) = gltf_json(None);
    while json.len() % 4 != 0 {
        json.push(' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut b = Vec::with_capacity(total);
    b.extend(b"glTF");
    b.extend(2u32.to_le_bytes());
    b.extend((total as u32).to_le_bytes());
    b.extend((json.len() as u32).to_le_bytes());
    b.extend(b"JSON");
    b.extend(json.as_bytes());
    b.extend((bin.len() as u32).to_le_bytes());
    b.extend(b"BIN\0");
    b.extend(&bin);
    vec![b]
}

/// A small sky-like gradient, `w x h`.
fn gradient(w: usize, h: usize) -> Vec<[f32; 3]> {
    (0..w * h).map(|k| [(k % w) as f32 / w as f32 * 4.0, (k / w) as f32 / h as f32, 0.25]).collect()
}

fn hdr_seeds() -> Vec<Vec<u8>> {
    // 16 wide: run-length encoded scanlines (8..32767 wide); 4 wide: flat RGBE.
    [(16, 8), (4, 2)]
        .into_iter()
        .map(|(w, h)| {
            let pixels: Vec<image::Rgb<f32>> = gradient(w, h).into_iter().map(image::Rgb).collect();
            let mut out = Vec::new();
            image::codecs::hdr::HdrEncoder::new(&mut out).encode(&pixels, w, h).expect("encode seed");
            out
        })
        .collect()
}

fn exr_seeds() -> Vec<Vec<u8>> {
    use exr::prelude::*;
    let (w, h) = (8, 4);
    let texels = gradient(w, h);
    [Compression::Uncompressed, Compression::RLE, Compression::ZIP1, Compression::PIZ]
        .into_iter()
        .map(|compression| {
            let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
                let t = texels[p.y() * w + p.x()];
                (t[0], t[1], t[2])
            });
            let layer = Layer::new(
                (w, h),
                LayerAttributes::default(),
                Encoding { compression, ..Encoding::default() },
                channels,
            );
            let mut out = std::io::Cursor::new(Vec::new());
            Image::from_layer(layer).write().to_buffered(&mut out).expect("encode seed");
            out.into_inner()
        })
        .collect()
}

fn scene_seeds() -> Vec<Vec<u8>> {
    let mut seeds: Vec<Vec<u8>> = [
        include_str!("../../../examples/scenes/bunny_spot.toml"),
        include_str!("../../../examples/scenes/bunny_courtyard.toml"),
        include_str!("../../../examples/scenes/candle.toml"),
    ]
    .iter()
    .map(|s| s.as_bytes().to_vec())
    .collect();
    seeds.push(
        br#"mesh = "models/thing.obj"
scale = 0.1
exposure = 2.0
profile = "dipole"
single_scattering = true
surface = false
deform = ["twist:30", "bump:0,1,0,0.5,0.1", "noise:0.01,3"]
material = { sigma_s_prime = [1.0, 1.2, 1.5], sigma_a = [0.01, 0.02, 0.03], eta = 1.4 }
[camera]
yaw = 30.0
pitch = 10.0
distance = 3.0
fov = 40.0
[[light]]
type = "directional"
direction = [0.0, -1.0, 0.0]
color = [1.0, 0.9, 0.8]
intensity = 2.0
"#
        .to_vec(),
    );
    seeds
}

fn lvol_seeds() -> Vec<Vec<u8>> {
    let dims = [4u32, 3, 2];
    let volume =
        DensityVolume::new(dims, (0..24).map(|k| k as f32 / 24.0).collect()).expect("valid seed volume");
    let mut b = b"LVOL".to_vec();
    b.extend(1u32.to_le_bytes());
    for d in volume.dims {
        b.extend(d.to_le_bytes());
    }
    for v in &volume.data {
        b.extend(v.to_le_bytes());
    }
    vec![b]
}

fn raw_seeds() -> Vec<Vec<u8>> {
    // Sides 4 x 3 x 2 (stored minus one), then the format byte, then the voxels.
    let mut u8s = vec![3, 2, 1, 0];
    u8s.extend((0..24).map(|k| k as u8 * 10));
    let mut f32s = vec![3, 2, 1, 2];
    f32s.extend((0..24).flat_map(|k| (k as f32 / 24.0).to_le_bytes()));
    vec![u8s, f32s]
}
