//! Mesh hierarchies for the hierarchical boundary element solve (Mertens et al. 2003, §3.2 and
//! §5.1).
//!
//! A [`Hierarchy`] is a tree of *clusters* over the faces of a [`Mesh`]: the leaves are the
//! original faces and every inner cluster is the union of its children (2 for a face-cluster
//! hierarchy, §5.1.1; 4 for a 4-to-1 subdivision hierarchy, §5.1.2). The tree is stored flat:
//!
//! * clusters are numbered in *preorder* (root = 0, a cluster's subtree is the index range
//!   `i..nodes[i].subtree_end`), so a subtree's per-cluster data is one contiguous slice and
//!   parallel passes split the arrays with `split_at_mut` instead of locking;
//! * the faces are reordered so that every cluster covers a contiguous range of *leaf
//!   positions* (`leaf_start..leaf_end`); [`Hierarchy::leaf_faces`] maps a leaf position to the
//!   original face index.
//!
//! Each cluster carries the data the refinement oracle and the form factor read (§5.1.1, §5.2):
//! area, midpoint (area-weighted centroid), area-weighted normal, the curvature measure `A'/A`
//! (projected over true area), a bounding-sphere radius and the cluster's *projected boundary
//! polygon*: the boundary edges of the cluster (interior edges cancel in the edge-based form
//! factor, §4.2) projected onto the plane through the midpoint with the averaged normal. A leaf's
//! polygon is its triangle. [`Hierarchy::refit`] recomputes all of this bottom-up after the mesh
//! deforms, without touching the topology (the point of §3.3's "hierarchy rebuilding").

use crate::mesh::Mesh;
use glam::Vec3;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

pub mod face_cluster;
pub mod shrink_wrap;
pub mod subdivision;

/// Marks "no cluster" (the root's parent, unused child slots).
pub const NO_NODE: u32 = u32::MAX;

/// The most boundary vertices a cluster polygon may have. Clusters with longer boundaries (or
/// with no single boundary loop: closed surfaces, holes, pinches) get no polygon, and the
/// oracle opens them instead of integrating over them with the form factor.
pub const MAX_POLYGON_VERTICES: usize = 256;

/// Subtrees with more leaves than this are processed in parallel by the recursive passes.
pub(crate) const PAR_LEAVES: u32 = 2048;

/// Topology of one cluster (fixed for the life of the hierarchy).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Node {
    /// Parent cluster, [`NO_NODE`] for the root.
    pub parent: u32,
    /// Child clusters (first `child_count` entries; the rest are [`NO_NODE`]).
    pub children: [u32; 4],
    /// Number of children: 0 for a leaf (an original face), 2 or 4 otherwise (the size-balanced
    /// merge of components may add binary nodes to a quad tree).
    pub child_count: u8,
    /// Depth below the root (root = 0).
    pub level: u16,
    /// One past the last cluster of this cluster's subtree (preorder numbering).
    pub subtree_end: u32,
    /// First leaf position covered by this cluster.
    pub leaf_start: u32,
    /// One past the last leaf position covered by this cluster.
    pub leaf_end: u32,
}

impl Node {
    /// Whether this cluster is an original face.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.child_count == 0
    }

    /// The child clusters.
    #[inline]
    pub fn children(&self) -> &[u32] {
        &self.children[..self.child_count as usize]
    }

    /// Number of original faces in this cluster.
    #[inline]
    pub fn leaf_count(&self) -> u32 {
        self.leaf_end - self.leaf_start
    }
}

/// Geometry of one cluster, recomputed by [`Hierarchy::refit`]. Lengths in mesh units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClusterGeom {
    /// Area-weighted centroid of the cluster's faces (the "midpoint" of §3.1).
    pub midpoint: Vec3,
    /// Unit area-weighted average normal (zero if the faces cancel exactly, e.g. a closed mesh).
    pub normal: Vec3,
    /// Total area of the cluster's faces, mesh units^2.
    pub area: f32,
    /// `A'`: the faces' area projected onto the plane of `normal`, `|Σ A_f n_f|` (faces turned
    /// away count negatively), mesh units^2. `A'/A` is the curvature measure of §5.1.1.
    pub projected_area: f32,
    /// Radius of a sphere about `midpoint` that contains every vertex of the cluster (a
    /// conservative bound for inner clusters), mesh units.
    pub radius: f32,
    /// Area enclosed by the projected boundary polygon, mesh units^2 (0 without a polygon).
    pub polygon_area: f32,
}

