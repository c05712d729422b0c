//! Procedural meshes: spheres, cubes and a candle, all closed, 2-manifold, genus 0, with
//! counter-clockwise faces seen from outside (positive [`Mesh::signed_volume`]).
//!
//! The coarse base meshes ([`icosahedron`], [`cube_base`], [`candle_base`]) are the level-0
//! meshes from which the hierarchy builds its 4-to-1 (butterfly) subdivision levels, the
//! hierarchy of Mertens et al. 2003 §3.2. The finer generators are for tests, demos and
//! benchmarks. Lengths are mesh units; all shapes are centred on the origin except the candle,
//! which stands on the plane `y = 0` with its axis along +y.

use super::Mesh;
use glam::Vec3;
use std::collections::HashMap;
use std::f32::consts::{FRAC_PI_2, PI, TAU};

/// The regular icosahedron inscribed in the unit sphere: 12 vertices, 20 faces, 30 edges.
pub fn icosahedron() -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let positions = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| Vec3::from_array(p).normalize())
    .to_vec();
    let triangles = vec![
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
    Mesh::new(positions, triangles)
}

/// A unit sphere from the icosahedron by `subdivisions` rounds of 4-to-1 midpoint subdivision,
/// new vertices projected onto the sphere: `20 * 4^n` faces, `10 * 4^n + 2` vertices.
/// Nearly uniform triangles; `subdivisions` up to about 10 fits in `u32` indices.
pub fn icosphere(subdivisions: u32) -> Mesh {
    let mut mesh = icosahedron();
    for _ in 0..subdivisions {
        mesh = super::refine::split(&mesh, |a, b| (a + b).normalize());
    }
    mesh
}

/// A latitude-longitude unit sphere: `segments` (>= 3) around the y axis, `rings` (>= 2)
/// from pole to pole, one vertex at each pole. `segments * (rings - 1) + 2` vertices,
/// `2 * segments * (rings - 1)` faces. Smaller values are raised to the minimum.
pub fn uv_sphere(segments: u32, rings: u32) -> Mesh {
    let rings = rings.max(2);
    let profile: Vec<[f32; 2]> = (0..=rings)
        .map(|i| {
            let theta = PI - PI * i as f32 / rings as f32;
            // Exact zeros at the poles so that revolve() makes single pole vertices.
            let r = if i == 0 || i == rings { 0.0 } else { theta.sin() };
            [r, theta.cos()]
        })
        .collect();
    revolve(&profile, segments)
}

/// The cube `[-1, 1]^3` with each side split into `subdivisions x subdivisions` squares, each
/// cut into two triangles along the same diagonal: `6 n^2 + 2` vertices, `12 n^2` faces.
/// Edge and corner vertices are shared, so the mesh is closed. `0` is treated as `1`.
pub fn cube(subdivisions: u32) -> Mesh {
    let n = subdivisions.max(1);
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |ijk: [u32; 3]| -> u32 {
        *index.entry(ijk).or_insert_with(|| {
            positions.push(Vec3::from_array(ijk.map(|i| -1.0 + 2.0 * i as f32 / n as f32)));
            positions.len() as u32 - 1
        })
    };
    let mut triangles = Vec::with_capacity(12 * (n * n) as usize);
    // For the side with outward normal +e_a, (e_u, e_v) is a right-handed frame: e_u x e_v = e_a.
    for (a, u, v) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let corner = |di: u32, dj: u32| {
                        let mut p = [0; 3];
                        p[a] = side;
                        p[u] = i + di;
                        p[v] = j + dj;
                        p
                    };
                    let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)].map(&mut vertex);
                    if side == n {
                        triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
                    } else {
                        triangles.extend([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]);
                    }
                }
            }
        }
    }
    Mesh::new(positions, triangles)
}

/// The coarse cube `[-1, 1]^3`: 8 vertices, 12 triangles (two per side).
pub fn cube_base() -> Mesh {
    cube(1)
}

/// Shape of [`candle`]: a closed cylinder standing on `y = 0` along +y, its top edge rounded by
/// a quarter-circle bevel, with a thin cylindrical wick on the top ending in a point.
/// All lengths in mesh units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CandleParams {
    /// Radius of the body. Default 0.5.
    pub radius: f32,
    /// Height of the body (the flat top is at `y = height`). Default 2.0.
    pub height: f32,
    /// Radius of the rounded top edge; `0` gives a sharp edge. Clamped to
    /// `0.9 * min(radius - wick_radius, height)`. Default 0.1.
    pub bevel: f32,
    /// Radius of the wick; `0` (or `wick_height == 0`) gives a flat top without a wick.
    /// Clamped below `radius`. Default 0.03.
    pub wick_radius: f32,
    /// Height of the wick's side above the top; its tip rises `wick_radius` higher. Default 0.25.
    pub wick_height: f32,
    /// Vertices around the axis (>= 3). Default 32.
    pub segments: u32,
    /// Rings along the side between the bottom edge and the bevel (>= 1). Default 8.
    pub side_rings: u32,
    /// Steps along the bevel's quarter circle (>= 1). Default 4.
    pub bevel_steps: u32,
}

