//! The exact reference solver (Mertens §3.1): `B` at every face midpoint as the sum over all
//! faces of `E_k F(A_k, x_o)`, O(N^2), parallel over receivers, with the energy bound of
//! [`super::energy`] where the profile asks for it.
//!
//! The only shortcut: a face out of the profile's reach ([`Profile::out_of_reach`]: farther than
//! 60 diffusion lengths `1/σ_tr` from the dipole's poles, and beyond its tables) contributes
//! less than `e^{-60}` of a near face and is skipped, as the form factor itself drops edge
//! parts past `e^{-40}`. This matters only for opaque materials at large scales (a face then sees a few
//! hundred neighbours), and leaves every result unchanged to well below `f32` precision.

use super::bound;
use crate::Rgb;
use crate::bssrdf::Profile;
use crate::formfactor::{FormFactorOptions, form_factor};
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;

/// Relative RMS error of `test` against `reference` (the exact solve's `B`, per face or
/// vertex): `sqrt(Σ (a - b)² / Σ a²)` over every element and channel. Unitless.
pub fn rel_rmse(reference: &[Rgb], test: &[Rgb]) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (a, b) in reference.iter().zip(test) {
        for c in 0..3 {
            num += ((a[c] - b[c]) as f64).powi(2);
            den += (a[c] as f64).powi(2);
        }
    }
    (num / den.max(1e-300)).sqrt()
}

/// Per-face `B` (same units as the irradiance) for per-face irradiance `face_irradiance`.
pub fn solve(mesh: &Mesh, profile: &Profile, face_irradiance: &[Rgb], opts: &FormFactorOptions) -> Vec<Rgb> {
    let all: Vec<usize> = (0..mesh.triangles.len()).collect();
    solve_receivers(mesh, profile, face_irradiance, opts, &all, None)
}

/// `B` at the faces `receivers` only (in that order), each gathered exactly as [`solve`] does
/// (from every face, with the same form factor and energy bound): O(N) per receiver, a
/// reference for sampled faces of meshes too large for the whole O(N²) solve. `progress`,
/// when given, counts receivers done (stage "exact").
pub fn solve_receivers(
    mesh: &Mesh,
    profile: &Profile,
    face_irradiance: &[Rgb],
    opts: &FormFactorOptions,
    receivers: &[usize],
    progress: Option<&Progress>,
) -> Vec<Rgb> {
    solve_receivers_with_gain(mesh, profile, face_irradiance, opts, receivers, progress, None, None)
}

/// [`solve_receivers`] with the finite-body gain per face (`gain`, one per face of `mesh`;
/// [`super::finite_body`]) applied with the energy bound, as the hierarchical solver does,
/// leaving room for what each face adds after the solve under uniform irradiance 1 (`term`:
/// the slab transmission, [`super::transmission`]).
#[allow(clippy::too_many_arguments)] // the solve's inputs, each one per face or per call
pub fn solve_receivers_with_gain(
    mesh: &Mesh,
    profile: &Profile,
    face_irradiance: &[Rgb],
    opts: &FormFactorOptions,
    receivers: &[usize],
    progress: Option<&Progress>,
    gain: Option<&[Rgb]>,
    term: Option<&[Rgb]>,
) -> Vec<Rgb> {
    assert_eq!(face_irradiance.len(), mesh.triangles.len());
    if let Some(p) = progress {
        p.start("exact", receivers.len());
    }
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
    let bound = profile.bounds_energy();
    receivers
        .par_iter()
        .map(|&o| {
            let x_o = mesh.face_centroid(o).as_dvec3();
            let n_o = mesh.face_normal(o).as_dvec3();
            // `B`, and `B` under uniform irradiance 1 for the energy bound.
            let (mut b, mut u) = ([0.0f64; 3], [0.0f64; 3]);
            for (k, tri) in tris.iter().enumerate() {
                let e = face_irradiance[k];
                if e == Rgb::ZERO && !bound {
                    continue;
                }
                let (c, r) = spheres[k];
                if profile.out_of_reach(x_o, n_o, c, r) {
                    continue;
                }
                let f = form_factor(tri, x_o, n_o, profile, opts);
                for c in 0..3 {
                    b[c] += e[c] as f64 * f[c];
                    u[c] += f[c];
                }
            }
            if let Some(p) = progress {
                p.add(1);
            }
            let b = Rgb::new(b[0] as f32, b[1] as f32, b[2] as f32);
            let u = Rgb::new(u[0] as f32, u[1] as f32, u[2] as f32);
            match (bound, gain) {
                (false, _) => b,
                (true, Some(g)) => match term {
                    Some(t) => b * bound::bound_with_gain_and_term(u, g[o], t[o]),
                    None => b * bound::bound_with_gain(u, g[o]),
                },
                (true, None) => b * bound::bound(u),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::Material;
    use crate::mesh::generate::icosphere;

    #[test]
    fn receivers_match_the_full_solve_and_count_progress() {
        let mesh = icosphere(2);
        let d = Profile::for_model_scale(&Material::by_name("marble").unwrap(), mesh.extent() as f64, 0.05);
        let e: Vec<Rgb> = (0..mesh.triangles.len()).map(|f| Rgb::splat((f % 7) as f32 * 0.1)).collect();
        let opts = FormFactorOptions::default();
        let all = solve(&mesh, &d, &e, &opts);
        let picks = [5, 0, 17, 63];
        let p = Progress::new();
        let some = solve_receivers(&mesh, &d, &e, &opts, &picks, Some(&p));
        for (&f, b) in picks.iter().zip(&some) {
            assert_eq!(all[f], *b);
        }
        assert_eq!(p.snapshot(), ("exact", 4, 4));
    }
}
