//! Midpoint refinement: every triangle split into four at its edge midpoints, the surface left
//! where it was.
//!
//! The solve keeps one radiosity `B` per face and the renderer interpolates it, and single
//! scattering, between vertices. Near a shadow edge both change over about a mean free path
//! `1 / sigma_t'`; a face many mean free paths wide averages the lit side into the dark one and
//! its vertices miss the single scattering's fall-off. Against Mitsuba (worst 8x8 block,
//! `docs/validation.md`) one split halves the error of a mesh whose edges are 12 mean free
//! paths (the 10 cm marble bunny) and a second gains nothing. [`auto_levels`] splits until the
//! mean edge is at most [`EDGE_PER_MEAN_FREE_PATH`] mean free paths: the bunny and the dragon
//! once, the sphere (split by hand: `--refine 1`) not, as its gain costs four times the solve.

use super::Mesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// Longest mean edge, in reduced mean free paths of the most opaque channel, that the solve
/// and the renderer resolve without splitting (see the module doc for the measurements).
pub const EDGE_PER_MEAN_FREE_PATH: f64 = 6.0;
/// Most splits [`auto_levels`] makes (each multiplies the faces by four).
pub const MAX_AUTO_LEVELS: u32 = 2;
/// Faces [`auto_levels`] does not split past: a mesh this dense is a scan whose faces are
/// small for any scale a viewer frames.
pub const MAX_AUTO_TRIANGLES: usize = 1 << 20;
/// Most splits asked for by hand (`--refine N`): 4^3 = 64 times the faces.
pub const MAX_LEVELS: u32 = 3;

/// How many times the mesh is split before the solve (`lucent render --refine`, scene key
/// `refine`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Refine {
    /// [`auto_levels`] from the material and scale (default).
    #[default]
    Auto,
    /// This many splits, 0 ..= [`MAX_LEVELS`] (0: the mesh as loaded).
    Levels(u32),
}

impl Refine {
    /// The splits for `mesh` when one mesh unit is `metres_per_unit` and the shortest reduced
    /// mean free path is `mean_free_path_m` metres.
    pub fn levels(self, mesh: &Mesh, metres_per_unit: f64, mean_free_path_m: f64) -> u32 {
        match self {
            Refine::Auto => auto_levels(mesh, metres_per_unit, mean_free_path_m),
            Refine::Levels(n) => n,
        }
    }
}

impl std::str::FromStr for Refine {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim();
        if t.eq_ignore_ascii_case("auto") {
            return Ok(Refine::Auto);
        }
        match t.parse::<u32>() {
            Ok(n) if n <= MAX_LEVELS => Ok(Refine::Levels(n)),
            _ => Err(format!("refine {s:?}: expected `auto` or a number of splits 0..={MAX_LEVELS}")),
        }
    }
}

/// Splits each face of `mesh` into four, placing the new vertex of edge `(a, b)` at
/// `place(a, b)`; the four children of face `f` are faces `4f..4f+4`, in the order
/// `[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]`. Edges shared by two faces share their
/// new vertex, so a closed mesh stays closed.
pub fn split(mesh: &Mesh, place: impl Fn(Vec3, Vec3) -> Vec3) -> Mesh {
    let mut positions = mesh.positions.clone();
    let mut edge_vertex: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.triangles.len() * 2);
    let mut mid = |a: u32, b: u32| -> u32 {
        *edge_vertex.entry((a.min(b), a.max(b))).or_insert_with(|| {
            positions.push(place(positions[a as usize], positions[b as usize]));
            positions.len() as u32 - 1
        })
    };
    let mut triangles = Vec::with_capacity(mesh.triangles.len() * 4);
    for &[a, b, c] in &mesh.triangles {
        triangles.extend(quarters([a, b, c], [mid(a, b), mid(b, c), mid(c, a)]));
    }
    Mesh::new(positions, triangles)
}

/// The four children of corners `[a, b, c]` with edge points `[ab, bc, ca]`, in [`split`]'s
/// order: positions and per-corner values split alike.
fn quarters<T: Copy>([a, b, c]: [T; 3], [ab, bc, ca]: [T; 3]) -> [[T; 3]; 4] {
    [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
}

/// [`split`] at the edge midpoints, `levels` times: the same surface with `4^levels` times the
/// faces.
pub fn split_midpoints(mesh: &Mesh, levels: u32) -> Mesh {
    let mut out = mesh.clone();
    for _ in 0..levels {
        out = split(&out, |a, b| 0.5 * (a + b));
    }
    out
}

/// Per-corner values (texture coordinates) of a mesh split by [`split_midpoints`] `levels`
/// times: the children's corners in the same order.
pub fn split_corner_uvs(corner_uvs: &[[Vec2; 3]], levels: u32) -> Vec<[Vec2; 3]> {
    let mut out = corner_uvs.to_vec();
    for _ in 0..levels {
        out = out
            .iter()
            .flat_map(|&[a, b, c]| quarters([a, b, c], [0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)]))
            .collect();
    }
    out
}

/// Mean edge length of `mesh` (each face's three edges; an edge shared by two faces counts
/// twice), mesh units. Zero for an empty mesh.
pub fn mean_edge(mesh: &Mesh) -> f64 {
    let sum: f64 = (0..mesh.triangles.len())
        .map(|f| {
            let [a, b, c] = mesh.corners(f);
            (a.distance(b) + b.distance(c) + c.distance(a)) as f64
        })
        .sum();
    sum / (3 * mesh.triangles.len()).max(1) as f64
}

