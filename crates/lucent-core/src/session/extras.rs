//! What a [`FrameSession`] adds around the solve: the texture's entry factors, the light an
//! oblique beam returns locally, the finite-body gain and view-ray single scattering.

use super::FrameSession;
use crate::Rgb;
use crate::irradiance::Entering;
use crate::shading::exit_chord::ExitChord;
use crate::shading::single_scattering::{ViewRayScene, view_ray_radiance, view_rays};
use crate::shading::transmitted_exit;
use crate::solver::finite_body::{FiniteBody, ThicknessRays};
use crate::solver::transmission::{CrossBody, Transmission};
use std::sync::Arc;

impl FrameSession {
    /// The carried part of `e` past the texture's entry factors (unchanged without a texture).
    pub(super) fn entered_carried(&self, e: &[Entering]) -> Vec<Rgb> {
        match &self.entry {
            Some(f) => e.iter().zip(f).map(|(e, f)| e.carried * *f).collect(),
            None => e.iter().map(|e| e.carried).collect(),
        }
    }

    /// Adds to `b` the slab transmission across the body of the carried irradiance `carried`
    /// (`solver::transmission`), where the transport asks for it, and to `sent` (per face,
    /// made on first use) the transmitted light `b` then holds.
    pub(super) fn add_transmission(&self, b: &mut [Rgb], sent: &mut Vec<Rgb>, carried: &[Rgb]) {
        if let Some(cross) = self.cross_body.as_ref().filter(|c| c.len() == b.len()) {
            if sent.len() != b.len() {
                *sent = vec![Rgb::ZERO; b.len()];
            }
            cross.add(b, sent, carried);
        }
    }

    /// Adds to `b` the light an oblique beam returns at its entry face (`bssrdf::entry`): the
    /// local part of `e`, past the texture's entry factors, times the profile's total diffuse
    /// reflectance.
    pub(super) fn add_local(&self, b: &mut [Rgb], e: &[Entering]) {
        if !self.profile.entry.has_local() {
            return;
        }
        let r = Rgb::from_array(self.profile.total_diffuse_reflectance().map(|v| v as f32));
        for (f, (b, e)) in b.iter_mut().zip(e).enumerate() {
            let texture = self.entry.as_ref().map_or(Rgb::ONE, |t| t[f]);
            *b += e.local * texture * r;
        }
    }

    /// Adds to `b` the exitance of the light of `e` scattered once at each face, past the
    /// texture's entry factors, where single scattering is not in the profile but along the
    /// view ray (else it is in `B` already, or left out). For bounced light, which no view ray
    /// follows: without it a bounce lost the quarter of its light a half-space scatters once.
    pub(super) fn add_single(&self, b: &mut [Rgb], e: &[Entering]) {
        if !self.transport.single_scattering_along_view() {
            return;
        }
        for (f, (b, e)) in b.iter_mut().zip(e).enumerate() {
            *b += e.single * self.entry.as_ref().map_or(Rgb::ONE, |t| t[f]);
        }
    }

    /// Measures the body under the faces for the current pose and profile (the shadow BVH is
    /// current), with one set of rays: the finite-body gain of every face, and the mean chord
    /// factor `N` of every vertex (`shading::exit_chord`). Both `None` where the profile does not
    /// bound energy (Mertens'); no `N` where its exit lobe is flat.
    pub(super) fn measure_body(&mut self) {
        self.face_gain = None;
        self.exit_chord = None;
        self.cross_body = None;
        self.face_terms = None;
        let Some(caster) = self.caster.as_ref().filter(|_| self.profile.bounds_energy()) else { return };
        let fb = self.finite_body.get_or_insert_with(|| FiniteBody::new(&self.profile));
        // Traced once; a small deformation moves the hits with the mesh.
        let rays = match self.thickness_rays.take() {
            Some(mut rays) if rays.fits(&self.mesh) => {
                rays.refresh(&self.mesh, caster.bvh(), caster.offset());
                rays
            }
            _ => ThicknessRays::trace(&self.mesh, caster.bvh(), caster.offset()),
        };
        let gains = Arc::new(fb.gains_along(&self.mesh, &rays, caster.offset()));
        if self.transport.transmission == Transmission::Slab {
            let cross = CrossBody::new(&self.profile, fb, &self.mesh, &rays, caster.offset(), &gains);
            self.cross_body = (!cross.is_empty()).then(|| Arc::new(cross));
        }
        self.face_gain = Some(gains);
        self.exit_chord = ExitChord::new(&self.profile).map(|chord| {
            let means = self.mesh.face_to_vertex(&chord.face_means(&self.mesh, &rays, caster.offset()));
            (chord, means)
        });
        self.thickness_rays = Some(rays);
    }

    /// What depends on the eye (the shadow BVH is current: the solve refits it first): the
    /// diffuse radiance `B / (c π)` per vertex as it leaves towards the eye, times the body's
    /// chord factor where the profile has one (`shading::exit_chord`), and view-ray single scattering where the transport asks for it (else empty). Without an
    /// eye: `B / (c π)` as solved, and no single scattering.
    pub(super) fn seen_from_eye(&self) -> (Vec<Rgb>, Vec<Rgb>) {
        let (Some(eye), Some(caster)) = (self.eye, &self.caster) else {
            return (self.diffuse.clone(), Vec::new());
        };
        let chord = self.exit_chord.as_ref();
        let single = self.transport.single_scattering_along_view();
        if chord.is_none() && !single {
            return (self.diffuse.clone(), Vec::new());
        }
        let normals = self.mesh.vertex_normals();
        let scene = ViewRayScene {
            mesh: &self.mesh,
            normals: &normals,
            bvh: caster.bvh(),
            offset: caster.offset(),
            profile: &self.profile,
            lights: &self.lights,
            environment: self.environment.as_ref(),
        };
        let diffuse = match chord {
            Some((chord, means)) => {
                let rays = view_rays(&scene, eye);
                let mut factors = chord.vertex_factors(&rays, means);
                let (face_b, sent) = &self.transmitted;
                if let Some(cross) = self.cross_body.as_ref().filter(|c| c.len() == sent.len()) {
                    factors = transmitted_exit::exit_factors(
                        cross,
                        &self.mesh,
                        face_b,
                        sent,
                        &rays,
                        &self.profile.exit_lobe,
                        &factors,
                    );
                }
                self.diffuse.iter().zip(factors).map(|(d, c)| *d * c).collect()
            }
            None => self.diffuse.clone(),
        };
        let single = if single { view_ray_radiance(&scene, eye) } else { Vec::new() };
        (diffuse, single)
    }
}
