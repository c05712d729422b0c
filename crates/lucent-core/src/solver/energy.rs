//! The energy bound on thin and touching parts (not in Mertens et al. 2003; issue "physically
//! right").
//!
//! Diffusion profiles are fitted to a flat, semi-infinite medium. On a thin part, or where two
//! parts nearly touch, a receiver gathers from surfaces on more than one side and the sum of its
//! form factors can exceed what light entering there could possibly give back. Under uniform
//! irradiance 1 on every face, reciprocity makes a face's `B` the share of light entering there
//! that leaves anywhere, which cannot exceed 1. Each face's `B` is therefore scaled, per channel,
//! by `min(1, 1 / U)`, where `U` is its `B` under uniform irradiance 1: where the profile keeps
//! energy (any thick, convex region: `U` is the flat total reflectance there, below 1) nothing
//! changes. `U` is gathered beside `B` (on the fly), or once per link set (render and
//! incremental modes), so the bound costs one extra add per link.

use crate::Rgb;

/// The factor applied to a face's `B` whose `B` under uniform irradiance 1 is `uniform`:
/// `min(1, 1/U)` per channel (1 where `U` is 0 or not finite).
#[inline]
pub fn bound(uniform: Rgb) -> Rgb {
    Rgb::from_array(uniform.to_array().map(|u| if u > 1.0 && u.is_finite() { 1.0 / u } else { 1.0 }))
}

/// What [`uniform_report`] measures on one mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformReport {
    /// Largest `B` over faces and channels under uniform irradiance 1 after the bound
    /// (unitless; at most 1 for the bounded profiles).
    pub max_b_uniform: f32,
    /// The same before the bound: how far the profile alone breaks energy conservation.
    pub max_b_unbounded: f32,
    /// Faces whose `B` exceeds 1 before the bound in some channel (those the bound lowers,
    /// where the profile has it on).
    pub faces_bounded: usize,
    /// Faces in the mesh.
    pub faces: usize,
    /// Links of the hierarchical solve.
    pub links: usize,
}

/// Solves `mesh` under uniform irradiance 1 with the hierarchical solver (on the fly) and
/// reports the largest `B` with and without the bound (`lucent bench energy`).
pub fn uniform_report(
    mesh: &crate::mesh::Mesh,
    dipole: &crate::bssrdf::Dipole,
    oracle: super::Oracle,
) -> UniformReport {
    let h = crate::hierarchy::face_cluster::build(mesh);
    let mut unbounded = dipole.clone();
    unbounded.energy_bound = false;
    let ones = vec![Rgb::ONE; mesh.triangles.len()];
    let solver = super::HierarchicalSolver::new(mesh.clone(), h, unbounded, oracle);
    let raw = solver.solve_on_the_fly(&ones);
    let max = |b: &[Rgb]| b.iter().map(|v| v.max_element()).fold(0.0f32, f32::max);
    let bounded: Vec<Rgb> =
        raw.face_b.iter().map(|&u| if dipole.bounds_energy() { u * bound(u) } else { u }).collect();
    UniformReport {
        max_b_uniform: max(&bounded),
        max_b_unbounded: max(&raw.face_b),
        faces_bounded: raw.face_b.iter().filter(|u| u.max_element() > 1.0).count(),
        faces: mesh.triangles.len(),
        links: raw.stats.links,
    }
}
