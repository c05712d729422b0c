//! Butterfly subdivision hierarchy (Mertens §5.1.2): interpolation, exact 4-to-1 covering and
//! the closed-manifold requirement.

use glam::Vec3;
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
    let h = &s.hierarchy;
    let mut checked = 0;
    for (i, n) in h.nodes.iter().enumerate() {
        let poly = &h.polygon_vertices[h.polygon_start[i] as usize..h.polygon_start[i + 1] as usize];
        if n.child_count != 4 || poly.len() != 3 {
            continue;
        }
        // The four children are the corner triangles and the middle one: their corners are the
        // parent's corners plus three shared edge vertices, and the parent's corners each
        // appear in exactly one child.
        let kids: Vec<&[u32]> = n
            .children()
            .iter()
            .map(|&c| {
                let c = c as usize;
                &h.polygon_vertices[h.polygon_start[c] as usize..h.polygon_start[c + 1] as usize]
            })
            .collect();
        for &corner in poly {
            assert_eq!(kids.iter().filter(|k| k.contains(&corner)).count(), 1);
        }
        let mut all: Vec<u32> = kids.iter().flat_map(|k| k.iter().copied()).collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 6);
        // Areas add up.
        let a: f32 = n.children().iter().map(|&c| h.geom[c as usize].area).sum();
        assert!((a - h.geom[i].area).abs() <= 1e-4 * a);
        checked += 1;
    }
    assert_eq!(checked, 8 + 32 + 128);
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
