//! Mesh validation and topology statistics.
//!
//! Mertens et al. 2003 (§3.1-3.2) integrate over a closed triangle mesh and build a
//! subdivision hierarchy over it, which needs finite positions, valid indices, faces with area
//! and, ideally, a closed 2-manifold. This module rejects what cannot be used and reports what
//! can be used but may degrade results:
//!
//! - fatal ([`MeshError`]): no vertices, no triangles, non-finite coordinates, indices out of
//!   range, or nothing left after removing degenerate faces;
//! - removed and reported: degenerate faces (a repeated index or zero area), and repeated
//!   faces (the same three vertices as another face: scanned reconstructions such as the vrip
//!   Stanford dragon hold hundreds, mostly back to back, which drew as black specks);
//! - repaired and reported: faces folded over their neighbours, whose vertices move to the
//!   mean of their neighbours ([`super::unfold`]: decimation fold-overs, dark dots on the
//!   decimated dragons);
//! - repaired and reported: a closed mesh wound inside out (every face's normal pointing in,
//!   so its signed volume is negative) has every face flipped ([`flip_if_inside_out`]); the
//!   profile integral and the light's entry both take the winding as outward, and such a mesh
//!   rendered nearly black. An open mesh keeps its winding (its signed volume means nothing);
//! - reported only: boundary edges (one face), non-manifold edges (more than two faces),
//!   inconsistently oriented edges, unreferenced vertices, connected components.

use super::{Mesh, MeshError};
use rayon::slice::ParallelSliceMut;
use std::collections::HashMap;
use std::fmt;

/// What validation found in a mesh (counts refer to the returned mesh unless noted).
/// A closed, consistently oriented 2-manifold has `boundary_edges == 0`,
/// `nonmanifold_edges == 0` and `inconsistent_edges == 0`; see [`MeshReport::is_closed_manifold`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MeshReport {
    /// Vertices in the returned mesh (unreferenced ones included).
    pub vertices: usize,
    /// Triangles in the returned mesh (degenerate ones already removed).
    pub triangles: usize,
    /// Vertices merged into an earlier vertex at a bitwise-equal position after loading
    /// (OBJ and glTF only, where files split vertices by normal or texture coordinate).
    pub welded_vertices: usize,
    /// Degenerate faces (a repeated vertex index, or zero area) found and *removed*.
    pub degenerate_faces: usize,
    /// Faces over the same three vertices as another face, *removed*: of each such group one
    /// face stays, the one whose winding agrees best with its neighbours' (so a face stored
    /// back to back with its reverse keeps the outward side).
    pub repeated_faces: usize,
    /// Faces folded over their neighbours found ([`super::unfold`]); their vertices were
    /// moved, see `unfolded_vertices` and `folded_faces`.
    pub folded_before: usize,
    /// Vertices moved to the mean of their neighbours to undo folded faces.
    pub unfolded_vertices: usize,
    /// Faces still folded over their neighbours after the moves.
    pub folded_faces: usize,
    /// Undirected edges used by exactly one face (holes, open borders).
    pub boundary_edges: usize,
    /// Undirected edges used by more than two faces.
    pub nonmanifold_edges: usize,
    /// Edges shared by exactly two faces that traverse it in the same direction (the two faces
    /// disagree about which side is outside).
    pub inconsistent_edges: usize,
    /// Vertices no face refers to (kept, so that indices stay as given).
    pub unreferenced_vertices: usize,
    /// Connected components, counting vertices connected through face edges (unreferenced
    /// vertices are not counted).
    pub components: usize,
    /// Euler characteristic `V - E + F` over referenced vertices: 2 per closed genus-0
    /// component.
    pub euler_characteristic: i64,
    /// The mesh was closed and wound inside out (negative signed volume), and every face was
    /// flipped (its second and third corners swapped) so that normals point outward.
    pub flipped_inside_out: bool,
    /// A text file (OBJ, OFF, ASCII PLY) whose last line has no line end: it may have been cut
    /// short, and the mesh may be missing its last faces.
    pub unterminated_last_line: bool,
}

impl MeshReport {
    /// True when every edge is shared by exactly two faces with opposite directions.
    pub fn is_closed_manifold(&self) -> bool {
        self.boundary_edges == 0 && self.nonmanifold_edges == 0 && self.inconsistent_edges == 0
    }

