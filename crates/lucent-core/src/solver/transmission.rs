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
//! head-on); `shading::transmitted_exit` gives the transmitted share of each vertex's `B` the
//! slab's exact lobe (at `η = 1`; elsewhere the half-space's).
//!
//! `E_k` is the far side's irradiance averaged over the slab's lateral spread around the point
//! across ([`super::cross_spread`]; the weights sum to 1, so a uniform far side gives the
//! one-point term). Light arriving at the far side at a slant collides nearer its face and
//! crosses less: at `η = 1` the slab's share `s T` is scaled by `T(τ, μ) / T(τ, 1)`
//! ([`ObliqueTable`], the same transport with a slanted source) over the entry term's carried
//! share at `μ` relative to head-on (which `E_k` already holds), `μ` the far side's mean
//! incidence cosine ([`crate::irradiance::Entering::mean_cos`], averaged with the same weights).
//!
//! With [`Transmission::Curved`] the share `1 - s` does the same for a sphere whose diameter is
//! the face's thickness ([`super::sphere_term`]): the sphere's random walk
//! ([`crate::bssrdf::sphere_walk`]) in place of what the profile and gain gather on its far
//! side, at the exit angle the point across's incidence cosine gives, for `E_k` at the point
//! across alone, less the same for the face's own `E_f`, so that under uniform light, where the
//! walked gain is exact, it adds nothing; at `η = 1` only.
//!
//! Left out: the slant at `η ≠ 1` (the term stays head-on), the energy bound's factor on the
//! replaced share (1 on a slab), and the light that leaves through a part's sides.

use crate::Rgb;
use crate::bssrdf::Entry;
use crate::bssrdf::Profile;
use crate::bssrdf::slab::{LobeRow, SlabTable};
use crate::bssrdf::slab_oblique::ObliqueTable;
use crate::irradiance::Entering;
use crate::mesh::Mesh;
use crate::mesh::bvh::Bvh;
use crate::solver::cross_spread::Spread;
use crate::solver::finite_body::{FiniteBody, ThicknessRays};
use crate::solver::sphere_term::{Row, SphereTerm};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;

/// How light that crosses the body to a face on its far side is carried.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Transmission {
    /// The profile at the chord, scaled by the finite-body gain (lucent before issue 50).
    HalfSpace,
    /// The exact slab transmittance at the face's thickness in place of the profile's far-side
    /// share, weighted by the slabness (module docs).
    Slab,
    /// [`Transmission::Slab`] on slab-like parts and the sphere's random walk on curved ones,
    /// by the slabness (`super::sphere_term`; `η = 1` only, elsewhere as `Slab`). The default.
    #[default]
    Curved,
}

impl Transmission {
    /// Every mode, in the order the command line lists them.
    pub const ALL: [Transmission; 3] = [Transmission::Curved, Transmission::Slab, Transmission::HalfSpace];

