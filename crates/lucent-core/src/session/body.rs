//! The body measure of a [`super::FrameSession`]: rays under every face measure how far the
//! body reaches behind it, which gives the finite-body gain of each face
//! (`solver::finite_body`), the slab transmission across the body (`solver::transmission`)
//! and the mean chord factor `N` of each vertex (`shading::exit_chord`), all for the profiles
//! that bound energy.

use super::{Changes, Frame};
use crate::Rgb;
use crate::irradiance::{Entering, ShadowCaster};
use crate::shading::exit_chord::ExitChord;
use crate::solver::finite_body::{FiniteBody, ThicknessRays};
use crate::solver::transmission::{CrossBody, Tilt, Transmission};
use std::sync::Arc;

/// The thickness rays and what they measure, remade when the mesh moves or the transport
/// changes.
#[derive(Default)]
pub(super) struct Body {
    /// The rays under each face that the gain measures the body with, traced once, followed
    /// through small deformations (`ThicknessRays::fits`).
    thickness_rays: Option<ThicknessRays>,
    /// The finite-body gain's table for the current profile.
    finite_body: Option<FiniteBody>,
    /// The finite-body gain per face, for the profiles that bound energy.
    face_gain: Option<Arc<Vec<Rgb>>>,
    /// The exit lobe's weights and the mean chord factor `N` per vertex, made with the gain
    /// from the same rays; `None` for a flat exit lobe.
    exit_chord: Option<(ExitChord, Vec<Rgb>)>,
    /// The slab transmission of every face across the body (`solver::transmission`), made
    /// with the gain from the same rays; `None` for [`Transmission::HalfSpace`], without a
    /// gain, or where no face has a term.
    cross_body: Option<Arc<CrossBody>>,
    /// `cross_body`'s terms under uniform irradiance 1, which the energy bound leaves room for.
    face_term: Option<Arc<Vec<Rgb>>>,
}

impl Body {
    /// The finite-body gain per face (`None`: the profile does not bound energy).
    pub(super) fn face_gain(&self) -> Option<&Arc<Vec<Rgb>>> {
        self.face_gain.as_ref()
    }

    /// Per face, what the slab transmission adds to `B` under uniform irradiance 1 (`None`:
    /// no transmission term), for the energy bound.
    pub(super) fn face_term(&self) -> Option<&Arc<Vec<Rgb>>> {
        self.face_term.as_ref()
    }

    /// The slab transmission across the body (`None`: not modelled for this transport).
    pub(super) fn cross_body(&self) -> Option<&CrossBody> {
        self.cross_body.as_deref()
    }

    /// Adds to `b` the slab transmission across the body of the carried irradiance `carried`
    /// (`solver::transmission`; `e`, per face, what it was made of, for its mean incidence
    /// cosine), where the transport has it, and to `sent` (per face, made on first use) the
    /// transmitted light `b` then holds.
    pub(super) fn add_transmission(
        &self,
        b: &mut [Rgb],
        sent: &mut Vec<Rgb>,
        carried: &[Rgb],
        e: &[Entering],
    ) {
        if let Some(cross) = self.cross_body.as_ref().filter(|c| c.len() == b.len()) {
            if sent.len() != b.len() {
                *sent = vec![Rgb::ZERO; b.len()];
            }
            let cos: Vec<Rgb> = e.iter().map(Entering::mean_cos).collect();
            cross.add(b, sent, carried, Some(&cos));
        }
    }

    /// Per face, how the sphere's transmitted light leaves ([`CrossBody::tilts`]; empty where
    /// not modelled or ablated) for the carried irradiance `carried` made of the light `e`.
    pub(super) fn tilts(&self, f: &Frame, carried: &[Rgb], e: &[Entering]) -> Vec<Tilt> {
        match self.cross_body.as_ref() {
            Some(cross) if !f.settings.ablate.round_exit => cross.tilts(&f.mesh, carried, e),
            _ => Vec::new(),
        }
    }

    /// The exit lobe's weights and the mean chord factor per vertex (`None`: a flat lobe).
    pub(super) fn exit_chord(&self) -> Option<&(ExitChord, Vec<Rgb>)> {
        self.exit_chord.as_ref()
    }

    /// Makes the measure current after `changes` with the shadow BVH `caster` (current for
    /// the pose): a new profile drops the gain's table; the body is measured again when the
    /// mesh or the transport changed, or no gain was measured yet.
    pub(super) fn update(&mut self, f: &Frame, caster: Option<&ShadowCaster>, changes: &Changes) {
        if changes.transport {
            self.finite_body = None;
        }
        if changes.geometry || changes.transport || self.face_gain.is_none() {
            self.measure(f, caster);
        }
    }

    /// Measures the body under the faces for the current pose and profile, with one set of
    /// rays: the finite-body gain and the slab transmission of every face, and the mean chord
    /// factor `N` of every vertex. All `None` where the profile does not bound energy
    /// (Mertens'); no `N` where its exit lobe is flat.
    fn measure(&mut self, f: &Frame, caster: Option<&ShadowCaster>) {
        self.face_gain = None;
        self.exit_chord = None;
        self.cross_body = None;
        self.face_term = None;
        let Some(caster) = caster.filter(|_| f.profile.bounds_energy()) else { return };
        let (mesh, profile) = (&f.mesh, &f.profile);
        let ablate = &f.settings.ablate;
        let fb =
            self.finite_body.get_or_insert_with(|| FiniteBody::new(profile).with_terms(ablate.gain_terms()));
        // Traced once; a small deformation moves the hits with the mesh.
        let rays = match self.thickness_rays.take() {
            Some(mut rays) if rays.fits(mesh) => {
                rays.refresh(mesh, caster.bvh(), caster.offset());
                rays
            }
            _ => ThicknessRays::trace(mesh, caster.bvh(), caster.offset()),
        };
        let gains = match ablate.gain {
            true => vec![Rgb::ONE; mesh.triangles.len()],
            false => fb.gains_along(mesh, &rays, caster.offset()),
        };
        if f.transport.transmission != Transmission::HalfSpace {
            let mode = f.transport.transmission;
            let cross = CrossBody::new(profile, fb, mesh, &rays, caster.offset(), &gains, mode).with_spread(
                profile,
                mesh,
                caster.bvh(),
                caster.offset(),
            );
            if !cross.is_empty() {
                self.face_term = Some(Arc::new(cross.uniform_terms()));
                self.cross_body = Some(Arc::new(cross));
            }
        }
        self.face_gain = Some(Arc::new(gains));
        self.exit_chord = ExitChord::new(profile).map(|chord| {
            let means = mesh.face_to_vertex(&chord.face_means(mesh, &rays, caster.offset()));
            (chord, means)
        });
        self.thickness_rays = Some(rays);
    }
}
