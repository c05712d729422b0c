//! The exit of light that crossed the body (issue 50; not in Mertens et al. 2003): flux
//! flowing out through a thin part's face with no source near it leaves forward-peaked. At 6.6
//! mean free paths (3 mm of marble's red) a slab's transmitted multiple scattering is 1.21 times
//! a Lambertian exit's radiance head-on and 0.83 at `μ = 0.45`, where the half-space's multiple
//! scattering, lucent's exit lobe, is 1.04-1.07 head-on (`validation/slab_walk.py lobe`, and
//! the 1D transport solve of `bssrdf::slab`, which tabulates it). Without it a 3 mm marble box
//! lit from behind read 16% dark against the path tracer with `B` right.

use crate::Rgb;
use crate::bssrdf::fresnel_transmittance;
use crate::bssrdf::{ExitLobe, Profile};
use crate::mesh::Mesh;
use crate::shading::single_scattering::ViewRay;
use crate::solver::transmission::{CrossBody, Tilt};
use glam::Vec3;
use rayon::prelude::*;

/// What a solve's `B` holds of light that crossed the body, per face, for the way it leaves.
#[derive(Clone, Debug, Default)]
pub(crate) struct Transmitted {
    /// `B` per face (radiosity units).
    pub face_b: Vec<Rgb>,
    /// The transmitted light it holds (`solver::transmission::CrossBody::add`; same units).
    pub sent: Vec<Rgb>,
    /// How the sphere's share of it leaves (`CrossBody::tilts`; empty: normal-centred).
    pub tilts: Vec<Tilt>,
}

/// Per vertex of `shares` (a solve's transmitted light, [`ExitShares`]), what multiplies the
/// diffuse radiance `B / (c π)` for the way the light crossing the body leaves, for a material
/// of relative index `eta`: the share `w` of the vertex's `B` that was transmitted
/// (`sent` over `face_b`, area-weighted over its faces) leaves as a slab's transmitted light
/// does (forward-peaked: 1.2 times a Lambertian exit head-on at 6.6 mean free paths, where
/// the half-space's multiple scattering is 1.04-1.07), the rest as before, times its chord
/// factor `chord`: `(1 - w) C + w p_T(μ_o) / lobe(μ_o)`, with `p_T` the slab's
/// (`bssrdf::slab::SlabTable::lobe`) at the vertex's thickness (weighted by the transmitted light) and
/// `lobe` the half-space's exit lobe the mesh pass applies. `rays` are the vertices' view
/// rays (`None`: not seen, `chord` as it is).
///
/// The sphere's share of it (`tilts`: at most the transmitted light, per face) came the short
/// way round rather than through the diameter, and leaves by its own lobe instead, from the
/// sphere walk's two moments there (`bssrdf::sphere_walk::Exits`): the mean normal cosine
/// `μ̄_n` ([`round_lobe`]) and the tilt `μ̄_t`, the flux-weighted mean of `ω_o · t` along the
/// flow (0.05-0.29 from 45 degrees to the terminator), as
/// `1 + β (μ_o - 2/3) + 7.5 μ̄_t μ_o (ω_o · t)` over a Lambertian exit. The tilt term keeps
/// the flux and has that first moment (the `7.5` is `1 / ∫ μ² (ω·t)² dω / π`); the forward walk
/// that scores where each photon leaves (docs/transmission.md) favours it over the plain
/// first-moment lobe `1 + 4 μ̄_t (ω_o · t)`: light that leaves at grazing angles is tilted less
/// (spheres of 2.4 to 15 mean free paths: rms log error of the radiance in 16-32 direction
/// cells 0.08-0.30 against 0.12-0.43, and 0.22-0.63 for no tilt). The moments are
/// area-weighted to the vertices by the share, like `B`. At `η ≠ 1` the moments are the
/// dielectric walk's, of the light refracted out, and the lobe is over the mesh pass's own,
/// `F_t(η, μ_o) T(μ_o) / c` (`bssrdf::exit`), which at `η = 1` is `T(μ_o)`.
pub(crate) fn exit_factors(
    cross: &CrossBody,
    shares: &ExitShares,
    rays: &[Option<ViewRay>],
    eta: f64,
    chord: &[Rgb],
) -> Vec<Rgb> {
    let eta = eta as f32;
    (0..rays.len())
        .into_par_iter()
        .map(|v| {
            let c = chord.get(v).copied().unwrap_or(Rgb::ONE);
            let Some(ray) = &rays[v] else { return c };
            // The light reaches the surface along -w_t and leaves refracted: its tangential
            // part grows by η (Snell), its normal cosine is μ_o.
            let w_in = -ray.w_t;
            let w_o = if eta == 1.0 {
                w_in
            } else {
                (w_in - w_in.dot(ray.normal) * ray.normal) * eta + ray.normal * ray.mu_o
            };
            shares.factor(v, cross, ray.mu_o, w_o, c)
        })
        .collect()
}

/// The least transmitted share of a vertex's `B` whose lobe a camera move with the split view
/// terms evaluates: below it the factor differs from the chord's by a few percent of this at
/// most (the lobes' ratio to the chord's stays within about 0.4-1.6), and a camera move at 203K
/// triangles does not read every vertex's share.
const SPLIT_MIN_SHARE: f32 = 0.02;