    /// True when nothing was removed and the mesh is one closed, consistently oriented
    /// component.
    pub fn is_clean(&self) -> bool {
        self.degenerate_faces == 0
            && self.repeated_faces == 0
            && self.folded_before == 0
            && self.is_closed_manifold()
            && self.components == 1
    }

    /// One line per thing lucent repaired or the user should know, with counts (empty for a
    /// clean mesh), e.g. `removed 2 degenerate faces`, `open mesh: 12 boundary edges`.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.unterminated_last_line {
            w.push("the last line has no line end: the file may be cut short".to_string());
        }
        if self.flipped_inside_out {
            w.push(
                "closed mesh wound inside out (negative signed volume): every face flipped to point outward"
                    .to_string(),
            );
        }
        if self.unfolded_vertices > 0 {
            w.push(format!(
                "moved {} vertices to undo faces folded over their neighbours ({} found)",
                self.unfolded_vertices, self.folded_before
            ));
        }
        for (n, what) in [
            (self.folded_faces, "{} faces stay folded over their neighbours"),
            (self.degenerate_faces, "removed {} degenerate faces (a repeated vertex or zero area)"),
            (self.repeated_faces, "removed {} repeated faces (the same three vertices as another face)"),
            (self.welded_vertices, "welded {} duplicate vertices"),
            (self.boundary_edges, "open mesh: {} boundary edges (subsurface light leaks at holes)"),
            (self.nonmanifold_edges, "non-manifold mesh: {} edges shared by more than two faces"),
            (self.inconsistent_edges, "{} edges between faces of opposite orientation"),
        ] {
            if n > 0 {
                w.push(what.replace("{}", &n.to_string()));
            }
        }
        w
    }
}

impl fmt::Display for MeshReport {
    /// One line, e.g. `1839 vertices, 3674 triangles, 1 component, closed manifold` or
    /// `..., removed 2 degenerate faces, 12 boundary edges`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} vertices, {} triangles, {} component{}",
            self.vertices,
            self.triangles,
            self.components,
            if self.components == 1 { "" } else { "s" }
        )?;
        if self.welded_vertices > 0 {
            write!(f, ", welded {} duplicate vertices", self.welded_vertices)?;
        }
        if self.degenerate_faces > 0 {
            write!(f, ", removed {} degenerate faces", self.degenerate_faces)?;
        }
        if self.repeated_faces > 0 {
            write!(f, ", removed {} repeated faces", self.repeated_faces)?;
        }
        if self.unfolded_vertices > 0 {
            write!(f, ", moved {} vertices of folded faces", self.unfolded_vertices)?;
        }
        if self.flipped_inside_out {
            write!(f, ", flipped inside out")?;
        }
        if self.is_closed_manifold() {
            write!(f, ", closed manifold")?;
        }
        for (n, what) in [
            (self.boundary_edges, "boundary edges"),
            (self.nonmanifold_edges, "non-manifold edges"),
            (self.inconsistent_edges, "inconsistently oriented edges"),
            (self.folded_faces, "folded faces"),
            (self.unreferenced_vertices, "unreferenced vertices"),
        ] {
            if n > 0 {
                write!(f, ", {n} {what}")?;
            }
        }
        Ok(())
    }
}

/// Checks `mesh` (see the module doc), removes degenerate and repeated faces, and returns the
/// cleaned mesh with its report. `source` names the mesh (its file) in errors.
pub fn validate(mesh: Mesh, source: &str) -> Result<(Mesh, MeshReport), MeshError> {
    validate_keeping(mesh, source, &mut Vec::<()>::new())
}

