//! The exact reference solver (Mertens §3.1): `B` at every face midpoint as the sum over all
//! faces of `E_k F(A_k, x_o)`, O(N^2), parallel over receivers.

use crate::Rgb;
use crate::bssrdf::Dipole;
use crate::formfactor::{FormFactorOptions, form_factor};
use crate::mesh::Mesh;
use glam::DVec3;
use rayon::prelude::*;

/// Per-face `B` (same units as the irradiance) for per-face irradiance `face_irradiance`.
pub fn solve(mesh: &Mesh, dipole: &Dipole, face_irradiance: &[Rgb], opts: &FormFactorOptions) -> Vec<Rgb> {
    assert_eq!(face_irradiance.len(), mesh.triangles.len());
    let tris: Vec<[DVec3; 3]> =
        (0..mesh.triangles.len()).map(|f| mesh.corners(f).map(|p| p.as_dvec3())).collect();
    (0..tris.len())
        .into_par_iter()
        .map(|o| {
            let x_o = mesh.face_centroid(o).as_dvec3();
            let n_o = mesh.face_normal(o).as_dvec3();
            let mut b = [0.0f64; 3];
            for (k, tri) in tris.iter().enumerate() {
                let e = face_irradiance[k];
                if e == Rgb::ZERO {
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
