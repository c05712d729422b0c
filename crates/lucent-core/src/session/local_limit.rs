//! The local limit at the vertices (issue 51, dense materials): where transport is far below a
//! face's size (`solver::local`: the profile's reach, which holds all but `TAIL` of `R_d`, is
//! shorter than the face's centroid is from its edges, and no other surface comes that close),
//! the subsurface radiance at a point is `R_d` times the irradiance at that point (Mertens eq. 6
//! with the profile's whole integral inside the face), and the irradiance changes across the
//! face with the light's cosine and distance and at shadow edges. The solve's one `B` per face
//! is that limit at the centroid. Instead of splitting such faces until a `B` per face resolves
//! the irradiance (`mesh::refine`, which `refine = auto` no longer does where the mean face is
//! local), each local face's corners get its own factor `k` (`B = k E`, `R_d_total` times the
//! energy bound and gain) times the lights' change from centroid to corner
//! (`irradiance::corners`), averaged into the vertices with the face areas as `B` is
//! (`Mesh::face_to_vertex`). A vertex shared with faces that are not local blends by area
//! towards their solved `B`, which holds their light from elsewhere. The share of `R_d` within
//! a local face's size is `1 - TAIL` or more by that test, so the corner value is the limit
//! itself; faces that are not local get no change, which keeps every other material's image as
//! it was. View-ray single scattering is evaluated per vertex already.

use super::Frame;
use super::irradiance::Irradiance;
use crate::Rgb;
use crate::irradiance::corners::corner_changes;
use crate::solver::HierarchicalSolver;

/// The change of `B` per vertex that the local limit at the corners of `solver`'s local faces
/// makes (see the module documentation), or `None` where no face is local, no light shines or
/// the method has no hierarchical solver (the exact sum keeps its `B` per face).
pub(super) fn vertex_change(
    f: &Frame,
    irradiance: &Irradiance,
    solver: Option<&HierarchicalSolver>,
) -> Option<Vec<Rgb>> {
    let solver = solver.filter(|_| f.settings.method == super::Method::Hierarchical)?;
    if irradiance.lights().is_empty() {
        return None;
    }
    let factors = solver.local_factors();
    let faces: Vec<u32> = (0..factors.len() as u32).filter(|&i| factors[i as usize].is_some()).collect();
    if faces.is_empty() {
        return None;
    }
    let mesh = &f.mesh;
    let entry = &f.profile.entry;
    let changes = corner_changes(mesh, &faces, irradiance.lights(), entry, irradiance.caster());
    // What an oblique beam returns at its entry point (`Irradiance::add_local`).
    let r_local = match entry.has_local() {
        true => Rgb::from_array(f.profile.total_diffuse_reflectance().map(|v| v as f32)),
        false => Rgb::ZERO,
    };
    let mut weight = vec![0.0f32; mesh.positions.len()];
    for (face, tri) in mesh.triangles.iter().enumerate() {
        let a = mesh.face_area(face);
        tri.iter().for_each(|&v| weight[v as usize] += a);
    }
    let mut sum = vec![Rgb::ZERO; mesh.positions.len()];
    for (&face, corners) in faces.iter().zip(&changes) {
        let face = face as usize;
        let k = factors[face].expect("local faces only");
        let a = mesh.face_area(face) * irradiance.entry_factor(face);
        for (&v, c) in mesh.triangles[face].iter().zip(corners) {
            sum[v as usize] += a * (k * c.carried + r_local * c.local);
        }
    }
    Some(sum.iter().zip(&weight).map(|(s, w)| if *w > 0.0 { *s / *w } else { Rgb::ZERO }).collect())
}