impl ClusterGeom {
    /// The curvature measure `A'/A` of §5.1.1: 1 for a planar cluster, smaller the more it
    /// bends (0 for a closed surface).
    #[inline]
    pub fn flatness(&self) -> f32 {
        if self.area > 0.0 { self.projected_area / self.area } else { 1.0 }
    }
}

/// A tree before preorder renumbering, as produced by the builders.
#[derive(Clone, Debug, Default)]
pub(crate) struct RawTree {
    /// Children of each raw node (empty for leaves).
    pub children: Vec<Vec<u32>>,
    /// The original face of each leaf raw node (`u32::MAX` for inner nodes).
    pub face: Vec<u32>,
    /// Explicit boundary polygons (mesh vertex indices, counter-clockwise seen from outside);
    /// when absent the polygon is the cluster's boundary loop.
    pub polygon: Option<Vec<Vec<u32>>>,
    /// The root raw node.
    pub root: u32,
}

/// A cluster hierarchy over the faces of one mesh (see the module documentation).
#[derive(Clone, Debug)]
pub struct Hierarchy {
    /// Cluster topology in preorder; `nodes[0]` is the root.
    pub nodes: Vec<Node>,
    /// Cluster geometry, parallel to `nodes`.
    pub geom: Vec<ClusterGeom>,
    /// Original face index of each leaf position (the face permutation).
    pub leaf_faces: Vec<u32>,
    /// Leaf cluster of each original face (inverse of `leaf_faces`, in cluster indices).
    pub face_node: Vec<u32>,
    /// `polygon_start[i]..polygon_start[i + 1]` indexes cluster `i`'s boundary polygon in
    /// `polygon_vertices` / `polygon_points` (empty range: no polygon).
    pub polygon_start: Vec<u32>,
    /// Mesh vertex indices of the boundary polygons, counter-clockwise seen from outside.
    pub polygon_vertices: Vec<u32>,
    /// The polygon vertices projected onto each cluster's plane (midpoint, averaged normal);
    /// mesh units. Recomputed by [`Hierarchy::refit`].
    pub polygon_points: Vec<Vec3>,
    /// Cluster owning each entry of `polygon_vertices` (for the parallel projection).
    polygon_owner: Vec<u32>,
    /// Vertex count of the mesh the hierarchy was built on.
    pub vertex_count: usize,
}

impl Hierarchy {
    /// Number of clusters (leaves included).
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the hierarchy is empty (a mesh without faces).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Number of leaves (original faces).
    pub fn leaf_count(&self) -> usize {
        self.leaf_faces.len()
    }

    /// The projected boundary polygon of cluster `i` (empty if it has none).
    #[inline]
    pub fn polygon(&self, i: usize) -> &[Vec3] {
        let (a, b) = (self.polygon_start[i], self.polygon_start[i + 1]);
        &self.polygon_points[a as usize..b as usize]
    }

    /// Depth of the deepest leaf (root = 0).
    pub fn depth(&self) -> usize {
        self.nodes.iter().map(|n| n.level as usize).max().unwrap_or(0)
    }

