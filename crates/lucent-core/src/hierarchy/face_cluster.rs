//! Face cluster hierarchy (Mertens et al. 2003, §5.1.1, after Garland, Willmott & Heckbert
//! 2001, "Hierarchical Face Clustering on Polygonal Surfaces").
//!
//! Bottom-up greedy contraction of the dual graph: every face starts as a cluster, the dual
//! edges (pairs of clusters sharing mesh edges) sit in a binary heap keyed by the cost of their
//! merge, and the cheapest merge is applied until no dual edge is left. Stale heap entries (an
//! endpoint already merged) are skipped when popped ("lazy invalidation"); every merge creates a
//! new cluster id, so an entry whose endpoints are both alive is always current.
//!
//! Cost. As in §5.1.1 the cost only asks for compact clusters and ignores curvature (the
//! oracle checks `A'/A` at run time instead). We use the squared perimeter of the merged
//! cluster, `P² / 4π = A · γ` with the compactness `γ = P² / (4π A)` (1 for a disc): it
//! prefers round merges among clusters of one size *and* small merges over large ones, which
//! keeps the tree balanced (depth ~ log N) where pure compactness would let one blob swallow
//! the mesh face by face.
//!
//! Meshes with several components (or faces sharing no edge) end with several roots; these are
//! merged by a size-balanced fallback (the two smallest by area first, Huffman-style). Open
//! meshes and any genus need nothing special. Non-manifold edges link every pair of their faces.

use super::{Hierarchy, RawTree};
use crate::mesh::Mesh;
use glam::Vec3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// The pending merges: a heap with four children a node, popping the greatest [`Merge`] (the
/// cheapest, through its reversed `Ord`) first, so in the order `std`'s binary heap pops them
/// (the order is total: the same tree). Each entry is one 128-bit key that orders as `Merge`
/// does. The heap holds millions of entries, and a pop waits on memory at every level: four
/// children share a 64-byte line, which halves the levels, and integer keys compare in one
/// step (eight children a node gave no more; docs/speed.md has the figures).
#[derive(Debug, Default)]
struct MergeQueue(Vec<u128>);

/// Children a node of [`MergeQueue`].
const ARITY: usize = 4;

impl MergeQueue {
    fn with_capacity(n: usize) -> Self {
        MergeQueue(Vec::with_capacity(n))
    }

    /// `m`'s key: greater for a greater `Merge` (lower cost, then lower `a`, then lower `b`).
    fn key(m: Merge) -> u128 {
        let bits = m.cost.to_bits();
        // `f64::total_cmp`'s order as an unsigned integer's.
        let ordered = bits ^ if bits >> 63 == 1 { u64::MAX } else { 1 << 63 };
        ((!ordered as u128) << 64) | ((!m.a as u128) << 32) | (!m.b as u128)
    }

    fn merge_of(k: u128) -> Merge {
        let ordered = !((k >> 64) as u64);
        let bits = ordered ^ if ordered >> 63 == 1 { 1 << 63 } else { u64::MAX };
        Merge { cost: f64::from_bits(bits), a: !((k >> 32) as u32), b: !(k as u32) }
    }

    fn push(&mut self, m: Merge) {
        let k = Self::key(m);
        let v = &mut self.0;
        let mut i = v.len();
        v.push(k);
        while i > 0 {
            let parent = (i - 1) / ARITY;
            if v[parent] >= k {
                break;
            }
            v[i] = v[parent];
            i = parent;
        }
        v[i] = k;
    }

    fn pop(&mut self) -> Option<Merge> {
        let v = &mut self.0;
        let last = v.pop()?;
        if v.is_empty() {
            return Some(Self::merge_of(last));
        }
        let top = v[0];
        // Sift `last` down from the root: at each level the greatest of up to four children
        // moves up while it is greater.
        let n = v.len();
        let mut i = 0;
        loop {
            let first = ARITY * i + 1;
            if first >= n {
                break;
            }
            let mut best = first;
            for c in first + 1..(first + ARITY).min(n) {
                if v[c] > v[best] {
                    best = c;
                }
            }
            if v[best] <= last {
                break;
            }
            v[i] = v[best];
            i = best;
        }
        v[i] = last;
        Some(Self::merge_of(top))
    }
}

/// A pending merge in the heap (min-heap on `cost` through the reversed `Ord`).
#[derive(Clone, Copy, Debug)]
struct Merge {
    cost: f64,
    a: u32,
    b: u32,
}

