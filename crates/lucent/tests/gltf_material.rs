//! glTF materials (issue 18, part 4): `KHR_materials_volume`, `KHR_materials_diffuse_transmission`,
//! the draft `KHR_materials_volume_scatter` and `KHR_materials_ior` map onto lucent's material as
//! `lucent::scene::gltf_material` documents; explicit materials win over the file's; malformed
//! values are one-line errors naming the file and the value. Small hand-written glTF files
//! (JSON with a `data:` URI buffer), no GPU.

use lucent::scene::gltf_material::single_scatter_albedo;
use lucent::scene::{Overrides, Scene};
use lucent_core::bssrdf::Material;
use std::path::{Path, PathBuf};

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lucent-gltfmat-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A closed tetrahedron of extent 1 (bounding box 1 x 1 x 1) with `material` (a JSON object)
/// as its only material, written to `dir/name`.
fn write_gltf(dir: &Path, name: &str, material: &str) -> PathBuf {
    let positions: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let indices: [u16; 12] = [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3];
    let mut buffer: Vec<u8> = positions.concat().iter().flat_map(|x| x.to_le_bytes()).collect();
    buffer.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
        "materials":[{material}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
          {{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}}],
        "buffers":[{{"byteLength":72,"uri":"data:application/octet-stream;base64,{}"}}]}}"#,
        base64(&buffer)
    );
    let path = dir.join(name);
    std::fs::write(&path, json).unwrap();
    path
}

/// The scene of `mesh` at 1 cm: 10 mm per mesh unit (the tetrahedron's extent is 1).
fn resolve(mesh: &Path) -> anyhow::Result<Scene> {
    Scene::resolve(&Overrides { mesh: Some(mesh.to_path_buf()), scale: Some(0.01), ..Default::default() })
}

fn assert_same(got: &Material, want: &Material) {
    for c in 0..3 {
        for (g, w) in [(got.sigma_s_prime[c], want.sigma_s_prime[c]), (got.sigma_a[c], want.sigma_a[c])] {
            assert!((g - w).abs() <= 1e-6 * w.abs(), "channel {c}: {got:?} vs {want:?}");
        }
    }
    assert_eq!(got.eta, want.eta);
}

const LN2: f64 = std::f64::consts::LN_2;

/// What a glTF file's f32 numbers hold.
fn f32s(v: [f32; 3]) -> [f64; 3] {
    v.map(f64::from)
}

#[test]
fn volume_maps_base_colour_and_attenuation() {
    let dir = scratch("volume");
    let m = r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.6,0.4,1]},
        "extensions":{"KHR_materials_volume":{"attenuationColor":[0.5,0.25,0.125],"attenuationDistance":0.1,"thicknessFactor":0.2}}}"#;
    let s = resolve(&write_gltf(&dir, "v.gltf", m)).unwrap();
    // sigma_t = k ln 2 / 0.1 per unit, 10 mm per unit: mfp = 1 / (k ln 2) mm (glTF numbers
    // are f32).
    let mfp = [1.0, 2.0, 3.0].map(|k| 10.0 * f64::from(0.1f32) / (k * LN2));
    let want = Material::from_albedo_mfp("x", f32s([0.8, 0.6, 0.4]), mfp, 1.5).unwrap();
    assert_same(s.material(), &want);
    assert_eq!(s.material().name, "glTF material 0");
}

#[test]
fn volume_scatter_gives_the_albedo_and_a_reduced_distance() {
    let dir = scratch("scatter");
    let m = r#"{"extensions":{
        "KHR_materials_volume":{"attenuationColor":[0.5,0.5,0.5],"attenuationDistance":0.1},
        "KHR_materials_volume_scatter":{"multiscatterColor":[0.572,0.227,0.075],"scatterAnisotropy":0.3},
        "KHR_materials_diffuse_transmission":{"diffuseTransmissionFactor":1.0},
        "KHR_materials_ior":{"ior":1.33}}}"#;
    let s = resolve(&write_gltf(&dir, "s.gltf", m)).unwrap();
    let albedo = [0.572, 0.227, 0.075];
    let mfp = albedo.map(|a| 10.0 * f64::from(0.1f32) / (LN2 * (1.0 - 0.3 * single_scatter_albedo(a))));
    let want = Material::from_albedo_mfp("x", albedo, mfp, 1.33).unwrap();
    assert_same(s.material(), &want);
    // The draft's formula: 0 and 1 map to themselves, and it is increasing.
    assert!(single_scatter_albedo(0.0).abs() < 1e-4 && (single_scatter_albedo(1.0) - 1.0).abs() < 1e-4);
    assert!(single_scatter_albedo(0.5) > single_scatter_albedo(0.2));
}

#[test]
fn diffuse_transmission_alone_keeps_the_default_distance() {
    let dir = scratch("dt");
    let m = r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.9,0.5,0.2,1]},
        "extensions":{"KHR_materials_diffuse_transmission":{"diffuseTransmissionFactor":0.25,"diffuseTransmissionColorFactor":[1,0.9,0.85]}}}"#;
    let s = resolve(&write_gltf(&dir, "dt.gltf", m)).unwrap();
    let (_, mfp) = Material::by_name("skimmilk").unwrap().albedo_mfp();
    let want = Material::from_albedo_mfp("x", f32s([0.9, 0.5, 0.2]), mfp, 1.5).unwrap();
    assert_same(s.material(), &want);
    // Colours at the ends of 0..=1 are clamped into the accepted albedos, not refused.
    let m = r#"{"pbrMetallicRoughness":{"baseColorFactor":[1,0,0.5,1]},
        "extensions":{"KHR_materials_diffuse_transmission":{}}}"#;
    let s = resolve(&write_gltf(&dir, "ends.gltf", m)).unwrap();
    let want = Material::from_albedo_mfp("x", [0.999, 0.001, 0.5], mfp, 1.5).unwrap();
    assert_same(s.material(), &want);
}