    /// Builds the flat preorder hierarchy from a builder's raw tree and computes its geometry.
    pub(crate) fn from_raw(mesh: &Mesh, raw: RawTree) -> Hierarchy {
        let n_faces = mesh.triangles.len();
        let n_raw = raw.children.len();
        let mut nodes: Vec<Node> = Vec::with_capacity(n_raw);
        let mut raw_of: Vec<u32> = Vec::with_capacity(n_raw);
        let mut leaf_faces = Vec::with_capacity(n_faces);
        // Iterative DFS assigning preorder indices; children are pushed in reverse so that
        // they are visited (and numbered) in order.
        let mut stack: Vec<(u32, u32, u16)> = vec![(raw.root, NO_NODE, 0)];
        while let Some((r, parent, level)) = stack.pop() {
            let i = nodes.len() as u32;
            let leaf_start = leaf_faces.len() as u32;
            if raw.children[r as usize].is_empty() {
                leaf_faces.push(raw.face[r as usize]);
            }
            nodes.push(Node {
                parent,
                children: [NO_NODE; 4],
                child_count: 0,
                level,
                subtree_end: 0,
                leaf_start,
                leaf_end: 0,
            });
            raw_of.push(r);
            if parent != NO_NODE {
                let p = &mut nodes[parent as usize];
                p.children[p.child_count as usize] = i;
                p.child_count += 1;
            }
            let ch = &raw.children[r as usize];
            assert!(ch.len() <= 4, "a cluster has at most 4 children");
            for &c in ch.iter().rev() {
                stack.push((c, i, level + 1));
            }
        }
        // Children carry larger indices than parents: close subtree and leaf ranges backwards.
        for i in (0..nodes.len()).rev() {
            let n = nodes[i];
            if n.is_leaf() {
                nodes[i].subtree_end = i as u32 + 1;
                nodes[i].leaf_end = n.leaf_start + 1;
            } else {
                let last = n.children[n.child_count as usize - 1] as usize;
                nodes[i].subtree_end = nodes[last].subtree_end;
                nodes[i].leaf_end = nodes[last].leaf_end;
            }
        }
        let mut face_node = vec![NO_NODE; n_faces];
        for (i, n) in nodes.iter().enumerate() {
            if n.is_leaf() {
                face_node[leaf_faces[n.leaf_start as usize] as usize] = i as u32;
            }
        }

        // Boundary polygons.
        let polygons: Vec<Vec<u32>> = match &raw.polygon {
            Some(p) => raw_of.iter().map(|&r| p[r as usize].clone()).collect(),
            None => boundary_loops(mesh, &nodes, &leaf_faces),
        };
        let mut polygon_start = Vec::with_capacity(nodes.len() + 1);
        let mut polygon_vertices = Vec::new();
        let mut polygon_owner = Vec::new();
        polygon_start.push(0);
        for (i, p) in polygons.iter().enumerate() {
            if p.len() >= 3 && p.len() <= MAX_POLYGON_VERTICES {
                polygon_vertices.extend_from_slice(p);
                polygon_owner.extend(std::iter::repeat_n(i as u32, p.len()));
            }
            polygon_start.push(polygon_vertices.len() as u32);
        }
        let mut h = Hierarchy {
            geom: vec![ClusterGeom::default(); nodes.len()],
            polygon_points: vec![Vec3::ZERO; polygon_vertices.len()],
            nodes,
            leaf_faces,
            face_node,
            polygon_start,
            polygon_vertices,
            polygon_owner,
            vertex_count: mesh.positions.len(),
        };
        h.refit(mesh);
        h
    }

    /// Recomputes every cluster's geometry and projected polygon from `mesh`'s current vertex
    /// positions, bottom-up and in parallel. The mesh must have the topology the hierarchy was
    /// built on (only positions may change).
    pub fn refit(&mut self, mesh: &Mesh) {
        self.refit_where(mesh, None);
    }

    /// [`Hierarchy::refit`] of only the clusters flagged in `changed` (indexed by cluster):
    /// those with a face that has a moved vertex, and their ancestors. The others keep their
    /// geometry, which is then still exact: a cluster's geometry and boundary polygon depend
    /// only on its own faces' vertices.
    pub fn refit_changed(&mut self, mesh: &Mesh, changed: &[bool]) {
        assert_eq!(changed.len(), self.nodes.len(), "refit: one flag per cluster");
        self.refit_where(mesh, Some(changed));
    }