    /// The name the command line and scene files use.
    pub fn name(self) -> &'static str {
        match self {
            Transmission::Curved => "curved",
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
        write!(f, "unknown transmission {:?} (expected curved, slab or halfspace)", self.0)
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

/// How the sphere's transmitted light leaves a face ([`CrossBody::tilts`]): flowing on, away
/// from where it entered, it leaves tilted that way (`shading::transmitted_exit`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Tilt {
    /// The unit tangent of the face along which the light flows on (the beam's direction
    /// across, projected), times the share of the light across that came as one beam (0..=1;
    /// diffuse light flows nowhere in particular).
    pub along: Vec3,
    /// The sphere's whole multiple scattering at the face (`B` units, per channel, >= 0).
    pub whole: Rgb,
    /// Its exit's tilt, the flux-weighted mean of `ω_o · along` per channel
    /// ([`crate::bssrdf::sphere_walk::Exits::tilt`]; unitless, about 0..0.3).
    pub mean: Rgb,
    /// Its exit's mean cosine with the normal per channel
    /// ([`crate::bssrdf::sphere_walk::Exits::normal`]; unitless, about 0.65-0.76).
    pub normal: Rgb,
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
    /// Per face: the slab's share of `coef`, `s T` per channel (unitless, >= 0), which the
    /// oblique factor scales.
    slab: Vec<Rgb>,
    /// The sphere's share (`super::sphere_term`; `None` but for [`Transmission::Curved`] at
    /// `η = 1`), and per face where it reads its tables, `1 - s` (0: no share), the gain and
    /// how round the surface is there ([`roundness`]).
    sphere: Option<Arc<SphereTerm>>,
    round: Vec<(Row, f32, Rgb, f32)>,
    /// Per face: what of the far side's irradiance it sends out after the term, the
    /// transmitted light, `s T + (1 - s) G X` per channel (unitless, >= 0).
    transmitted: Vec<Rgb>,
    /// Per face: the thickness under it (mesh units; 0 where `far` is none).
    thickness: Vec<f32>,
    /// Extinction `σ_t` per mesh unit, per channel.
    sigma_t: [f64; 3],
    /// The slab tables per channel.
    tables: [Arc<SlabTable>; 3],
    /// The slab's transmittance at a slant over head-on per channel (`None` where `η ≠ 1`:
    /// not modelled, the term is the head-on one).
    oblique: Option<[Arc<ObliqueTable>; 3]>,
    /// The entry term the carried irradiance went through (`bssrdf::entry`).
    entry: Arc<Entry>,
    /// Where the far side's irradiance is averaged around the point across
    /// ([`super::cross_spread`]); `None`: at that point alone.
    spread: Option<Spread>,
}

impl CrossBody {
    /// The terms of every face of `mesh` for `profile`, from the body's rays (`offset` inside
    /// the faces) and each face's finite-body gain `gains` (what multiplied the gathered far
    /// side's share): with the sphere's share on curved parts for [`Transmission::Curved`]
    /// (`super::sphere_term`), the slab's alone otherwise.
    pub fn new(
        profile: &Profile,
        fb: &FiniteBody,
        mesh: &Mesh,
        rays: &ThicknessRays,
        offset: f32,
        gains: &[Rgb],
        mode: Transmission,
    ) -> Self {
        let tables: [_; 3] = std::array::from_fn(|c| SlabTable::cached(profile.alpha_prime[c], profile.eta));
        let sphere = if mode == Transmission::Curved { Some(fb.sphere_term(profile)) } else { None };
        let normals = if sphere.is_some() { mesh.vertex_normals() } else { Vec::new() };
        type Face = (u32, Rgb, Rgb, f32, Rgb, (Row, f32, Rgb, f32));
        let rows: Vec<Face> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|f| {
                let none =
                    (u32::MAX, Rgb::ZERO, Rgb::ZERO, 0.0, Rgb::ZERO, (Row::default(), 0.0, Rgb::ZERO, 0.0));
                let (Some((t, s)), Some(k)) = (rays.body(mesh, f, offset), rays.inward_face(f)) else {
                    return none;
                };
                // Only across the body: the face hit must face away from this one.
                if mesh.face_normal(k).dot(mesh.face_normal(f)) >= 0.0 || (s <= 0.0 && sphere.is_none()) {
                    return none;
                }
                let carried = fb.slab_carried(t);
                let g = gains[f].to_array();
                let exact: [f64; 3] =
                    std::array::from_fn(|c| tables[c].at(profile.sigma_t[c] * t as f64).transmitted);
                // The sphere's share (`super::sphere_term`), read per light in `add`.
                let round = match &sphere {
                    Some(sp) => (sp.row(t), (1.0 - s) as f32, gains[f], roundness(mesh, &normals, f, t)),
                    None => none.5,
                };
                let coef = std::array::from_fn(|c| (s * (exact[c] - g[c] as f64 * carried[c])) as f32);
                let sent =
                    std::array::from_fn(|c| (s * exact[c] + (1.0 - s) * g[c] as f64 * carried[c]) as f32);
                let slab = std::array::from_fn(|c| (s * exact[c]) as f32);
                (k as u32, Rgb::from_array(coef), Rgb::from_array(sent), t, Rgb::from_array(slab), round)
            })
            .collect();
        let oblique = (profile.eta == 1.0)
            .then(|| std::array::from_fn(|c| ObliqueTable::cached(profile.alpha_prime[c])));
        CrossBody {
            far: rows.iter().map(|r| r.0).collect(),
            coef: rows.iter().map(|r| r.1).collect(),
            transmitted: rows.iter().map(|r| r.2).collect(),
            thickness: rows.iter().map(|r| r.3).collect(),
            slab: rows.iter().map(|r| r.4).collect(),
            round: rows.iter().map(|r| r.5).collect(),
            sphere,
            sigma_t: profile.sigma_t,
            tables,
            oblique,
            entry: profile.entry.clone(),
            spread: None,
        }
    }