impl Default for CandleParams {
    fn default() -> Self {
        CandleParams {
            radius: 0.5,
            height: 2.0,
            bevel: 0.1,
            wick_radius: 0.03,
            wick_height: 0.25,
            segments: 32,
            side_rings: 8,
            bevel_steps: 4,
        }
    }
}

impl CandleParams {
    /// The coarse version used by [`candle_base`]: 6 segments, one side ring, a chamfered
    /// top edge (one bevel step), the default proportions.
    pub fn coarse() -> Self {
        CandleParams { segments: 6, side_rings: 1, bevel_steps: 1, ..Self::default() }
    }
}

/// A candle (see [`CandleParams`]): a surface of revolution around +y whose profile runs from
/// the centre of the bottom to the tip of the wick, so it is closed and genus 0.
pub fn candle(p: &CandleParams) -> Mesh {
    let radius = p.radius.max(1e-6);
    let height = p.height.max(1e-6);
    let wick_r = p.wick_radius.clamp(0.0, 0.5 * radius);
    let has_wick = wick_r > 0.0 && p.wick_height > 0.0;
    let bevel = p.bevel.clamp(0.0, 0.9 * (radius - if has_wick { wick_r } else { 0.0 }).min(height));

    let mut profile = vec![[0.0, 0.0], [radius, 0.0]];
    let side_top = height - bevel;
    let side_rings = p.side_rings.max(1);
    for i in 1..=side_rings {
        profile.push([radius, side_top * i as f32 / side_rings as f32]);
    }
    if bevel > 0.0 {
        let steps = p.bevel_steps.max(1);
        for i in 1..=steps {
            let a = FRAC_PI_2 * i as f32 / steps as f32;
            profile.push([radius - bevel + bevel * a.cos(), side_top + bevel * a.sin()]);
        }
    }
    if has_wick {
        profile.push([wick_r, height]);
        profile.push([wick_r, height + p.wick_height]);
        profile.push([0.0, height + p.wick_height + wick_r]);
    } else {
        profile.push([0.0, height]);
    }
    revolve(&profile, p.segments)
}

/// The coarse candle base mesh, `candle(&CandleParams::coarse())`: 32 vertices, 60 faces.
pub fn candle_base() -> Mesh {
    candle(&CandleParams::coarse())
}

/// Revolves a profile of `[r, y]` points around the y axis with `segments` (>= 3) steps.
/// The first and last points must lie on the axis (`r == 0`, they become single pole
/// vertices), the others off it (`r > 0`); `y` runs from the bottom pole to the top pole so
/// that faces come out counter-clockwise seen from outside.
fn revolve(profile: &[[f32; 2]], segments: u32) -> Mesh {
    debug_assert!(profile.len() >= 3);
    debug_assert!(profile[0][0] == 0.0 && profile[profile.len() - 1][0] == 0.0);
    let s = segments.max(3);
    let rings = &profile[1..profile.len() - 1];
    let mut positions = vec![Vec3::new(0.0, profile[0][1], 0.0)];
    for &[r, y] in rings {
        for j in 0..s {
            let phi = TAU * j as f32 / s as f32;
            positions.push(Vec3::new(r * phi.cos(), y, r * phi.sin()));
        }
    }
    let top = positions.len() as u32;
    positions.push(Vec3::new(0.0, profile[profile.len() - 1][1], 0.0));

    let ring = |i: usize, j: u32| 1 + i as u32 * s + j % s;
    let mut triangles = Vec::with_capacity(2 * s as usize * rings.len());
    for j in 0..s {
        triangles.push([0, ring(0, j), ring(0, j + 1)]);
    }
    for i in 0..rings.len() - 1 {
        for j in 0..s {
            let (a, b) = (ring(i, j), ring(i, j + 1));
            let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
            triangles.extend([[a, c, b], [b, c, d]]);
        }
    }
    let last = rings.len() - 1;
    for j in 0..s {
        triangles.push([top, ring(last, j + 1), ring(last, j)]);
    }
    Mesh::new(positions, triangles)
}
