//! Light that crosses the body: a thin part's transmission from the transport through a slab
//! of its thickness (issue 50; not in Mertens et al. 2003).
//!
//! Every profile is a half-space's response. Evaluated at the chord between a thin part's far
//! side and its near side it carries what a half-space returns beyond that distance along its
//! surface, `X(t)`, and the finite-body gain then scales it like the light a face returns on its
//! own side. What a slab really transmits is another quantity: on a 3 mm marble slab lit from
//! behind the half-space tail with the gain gives 0.121 / 0.085 / 0.060 (R / G / B) where the
//! transport equation gives 0.202 / 0.169 / 0.143, and the hue is wrong with it (the slab
//! transmits blue far better than the tail's `e^{-σ_tr t}` says).
//!
//! The exact answer for a slab is known ([`crate::bssrdf::slab`]: the one-dimensional transport
//! equation, multiple scattering only, per albedo and optical thickness, like the half-space's
//! exact albedo that calibrates `pbd`). So each face `f` whose inward ray (the finite body's
//! thickness ray, [`ThicknessRays`]) crosses the body to a face `k` facing away takes
//!
//! ```text
//! B_f += s_f (T(σ_t t_f) - G_f X(t_f)) E_k
//! ```
//!
//! per channel: the gathered far side's share as the profile and gain carry it, `G_f X(t_f)`
//! per unit irradiance on the far side, is replaced by the slab's exact transmittance `T`, both
//! for the light entering under the face, `E_k`. `s_f` is the face's slabness (the gain's:
//! 1 on a slab, 0 on a sphere, where the chord-evaluated profile integrates over the body as a
//! radial profile does over a plane and the sphere's walked gain is exact under uniform light).
//! On a laterally uniform slab this is exact for normal incidence; where the far side's light
//! changes over the thickness it takes the light at the point across for the whole far side.
//!
//! The transmitted light also leaves differently: flux flowing out through the face, with no
//! source near it, is forward-peaked (at 6.6 mean free paths 1.21 times a Lambertian exit's
//! radiance head-on, 0.55 at grazing, where the half-space's multiple scattering is 1.04-1.07
//! head-on); [`CrossBody::exit_factors`] gives the transmitted share of each vertex's `B` the
//! slab's exact lobe (at `η = 1`; elsewhere the half-space's).
//!
//! Left out: the slab's transmittance at oblique incidence (`E_k` carries the half-space's
//! entry term, whose albedo ratio rises toward grazing where a slab transmits less), the energy
//! bound's factor on the replaced share (1 on a slab), and the lateral spread of the
//! transmitted light (about the thickness).

use crate::Rgb;
use crate::bssrdf::slab::SlabTable;
use crate::bssrdf::{Dipole, ExitLobe};
use crate::mesh::Mesh;
use crate::shading::single_scattering::ViewRay;
use crate::solver::finite_body::{FiniteBody, ThicknessRays};
use rayon::prelude::*;
use std::sync::Arc;

/// How light that crosses the body to a face on its far side is carried.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Transmission {
    /// The profile at the chord, scaled by the finite-body gain (lucent before issue 50).
    HalfSpace,
    /// The exact slab transmittance at the face's thickness in place of the profile's far-side
    /// share, weighted by the slabness (module docs). The default.
    #[default]
    Slab,
}

impl Transmission {
    /// Every mode, in the order the command line lists them.
    pub const ALL: [Transmission; 2] = [Transmission::Slab, Transmission::HalfSpace];

    /// The name the command line and scene files use.
    pub fn name(self) -> &'static str {
        match self {
            Transmission::Slab => "slab",
            Transmission::HalfSpace => "halfspace",
        }
    }
}

/// A name that is not a [`Transmission`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownTransmission(pub String);

impl std::fmt::Display for UnknownTransmission {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "unknown transmission {:?} (expected slab or halfspace)", self.0)
    }
}

impl std::error::Error for UnknownTransmission {}

impl std::str::FromStr for Transmission {
    type Err = UnknownTransmission;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Transmission::ALL
            .into_iter()
            .find(|t| t.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownTransmission(s.to_string()))
    }
}

/// Per face, the far face its thickness ray crossed to and the coefficient of its irradiance
/// added to the face's `B` (module docs).
#[derive(Clone, Debug)]
pub struct CrossBody {
    /// Per face: the face across the body (`u32::MAX`: none, or one not facing away).
    far: Vec<u32>,
    /// Per face: `s (T - G X)` per channel (unitless; negative where the profile carries more
    /// than the slab transmits).
    coef: Vec<Rgb>,
    /// Per face: what of the far side's irradiance it sends out after the term, the
    /// transmitted light, `s T + (1 - s) G X` per channel (unitless, >= 0).
    transmitted: Vec<Rgb>,
    /// Per face: the thickness under it (mesh units; 0 where `far` is none).
    thickness: Vec<f32>,
    /// Extinction `σ_t` per mesh unit, per channel.
    sigma_t: [f64; 3],
    /// The slab tables per channel.
    tables: [Arc<SlabTable>; 3],
}