/// What [`exit_factors`] needs per vertex that does not depend on the eye (made once per
/// solve; the split view terms evaluate [`ExitShares::factor`] per eye from it).
#[derive(Clone, Debug, Default)]
pub(crate) struct ExitShares {
    /// Per vertex: its share of transmitted light, `None` where it holds none.
    vertices: Vec<Option<VertexShare>>,
    /// The vertices a camera move with the split view terms evaluates: a normal kept and a
    /// transmitted share of at least [`SPLIT_MIN_SHARE`] (ascending).
    split: Vec<u32>,
    /// The mesh pass's exit over a Lambertian one, `F_t(η, μ_o) T(μ_o) / c` (`bssrdf::exit`;
    /// `T` alone at `η = 1`), tabulated once: `c` is an integral and `F_t` costs a square root.
    base: ExitLobe,
}

/// One vertex's transmitted light, area-weighted from its faces.
#[derive(Clone, Copy, Debug)]
struct VertexShare {
    /// `B` (radiosity units).
    b: Rgb,
    /// The transmitted share of `B` and the sphere's share of it (unitless, `0 <= round <= sent
    /// <= 1` per channel).
    sent: Rgb,
    round: Rgb,
    /// The thickness under it, weighted by the transmitted light (mesh units).
    thickness: f32,
    /// The sphere's share's mean normal cosine (unitless; 2/3 where it has none).
    mean_cos: Rgb,
    /// The sphere's share's first moment along the flow, `Σ share μ̄_t t` per axis (`B` units).
    along: [Rgb; 3],
    /// The unit vertex normal (zero where none was given).
    normal: Vec3,
}

impl ExitShares {
    /// The shares of `transmitted`'s light at every vertex of `mesh`, with its unit vertex
    /// `normals` for [`ExitShares::seen_from`] (empty: not kept), for `profile`'s exit.
    pub(crate) fn new(
        cross: &CrossBody,
        mesh: &Mesh,
        normals: &[Vec3],
        transmitted: &Transmitted,
        profile: &Profile,
    ) -> Self {
        let Transmitted { face_b, sent, tilts } = transmitted;
        let b_v = mesh.face_to_vertex(face_b);
        let sent_v = mesh.face_to_vertex(sent);
        let weighted: Vec<Rgb> =
            sent.iter().zip(cross.thickness()).map(|(s, &t)| Rgb::splat(s.element_sum() * t)).collect();
        let t_v = mesh.face_to_vertex(&weighted);
        let sum_v =
            mesh.face_to_vertex(&sent.iter().map(|s| Rgb::splat(s.element_sum())).collect::<Vec<_>>());
        // Per face, the sphere's share of the transmitted light (at most all of it).
        let round: Vec<Rgb> = if tilts.len() == sent.len() {
            tilts.iter().zip(sent).map(|(t, s)| t.whole.min(*s).max(Rgb::ZERO)).collect()
        } else {
            Vec::new()
        };
        let round_v = if round.is_empty() { Vec::new() } else { mesh.face_to_vertex(&round) };
        // Per vertex, the share-weighted mean of its exit's normal cosine (times the share).
        let normal_v = if round.is_empty() {
            Vec::new()
        } else {
            mesh.face_to_vertex(&tilts.iter().zip(&round).map(|(t, r)| *r * t.normal).collect::<Vec<_>>())
        };
        // Per vertex and channel, its first moment `Σ share μ̄_t t` (B units), by axis.
        let tilt_v: Option<[Vec<Rgb>; 3]> = (!round.is_empty()).then(|| {
            std::array::from_fn(|axis| {
                let component: Vec<Rgb> =
                    tilts.iter().zip(&round).map(|(t, r)| *r * t.mean * t.along[axis]).collect();
                mesh.face_to_vertex(&component)
            })
        });
        let vertices: Vec<Option<VertexShare>> = (0..mesh.positions.len())
            .into_par_iter()
            .map(|v| {
                let b = b_v[v];
                if sum_v[v].x <= 0.0 || b.max_element() <= 0.0 {
                    return None;
                }
                let per_b = |x: Rgb| {
                    Rgb::from_array(std::array::from_fn(|k| if b[k] > 0.0 { x[k] / b[k] } else { 0.0 }))
                };
                let sent = per_b(sent_v[v]).clamp(Rgb::ZERO, Rgb::ONE);
                let round_sum = round_v.get(v).copied().unwrap_or(Rgb::ZERO);
                let round = per_b(round_sum).clamp(Rgb::ZERO, sent);
                let normal = normal_v.get(v).copied().unwrap_or(Rgb::ZERO);
                let mean_cos = Rgb::from_array(std::array::from_fn(|k| {
                    if round_sum[k] > 0.0 { normal[k] / round_sum[k] } else { 2.0 / 3.0 }
                }));
                let along = tilt_v.as_ref().map_or([Rgb::ZERO; 3], |t| std::array::from_fn(|a| t[a][v]));
                let normal = normals.get(v).copied().unwrap_or(Vec3::ZERO);
                Some(VertexShare {
                    b,
                    sent,
                    round,
                    thickness: t_v[v].x / sum_v[v].x,
                    mean_cos,
                    along,
                    normal,
                })
            })
            .collect();
        let (eta, inv_c) = (profile.eta, profile.exit_normalization());
        let base = if eta == 1.0 {
            profile.exit_lobe.clone()
        } else {
            profile.exit_lobe.times(|mu| (fresnel_transmittance(mu as f64, eta) * inv_c) as f32)
        };
        let split = vertices
            .iter()
            .enumerate()
            .filter(|(_, s)| {
                s.as_ref().is_some_and(|s: &VertexShare| {
                    s.normal != Vec3::ZERO && s.sent.max_element() >= SPLIT_MIN_SHARE
                })
            })
            .map(|(v, _)| v as u32)
            .collect();
        ExitShares { vertices, split, base }
    }