    fn refit_where(&mut self, mesh: &Mesh, changed: Option<&[bool]>) {
        assert_eq!(mesh.positions.len(), self.vertex_count, "refit: vertex count changed");
        if self.nodes.is_empty() {
            return;
        }
        let nodes = &self.nodes;
        let leaf_faces = &self.leaf_faces;
        let is_changed = |i: usize| changed.is_none_or(|c| c[i]);
        refit_subtree(nodes, leaf_faces, mesh, 0, &mut self.geom, changed);
        // Project polygon vertices onto their cluster's plane.
        let geom = &self.geom;
        self.polygon_points
            .par_iter_mut()
            .zip(self.polygon_vertices.par_iter())
            .zip(self.polygon_owner.par_iter())
            .filter(|(_, o)| is_changed(**o as usize))
            .for_each(|((p, &v), &o)| {
                let g = &geom[o as usize];
                let x = mesh.positions[v as usize];
                *p = x - (x - g.midpoint).dot(g.normal) * g.normal;
            });
        let starts = &self.polygon_start;
        let points = &self.polygon_points;
        self.geom.par_iter_mut().enumerate().filter(|(i, _)| is_changed(*i)).for_each(|(i, g)| {
            let pts = &points[starts[i] as usize..starts[i + 1] as usize];
            g.polygon_area = polygon_area(pts, g.normal);
        });
    }
}

/// Signed area of a planar polygon along `normal` (Newell's formula).
fn polygon_area(pts: &[Vec3], normal: Vec3) -> f32 {
    if pts.len() < 3 {
        return 0.0;
    }
    let mut s = Vec3::ZERO;
    let o = pts[0];
    for k in 1..pts.len() - 1 {
        s += (pts[k] - o).cross(pts[k + 1] - o);
    }
    0.5 * s.dot(normal).abs()
}

/// Geometry of a leaf (one face).
fn leaf_geom(mesh: &Mesh, face: usize) -> ClusterGeom {
    let [a, b, c] = mesh.corners(face);
    let cross = (b - a).cross(c - a);
    let area = 0.5 * cross.length();
    let midpoint = (a + b + c) / 3.0;
    let radius = (a - midpoint).length().max((b - midpoint).length()).max((c - midpoint).length());
    ClusterGeom {
        midpoint,
        normal: cross.normalize_or_zero(),
        area,
        projected_area: area,
        radius,
        polygon_area: 0.0,
    }
}

/// Splits the preorder slice of cluster `r`'s descendants (`r + 1..subtree_end`) into its
/// children's subtrees, as `(child, slice)`: preorder numbers the children in order, each
/// subtree contiguous.
pub(crate) fn split_subtrees<'a, T>(
    nodes: &[Node],
    r: usize,
    rest: &'a mut [T],
) -> Vec<(usize, &'a mut [T])> {
    split_children(nodes, r, rest, |c| (nodes[c].subtree_end as usize) - c)
}

/// Splits the leaf-ordered slice of cluster `r`'s leaves among its children, as
/// `(child, slice)`.
pub(crate) fn split_leaves<'a, T>(
    nodes: &[Node],
    r: usize,
    leaves: &'a mut [T],
) -> Vec<(usize, &'a mut [T])> {
    split_children(nodes, r, leaves, |c| nodes[c].leaf_count() as usize)
}

/// Splits `rest` into consecutive slices of `len(child)` entries, one per child of `r`.
fn split_children<'a, T>(
    nodes: &[Node],
    r: usize,
    rest: &'a mut [T],
    len: impl Fn(usize) -> usize,
) -> Vec<(usize, &'a mut [T])> {
    let mut rest = rest;
    let mut parts = Vec::with_capacity(4);
    for &c in nodes[r].children() {
        let (a, b) = std::mem::take(&mut rest).split_at_mut(len(c as usize));
        parts.push((c as usize, a));
        rest = b;
    }
    parts
}

