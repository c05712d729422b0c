//! The body's chord along the view ray: the exit lobe of a finite body (not in Mertens et al.
//! 2003; issue "physically right").
//!
//! The exit lobe ([`crate::bssrdf::ExitLobe`]) is a half-space's: the diffuse light that leaves
//! towards the eye was scattered somewhere along the refracted view ray, which in a half-space
//! runs on for ever. In a body a few mean free paths across, the view ray leaves the body again
//! after its chord `L`, and nothing beyond scatters light back along it. Near the limb of a 2 cm
//! ketchup sphere (red: a 4 mm mean free path on a 10 mm radius) that chord is a few
//! millimetres, and lucent's multiple scattering read 79% over the path tracer's at grazing exit
//! in the lit band. With the scattering source about even over the first mean free paths, a chord
//! keeps `1 - e^{-σ_t L}` of the half-space's radiance. What a short chord does not send out
//! leaves along the long ones (`B` is still the whole exitance), so the factor is divided by its
//! mean over the exit directions as the lobe weights them:
//!
//! ```text
//! C(ω_o) = (1 - e^{-σ_t L(ω_t)}) / N,
//! N = ∫ F_t T(μ_o) (1 - e^{-σ_t L(μ_t)}) μ_o dμ_o / ∫ F_t T(μ_o) μ_o dμ_o,
//! ```
//!
//! with `ω_t` the refracted view direction and `μ_t` its cosine inside. `L(ω_t)` is traced per
//! vertex along the view ray. `N` needs chords in every direction; the finite-body gain's rays
//! under each face ([`ThicknessRays`]) give the thickness `t` along the inward normal and the
//! slabness `s` from the four tilted ones (a sphere's 45° chords are `t cos 45°`, a slab's
//! `t / cos 45°`), and the chords are taken as `L(μ_t) = t μ_t^{1 - 2s}`: a sphere's `2 R μ_t`
//! at `s = 0`, a slab's `t / μ_t` at `s = 1`. On a sphere `C` is exact for an even source; a
//! half-space (or any part many mean free paths thick) gets `C = 1`.

use crate::Rgb;
use crate::bssrdf::halfspace::gauss_legendre;
use crate::bssrdf::{Profile, fresnel_transmittance, refracted_cosine};
use crate::mesh::Mesh;
use crate::solver::finite_body::ThicknessRays;
use rayon::prelude::*;

use super::single_scattering::ViewRay;

/// Exit cosines over which `N` is integrated (Gauss-Legendre on `μ_o` in `0..1`).
const NODES: usize = 16;

/// The largest factor a vertex takes. On a sphere `C` stays under 1.5 (a vanishing sphere's
/// head-on chord over its mean); a thin part seen along its length can find a chord far longer
/// than its modelled mean, which no even source makes brighter than this.
pub const MAX_FACTOR: f32 = 1.5;

/// The lobe's weights over exit cosine and the material's extinction, for one profile.
#[derive(Clone, Debug, PartialEq)]
pub struct ExitChord {
    /// Per node: the refracted cosine inside `μ_t` and, per channel, `w F_t T μ_o` normalised to
    /// sum to 1.
    nodes: Vec<(f32, [f32; 3])>,
    /// Extinction `σ_t'` per mesh unit, per channel.
    sigma_t: [f32; 3],
}

impl ExitChord {
    /// The weights of `dipole`'s exit lobe at its index (`None` for a flat lobe: Mertens'
    /// profile keeps the paper's `F_t B / π`, and so no chord either).
    pub fn new(profile: &Profile) -> Option<Self> {
        if profile.exit_lobe.is_flat() {
            return None;
        }
        let eta = profile.eta;
        let q = gauss_legendre(NODES, 0.0, 1.0);
        let raw: Vec<(f32, [f64; 3])> = q
            .iter()
            .map(|&(mu, w)| {
                let t = profile.exit_lobe.at(mu as f32);
                let base = w * fresnel_transmittance(mu, eta) * mu;
                (refracted_cosine(mu, eta) as f32, std::array::from_fn(|c| base * t[c] as f64))
            })
            .collect();
        let total: [f64; 3] = std::array::from_fn(|c| raw.iter().map(|(_, a)| a[c]).sum::<f64>().max(1e-30));
        let nodes =
            raw.iter().map(|(mu_t, a)| (*mu_t, std::array::from_fn(|c| (a[c] / total[c]) as f32))).collect();
        Some(ExitChord { nodes, sigma_t: profile.sigma_t.map(|s| s as f32) })
    }

