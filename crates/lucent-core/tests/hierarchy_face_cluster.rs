//! Face cluster hierarchy (Mertens §5.1.1): structure invariants on closed, open, genus-1 and
//! multi-component meshes, and refit against a rebuild.

use glam::Vec3;
use lucent_core::hierarchy::{Hierarchy, NO_NODE, face_cluster};
use lucent_core::mesh::Mesh;

/// A torus (genus 1) with `nu x nv` quads split into triangles.
fn torus(nu: u32, nv: u32) -> Mesh {
    let (big, small) = (1.0f32, 0.35f32);
    let mut pos = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (u, v) =
                (i as f32 / nu as f32 * std::f32::consts::TAU, j as f32 / nv as f32 * std::f32::consts::TAU);
            let r = big + small * v.cos();
            pos.push(Vec3::new(r * u.cos(), small * v.sin(), r * u.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut tris = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            tris.push([id(i, j), id(i, j + 1), id(i + 1, j)]);
            tris.push([id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)]);
        }
    }
    Mesh::new(pos, tris)
}

/// An open square grid of `n x n` quads in the plane y = 0, offset by `o`.
fn grid(n: u32, o: Vec3) -> Mesh {
    let mut pos = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            pos.push(o + Vec3::new(i as f32 / n as f32, 0.0, j as f32 / n as f32));
        }
    }
    let id = |i: u32, j: u32| i * (n + 1) + j;
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            tris.push([id(i, j), id(i, j + 1), id(i + 1, j)]);
            tris.push([id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)]);
        }
    }
    Mesh::new(pos, tris)
}

fn merge(a: &Mesh, b: &Mesh) -> Mesh {
    let off = a.positions.len() as u32;
    let mut m = a.clone();
    m.positions.extend_from_slice(&b.positions);
    m.triangles.extend(b.triangles.iter().map(|t| t.map(|v| v + off)));
    m
}

/// Every invariant of a flat preorder hierarchy.
fn check_structure(mesh: &Mesh, h: &Hierarchy) {
    let n = mesh.triangles.len();
    assert_eq!(h.leaf_count(), n);
    // The permutation covers every face exactly once.
    let mut seen = vec![false; n];
    for &f in &h.leaf_faces {
        assert!(!seen[f as usize], "face {f} twice");
        seen[f as usize] = true;
    }
    assert!(seen.iter().all(|&s| s));
    let root = &h.nodes[0];
    assert_eq!(root.parent, NO_NODE);
    assert_eq!((root.leaf_start, root.leaf_end), (0, n as u32));
    assert_eq!(root.subtree_end as usize, h.len());
    for (i, node) in h.nodes.iter().enumerate() {
        if node.is_leaf() {
            assert_eq!(node.leaf_count(), 1);
            let f = h.leaf_faces[node.leaf_start as usize];
            assert_eq!(h.face_node[f as usize] as usize, i);
            continue;
        }
        assert!(node.child_count >= 2);
        // Children partition the parent's leaf range and subtree range, in order.
        let mut leaf = node.leaf_start;
        let mut next = i as u32 + 1;
        for &c in node.children() {
            let cn = &h.nodes[c as usize];
            assert_eq!(cn.parent as usize, i);
            assert_eq!(cn.level, node.level + 1);
            assert_eq!(c, next);
            assert_eq!(cn.leaf_start, leaf);
            leaf = cn.leaf_end;
            next = cn.subtree_end;
        }
        assert_eq!(leaf, node.leaf_end);
        assert_eq!(next, node.subtree_end);
        // Area is the sum of the faces' areas.
        let a: f64 = (node.leaf_start..node.leaf_end)
            .map(|p| mesh.face_area(h.leaf_faces[p as usize] as usize) as f64)
            .sum();
        assert!((h.geom[i].area as f64 - a).abs() <= 1e-4 * a.max(1e-12));
        // The bounding sphere contains every vertex of the cluster.
        let g = &h.geom[i];
        for p in node.leaf_start..node.leaf_end {
            for v in mesh.corners(h.leaf_faces[p as usize] as usize) {
                assert!((v - g.midpoint).length() <= g.radius * (1.0 + 1e-5) + 1e-6);
            }
        }
        assert!(g.flatness() <= 1.0 + 1e-5 && g.flatness() >= 0.0);
    }
}

#[test]
fn torus_covers_every_face_once() {
    let mesh = torus(40, 20);
    let h = face_cluster::build(&mesh);
    check_structure(&mesh, &h);
    // A closed surface has no single boundary loop at the root, and a curved one is far from
    // flat there.
    assert!(h.polygon(0).is_empty());
    assert!(h.geom[0].flatness() < 0.1);
    // Balanced enough: depth within a small factor of log2(N).
    let log2n = (mesh.triangles.len() as f64).log2();
    assert!((h.depth() as f64) < 3.0 * log2n, "depth {}", h.depth());
}

