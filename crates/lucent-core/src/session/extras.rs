//! What a [`FrameSession`] adds around the solve: the texture's entry factors, the light an
//! oblique beam returns locally, the finite-body gain and view-ray single scattering.

use super::FrameSession;
use crate::Rgb;
use crate::irradiance::Entering;
use crate::shading;
use crate::solver::finite_body::{FiniteBody, ThicknessRays};
use std::sync::Arc;

impl FrameSession {
    /// The carried part of `e` past the texture's entry factors (unchanged without a texture).
    pub(super) fn entered_carried(&self, e: &[Entering]) -> Vec<Rgb> {
        match &self.entry {
            Some(f) => e.iter().zip(f).map(|(e, f)| e.carried * *f).collect(),
            None => e.iter().map(|e| e.carried).collect(),
        }
    }

    /// Adds to `b` the light an oblique beam returns at its entry face (`bssrdf::entry`): the
    /// local part of `e`, past the texture's entry factors, times the profile's total diffuse
    /// reflectance.
    pub(super) fn add_local(&self, b: &mut [Rgb], e: &[Entering]) {
        if !self.dipole.entry.has_local() {
            return;
        }
        let r = Rgb::from_array(self.dipole.total_diffuse_reflectance().map(|v| v as f32));
        for (f, (b, e)) in b.iter_mut().zip(e).enumerate() {
            let texture = self.entry.as_ref().map_or(Rgb::ONE, |t| t[f]);
            *b += e.local * texture * r;
        }
    }

    /// The finite-body gain of every face for the current pose and profile (the shadow BVH is
    /// current), or `None` where the profile does not bound energy (Mertens').
    pub(super) fn face_gains(&mut self) -> Option<Arc<Vec<Rgb>>> {
        let caster = self.caster.as_ref().filter(|_| self.dipole.bounds_energy())?;
        let fb = self.finite_body.get_or_insert_with(|| FiniteBody::new(&self.dipole));
        // Traced once; a small deformation moves the hits with the mesh.
        let rays = match self.thickness_rays.take() {
            Some(mut rays) if rays.fits(&self.mesh) => {
                rays.refresh(&self.mesh, caster.bvh(), caster.offset());
                rays
            }
            _ => ThicknessRays::trace(&self.mesh, caster.bvh(), caster.offset()),
        };
        let gains = fb.gains_along(&self.mesh, &rays, caster.offset());
        self.thickness_rays = Some(rays);
        Some(Arc::new(gains))
    }

    /// View-ray single scattering per vertex where the transport asks for it and an eye is set,
    /// else nothing (the shadow BVH is current: the solve refits it first).
    pub(super) fn single_scattering(&self) -> Vec<Rgb> {
        let (Some(eye), Some(caster)) = (self.eye, &self.caster) else { return Vec::new() };
        if !self.transport.single_scattering_along_view() {
            return Vec::new();
        }
        let normals = self.mesh.vertex_normals();
        let scene = shading::single_scattering::ViewRayScene {
            mesh: &self.mesh,
            normals: &normals,
            bvh: caster.bvh(),
            offset: caster.offset(),
            dipole: &self.dipole,
            lights: &self.lights,
            environment: self.environment.as_ref(),
        };
        shading::single_scattering::view_ray_radiance(&scene, eye)
    }
}