    /// The same terms with the far side's irradiance averaged over the slab's lateral spread
    /// ([`super::cross_spread`]), its rays traced against `bvh` (over `mesh`, the pose these
    /// terms were made for) from `offset` inside the faces.
    pub fn with_spread(mut self, profile: &Profile, mesh: &Mesh, bvh: &Bvh, offset: f32) -> Self {
        if self.far.len() == mesh.triangles.len() {
            self.spread = Some(Spread::trace(profile, mesh, bvh, offset, &self.far, &self.thickness));
        }
        self
    }

    /// Adds each face's term for the irradiance `carried` (per face, what enters and the
    /// profile carries; `cos`, if given, its mean incidence cosine per face,
    /// [`crate::irradiance::Entering::mean_cos`]; else head-on) to `b`, keeping `B`
    /// non-negative, and the transmitted light it then holds to `sent` (per face;
    /// `shading::transmitted_exit` reads it).
    pub fn add(&self, b: &mut [Rgb], sent: &mut [Rgb], carried: &[Rgb], cos: Option<&[Rgb]>) {
        if self.far.len() != b.len() || carried.len() != b.len() || sent.len() != b.len() {
            return;
        }
        let cos = cos.filter(|c| c.len() == b.len());
        b.par_iter_mut().zip(sent.par_iter_mut()).enumerate().for_each(|(f, (b, sent))| {
            let k = self.far[f];
            if k != u32::MAX {
                let k = k as usize;
                let (e, e_cos) = match (&self.spread, cos) {
                    (Some(s), Some(c)) => {
                        (s.average(f, k, |j| carried[j]), s.average(f, k, |j| carried[j] * c[j]))
                    }
                    (Some(s), None) => (s.average(f, k, |j| carried[j]), Rgb::ZERO),
                    (None, Some(c)) => (carried[k], carried[k] * c[k]),
                    (None, None) => (carried[k], Rgb::ZERO),
                };
                let slant = match cos {
                    Some(_) => self.slant(f, e, e_cos),
                    None => Rgb::ONE,
                };
                let extra = self.slab[f] * (slant - Rgb::ONE) * e;
                // The sphere's share moves light from the face's own side to the far side's:
                // under uniform light it adds nothing (the walked gain is exact there).
                let (across, own, whole) = self.round_shares(f, k, carried, cos);
                *b = (*b + self.coef[f] * e + extra + across - own).max(Rgb::ZERO);
                // Where the sphere's share is modelled, its light that crossed is its whole
                // multiple scattering there, not the slab's far-side gather.
                let sent_here = match whole {
                    Some(whole) => self.slab[f] * e + extra + whole,
                    None => self.transmitted[f] * e + extra,
                };
                *sent += sent_here.max(Rgb::ZERO).min(*b);
            }
        });
    }