/// [`validate`], also dropping from `per_face` (one entry per face of `mesh`, e.g. texture
/// coordinates; left alone unless its length is the face count) the entries of removed faces.
/// Where the report says `flipped_inside_out`, each face's second and third corners were
/// swapped: per-corner data in `per_face` must be swapped the same way by the caller.
pub fn validate_keeping<T>(
    mut mesh: Mesh,
    source: &str,
    per_face: &mut Vec<T>,
) -> Result<(Mesh, MeshReport), MeshError> {
    let fail = |reason: String| MeshError::invalid(source, reason);
    if mesh.positions.is_empty() {
        return Err(fail("empty mesh: no vertices".into()));
    }
    if mesh.triangles.is_empty() {
        return Err(fail("empty mesh: no triangles".into()));
    }
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(fail(format!(
            "vertex {i} has a non-finite coordinate {:?}",
            mesh.positions[i].to_array()
        )));
    }
    let n = mesh.positions.len();
    if let Some((f, t)) = mesh.triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&i| i as usize >= n))
    {
        return Err(fail(format!("face {f} has vertex index out of range: {t:?} with {n} vertices")));
    }

    let before = mesh.triangles.len();
    let mut keep: Vec<bool> = mesh.triangles.iter().map(|t| !is_degenerate(&mesh.positions, t)).collect();
    let degenerate_faces = keep.iter().filter(|&&k| !k).count();
    if degenerate_faces == before {
        return Err(fail(format!("all {before} triangles are degenerate (zero area or repeated vertex)")));
    }
    let repeated_faces = drop_repeated_faces(&mesh.triangles, &mut keep);
    if per_face.len() == before {
        let mut k = keep.iter();
        per_face.retain(|_| *k.next().unwrap_or(&false));
    }
    let mut k = keep.iter();
    mesh.triangles.retain(|_| *k.next().unwrap_or(&false));

    let unfolded = super::unfold::unfold(&mut mesh);
    let mut report = analyze(&mesh);
    report.degenerate_faces = degenerate_faces;
    report.repeated_faces = repeated_faces;
    report.folded_before = unfolded.folded_before;
    report.unfolded_vertices = unfolded.moved_vertices;
    report.folded_faces = unfolded.folded_after;
    report.flipped_inside_out = flip_if_inside_out(&mut mesh, &report);
    Ok((mesh, report))
}

/// Clears `keep` for every kept face over the same three vertices as another kept face, but
/// one per group: the face whose directed edges its neighbours (faces outside any group)
/// traverse most often the other way, i.e. the winding that agrees with the surface around it
/// (the first on a tie). Returns how many faces it cleared.
fn drop_repeated_faces(triangles: &[[u32; 3]], keep: &mut [bool]) -> usize {
    let sorted = |t: &[u32; 3]| {
        let mut k = *t;
        k.sort_unstable();
        k
    };
    let mut order: Vec<u32> = (0..triangles.len() as u32).filter(|&f| keep[f as usize]).collect();
    order.par_sort_by_key(|&f| (sorted(&triangles[f as usize]), f));
    let groups: Vec<&[u32]> =
        order.chunk_by(|&a, &b| sorted(&triangles[a as usize]) == sorted(&triangles[b as usize])).collect();
    if groups.iter().all(|g| g.len() == 1) {
        return 0;
    }
    let edges_of = |t: &[u32; 3]| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
    let mut directed: Vec<(u32, u32)> =
        groups.iter().filter(|g| g.len() == 1).flat_map(|g| edges_of(&triangles[g[0] as usize])).collect();
    directed.par_sort_unstable();
    let uses = |e: (u32, u32)| directed.partition_point(|&x| x <= e) - directed.partition_point(|&x| x < e);
    let agreement = |t: &[u32; 3]| {
        edges_of(t).iter().map(|&(a, b)| uses((b, a)) as i64 - uses((a, b)) as i64).sum::<i64>()
    };
    let mut dropped = 0;
    for g in groups.iter().filter(|g| g.len() > 1) {
        // `max_by_key` keeps the last of equal maxima; reversing makes it the first.
        let best = *g.iter().rev().max_by_key(|&&f| agreement(&triangles[f as usize])).unwrap_or(&g[0]);
        for &f in g.iter().filter(|&&f| f != best) {
            keep[f as usize] = false;
            dropped += 1;
        }
    }
    dropped
}

/// Whether a face repeats a vertex index or has zero area. The area test is relative to the
/// face's longest edge, in f64, so it flags exactly collinear corners and slivers whose angle
/// is below ~1e-12 rad, and nothing that merely is small.
pub fn is_degenerate(positions: &[glam::Vec3], t: &[u32; 3]) -> bool {
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        return true;
    }
    let [a, b, c] = t.map(|i| positions[i as usize].as_dvec3());
    let cross = (b - a).cross(c - a).length();
    let longest = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    cross <= 1e-12 * longest
}