impl CrossBody {
    /// The terms of every face of `mesh` for `dipole`, from the body's rays (`offset` inside
    /// the faces) and each face's finite-body gain `gains` (what multiplied the gathered far
    /// side's share).
    pub fn new(
        dipole: &Dipole,
        fb: &FiniteBody,
        mesh: &Mesh,
        rays: &ThicknessRays,
        offset: f32,
        gains: &[Rgb],
    ) -> Self {
        let tables: [_; 3] = std::array::from_fn(|c| SlabTable::cached(dipole.alpha_prime[c], dipole.eta));
        let rows: Vec<(u32, Rgb, Rgb, f32)> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|f| {
                let none = (u32::MAX, Rgb::ZERO, Rgb::ZERO, 0.0);
                let (Some((t, s)), Some(k)) = (rays.body(mesh, f, offset), rays.inward_face(f)) else {
                    return none;
                };
                // Only across the body: the face hit must face away from this one.
                if mesh.face_normal(k).dot(mesh.face_normal(f)) >= 0.0 || s <= 0.0 {
                    return none;
                }
                let carried = fb.slab_carried(t);
                let g = gains[f].to_array();
                let exact: [f64; 3] = std::array::from_fn(|c| tables[c].at(dipole.sigma_t[c] * t as f64).transmitted);
                let coef = std::array::from_fn(|c| (s * (exact[c] - g[c] as f64 * carried[c])) as f32);
                let sent = std::array::from_fn(|c| (s * exact[c] + (1.0 - s) * g[c] as f64 * carried[c]) as f32);
                (k as u32, Rgb::from_array(coef), Rgb::from_array(sent), t)
            })
            .collect();
        CrossBody {
            far: rows.iter().map(|r| r.0).collect(),
            coef: rows.iter().map(|r| r.1).collect(),
            transmitted: rows.iter().map(|r| r.2).collect(),
            thickness: rows.iter().map(|r| r.3).collect(),
            sigma_t: dipole.sigma_t,
            tables,
        }
    }

    /// Adds each face's term for the irradiance `carried` (per face, what enters and the
    /// profile carries) to `b`, keeping `B` non-negative, and the transmitted light it then
    /// holds to `sent` (per face; the exit lobe of [`CrossBody::exit_factors`] reads it).
    pub fn add(&self, b: &mut [Rgb], sent: &mut [Rgb], carried: &[Rgb]) {
        if self.far.len() != b.len() || carried.len() != b.len() || sent.len() != b.len() {
            return;
        }
        b.par_iter_mut().zip(sent.par_iter_mut()).enumerate().for_each(|(f, (b, sent))| {
            let k = self.far[f];
            if k != u32::MAX {
                let e = carried[k as usize];
                *b = (*b + self.coef[f] * e).max(Rgb::ZERO);
                *sent += (self.transmitted[f] * e).min(*b);
            }
        });
    }

    /// Per vertex of `mesh`, what multiplies the diffuse radiance `B / (c π)` for the way the
    /// light crossing the body leaves: the share `w` of the vertex's `B` that was transmitted
    /// (`sent` over `face_b`, area-weighted over its faces) leaves as a slab's transmitted light
    /// does (forward-peaked: 1.2 times a Lambertian exit head-on at 6.6 mean free paths, where
    /// the half-space's multiple scattering is 1.04-1.07), the rest as before, times its chord
    /// factor `chord`: `(1 - w) C + w p_T(μ_o) / lobe(μ_o)`, with `p_T` the slab's
    /// ([`SlabTable::lobe`]) at the vertex's thickness (weighted by the transmitted light) and
    /// `lobe` the half-space's exit lobe the mesh pass applies. `rays` are the vertices' view
    /// rays (`None`: not seen, `chord` as it is).
    pub(crate) fn exit_factors(
        &self,
        mesh: &Mesh,
        face_b: &[Rgb],
        sent: &[Rgb],
        rays: &[Option<ViewRay>],
        lobe: &ExitLobe,
        chord: &[Rgb],
    ) -> Vec<Rgb> {
        let b_v = mesh.face_to_vertex(face_b);
        let sent_v = mesh.face_to_vertex(sent);
        let weighted: Vec<Rgb> =
            sent.iter().zip(&self.thickness).map(|(s, &t)| Rgb::splat(s.element_sum() * t)).collect();
        let t_v = mesh.face_to_vertex(&weighted);
        let sum_v = mesh.face_to_vertex(&sent.iter().map(|s| Rgb::splat(s.element_sum())).collect::<Vec<_>>());
        (0..mesh.positions.len())
            .into_par_iter()
            .map(|v| {
                let c = chord.get(v).copied().unwrap_or(Rgb::ONE);
                let Some(ray) = &rays[v] else { return c };
                if sum_v[v].x <= 0.0 {
                    return c;
                }
                let t = t_v[v].x / sum_v[v].x;
                let l = lobe.at(ray.mu_o).to_array();
                Rgb::from_array(std::array::from_fn(|k| {
                    let w = if b_v[v][k] > 0.0 { (sent_v[v][k] / b_v[v][k]).clamp(0.0, 1.0) } else { 0.0 };
                    let p = self.tables[k].lobe(self.sigma_t[k] * t as f64, ray.mu_o);
                    match p {
                        Some(p) if l[k] > 1e-6 => (1.0 - w) * c[k] + w * p / l[k],
                        _ => c[k],
                    }
                }))
            })
            .collect()
    }

    /// What face `f`'s term adds to its `B` under uniform irradiance 1 (the positive part of
    /// its coefficient): what the energy bound leaves room for
    /// ([`super::energy::bound_with_gain_and_term`]).
    pub fn uniform_term(&self, f: usize) -> Rgb {
        if self.far.get(f).is_some_and(|&k| k != u32::MAX) { self.coef[f].max(Rgb::ZERO) } else { Rgb::ZERO }
    }

    /// Per face, [`CrossBody::uniform_term`].
    pub fn uniform_terms(&self) -> Vec<Rgb> {
        (0..self.far.len()).map(|f| self.uniform_term(f)).collect()
    }

    /// Faces it was made for.
    pub fn len(&self) -> usize {
        self.far.len()
    }

    /// Whether no face has a term.
    pub fn is_empty(&self) -> bool {
        self.far.iter().all(|&k| k == u32::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bssrdf::Material;
    use crate::irradiance::{Light, SceneLight};
    use crate::mesh::generate;
    use crate::session::{FrameSession, FrameSettings, Transport};
    use glam::Vec3;

    /// `B` per channel, averaged over the faces facing +z within `half` of the centre, of a box
    /// 50 x 50 x 3 mm of `material` (index 1) lit head-on from -z with irradiance 1.
    fn backlit_box(material: &str, transmission: Transmission, half: f32) -> [f32; 3] {
        let mut mesh = generate::cube(24);
        mesh.positions.iter_mut().for_each(|p| p.z *= 0.06);
        let mut m = Material::by_name(material).unwrap();
        m.eta = 1.0;
        let transport = Transport { transmission, ..Transport::new(m, 0.05) };
        let mut s = FrameSession::new(mesh.clone(), None, transport, FrameSettings::default());
        s.set_lights(vec![SceneLight::from(Light::Directional { direction: Vec3::Z, irradiance: Vec3::ONE })]);
        let b = s.solve().face_b.clone();
        let (mut sum, mut n) = (Rgb::ZERO, 0);
        for f in 0..mesh.triangles.len() {
            let c = mesh.face_centroid(f);
            if mesh.face_normal(f).z > 0.9 && c.x.abs() < half && c.y.abs() < half {
                sum += b[f];
                n += 1;
            }
        }
        (sum / n as f32).to_array()
    }

    /// A thin box lit from behind transmits what a slab of its thickness does: the centre of
    /// its far face against `validation/slab_walk.py material --name NAME --mm 3 --photons
    /// 1000000 --seed 5` (multiple scattering, standard error 0.0003-0.0004). The box is 50 mm
    /// wide, so light also leaves through its sides: skim milk's red, which reaches farthest,
    /// loses 4% of the infinite slab's at the centre (hence 6% there, 2% for marble).
    #[test]
    fn a_thin_backlit_box_transmits_the_exact_slab() {
        for (m, want, tol) in [("marble", [0.2020, 0.1685, 0.1431], 0.02), ("skimmilk", [0.2864, 0.2806, 0.1932], 0.06)] {
            let got = backlit_box(m, Transmission::Slab, 0.2);
            for c in 0..3 {
                assert!((got[c] / want[c] - 1.0).abs() < tol, "{m} channel {c}: {got:?} vs {want:?}");
            }
            // The blue scattered back, the red transmitted: the slab's hue, not the tail's.
            assert!(got[0] > got[2], "{m}: {got:?}");
        }
    }

    #[test]
    fn names_round_trip() {
        for t in Transmission::ALL {
            assert_eq!(t.name().parse::<Transmission>(), Ok(t));
        }
        assert!("sideways".parse::<Transmission>().is_err());
    }
}
