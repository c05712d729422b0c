//! Small meshes for the irradiance tests, built here so the tests depend only on the `Mesh`
//! type (faces counter-clockwise seen from outside).
#![allow(dead_code)]

use glam::Vec3;
use lucent_core::mesh::Mesh;
use std::f32::consts::PI;

/// A UV sphere of `radius` around `center` with `segments` around and `rings` from pole to pole.
pub fn uv_sphere(center: Vec3, radius: f32, segments: u32, rings: u32) -> Mesh {
    let mut positions = vec![center + Vec3::Y * radius];
    for r in 1..rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = 2.0 * PI * s as f32 / segments as f32;
            positions.push(
                center + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()),
            );
        }
    }
    positions.push(center - Vec3::Y * radius);
    let south = positions.len() as u32 - 1;
    let ring = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, ring(1, s + 1), ring(1, s)]);
        triangles.push([south, ring(rings - 1, s), ring(rings - 1, s + 1)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (ring(r, s), ring(r, s + 1), ring(r + 1, s), ring(r + 1, s + 1));
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    Mesh::new(positions, triangles)
}

/// A square in the plane `y = 0`, `size` wide, centred on the origin, facing +Y, split into
/// `n x n` cells of two triangles.
pub fn plane(size: f32, n: u32) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(Vec3::new(
                size * (i as f32 / n as f32 - 0.5),
                0.0,
                size * (j as f32 / n as f32 - 0.5),
            ));
        }
    }
    let v = |i: u32, j: u32| j * (n + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from +Y.
            triangles.push([v(i, j), v(i, j + 1), v(i + 1, j + 1)]);
            triangles.push([v(i, j), v(i + 1, j + 1), v(i + 1, j)]);
        }
    }
    Mesh::new(positions, triangles)
}

/// A torus around +Y with `major` and `minor` radii, `n x n` quads: `2 n²` triangles.
pub fn torus(major: f32, minor: f32, n: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..n {
        let u = 2.0 * PI * i as f32 / n as f32;
        for j in 0..n {
            let v = 2.0 * PI * j as f32 / n as f32;
            let r = major + minor * v.cos();
            positions.push(Vec3::new(r * u.cos(), minor * v.sin(), r * u.sin()));
        }
    }
    let idx = |i: u32, j: u32| (i % n) * n + j % n;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1));
            triangles.push([a, c, d]);
            triangles.push([a, d, b]);
        }
    }
    Mesh::new(positions, triangles)
}

/// `a` and `b` in one mesh (`a`'s faces first).
pub fn merge(a: &Mesh, b: &Mesh) -> Mesh {
    let off = a.positions.len() as u32;
    let mut m = a.clone();
    m.positions.extend(&b.positions);
    m.triangles.extend(b.triangles.iter().map(|t| t.map(|i| i + off)));
    m
}

/// Twists the mesh about +Y by `radians_per_unit * y`.
pub fn twist(mesh: &mut Mesh, radians_per_unit: f32) {
    for p in &mut mesh.positions {
        let (s, c) = (radians_per_unit * p.y).sin_cos();
        *p = Vec3::new(c * p.x - s * p.z, p.y, s * p.x + c * p.z);
    }
}
