//! The exact reference solver (Mertens §3.1): `B` at every face midpoint as the sum over all
//! faces of `E_k F(A_k, x_o)`, O(N^2), parallel over receivers.
//!
//! The only shortcut: a face whose every point is farther than [`NEGLIGIBLE_SIGMA_DIST`]
//! diffusion lengths (`1/σ_tr`) from all six dipole sources contributes less than
//! `e^{-60}` of a near face and is skipped, as the form factor itself drops edge parts past
//! `e^{-40}`. This matters only for opaque materials at large scales (a face then sees a few
//! hundred neighbours), and leaves every result unchanged to well below `f32` precision.

use crate::Rgb;
use crate::bssrdf::Dipole;
use crate::formfactor::{FormFactorOptions, form_factor};
use crate::mesh::Mesh;
use glam::DVec3;
use rayon::prelude::*;

/// Faces farther than this many diffusion lengths from every dipole source are skipped
/// (their transport is below `e^{-60}` of a near face's).
pub const NEGLIGIBLE_SIGMA_DIST: f64 = 60.0;

/// Per-face `B` (same units as the irradiance) for per-face irradiance `face_irradiance`.
pub fn solve(mesh: &Mesh, dipole: &Dipole, face_irradiance: &[Rgb], opts: &FormFactorOptions) -> Vec<Rgb> {
    assert_eq!(face_irradiance.len(), mesh.triangles.len());
    let tris: Vec<[DVec3; 3]> =
        (0..mesh.triangles.len()).map(|f| mesh.corners(f).map(|p| p.as_dvec3())).collect();
    // Bounding sphere of each face (about its vertex average).
    let spheres: Vec<(DVec3, f64)> = tris
        .iter()
        .map(|t| {
            let c = (t[0] + t[1] + t[2]) / 3.0;
            (c, t.iter().map(|p| p.distance(c)).fold(0.0, f64::max))
        })
        .collect();
    (0..tris.len())
        .into_par_iter()
        .map(|o| {
            let x_o = mesh.face_centroid(o).as_dvec3();
            let n_o = mesh.face_normal(o).as_dvec3();
            let sources: [(DVec3, f64); 6] = std::array::from_fn(|k| {
                let c = k / 2;
                let z = if k % 2 == 0 { -dipole.z_r[c] } else { dipole.z_v[c] };
                (x_o + z * n_o, dipole.sigma_tr[c])
            });
            let mut b = [0.0f64; 3];
            for (k, tri) in tris.iter().enumerate() {
                let e = face_irradiance[k];
                if e == Rgb::ZERO {
                    continue;
                }
                let (c, r) = spheres[k];
                if sources.iter().all(|&(s, sigma)| sigma * (s.distance(c) - r) > NEGLIGIBLE_SIGMA_DIST) {
                    continue;
                }
                let f = form_factor(tri, x_o, n_o, dipole, opts);
                for c in 0..3 {
                    b[c] += e[c] as f64 * f[c];
                }
            }
            Rgb::new(b[0] as f32, b[1] as f32, b[2] as f32)
        })
        .collect()
}