    /// What multiplies vertex `v`'s diffuse radiance `B / (c π)` seen at the exit cosine `mu_o`
    /// along the unit direction `w_o` outside (toward the eye), given its chord factor `c`: the
    /// non-transmitted share keeps `c`, the slab's share leaves by the slab's lobe, the
    /// sphere's by its own (both over the mesh pass's lobe).
    pub(crate) fn factor(&self, v: usize, cross: &CrossBody, mu_o: f32, w_o: Vec3, c: Rgb) -> Rgb {
        match self.vertices.get(v).and_then(Option::as_ref) {
            Some(share) => self.factor_of(share, cross, mu_o, w_o, c),
            None => c,
        }
    }

    /// [`ExitShares::factor`] of one vertex's share.
    fn factor_of(&self, share: &VertexShare, cross: &CrossBody, mu_o: f32, w_o: Vec3, c: Rgb) -> Rgb {
        let l = self.base.at(mu_o).to_array();
        let along = share.along[0] * w_o.x + share.along[1] * w_o.y + share.along[2] * w_o.z;
        Rgb::from_array(std::array::from_fn(|k| {
            if share.b[k] <= 0.0 || l[k] <= 1e-6 {
                return c[k];
            }
            // The slab's share leaves by the slab's lobe; the sphere's, which came the short
            // way round rather than through the diameter, by its own: the walk's two moments
            // there, its mean normal cosine and its tilt.
            let (w, w_round) = (share.sent[k], share.round[k]);
            let w_slab = w - w_round;
            let slab = match cross.transmitted_lobe(k, share.thickness, mu_o) {
                Some(p) => w_slab * p / l[k],
                None => w_slab * c[k],
            };
            let sphere =
                (w_round * round_lobe(share.mean_cos[k], mu_o) + 7.5 * mu_o * along[k] / share.b[k]) / l[k];
            ((1.0 - w) * c[k] + slab + sphere).max(0.0)
        }))
    }

    /// The vertices a camera move with the split view terms evaluates
    /// ([`ExitShares::factor_from_eye`]); the rest keep the chord's factor.
    pub(crate) fn split_vertices(&self) -> &[u32] {
        &self.split
    }

    /// [`ExitShares::factor`] of vertex `v` at `position` seen from `eye` (mesh units), the
    /// direction mirrored to the front where the vertex is turned slightly away (as the view
    /// rays are), over the chord factor `c`; `None` where the factor is the chord's: no
    /// transmitted light worth a camera move's time (not one of
    /// [`ExitShares::split_vertices`]), or turned well away (more than 120 degrees: none of its
    /// faces is drawn but in the sharpest creases).
    pub(crate) fn factor_from_eye(
        &self,
        v: usize,
        position: Vec3,
        eye: Vec3,
        cross: &CrossBody,
        c: impl FnOnce() -> Rgb,
    ) -> Option<Rgb> {
        let share = self.vertices.get(v).and_then(Option::as_ref)?;
        let n = share.normal;
        if n == Vec3::ZERO {
            return None;
        }
        let mut w_o = (eye - position).normalize_or_zero();
        let mut mu_o = n.dot(w_o);
        if mu_o < -0.5 {
            return None;
        }
        if mu_o < 0.0 {
            w_o -= 2.0 * mu_o * n;
            mu_o = -mu_o;
        }
        Some(self.factor_of(share, cross, mu_o.clamp(1e-3, 1.0), w_o, c()))
    }
}

/// The radiance of a sphere's transmitted light leaving at exit cosine `mu_o` over a Lambertian
/// exit's, for an exit whose flux-weighted mean cosine is `mean_cos`: `1 + β (μ_o - 2/3)`, the
/// lowest-order lobe with that mean and the same flux (`β = 18 (mean - 2/3)`; Milne's deep
/// half-space, mean 0.711, gives 0.63 at `μ_o = 0.2` and 1.26 head-on, as its `H` function
/// does). `β` is kept to ±1.5, where the lobe stays non-negative.
fn round_lobe(mean_cos: f32, mu_o: f32) -> f32 {
    let beta = (18.0 * (mean_cos - 2.0 / 3.0)).clamp(-1.5, 1.5);
    1.0 + beta * (mu_o - 2.0 / 3.0)
}