impl PartialEq for Merge {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Merge {}
impl PartialOrd for Merge {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Merge {
    fn cmp(&self, o: &Self) -> Ordering {
        // Reversed for a min-heap; ties broken by ids so the build is deterministic.
        o.cost.total_cmp(&self.cost).then_with(|| o.a.cmp(&self.a)).then_with(|| o.b.cmp(&self.b))
    }
}

/// Builds the binary face cluster hierarchy of `mesh` (see the module documentation).
/// A mesh without faces gives an empty hierarchy.
pub fn build(mesh: &Mesh) -> Hierarchy {
    if mesh.triangles.is_empty() {
        return Hierarchy {
            nodes: Vec::new(),
            geom: Vec::new(),
            leaf_faces: Vec::new(),
            face_node: Vec::new(),
            polygon_start: vec![0],
            polygon_vertices: Vec::new(),
            polygon_points: Vec::new(),
            polygon_owner: Vec::new(),
            vertex_count: mesh.positions.len(),
        };
    }
    let mut clusters = Clusters::faces(mesh);
    clusters.link_dual_edges(mesh);
    clusters.contract(mesh.triangles.len());
    let root = clusters.join_components(mesh);
    Hierarchy::from_raw(
        mesh,
        RawTree { children: clusters.children, face: clusters.face, polygon: None, root },
    )
}

/// The clusters during the build, by id: the faces first, then one per merge.
struct Clusters {
    /// The two clusters each one merged (empty for a face).
    children: Vec<Vec<u32>>,
    /// The mesh face of a face cluster, `u32::MAX` for a merged one.
    face: Vec<u32>,
    /// Area, mesh units².
    area: Vec<f64>,
    /// Boundary length, mesh units (set for the dual-graph contraction only).
    perimeter: Vec<f64>,
    /// Whether the cluster is not yet merged into another (dual-graph contraction only).
    alive: Vec<bool>,
    /// Dual adjacency: (neighbour id at the time of insertion, shared boundary length).
    adj: Vec<Vec<(u32, f64)>>,
    /// Union-find forwarding from merged ids to their current cluster.
    forward: Vec<u32>,
}

/// Length of the mesh edge between vertices `a` and `b`.
fn edge_len(mesh: &Mesh, a: u32, b: u32) -> f64 {
    (mesh.positions[a as usize].as_dvec3() - mesh.positions[b as usize].as_dvec3()).length()
}

/// The cost of merging clusters of perimeters `pa` and `pb` that share a boundary of length
/// `shared`: the merged cluster's `P² / 4π` (see the module documentation).
fn merge_cost(pa: f64, pb: f64, shared: f64) -> f64 {
    let p = (pa + pb - 2.0 * shared).max(0.0);
    p * p / (4.0 * std::f64::consts::PI)
}

/// The current cluster of id `x` (following merges), compressing the path.
fn find(forward: &mut [u32], mut x: u32) -> u32 {
    let mut root = x;
    while forward[root as usize] != root {
        root = forward[root as usize];
    }
    while forward[x as usize] != root {
        let nx = forward[x as usize];
        forward[x as usize] = root;
        x = nx;
    }
    root
}

impl Clusters {
    /// One cluster per face, with room for every merge, and no adjacency yet.
    fn faces(mesh: &Mesh) -> Self {
        let cap = 2 * mesh.triangles.len() - 1;
        let mut c = Clusters {
            children: Vec::with_capacity(cap),
            face: Vec::with_capacity(cap),
            area: Vec::with_capacity(cap),
            perimeter: Vec::with_capacity(cap),
            alive: Vec::with_capacity(cap),
            adj: Vec::with_capacity(cap),
            forward: Vec::with_capacity(cap),
        };
        for (f, &[a, b, v]) in mesh.triangles.iter().enumerate() {
            c.children.push(Vec::new());
            c.face.push(f as u32);
            c.area.push(mesh.face_area(f) as f64);
            c.perimeter.push(edge_len(mesh, a, b) + edge_len(mesh, b, v) + edge_len(mesh, v, a));
            c.alive.push(true);
            c.adj.push(Vec::new());
            c.forward.push(f as u32);
        }
        c
    }