#[test]
fn explicit_materials_win_and_plain_files_keep_the_default() {
    let dir = scratch("precedence");
    let m = r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.6,0.4,1]},
        "extensions":{"KHR_materials_volume":{"attenuationColor":[0.5,0.5,0.5],"attenuationDistance":0.1}}}"#;
    let path = write_gltf(&dir, "p.gltf", m);
    let flag = Overrides { mesh: Some(path.clone()), material: Some("marble".into()), ..Default::default() };
    assert_eq!(Scene::resolve(&flag).unwrap().material().name, "Marble");
    let colour =
        Overrides { mesh: Some(path.clone()), colour: Some(([0.5; 3], [1.0; 3])), ..Default::default() };
    assert_eq!(Scene::resolve(&colour).unwrap().material().name, "custom");
    // A scene file's material key wins over the mesh's; without the key the mesh's applies.
    std::fs::write(dir.join("with.toml"), "mesh = \"p.gltf\"\nmaterial = \"wax\"\n").unwrap();
    std::fs::write(dir.join("without.toml"), "mesh = \"p.gltf\"\n").unwrap();
    let scene = |name: &str| Overrides { scene: Some(dir.join(name)), ..Default::default() };
    assert_eq!(Scene::resolve(&scene("with.toml")).unwrap().material().name, "Wax");
    assert_eq!(Scene::resolve(&scene("without.toml")).unwrap().material().name, "glTF material 0");
    // No subsurface extension: the default material.
    let plain =
        write_gltf(&dir, "plain.gltf", r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.6,0.4,1]}}"#);
    assert_eq!(resolve(&plain).unwrap().material().name, "Skimmilk");
}

#[test]
fn malformed_values_are_one_line_errors_naming_file_and_value() {
    let dir = scratch("bad");
    let cases = [
        (r#"{"KHR_materials_volume":{"attenuationDistance":-2}}"#, "-2"),
        (r#"{"KHR_materials_volume":{"attenuationColor":[1.5,0.5,0.5],"attenuationDistance":1}}"#, "1.5"),
        (r#"{"KHR_materials_diffuse_transmission":{"diffuseTransmissionFactor":2}}"#, "2"),
        (r#"{"KHR_materials_diffuse_transmission":{"diffuseTransmissionFactor":"half"}}"#, "\"half\""),
        (r#"{"KHR_materials_diffuse_transmission":{"diffuseTransmissionColorFactor":[1,1]}}"#, "[1,1]"),
        (r#"{"KHR_materials_volume_scatter":{"multiscatterColor":[0.5,-0.1,0.5]}}"#, "-0.1"),
        (r#"{"KHR_materials_volume_scatter":{"scatterAnisotropy":1}}"#, "1"),
        (r#"{"KHR_materials_ior":{"ior":0.5}}"#, "0.5"),
        (r#"{"KHR_materials_volume_scatter":{"scatterAnisotropy":NaN}}"#, "not a valid glTF"),
    ];
    for (k, (extensions, value)) in cases.iter().enumerate() {
        let name = format!("bad{k}.gltf");
        let path = write_gltf(&dir, &name, &format!(r#"{{"extensions":{extensions}}}"#));
        let e = format!("{:#}", resolve(&path).err().unwrap_or_else(|| panic!("{extensions} was accepted")));
        assert!(e.contains(&name) && e.contains(value) && !e.contains('\n'), "{extensions}: {e}");
    }
}

/// On the command line: the note and the coefficients on stdout; a malformed value is one
/// `lucent: error:` line naming the file and the value, exit 1, and no image (the material is
/// resolved before any GPU work, so this needs no adapter).
#[test]
fn cli_prints_the_note_and_refuses_bad_values_in_one_line() {
    let dir = scratch("cli");
    let bad =
        write_gltf(&dir, "bad.gltf", r#"{"extensions":{"KHR_materials_volume":{"attenuationDistance":-3}}}"#);
    let out = dir.join("bad.png");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_lucent"))
        .args(["render", "--mesh"])
        .arg(&bad)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("lucent: error:")).collect();
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(errors[0].contains("bad.gltf") && errors[0].contains("attenuationDistance -3"), "{stderr}");
    assert!(!out.exists());
    // A good file: the note (printed before any GPU work, so whether or not an adapter exists).
    let good = write_gltf(
        &dir,
        "good.gltf",
        r#"{"extensions":{"KHR_materials_diffuse_transmission":{"diffuseTransmissionFactor":0.5}}}"#,
    );
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_lucent"))
        .args(["render", "--width", "64", "--height", "48", "--mesh"])
        .arg(&good)
        .arg("--out")
        .arg(dir.join("good.png"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let note = stdout
        .lines()
        .find(|l| l.contains("good.gltf: glTF material 0:"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(note.contains("diffuseTransmissionFactor 0.5") && note.contains("not modelled"), "{note}");
    assert!(stdout.contains("lucent: material: albedo 0.999,0.999,0.999"), "{stdout}");
}
