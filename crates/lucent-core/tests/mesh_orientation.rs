//! Inside-out meshes (issue 50, item 4): a closed mesh whose every face points in (negative
//! signed volume) is flipped on load and says so once; an open mesh keeps its winding.

use lucent_core::mesh::io::{MeshFormat, parse_mesh};
use lucent_core::mesh::{Mesh, embedded, generate};

/// OFF keeps the file's vertex order (OBJ reorders by first use), so a flipped mesh can be
/// compared with the original face for face.
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

fn inverted(m: &Mesh) -> Mesh {
    Mesh::new(m.positions.clone(), m.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect())
}

fn load(m: &Mesh) -> (Mesh, lucent_core::mesh::MeshReport) {
    parse_mesh(off_text(m).as_bytes(), MeshFormat::Off, "test.off").unwrap()
}

fn inside_out_warnings(r: &lucent_core::mesh::MeshReport) -> usize {
    r.warnings().iter().filter(|w| w.contains("inside out")).count()
}

#[test]
fn inside_out_sphere_is_flipped_to_the_right_mesh_with_one_warning() {
    let right = generate::icosphere(3);
    assert!(right.signed_volume() > 0.0);
    let (loaded, report) = load(&inverted(&right));
    assert!(report.flipped_inside_out, "{report}");
    assert_eq!(loaded.triangles, right.triangles, "every face flipped back");
    assert_eq!(loaded.positions, right.positions);
    assert!(loaded.signed_volume() > 0.0);
    assert_eq!(inside_out_warnings(&report), 1, "{:?}", report.warnings());
    assert!(report.to_string().contains("flipped inside out"), "{report}");
}

#[test]
fn inside_out_bunny_loads_as_the_right_bunny() {
    let right = embedded::bunny();
    let (loaded, report) = load(&inverted(&right));
    assert!(report.flipped_inside_out);
    assert_eq!(loaded.triangles, right.triangles);
    assert!((loaded.signed_volume() - right.signed_volume()).abs() <= 1e-12 * right.signed_volume().abs());
}

#[test]
fn a_rightly_wound_mesh_is_left_alone() {
    let right = generate::icosphere(3);
    let (loaded, report) = load(&right);
    assert!(!report.flipped_inside_out);
    assert_eq!(loaded.triangles, right.triangles);
    assert_eq!(inside_out_warnings(&report), 0);
}

#[test]
fn an_open_mesh_keeps_its_winding_even_with_negative_signed_volume() {
    let mut open = inverted(&generate::icosphere(3));
    open.triangles.truncate(open.triangles.len() - 5);
    assert!(open.signed_volume() < 0.0, "the test mesh must look inside out by volume");
    let (loaded, report) = load(&open);
    assert!(report.boundary_edges > 0);
    assert!(!report.flipped_inside_out);
    assert_eq!(loaded.triangles, open.triangles, "an open mesh's winding is kept");
    assert_eq!(inside_out_warnings(&report), 0);
}

#[test]
fn an_inside_out_textured_obj_keeps_each_corner_with_its_uv() {
    // A unit cube (the icosphere's first cousin with eight corners) wound inside out, with a
    // distinct UV per vertex: after the flip each vertex must still carry its own UV.
    let cube = generate::cube(1);
    assert_eq!(cube.positions.len(), 8);
    let mut obj = String::new();
    for (k, p) in cube.positions.iter().enumerate() {
        obj += &format!("v {} {} {}\nvt {} 0\n", p.x, p.y, p.z, k as f32 / 8.0);
    }
    for t in &inverted(&cube).triangles {
        let [a, b, c] = t.map(|i| i + 1);
        obj += &format!("f {a}/{a} {b}/{b} {c}/{c}\n");
    }
    let dir = std::env::temp_dir().join(format!("lucent-orientation-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("cube.obj");
    std::fs::write(&path, &obj).unwrap();
    let (mesh, report, texture) = lucent_core::mesh::load_textured_mesh(&path).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(report.flipped_inside_out, "{report}");
    assert!(mesh.signed_volume() > 0.0);
    let texture = texture.expect("the OBJ has UVs");
    // Vertex k of the cube carries u = k / 8.
    let u_of = |p: glam::Vec3| cube.positions.iter().position(|&q| q == p).unwrap() as f32 / 8.0;
    for (t, uvs) in mesh.triangles.iter().zip(&texture.corner_uvs) {
        for k in 0..3 {
            assert_eq!(uvs[k].x, u_of(mesh.positions[t[k] as usize]), "face {t:?}");
        }
    }
}
