//! Butterfly subdivision hierarchy (Mertens §5.1.2): interpolation, exact 4-to-1 covering and
//! the closed-manifold requirement.

mod hierarchy_util;

use glam::Vec3;
use hierarchy_util::check_quad_tree;
use lucent_core::hierarchy::subdivision::{SubdivisionError, butterfly, octahedron};
use lucent_core::mesh::Mesh;

#[test]
fn interpolates_and_children_cover_parents() {
    let base = octahedron(Vec3::new(1.0, 1.5, 0.8));
    let s = butterfly(&base, 3).unwrap();
    assert_eq!(s.mesh.triangles.len(), 8 * 64);
    // Interpolating: the coarse vertices keep their index and position.
    for (i, p) in base.positions.iter().enumerate() {
        assert_eq!(s.mesh.positions[i], *p);
    }
    // Each parent is covered exactly by its corner triangles and the middle one, and the
    // areas add up.
    assert_eq!(check_quad_tree(&s.hierarchy), 8 + 32 + 128);
    // The limit surface of an octahedron is smooth: each level moves new vertices less.
    let s4 = butterfly(&base, 4).unwrap();
    for (i, p) in s.mesh.positions.iter().enumerate() {
        assert_eq!(s4.mesh.positions[i], *p, "level-3 vertices are kept at level 4");
    }
}

#[test]
fn regular_stencil_reproduces_a_plane() {
    // The butterfly weights sum to one and reproduce linear functions: a closed mesh whose
    // vertices lie on two parallel planes keeps each new vertex between its edge's planes.
    let base = octahedron(Vec3::ONE);
    let s = butterfly(&base, 2).unwrap();
    for p in &s.mesh.positions {
        assert!(p.length() < 1.2 && p.length() > 0.5, "{p}");
    }
}

#[test]
fn open_mesh_is_rejected() {
    let m = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
    assert!(matches!(butterfly(&m, 1), Err(SubdivisionError::NotClosedManifold(_, _))));
    assert_eq!(butterfly(&Mesh::default(), 1).unwrap_err(), SubdivisionError::Empty);
}