    /// The dual edges: every pair of faces sharing an undirected mesh edge, with its length.
    fn link_dual_edges(&mut self, mesh: &Mesh) {
        let mut edges: Vec<(u64, u32)> = Vec::with_capacity(3 * mesh.triangles.len());
        for (f, tri) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a == b {
                    continue;
                }
                let key = ((a.min(b) as u64) << 32) | a.max(b) as u64;
                edges.push((key, f as u32));
            }
        }
        edges.sort_unstable();
        let mut i = 0;
        while i < edges.len() {
            let mut j = i + 1;
            while j < edges.len() && edges[j].0 == edges[i].0 {
                j += 1;
            }
            let key = edges[i].0;
            // An edge of k faces counts in each face's perimeter; as a shared boundary of each of
            // the k(k-1)/2 pairs it counts 1/(k-1) of its length, so that merging all k removes
            // it from the perimeter exactly once per face. Counted whole per pair, a
            // non-manifold edge took up to (k-1) times its length off, clusters grown over
            // such edges reached perimeter 0 (merge cost 0), and on a scanned mesh (the 11K
            // Stanford dragon, 803 non-manifold edges) one cluster ate the mesh face by face:
            // a hierarchy 3,240 levels deep, whose far faces could never be grouped.
            let len = edge_len(mesh, (key >> 32) as u32, key as u32) / (j - i - 1).max(1) as f64;
            for x in i..j {
                for y in x + 1..j {
                    let (f, g) = (edges[x].1, edges[y].1);
                    if f != g {
                        self.adj[f as usize].push((g, len));
                        self.adj[g as usize].push((f, len));
                    }
                }
            }
            i = j;
        }
        // Faces sharing two edges (folds) appear twice: combine.
        for a in self.adj.iter_mut() {
            combine_duplicates(a);
        }
    }

    /// Greedy contraction of the dual graph of the `n` faces, cheapest merge first, until no
    /// dual edge is left.
    fn contract(&mut self, n: usize) {
        let mut heap = MergeQueue::with_capacity(3 * n);
        for a in 0..n {
            for &(b, shared) in &self.adj[a] {
                if (a as u32) < b {
                    heap.push(Merge {
                        cost: merge_cost(self.perimeter[a], self.perimeter[b as usize], shared),
                        a: a as u32,
                        b,
                    });
                }
            }
        }
        while let Some(Merge { a, b, .. }) = heap.pop() {
            if !self.alive[a as usize] || !self.alive[b as usize] {
                continue;
            }
            self.merge(a, b, &mut heap);
        }
    }

    /// Merges the live clusters `a` and `b` into a new one and queues its merges with its
    /// neighbours.
    fn merge(&mut self, a: u32, b: u32, heap: &mut MergeQueue) {
        let c = self.children.len() as u32;
        // Entries may name clusters merged since: resolve them (their lengths add up).
        let mut shared = 0.0;
        let list = std::mem::take(&mut self.adj[a as usize]);
        for &(x, len) in &list {
            if find(&mut self.forward, x) == b {
                shared += len;
            }
        }
        self.adj[a as usize] = list;
        let mut nb: Vec<(u32, f64)> =
            Vec::with_capacity(self.adj[a as usize].len() + self.adj[b as usize].len());
        for src in [a, b] {
            for &(x, len) in &std::mem::take(&mut self.adj[src as usize]) {
                let x = find(&mut self.forward, x);
                if x != a && x != b && self.alive[x as usize] {
                    nb.push((x, len));
                }
            }
        }
        combine_duplicates(&mut nb);
        self.alive[a as usize] = false;
        self.alive[b as usize] = false;
        self.forward[a as usize] = c;
        self.forward[b as usize] = c;
        self.children.push(vec![a, b]);
        self.face.push(u32::MAX);
        self.area.push(self.area[a as usize] + self.area[b as usize]);
        let p = (self.perimeter[a as usize] + self.perimeter[b as usize] - 2.0 * shared).max(0.0);
        self.perimeter.push(p);
        self.alive.push(true);
        self.forward.push(c);
        for &(x, len) in &nb {
            heap.push(Merge { cost: merge_cost(p, self.perimeter[x as usize], len), a: x, b: c });
            // The neighbour's own entries for a and b now resolve to c through `forward`.
        }
        self.adj.push(nb);
    }

    /// Joins the roots left (components, or faces sharing no edge) and returns the root. Up to
    /// [`SPATIAL_JOIN_MAX`] roots, the smallest by area joins the root whose union with it has
    /// the shortest bounding-box diagonal: joined by area alone, small pieces scattered over a
    /// scan (the 871K Stanford dragon has 150) made clusters as wide as the model with almost
    /// no area, which no receiver is ever separated from, so every face linked to each piece.
    /// Beyond that, size-balanced by area alone (the two smallest first).
    fn join_components(&mut self, mesh: &Mesh) -> u32 {
        let live: Vec<u32> = (0..self.children.len() as u32).filter(|&x| self.alive[x as usize]).collect();
        if live.len() > 1 && live.len() <= SPATIAL_JOIN_MAX {
            return self.join_nearest(mesh, live);
        }
        let mut roots: BinaryHeap<Merge> = (0..self.children.len() as u32)
            .filter(|&x| self.alive[x as usize])
            .map(|x| Merge { cost: self.area[x as usize], a: x, b: x })
            .collect();
        while roots.len() > 1 {
            let x = roots.pop().expect("len > 1").a;
            let y = roots.pop().expect("len > 1").a;
            let c = self.children.len() as u32;
            self.children.push(vec![x, y]);
            self.face.push(u32::MAX);
            self.area.push(self.area[x as usize] + self.area[y as usize]);
            roots.push(Merge { cost: self.area[c as usize], a: c, b: c });
        }
        roots.pop().expect("at least one face").a
    }
}

