//! Subdivision hierarchy (Mertens et al. 2003, §5.1.2): interpolating 4-to-1 *modified
//! butterfly* subdivision (Dyn, Levin & Gregory 1990; Zorin, Schröder & Sweldens 1996) of a
//! closed coarse base mesh. Every coarse triangle is split into four (three corner triangles
//! and the middle one), the coarse vertices never move (the scheme interpolates), and each new
//! edge vertex is
//!
//! * between two valence-6 vertices: the 8-point butterfly
//!   `1/2 (a + b) + 1/8 (c + d) - 1/16 (e1 + e2 + e3 + e4)`;
//! * next to one extraordinary vertex `v` of valence `k` (ring `v_0 = ` the other endpoint,
//!   `v_1 .. v_{k-1}` counter-clockwise): `3/4 v + Σ s_j v_j` with `s_j = (1/4 + cos(2πj/k) +
//!   1/2 cos(4πj/k)) / k` for `k >= 5`, `(5/12, -1/12, -1/12)` for `k = 3` and
//!   `(3/8, 0, -1/8, 0)` for `k = 4`;
//! * between two extraordinary vertices: the average of both stencils.
//!
//! The result is the fine mesh and the quad-tree hierarchy over it whose clusters are the
//! triangles of every level; a cluster's polygon is its coarse triangle (three fine-mesh
//! vertices: "every cluster is represented by exactly one triangle", §5.1.3). The base faces
//! are grouped four by four (in order) up to a single root. Shrink-wrapping arbitrary closed
//! meshes onto the same 4-to-1 connectivity (§5.1.2's second method) is in
//! [`super::shrink_wrap`].

use super::{Hierarchy, RawTree};
use crate::mesh::Mesh;
use glam::Vec3;
use std::collections::HashMap;

/// Why a base mesh cannot be subdivided.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SubdivisionError {
    /// The base mesh has no faces.
    #[error("the base mesh has no faces")]
    Empty,
    /// An edge is not shared by exactly two consistently oriented faces.
    #[error("the base mesh is not a closed, consistently oriented manifold (edge {0}-{1})")]
    NotClosedManifold(u32, u32),
}

/// A subdivided mesh with its quad-tree hierarchy.
#[derive(Clone, Debug)]
pub struct Subdivided {
    /// The finest mesh (`base faces x 4^levels` triangles).
    pub mesh: Mesh,
    /// The hierarchy whose leaves are `mesh`'s faces.
    pub hierarchy: Hierarchy,
}

/// Subdivides `base` `levels` times with the modified butterfly scheme.
pub fn butterfly(base: &Mesh, levels: u32) -> Result<Subdivided, SubdivisionError> {
    split_4_to_1(base.positions.clone(), &base.triangles, levels, edge_point, |_, _| {})
}

/// The 4-to-1 split shared by [`butterfly`] and shrink-wrapping: subdivides the closed mesh
/// `(positions, base)` `levels` times, placing each new edge vertex with
/// `new_vertex(positions, ring_map, a, b)` and calling `after_level(positions, faces)` once the
/// faces of each finer level exist (a scheme that moves vertices does it there). The hierarchy
/// (one cluster per triangle of every level, base faces grouped four by four up to one root)
/// is built from the final positions, so every caller gets the same tree for the same base.
pub(crate) fn split_4_to_1(
    mut positions: Vec<Vec3>,
    base: &[[u32; 3]],
    levels: u32,
    mut new_vertex: impl FnMut(&[Vec3], &HashMap<(u32, u32), u32>, u32, u32) -> Vec3,
    mut after_level: impl FnMut(&mut Vec<Vec3>, &[[u32; 3]]),
) -> Result<Subdivided, SubdivisionError> {
    if base.is_empty() {
        return Err(SubdivisionError::Empty);
    }
    let mut faces: Vec<[u32; 3]> = base.to_vec();
    // Raw tree nodes: one per face of every level.
    let mut children: Vec<Vec<u32>> = vec![Vec::new(); faces.len()];
    let mut polygon: Vec<Vec<u32>> = faces.iter().map(|f| f.to_vec()).collect();
    let mut level_nodes: Vec<u32> = (0..faces.len() as u32).collect();
    let base_nodes = level_nodes.clone();
    for _ in 0..levels {
        let next_of = ring_map(&faces)?;
        let mut edge_vertex: HashMap<(u32, u32), u32> = HashMap::with_capacity(faces.len() * 2);
        let mut new_faces = Vec::with_capacity(faces.len() * 4);
        let mut new_nodes = Vec::with_capacity(faces.len() * 4);
        for (fi, &[a, b, c]) in faces.iter().enumerate() {
            let mut mid = |x: u32, y: u32| -> u32 {
                let key = (x.min(y), x.max(y));
                *edge_vertex.entry(key).or_insert_with(|| {
                    let p = new_vertex(&positions, &next_of, x, y);
                    positions.push(p);
                    positions.len() as u32 - 1
                })
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            let parent = level_nodes[fi];
            for t in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
                let node = children.len() as u32;
                children.push(Vec::new());
                polygon.push(t.to_vec());
                children[parent as usize].push(node);
                new_faces.push(t);
                new_nodes.push(node);
            }
        }
        faces = new_faces;
        level_nodes = new_nodes;
        after_level(&mut positions, &faces);
    }
    let mut face = vec![u32::MAX; children.len()];
    for (f, &node) in level_nodes.iter().enumerate() {
        face[node as usize] = f as u32;
    }
    // Group the base faces four by four up to one root (no polygon for these groups).
    let mut tops = base_nodes;
    while tops.len() > 1 {
        let mut up = Vec::new();
        for group in tops.chunks(4) {
            if group.len() == 1 {
                up.push(group[0]);
                continue;
            }
            let node = children.len() as u32;
            children.push(group.to_vec());
            polygon.push(Vec::new());
            face.push(u32::MAX);
            up.push(node);
        }
        tops = up;
    }
    let mesh = Mesh::new(positions, faces);
    let hierarchy =
        Hierarchy::from_raw(&mesh, RawTree { children, face, polygon: Some(polygon), root: tops[0] });
    Ok(Subdivided { mesh, hierarchy })
}