/// Edge, orientation and component statistics of `mesh` (indices must be in range).
/// `welded_vertices` and `degenerate_faces` are left at zero.
pub fn analyze(mesh: &Mesh) -> MeshReport {
    // Each face edge as (min, max, forward?); sorting groups the uses of each undirected edge.
    let mut edges: Vec<(u32, u32, bool)> = Vec::with_capacity(mesh.triangles.len() * 3);
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), a < b));
        }
    }
    edges.par_sort_unstable();
    let (mut unique, mut boundary, mut nonmanifold, mut inconsistent) = (0, 0, 0, 0);
    for run in edges.chunk_by(|x, y| x.0 == y.0 && x.1 == y.1) {
        unique += 1;
        match run.len() {
            1 => boundary += 1,
            2 => inconsistent += usize::from(run[0].2 == run[1].2),
            _ => nonmanifold += 1,
        }
    }

    // Union-find over vertices joined by face edges.
    let n = mesh.positions.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    let mut referenced = vec![false; n];
    for t in &mesh.triangles {
        for &v in t {
            referenced[v as usize] = true;
        }
        let r0 = find(&mut parent, t[0]);
        for &v in &t[1..] {
            let r = find(&mut parent, v);
            if r != r0 {
                parent[r as usize] = r0;
            }
        }
    }
    let used = referenced.iter().filter(|&&r| r).count();
    let components = (0..n as u32).filter(|&v| referenced[v as usize] && find(&mut parent, v) == v).count();

    MeshReport {
        vertices: n,
        triangles: mesh.triangles.len(),
        welded_vertices: 0,
        degenerate_faces: 0,
        repeated_faces: 0,
        folded_before: 0,
        unfolded_vertices: 0,
        folded_faces: 0,
        boundary_edges: boundary,
        nonmanifold_edges: nonmanifold,
        inconsistent_edges: inconsistent,
        unreferenced_vertices: n - used,
        components,
        euler_characteristic: used as i64 - unique as i64 + mesh.triangles.len() as i64,
        flipped_inside_out: false,
        unterminated_last_line: false,
    }
}

/// Flips every face of `mesh` (swaps its second and third corners) when `report` says it is a
/// closed, consistently oriented manifold and its signed volume is negative, i.e. every normal
/// points in; returns whether it flipped. An open or non-manifold mesh keeps its winding: its
/// signed volume depends on where the holes are and does not tell inside from outside.
pub fn flip_if_inside_out(mesh: &mut Mesh, report: &MeshReport) -> bool {
    if !report.is_closed_manifold() || mesh.signed_volume() >= 0.0 {
        return false;
    }
    for t in &mut mesh.triangles {
        t.swap(1, 2);
    }
    true
}

/// Merges vertices at bitwise-equal positions (`-0.0` and `0.0` count as equal) into the
/// first one, re-indexes the faces and drops the merged vertices. Returns how many vertices
/// were merged. Faces that become degenerate are left for [`validate`] to remove; a mesh with
/// out-of-range indices is left unchanged.
pub fn weld_exact_duplicates(mesh: &mut Mesh) -> usize {
    // Leave a mesh with invalid indices untouched, so validate() reports them as given.
    let n = mesh.positions.len();
    if mesh.triangles.iter().flatten().any(|&v| v as usize >= n) {
        return 0;
    }
    let key = |p: glam::Vec3| (p + glam::Vec3::ZERO).to_array().map(f32::to_bits);
    let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(mesh.positions.len());
    let mut remap = Vec::with_capacity(mesh.positions.len());
    let mut kept = Vec::with_capacity(mesh.positions.len());
    for &p in &mesh.positions {
        let next = kept.len() as u32;
        let id = *first.entry(key(p)).or_insert(next);
        if id == next {
            kept.push(p);
        }
        remap.push(id);
    }
    let merged = mesh.positions.len() - kept.len();
    if merged > 0 {
        mesh.positions = kept;
        for t in &mut mesh.triangles {
            for v in t.iter_mut() {
                *v = remap[*v as usize];
            }
        }
    }
    merged
}

impl Mesh {
    /// Signed volume enclosed by the mesh, in mesh units^3 (divergence theorem, sum of
    /// `a . (b x c) / 6` over faces, in f64). Positive for a closed mesh with outward
    /// counter-clockwise faces; meaningless for an open mesh.
    pub fn signed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize].as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Edge, orientation and component statistics (see [`analyze`]).
    pub fn topology(&self) -> MeshReport {
        analyze(self)
    }
}