    /// `N` (module docs) for a part of thickness `t` (mesh units) and slabness `s` (0..=1).
    pub fn mean(&self, t: f32, s: f32) -> Rgb {
        let p = 1.0 - 2.0 * s.clamp(0.0, 1.0);
        Rgb::from_array(std::array::from_fn(|c| {
            self.nodes
                .iter()
                .map(|&(mu_t, a)| a[c] * kept(self.sigma_t[c] * t * mu_t.max(1e-4).powf(p)))
                .sum::<f32>()
                .max(1e-6)
        }))
    }

    /// `N` of every face of `mesh` from its [`ThicknessRays`] (rays from `offset` inside the
    /// faces): 1 where the inward ray left the mesh or the face has no normal.
    pub fn face_means(&self, mesh: &Mesh, rays: &ThicknessRays, offset: f32) -> Vec<Rgb> {
        (0..mesh.triangles.len())
            .into_par_iter()
            .map(|f| rays.body(mesh, f, offset).map_or(Rgb::ONE, |(t, s)| self.mean(t, s as f32)))
            .collect()
    }

    /// The factor `C` per vertex along its view ray (`rays`, from
    /// `single_scattering::view_rays`; 1 where the vertex is not seen), given each vertex's `N`
    /// (`vertex_means`, area-weighted over its faces). The diffuse radiance `B / (c π)` is
    /// multiplied by it.
    pub(crate) fn vertex_factors(&self, rays: &[Option<ViewRay>], vertex_means: &[Rgb]) -> Vec<Rgb> {
        rays.par_iter()
            .zip(vertex_means)
            .map(|(ray, n)| {
                let Some(ray) = ray else { return Rgb::ONE };
                let c = Rgb::from_array(std::array::from_fn(|k| kept(self.sigma_t[k] * ray.exit)));
                (c / *n).min(Rgb::splat(MAX_FACTOR))
            })
            .collect()
    }
}

/// `1 - e^{-x}`: the share of a half-space's radiance a chord `x` (optical units) keeps.
fn kept(x: f32) -> f32 {
    -(-x).exp_m1()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::{Material, ProfileKind};

    /// Ketchup in millimetres, single scattering along the view ray (not in `B`).
    fn ketchup(eta: f64) -> Profile {
        let mut m = Material::by_name("ketchup").unwrap();
        m.eta = eta;
        Profile::of_kind(&m, 1.0, ProfileKind::Pbd, false)
    }

    /// Over a sphere's exit directions, as the lobe weighs them, the factor averages to 1: the
    /// chord moves light between directions, and `B` all still leaves.
    #[test]
    fn on_a_sphere_the_factor_keeps_the_exitance() {
        for eta in [1.0, 1.3] {
            let chord = ExitChord::new(&ketchup(eta)).unwrap();
            for t in [0.5f32, 4.0, 20.0] {
                let n = chord.mean(t, 0.0);
                let mean: Rgb = chord
                    .nodes
                    .iter()
                    .map(|&(mu_t, a)| {
                        Rgb::from_array(a) * Rgb::from_array(chord.sigma_t.map(|s| kept(s * t * mu_t))) / n
                    })
                    .sum();
                assert!((mean - Rgb::ONE).abs().max_element() < 1e-5, "eta {eta} t {t}: {mean}");
            }
        }
    }

    /// A part many mean free paths thick is a half-space: no change; thin ones keep less on
    /// average, a sphere less than a slab of its thickness (its grazing chords are short).
    #[test]
    fn thick_parts_are_half_spaces_and_thin_spheres_lose_more_than_slabs() {
        let chord = ExitChord::new(&ketchup(1.0)).unwrap();
        let sigma_min = chord.sigma_t.iter().cloned().fold(f32::INFINITY, f32::min);
        let thick = chord.mean(200.0 / sigma_min, 0.0);
        assert!((thick - Rgb::ONE).abs().max_element() < 1e-3, "{thick}");
        let (sphere, slab) = (chord.mean(2.0, 0.0), chord.mean(2.0, 1.0));
        assert!(sphere.x < slab.x && slab.x < 1.0, "sphere {sphere} slab {slab}");
        // A sphere's mean in closed form for a flat lobe at eta 1: 1 - 2 (1 - e^{-x} (1 + x)) / x²;
        // the half-space lobe tilts it by a few per cent at most.
        let x = chord.sigma_t[0] * 2.0;
        let flat = 1.0 - 2.0 * (1.0 - (-x).exp() * (1.0 + x)) / (x * x);
        assert!((sphere.x / flat - 1.0).abs() < 0.05, "{} against {flat}", sphere.x);
    }

    /// Mertens' profile keeps the paper's flat lobe, and so no chord.
    #[test]
    fn mertens_has_no_chord() {
        let d = Profile::new(&Material::by_name("marble").unwrap(), 1.0);
        assert!(ExitChord::new(&d).is_none());
    }
}