/// `(v, x) -> y` for every face corner `(v, x, y)` (counter-clockwise): walking `x -> y` turns
/// around `v`. Fails unless every directed edge has exactly one twin.
fn ring_map(faces: &[[u32; 3]]) -> Result<HashMap<(u32, u32), u32>, SubdivisionError> {
    let mut next = HashMap::with_capacity(faces.len() * 3);
    for &[a, b, c] in faces {
        for (v, x, y) in [(a, b, c), (b, c, a), (c, a, b)] {
            if next.insert((v, x), y).is_some() {
                return Err(SubdivisionError::NotClosedManifold(v, x));
            }
        }
    }
    for &(v, x) in next.keys() {
        if !next.contains_key(&(x, v)) {
            return Err(SubdivisionError::NotClosedManifold(v, x));
        }
    }
    Ok(next)
}

/// The one-ring of `v` starting at its neighbour `x`, counter-clockwise.
fn ring(next: &HashMap<(u32, u32), u32>, v: u32, x: u32) -> Vec<u32> {
    let mut out = vec![x];
    let mut cur = x;
    loop {
        cur = next[&(v, cur)];
        if cur == x || out.len() > 64 {
            break;
        }
        out.push(cur);
    }
    out
}

/// The extraordinary-vertex stencil of `v` for the edge towards `ring[0]`.
fn vertex_stencil(p: &[Vec3], v: u32, ring: &[u32]) -> Vec3 {
    let k = ring.len();
    let weights: Vec<f32> = match k {
        3 => vec![5.0 / 12.0, -1.0 / 12.0, -1.0 / 12.0],
        4 => vec![3.0 / 8.0, 0.0, -1.0 / 8.0, 0.0],
        _ => (0..k)
            .map(|j| {
                let t = std::f32::consts::TAU * j as f32 / k as f32;
                (0.25 + t.cos() + 0.5 * (2.0 * t).cos()) / k as f32
            })
            .collect(),
    };
    let mut q = 0.75 * p[v as usize];
    for (w, &u) in weights.iter().zip(ring) {
        q += *w * p[u as usize];
    }
    q
}

/// The new vertex on edge `a`-`b`.
fn edge_point(p: &[Vec3], next: &HashMap<(u32, u32), u32>, a: u32, b: u32) -> Vec3 {
    let ra = ring(next, a, b);
    let rb = ring(next, b, a);
    match (ra.len() == 6, rb.len() == 6) {
        (true, true) => {
            let g = |i: u32| p[i as usize];
            0.5 * (g(a) + g(b)) + 0.125 * (g(ra[1]) + g(ra[5]))
                - 0.0625 * (g(ra[2]) + g(ra[4]) + g(rb[2]) + g(rb[4]))
        }
        (false, true) => vertex_stencil(p, a, &ra),
        (true, false) => vertex_stencil(p, b, &rb),
        (false, false) => 0.5 * (vertex_stencil(p, a, &ra) + vertex_stencil(p, b, &rb)),
    }
}

/// The regular octahedron (8 faces, all vertices of valence 4) scaled by `scale` per axis: a
/// base mesh whose `L`-times subdivision has `8 * 4^L` faces (2048, 8192, 32768, 131072 for
/// `L = 4..7`, close to Mertens' table 3 sizes).
pub fn octahedron(scale: Vec3) -> Mesh {
    let pos = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].iter().map(|&p| p * scale).collect();
    let tris = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    Mesh::new(pos, tris)
}