/// Refits the subtree rooted at `i`, whose geometry is the slice `g` (`g[0]` is cluster `i`).
/// With `changed`, unflagged subtrees are skipped.
fn refit_subtree(
    nodes: &[Node],
    leaf_faces: &[u32],
    mesh: &Mesh,
    i: usize,
    g: &mut [ClusterGeom],
    changed: Option<&[bool]>,
) {
    if changed.is_some_and(|c| !c[i]) {
        return;
    }
    let n = nodes[i];
    let (head, rest) = g.split_first_mut().expect("non-empty subtree");
    if n.is_leaf() {
        *head = leaf_geom(mesh, leaf_faces[n.leaf_start as usize] as usize);
        return;
    }
    let mut parts = split_subtrees(nodes, i, rest);
    if n.leaf_count() > PAR_LEAVES {
        parts.par_iter_mut().for_each(|(c, s)| refit_subtree(nodes, leaf_faces, mesh, *c, s, changed));
    } else {
        for (c, s) in parts.iter_mut() {
            refit_subtree(nodes, leaf_faces, mesh, *c, s, changed);
        }
    }
    let mut area = 0.0f32;
    let mut weighted = Vec3::ZERO;
    let mut nsum = Vec3::ZERO;
    for (_, s) in &parts {
        let cg = &s[0];
        area += cg.area;
        weighted += cg.area * cg.midpoint;
        nsum += cg.projected_area * cg.normal;
    }
    let midpoint = if area > 0.0 {
        weighted / area
    } else {
        parts.iter().map(|(_, s)| s[0].midpoint).sum::<Vec3>() / parts.len() as f32
    };
    let radius =
        parts.iter().map(|(_, s)| (s[0].midpoint - midpoint).length() + s[0].radius).fold(0.0f32, f32::max);
    *head = ClusterGeom {
        midpoint,
        normal: nsum.normalize_or_zero(),
        area,
        projected_area: nsum.length(),
        radius,
        polygon_area: 0.0,
    };
}

/// For every cluster, its boundary as one loop of mesh vertex indices (counter-clockwise seen
/// from outside, following the faces' winding), or an empty list when the boundary is not a
/// single simple loop (closed surfaces, annuli, pinched or non-manifold boundaries) or is
/// longer than [`MAX_POLYGON_VERTICES`].
///
/// The boundary half-edges of a cluster are those of its children minus the pairs `(a, b)`,
/// `(b, a)` that now lie inside it, merged bottom-up.
fn boundary_loops(mesh: &Mesh, nodes: &[Node], leaf_faces: &[u32]) -> Vec<Vec<u32>> {
    let mut loops: Vec<Vec<u32>> = vec![Vec::new(); nodes.len()];
    // Half-edge lists, freed once the parent has consumed them. A list longer than the cap is
    // still tracked so that ancestors (whose boundary may shrink again) stay correct.
    let mut half: Vec<Option<Vec<(u32, u32)>>> = vec![None; nodes.len()];
    for i in (0..nodes.len()).rev() {
        let n = nodes[i];
        let he: Vec<(u32, u32)> = if n.is_leaf() {
            let [a, b, c] = mesh.triangles[leaf_faces[n.leaf_start as usize] as usize];
            vec![(a, b), (b, c), (c, a)]
        } else {
            let mut set: HashSet<(u32, u32)> = HashSet::new();
            for &c in n.children() {
                for e in half[c as usize].take().unwrap_or_default() {
                    if !set.remove(&(e.1, e.0)) {
                        set.insert(e);
                    }
                }
            }
            set.into_iter().collect()
        };
        loops[i] = chain_single_loop(&he);
        half[i] = Some(he);
    }
    loops
}

/// Chains half-edges into one loop; empty if they do not form exactly one simple loop.
fn chain_single_loop(he: &[(u32, u32)]) -> Vec<u32> {
    if he.len() < 3 || he.len() > MAX_POLYGON_VERTICES {
        return Vec::new();
    }
    let mut next: HashMap<u32, u32> = HashMap::with_capacity(he.len());
    for &(a, b) in he {
        if next.insert(a, b).is_some() {
            return Vec::new(); // pinch: two boundary edges leave one vertex
        }
    }
    let start = he[0].0;
    let mut out = Vec::with_capacity(he.len());
    let mut v = start;
    loop {
        out.push(v);
        match next.get(&v) {
            Some(&w) => v = w,
            None => return Vec::new(),
        }
        if v == start || out.len() > he.len() {
            break;
        }
    }
    if v == start && out.len() == he.len() { out } else { Vec::new() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_loop_chaining() {
        let he = [(0, 1), (1, 2), (2, 3), (3, 0)];
        assert_eq!(chain_single_loop(&he), vec![0, 1, 2, 3]);
        // Two loops (an annulus) give no polygon.
        let he = [(0, 1), (1, 2), (2, 0), (5, 4), (4, 3), (3, 5)];
        assert!(chain_single_loop(&he).is_empty());
    }
}
