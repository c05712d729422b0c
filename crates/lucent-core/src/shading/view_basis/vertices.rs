//! The per-vertex half of a camera move: each vertex's area-weighted mean over its faces that
//! face the eye, the chord factor and the drawn diffuse radiance in the same pass, then the
//! single scattering's floor at the neighbours (as `single_scattering` raises it) from each
//! vertex's distinct neighbours, listed once per topology, into buffers the caller keeps.
//! The sums run in the order the per-face evaluation's did (each vertex's faces in
//! `Mesh::vertex_faces`'s order), so the values are those of `ViewBasis::seen` before issue
//! 51's camera-move work, bit for bit, given the same faces.

use super::eye::FaceSeen;
use crate::Rgb;
use crate::mesh::Mesh;
use crate::shading::exit_chord::MAX_FACTOR;
use crate::shading::single_scattering::NEIGHBOUR_FLOOR;
use glam::{Vec4, Vec4Swizzles};
use rayon::prelude::*;

/// Vertices per parallel task: large enough that two cores' hand-over costs little against
/// the work (about 20 µs a task).
const CHUNK: usize = 8192;

/// Compressed rows of each vertex's distinct neighbours (the other vertices of its faces),
/// from `vertex_faces`'s rows `(offsets, faces)`: `(offsets, neighbours)`.
pub(super) fn neighbours(mesh: &Mesh, offsets: &[u32], faces: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let rows: Vec<Vec<u32>> = (0..offsets.len() - 1)
        .into_par_iter()
        .map(|v| {
            let mut row: Vec<u32> = faces[offsets[v] as usize..offsets[v + 1] as usize]
                .iter()
                .flat_map(|&f| mesh.triangles[f as usize])
                .filter(|&u| u as usize != v)
                .collect();
            row.sort_unstable();
            row.dedup();
            row
        })
        .collect();
    let mut starts = Vec::with_capacity(rows.len() + 1);
    starts.push(0u32);
    for row in &rows {
        starts.push(starts[starts.len() - 1] + row.len() as u32);
    }
    (starts, rows.concat())
}

/// What the mean pass multiplies and writes besides the means.
#[derive(Clone, Copy)]
pub(super) struct Means<'a> {
    /// The diffuse radiance `B / (c π)` per vertex: `radiance` gets it times the chord factor
    /// (`None`: the chord factor itself).
    pub(super) diffuse: Option<&'a [Rgb]>,
    /// Each vertex's mean chord factor `N` (`None`: no chord factor, i.e. 1).
    pub(super) chord_means: Option<&'a [Rgb]>,
}

/// Per vertex of the rows `(offsets, vertex_faces)` (each vertex's faces, as `Mesh::vertex_faces`
/// orders them, by their positions in `per_face`), from the faces' `per_face`: `radiance`
/// (see [`Means`]) and the mean single scattering before the neighbour floor, `single`
/// (fourth lane 0).
pub(super) fn means(
    per_face: &[FaceSeen],
    (offsets, vertex_faces): (&[u32], &[u32]),
    m: Means,
    radiance: &mut [Rgb],
    single: &mut [Vec4],
) {
    radiance.par_chunks_mut(CHUNK).zip(single.par_chunks_mut(CHUNK)).enumerate().for_each(
        |(c, (radiance, single))| {
            for (j, (rad, l_out)) in radiance.iter_mut().zip(single.iter_mut()).enumerate() {
                let v = c * CHUNK + j;
                // (w, kept) and (single, 0) summed lane by lane: the same additions, in the
                // same order, as three scalars each.
                let (mut wk, mut l) = (Vec4::ZERO, Vec4::ZERO);
                for &f in &vertex_faces[offsets[v] as usize..offsets[v + 1] as usize] {
                    let [a, b] = per_face[f as usize].0;
                    wk += a;
                    l += b;
                }
                let w = wk.x;
                let (kept, mean) =
                    if w > 0.0 { (wk.yzw() / w, l / Vec4::splat(w)) } else { (Rgb::ZERO, Vec4::ZERO) };
                *l_out = mean;
                let factor = m.chord_means.map(|n| {
                    // A vertex no facing face holds is not seen: factor 1, as per eye.
                    if kept == Rgb::ZERO { Rgb::ONE } else { (kept / n[v]).min(Rgb::splat(MAX_FACTOR)) }
                });
                *rad = match (m.diffuse, factor) {
                    (Some(d), Some(c)) => d[v] * c,
                    (Some(d), None) => d[v],
                    (None, c) => c.unwrap_or(Rgb::ONE),
                };
            }
        },
    );
}

/// `out[v]`: `r[v]` raised to [`NEIGHBOUR_FLOOR`] times the brightest of its `neighbours`'
/// (rows `(offsets, neighbours)`). Four lanes at once (`Vec4::max` picks as `Vec3::max`
/// does, `a > b ? a : b`), the fourth dropped.
pub(super) fn floor_at_neighbours(r: &[Vec4], (offsets, neighbours): (&[u32], &[u32]), out: &mut [Rgb]) {
    out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
        for (j, o) in out.iter_mut().enumerate() {
            let v = c * CHUNK + j;
            let mut floor = Vec4::ZERO;
            for &u in &neighbours[offsets[v] as usize..offsets[v + 1] as usize] {
                floor = floor.max(r[u as usize]);
            }
            *o = r[v].max(floor * NEIGHBOUR_FLOOR).truncate();
        }
    });
}
