//! Test scenes: small generated meshes whose per-vertex radiance is a closed-form function, so
//! the images depend only on the GPU path (raster, Fresnel, tone map, read-back), not on the
//! solvers.

#![allow(dead_code)]

use glam::Vec3;

/// The square `[-1, 1]²` in the plane `z = 0`, facing `+z` (counter-clockwise from there):
/// positions, normals and its two triangles. Vertices 0 and 3 make the left edge (`x = -1`).
pub fn square() -> ([Vec3; 4], [Vec3; 4], [[u32; 3]; 2]) {
    let pos = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    (pos, [Vec3::Z; 4], [[0, 1, 2], [0, 2, 3]])
}

/// A unit icosphere subdivided `levels` times (20 * 4^levels faces), counter-clockwise seen
/// from outside. Returns positions (also the unit normals) and triangles.
pub fn icosphere(levels: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let m = lucent_core::mesh::generate::icosphere(levels);
    (m.positions, m.triangles)
}

/// A torus around the y axis (major radius `r_major`, minor `r_minor`), `nu` x `nv` quads.
/// Returns positions, unit normals and triangles (counter-clockwise from outside).
pub fn torus(r_major: f32, r_minor: f32, nu: u32, nv: u32) -> (Vec<Vec3>, Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::new();
    let mut nrm = Vec::new();
    for i in 0..nu {
        let u = i as f32 / nu as f32 * std::f32::consts::TAU;
        for j in 0..nv {
            let v = j as f32 / nv as f32 * std::f32::consts::TAU;
            let n = Vec3::new(u.cos() * v.cos(), v.sin(), u.sin() * v.cos());
            let c = Vec3::new(u.cos(), 0.0, u.sin()) * r_major;
            pos.push(c + n * r_minor);
            nrm.push(n);
        }
    }
    let idx = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut tris = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            tris.push([a, c, b]);
            tris.push([a, d, c]);
        }
    }
    (pos, nrm, tris)
}