/// Whether transport at `mesh`'s mean face is local: the profile's `reach` (mesh units, the
/// radius holding all but `solver::local::TAIL` of `∫ R dA`) is shorter than the distance from
/// an equilateral triangle of the mean edge's centroid to its edges, `edge / (2 √3)`, the test
/// `solver::local` puts to every face. There `B` is the local limit `R_d E` (no light crosses a
/// face), so splitting only samples the irradiance more finely; the session evaluates that limit
/// at the vertices instead (`session::local_limit`), and [`Refine::Auto`] does not split.
pub fn mean_face_is_local(mesh: &Mesh, reach: f64) -> bool {
    mean_edge(mesh) / (2.0 * 3f64.sqrt()) > reach
}

/// Splits that bring `mesh`'s mean edge to at most [`EDGE_PER_MEAN_FREE_PATH`] times
/// `mean_free_path_m`, the shortest reduced mean free path `1 / (sigma_s' + sigma_a)` over the
/// channels, metres, when one mesh unit is `metres_per_unit`: at most [`MAX_AUTO_LEVELS`], and
/// none that would take the mesh past [`MAX_AUTO_TRIANGLES`] faces.
pub fn auto_levels(mesh: &Mesh, metres_per_unit: f64, mean_free_path_m: f64) -> u32 {
    let limit = EDGE_PER_MEAN_FREE_PATH * mean_free_path_m;
    let mut edge = mean_edge(mesh) * metres_per_unit;
    let mut faces = mesh.triangles.len();
    let mut levels = 0;
    while levels < MAX_AUTO_LEVELS && edge > limit && faces * 4 <= MAX_AUTO_TRIANGLES && limit > 0.0 {
        levels += 1;
        edge *= 0.5;
        faces *= 4;
    }
    levels
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn a_split_keeps_the_surface_closed_and_its_area() {
        let cube = generate::cube(1);
        let fine = split_midpoints(&cube, 2);
        assert_eq!(fine.triangles.len(), cube.triangles.len() * 16);
        let area = |m: &Mesh| (0..m.triangles.len()).map(|f| m.face_area(f) as f64).sum::<f64>();
        assert!((area(&fine) - area(&cube)).abs() < 1e-4 * area(&cube));
        // Closed: every directed edge has its reverse exactly once.
        let mut directed: HashMap<(u32, u32), i32> = HashMap::new();
        for &[a, b, c] in &fine.triangles {
            for (i, j) in [(a, b), (b, c), (c, a)] {
                *directed.entry((i, j)).or_default() += 1;
            }
        }
        assert!(directed.iter().all(|(&(i, j), &n)| n == 1 && directed.get(&(j, i)) == Some(&1)));
        // Euler characteristic of a sphere.
        let (v, f) = (fine.positions.len() as i64, fine.triangles.len() as i64);
        assert_eq!(v - f * 3 / 2 + f, 2);
        assert!((mean_edge(&fine) - 0.25 * mean_edge(&cube)).abs() < 1e-6);
    }

    #[test]
    fn children_keep_their_parents_normal_and_uvs_follow_them() {
        let m = generate::icosahedron();
        let fine = split_midpoints(&m, 1);
        for f in 0..m.triangles.len() {
            let n = m.face_cross(f).normalize();
            for k in 0..4 {
                assert!(fine.face_cross(4 * f + k).normalize().dot(n) > 1.0 - 1e-5);
            }
        }
        let uvs = vec![[Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)]];
        let fine_uvs = split_corner_uvs(&uvs, 1);
        assert_eq!(fine_uvs[3], [Vec2::new(0.5, 0.0), Vec2::new(0.5, 0.5), Vec2::new(0.0, 0.5)]);
        assert_eq!(fine_uvs[1][0], Vec2::new(1.0, 0.0));
    }

    #[test]
    fn refine_parses_auto_and_counts_and_names_the_range() {
        assert_eq!("auto".parse::<Refine>(), Ok(Refine::Auto));
        assert_eq!(" 2 ".parse::<Refine>(), Ok(Refine::Levels(2)));
        for bad in ["4", "-1", "many", ""] {
            let e = bad.parse::<Refine>().unwrap_err();
            assert!(e.contains("0..=3") && e.contains(&format!("{bad:?}")), "{e}");
        }
    }

    #[test]
    fn auto_levels_split_coarse_meshes_of_opaque_materials_only() {
        let m = generate::icosahedron(); // edge 1.05 units
        let e = mean_edge(&m);
        // 1 mm mean free path: a 6 mm edge stays, a 7 mm edge is split once, a 20 mm edge twice,
        // a 1 m edge only up to the most splits.
        let levels = |edge_m: f64| auto_levels(&m, edge_m / e, 1e-3);
        assert_eq!(levels(5.99e-3), 0);
        assert_eq!(levels(7e-3), 1);
        assert_eq!(levels(20e-3), 2);
        assert_eq!(levels(1.0), MAX_AUTO_LEVELS);
        // A mesh near the face budget is left alone.
        let dense = generate::icosphere(7); // 327,680 faces: one split would pass the budget
        assert_eq!(auto_levels(&dense, 1.0, 1e-6), 0);
    }
}