#[test]
fn open_mesh_and_components() {
    let mesh = merge(&grid(12, Vec3::ZERO), &grid(7, Vec3::new(3.0, 0.5, 0.0)));
    let h = face_cluster::build(&mesh);
    check_structure(&mesh, &h);
    // Each component's faces form one subtree below the root (components are merged last).
    let root = &h.nodes[0];
    assert_eq!(root.child_count, 2);
    let counts: Vec<u32> = root.children().iter().map(|&c| h.nodes[c as usize].leaf_count()).collect();
    assert!(counts.contains(&(2 * 144)) && counts.contains(&(2 * 49)));
    // A planar grid cluster is flat and its polygon bounds the same area as its faces.
    for (i, g) in h.geom.iter().enumerate() {
        assert!((g.flatness() - 1.0).abs() < 1e-4);
        if !h.polygon(i).is_empty() {
            assert!(
                (g.polygon_area - g.area).abs() <= 1e-4 * g.area,
                "cluster {i}: polygon {} vs area {}",
                g.polygon_area,
                g.area
            );
        }
    }
    // The first grid's cluster is a square: its boundary loop has 4 * 12 edges.
    let c =
        root.children().iter().find(|&&c| h.nodes[c as usize].leaf_count() == 288).copied().unwrap() as usize;
    assert_eq!(h.polygon(c).len(), 48);
}

#[test]
fn refit_matches_rebuild() {
    let mesh = torus(30, 16);
    let mut h = face_cluster::build(&mesh);
    let mut moved = mesh.clone();
    for p in moved.positions.iter_mut() {
        // A twist about y and a bump: positions change, topology does not.
        let a = 0.8 * p.y;
        let (s, c) = a.sin_cos();
        *p = Vec3::new(c * p.x + s * p.z, p.y * 1.3, -s * p.x + c * p.z)
            + Vec3::Y * 0.2 * (-(p.x * p.x + p.z * p.z - 1.0).powi(2) * 8.0).exp();
    }
    h.refit(&moved);
    // A rebuild over the same topology with the same merge order: build the tree on the
    // original mesh again, then compute geometry directly on the moved mesh.
    let fresh = face_cluster::build(&mesh);
    let mut direct = fresh.clone();
    direct.refit(&moved);
    for i in 0..h.len() {
        let (a, b) = (&h.geom[i], &direct.geom[i]);
        assert!((a.midpoint - b.midpoint).length() < 1e-5);
        assert!((a.area - b.area).abs() < 1e-5 * b.area.max(1e-6));
    }
    // And against first principles for every cluster: area, midpoint, normal, flatness.
    for (i, node) in h.nodes.iter().enumerate() {
        let mut area = 0.0f64;
        let mut mid = glam::DVec3::ZERO;
        let mut nsum = glam::DVec3::ZERO;
        for p in node.leaf_start..node.leaf_end {
            let f = h.leaf_faces[p as usize] as usize;
            let a = moved.face_area(f) as f64;
            area += a;
            mid += a * moved.face_centroid(f).as_dvec3();
            nsum += a * moved.face_normal(f).as_dvec3();
        }
        let g = &h.geom[i];
        assert!((g.area as f64 - area).abs() < 1e-4 * area);
        assert!((g.midpoint.as_dvec3() - mid / area).length() < 1e-4);
        assert!((g.projected_area as f64 - nsum.length()).abs() < 1e-3 * area);
        if nsum.length() > 1e-3 * area {
            assert!((g.normal.as_dvec3() - nsum.normalize()).length() < 1e-3);
        }
    }
}

/// A local move refits only the clusters it touches (the incremental solver's refit) and gives
/// exactly the geometry and boundary polygons of a full refit.
#[test]
fn local_refit_equals_full_refit() {
    let mesh = torus(30, 16);
    let mut local = face_cluster::build(&mesh);
    let mut moved = mesh.clone();
    for p in moved.positions.iter_mut().filter(|p| p.x > 0.9 && p.z.abs() < 0.4) {
        *p += Vec3::new(0.05, 0.1 * p.z, -0.02);
    }
    let moved_vertex: Vec<bool> = mesh.positions.iter().zip(&moved.positions).map(|(a, b)| a != b).collect();
    assert!(moved_vertex.iter().filter(|&&m| m).count() > 10);
    let mut changed = vec![false; local.len()];
    for i in (0..local.len()).rev() {
        let n = local.nodes[i];
        if n.is_leaf() {
            let t = moved.triangles[local.leaf_faces[n.leaf_start as usize] as usize];
            changed[i] |= t.iter().any(|&v| moved_vertex[v as usize]);
        }
        if n.parent != NO_NODE {
            changed[n.parent as usize] |= changed[i];
        }
    }
    assert!(changed.iter().filter(|&&c| !c).count() > local.len() / 2, "the move is local");
    let mut full = local.clone();
    full.refit(&moved);
    local.refit_changed(&moved, &changed);
    assert_eq!(local.geom, full.geom);
    for i in 0..local.len() {
        assert_eq!(local.polygon(i), full.polygon(i), "cluster {i}");
    }
}