/// The most roots [`Clusters::join_components`] joins by position (quadratic in their number).
const SPATIAL_JOIN_MAX: usize = 4096;

impl Clusters {
    /// The bounding box of cluster `x`'s faces.
    fn bounds(&self, mesh: &Mesh, x: u32) -> (Vec3, Vec3) {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        let mut stack = vec![x];
        while let Some(c) = stack.pop() {
            let f = self.face[c as usize];
            if f == u32::MAX {
                stack.extend_from_slice(&self.children[c as usize]);
            } else {
                for &v in &mesh.triangles[f as usize] {
                    lo = lo.min(mesh.positions[v as usize]);
                    hi = hi.max(mesh.positions[v as usize]);
                }
            }
        }
        (lo, hi)
    }

    /// [`Clusters::join_components`] by position.
    fn join_nearest(&mut self, mesh: &Mesh, live: Vec<u32>) -> u32 {
        let mut roots: Vec<(u32, Vec3, Vec3)> = live
            .into_iter()
            .map(|x| {
                let (lo, hi) = self.bounds(mesh, x);
                (x, lo, hi)
            })
            .collect();
        while roots.len() > 1 {
            let area = |r: &(u32, Vec3, Vec3)| self.area[r.0 as usize];
            let i =
                (0..roots.len()).min_by(|&a, &b| area(&roots[a]).total_cmp(&area(&roots[b]))).expect("roots");
            let (x, lo, hi) = roots.swap_remove(i);
            let diagonal = |r: &(u32, Vec3, Vec3)| (hi.max(r.2) - lo.min(r.1)).length();
            let j = (0..roots.len())
                .min_by(|&a, &b| diagonal(&roots[a]).total_cmp(&diagonal(&roots[b])))
                .expect("another root");
            let (y, lo_y, hi_y) = roots[j];
            let c = self.children.len() as u32;
            self.children.push(vec![x, y]);
            self.face.push(u32::MAX);
            self.area.push(self.area[x as usize] + self.area[y as usize]);
            roots[j] = (c, lo.min(lo_y), hi.max(hi_y));
        }
        roots[0].0
    }
}

/// Sorts `list` by neighbour id and sums the lengths of repeated ids into one entry, in place.
fn combine_duplicates(list: &mut Vec<(u32, f64)>) {
    if list.len() < 2 {
        return;
    }
    list.sort_unstable_by_key(|e| e.0);
    list.dedup_by(|next, kept| {
        let same = next.0 == kept.0;
        if same {
            kept.1 += next.1;
        }
        same
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The queue pops what `std`'s binary heap pops, entry for entry, with pushes and pops
    /// interleaved, costs repeated (ties broken by the ids), zero of both signs and very
    /// large and small costs.
    #[test]
    fn merge_queue_pops_in_the_binary_heaps_order() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
        let costs = [0.0, -0.0, 1e-300, 0.5, 0.5, 2.0, 1e300, f64::MAX];
        let (mut q, mut want) = (MergeQueue::with_capacity(0), BinaryHeap::new());
        for step in 0..20_000 {
            if rng.random_range(0..3) > 0 || want.is_empty() {
                let cost = if step % 2 == 0 {
                    costs[rng.random_range(0..costs.len())]
                } else {
                    rng.random_range(0.0..4.0)
                };
                let m = Merge { cost, a: rng.random_range(0..50), b: rng.random_range(0..u32::MAX) };
                q.push(m);
                want.push(m);
            } else {
                let (got, w) = (q.pop().expect("not empty"), want.pop().expect("not empty"));
                assert_eq!((got.cost.to_bits(), got.a, got.b), (w.cost.to_bits(), w.a, w.b), "step {step}");
            }
        }
        while let Some(w) = want.pop() {
            let got = q.pop().expect("as many entries");
            assert_eq!((got.cost.to_bits(), got.a, got.b), (w.cost.to_bits(), w.a, w.b));
        }
        assert!(q.pop().is_none());
    }
}
