//! Test scenes: small generated meshes whose per-vertex radiance is a closed-form function, so
//! the images depend only on the GPU path (raster, Fresnel, tone map, read-back), not on the
//! solvers.

#![allow(dead_code)]

use glam::Vec3;
use lucent_gpu::GpuContext;

/// The context, or a failure that says what is missing (tests must not skip silently).
pub fn ctx() -> GpuContext {
    GpuContext::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

/// A unit icosphere subdivided `levels` times (20 * 4^levels faces), counter-clockwise seen
/// from outside. Returns positions (also the unit normals) and triangles.
pub fn icosphere(levels: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, p: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push(((p[a as usize] + p[b as usize]) * 0.5).normalize());
                (p.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut p);
            let bc = midpoint(b, c, &mut p);
            let ca = midpoint(c, a, &mut p);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    (p, tris)
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