    /// The sphere's share of face `f` (`super::sphere_term`): what it receives from the light
    /// carried at `k`, the face across, and what it gives up of its own, each at its mean
    /// incidence cosine (head-on without `cos`), and the sphere's whole multiple scattering of
    /// the light across (`None`: no sphere's share; then the slab's far-side gather stands for
    /// it).
    fn round_shares(
        &self,
        f: usize,
        k: usize,
        carried: &[Rgb],
        cos: Option<&[Rgb]>,
    ) -> (Rgb, Rgb, Option<Rgb>) {
        let (Some(sphere), (row, round, gain, q)) = (&self.sphere, self.round[f]) else {
            return (Rgb::ZERO, Rgb::ZERO, None);
        };
        if round <= 0.0 {
            return (Rgb::ZERO, Rgb::ZERO, None);
        }
        let mu = |j: usize| cos.map_or(Rgb::ONE, |c| exit_cos(c[j], q));
        let own = sphere.own_share(row, round, gain, mu(f));
        let whole = sphere.whole(row, round, mu(k)) * carried[k];
        (sphere.share(row, round, gain, mu(k)) * carried[k], own * carried[f], Some(whole))
    }

    /// Per face, how the sphere's share of its transmitted light leaves (empty where the sphere
    /// is not modelled), for the carried irradiance `carried` made of the light `e` per face:
    /// the walk's tilt at the exit angle the light across gives (module docs of
    /// `super::sphere_term`), along the beam's direction across projected on the face.
    pub(crate) fn tilts(&self, mesh: &Mesh, carried: &[Rgb], e: &[Entering]) -> Vec<Tilt> {
        let Some(sphere) = &self.sphere else { return Vec::new() };
        if self.far.len() != mesh.triangles.len()
            || carried.len() != self.far.len()
            || e.len() != self.far.len()
        {
            return Vec::new();
        }
        (0..self.far.len())
            .into_par_iter()
            .map(|f| {
                let (k, (row, round, _, q)) = (self.far[f], self.round[f]);
                if k == u32::MAX || round <= 0.0 {
                    return Tilt::default();
                }
                let k = k as usize;
                let (whole, mean, normal) = sphere.tilted(row, round, exit_cos(e[k].mean_cos(), q));
                let total = carried[k].element_sum();
                let flow = e[k].flow;
                let n = mesh.face_normal(f);
                let tangent = flow - n * n.dot(flow);
                // Light from every side (the environment's, bounced) flows nowhere in particular.
                let along = if total > 0.0 && tangent.length_squared() > 1e-12 * flow.length_squared() {
                    tangent.normalize() * (flow.length() / total).min(1.0)
                } else {
                    Vec3::ZERO
                };
                Tilt { along, whole: whole * carried[k], mean, normal }
            })
            .collect()
    }

    /// The oblique factor of face `f` per channel for far-side light `e` arriving at the mean
    /// cosine `e_cos / e`: the slab's `T(τ, μ) / T(τ, 1)` over the entry term's carried share
    /// at `μ` (relative to head-on), which `e` already holds (module docs). 1 where not
    /// modelled.
    fn slant(&self, f: usize, e: Rgb, e_cos: Rgb) -> Rgb {
        let Some(oblique) = &self.oblique else { return Rgb::ONE };
        let head_on = self.entry.at(1.0);
        let (e, e_cos, head_on) = (e.to_array(), e_cos.to_array(), head_on.to_array());
        Rgb::from_array(std::array::from_fn(|c| {
            if e[c] <= 0.0 || head_on[c] <= 0.0 {
                return 1.0;
            }
            let mu = (e_cos[c] / e[c]).clamp(0.0, 1.0);
            let carried = self.entry.at(mu).to_array()[c] / head_on[c];
            let tau = self.sigma_t[c] * self.thickness[f] as f64;
            if carried <= 0.0 { 1.0 } else { (oblique[c].ratio(tau, mu as f64) / carried as f64) as f32 }
        }))
    }

    /// Per face: the thickness under it (mesh units; 0 where it has no term).
    pub(crate) fn thickness(&self) -> &[f32] {
        &self.thickness
    }

    /// Where channel `c`'s transmitted lobe is read for a part `thickness` mesh units thick
    /// ([`SlabTable::lobe_row`]); `None` where not modelled.
    pub(crate) fn transmitted_lobe_row(&self, c: usize, thickness: f32) -> Option<LobeRow> {
        self.tables[c].lobe_row(self.sigma_t[c] * thickness as f64)
    }

    /// The transmitted light's radiance over a Lambertian exit's in channel `c` at exit
    /// cosine `mu`, at `row` ([`CrossBody::transmitted_lobe_row`]).
    #[inline]
    pub(crate) fn transmitted_lobe_at(&self, c: usize, row: LobeRow, mu: f32) -> f32 {
        self.tables[c].lobe_at(row, mu)
    }

    /// What face `f`'s term adds to its `B` under uniform irradiance 1 (the positive part of
    /// its coefficient): what the energy bound leaves room for
    /// ([`super::bound::bound_with_gain_and_term`]).
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

/// The cosine the sphere's share reads for light arriving at `cos` on a surface of roundness
/// `q` ([`roundness`]): the exit angle the light's cosine stands for holds on a round surface; a
/// flat one (`q` 0) lit at a slant is a slab's slant, not a sphere's rim, and reads head-on.
fn exit_cos(cos: Rgb, q: f32) -> Rgb {
    Rgb::ONE - (Rgb::ONE - cos) * q
}

/// How round the surface is at face `f` for a part `thickness` thick (0..=1): its largest
/// convex curvature (the vertex normals' turn away from the face's over their distance from
/// its centroid, `normals` per vertex, in the three directions of its vertices) times the
/// radius `thickness / 2` of the sphere the term reads. 1 on a sphere (whose curvature is
/// `2 / t`), at least 3/4 on a cylinder of diameter `t` (the three directions lie 120 degrees
/// apart, so one is within 30 of the bend), 0 on a flat face.
fn roundness(mesh: &Mesh, normals: &[Vec3], f: usize, thickness: f32) -> f32 {
    let (n, c) = (mesh.face_normal(f), mesh.face_centroid(f));
    let mut most = 0.0f32;
    for &v in &mesh.triangles[f] {
        let d = mesh.positions[v as usize] - c;
        let (Some(nv), len2) = (normals.get(v as usize), d.length_squared()) else { return 0.0 };
        if len2 > 0.0 {
            most = most.max((*nv - n).dot(d) / len2);
        }
    }
    (most * 0.5 * thickness).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sphere is round for the sphere of its own diameter, a cube's faces are flat away from
    /// their edges.
    #[test]
    fn a_sphere_is_round_and_a_cube_s_face_is_flat() {
        let sphere = crate::mesh::generate::icosphere(4);
        let normals = sphere.vertex_normals();
        let q: Vec<f32> = (0..sphere.triangles.len()).map(|f| roundness(&sphere, &normals, f, 2.0)).collect();
        let mean = q.iter().sum::<f32>() / q.len() as f32;
        assert!(mean > 0.9 && q.iter().all(|&v| v > 0.75), "sphere: mean {mean}");
        let cube = crate::mesh::generate::cube(16);
        let normals = cube.vertex_normals();
        let flat = (0..cube.triangles.len()).filter(|&f| roundness(&cube, &normals, f, 2.0) == 0.0).count();
        // A 16 x 16 grid a side: the faces off the edges' ring (14 x 14 squares) are flat.
        assert!(flat >= 6 * 14 * 14 * 2, "{flat} of {} faces flat", cube.triangles.len());
    }

    #[test]
    fn names_round_trip() {
        for t in Transmission::ALL {
            assert_eq!(t.name().parse::<Transmission>(), Ok(t));
        }
        assert!("sideways".parse::<Transmission>().is_err());
    }
}
