//! The irradiance stage of a [`super::FrameSession`] (Mertens §5.3): the lights, the
//! environment and the texture's entry factors become the Fresnel-transmitted irradiance of
//! every face. It owns the shadow BVH over the current pose, which the body, bounce and view
//! stages trace too.

use super::{Changes, Frame};
use crate::Rgb;
use crate::irradiance::{
    Entering, Environment, FaceLit, SceneLight, ShadowCaster, face_entering, face_entering_lit,
};

/// Lights, environment and entry factors, the shadow BVH, and the irradiance they last gave.
#[derive(Default)]
pub(super) struct Irradiance {
    /// The lights, mesh units.
    lights: Vec<SceneLight>,
    /// The distant environment, if any.
    environment: Option<Environment>,
    /// Per-face entry factors of a texture (`sqrt` of its colour over the face), if any.
    entry: Option<Vec<Rgb>>,
    /// The shadow BVH over the current pose, made when the first stage needs it and refitted
    /// whenever the mesh moves.
    caster: Option<ShadowCaster>,
    /// Irradiance at the faces as last computed (reused when only the solver changed).
    faces: Vec<Entering>,
    /// Which faces each light reached when `faces` was computed (the view stage asks again).
    lit: FaceLit,
}

impl Irradiance {
    /// The lights, mesh units.
    pub(super) fn lights(&self) -> &[SceneLight] {
        &self.lights
    }

    /// The distant environment, if any.
    pub(super) fn environment(&self) -> Option<&Environment> {
        self.environment.as_ref()
    }

    /// The shadow BVH over the current pose, once a stage needed it.
    pub(super) fn caster(&self) -> Option<&ShadowCaster> {
        self.caster.as_ref()
    }

    /// Irradiance at the faces as last computed.
    pub(super) fn faces(&self) -> &[Entering] {
        &self.faces
    }

    /// Which faces each light reached, as [`Irradiance::faces`] found.
    pub(super) fn lit(&self) -> &FaceLit {
        &self.lit
    }

    /// Replaces the lights; whether they changed.
    pub(super) fn set_lights(&mut self, lights: Vec<SceneLight>) -> bool {
        let changed = self.lights != lights;
        if changed {
            self.lights = lights;
        }
        changed
    }

    /// Replaces the environment; whether it changed.
    pub(super) fn set_environment(&mut self, environment: Option<Environment>) -> bool {
        let changed = self.environment != environment;
        if changed {
            self.environment = environment;
        }
        changed
    }

    /// Replaces the texture's entry factors (one per face, checked by the session); whether
    /// they changed.
    pub(super) fn set_entry_factors(&mut self, entry: Option<Vec<Rgb>>) -> bool {
        let changed = self.entry != entry;
        if changed {
            self.entry = entry;
        }
        changed
    }

    /// Makes the irradiance current after `changes`: recomputed when the mesh, the light or the
    /// profile changed (or none was computed yet), the shadow BVH refitted first when the mesh
    /// moved.
    pub(super) fn update(&mut self, f: &Frame, changes: &Changes) {
        if changes.geometry || changes.light || changes.transport || self.faces.is_empty() {
            (self.faces, self.lit) = self.face_irradiance(f, changes.geometry);
        }
    }

    /// Fresnel-transmitted irradiance at the faces (§5.3) and which faces each light reached,
    /// refitting the shadow BVH first when the mesh `moved`.
    fn face_irradiance(&mut self, f: &Frame, moved: bool) -> (Vec<Entering>, FaceLit) {
        let settings = &f.settings;
        let shadows = self.lights.iter().any(|l| l.shadows)
            || (self.environment.is_some() && settings.environment_shadows);
        // The body, the bounces and view-ray single scattering trace rays too.
        let need_caster = shadows
            || settings.bounces > 0
            || f.transport.single_scattering_along_view()
            || f.profile.bounds_energy();
        match &mut self.caster {
            Some(c) if moved => {
                c.update(&f.mesh);
            }
            None if need_caster => self.caster = Some(ShadowCaster::new(&f.mesh)),
            _ => {}
        }
        // Lights shadow per their own flag; the environment only when asked.
        let caster = self.caster.as_ref().filter(|_| shadows);
        let env = self.environment.filter(|_| caster.is_none() || settings.environment_shadows);
        let (mut e, lit) = face_entering_lit(&f.mesh, &self.lights, env.as_ref(), &f.profile.entry, caster);
        if caster.is_some()
            && !settings.environment_shadows
            && let Some(env) = &self.environment
        {
            // Shadowed lights with an unshadowed environment: add the open environment.
            let open = face_entering(&f.mesh, &[], Some(env), &f.profile.entry, None);
            e.iter_mut().zip(open).for_each(|(e, o)| *e += o);
        }
        (e, lit)
    }

    /// The texture's entry factor of face `face` (1 without a texture).
    pub(super) fn entry_factor(&self, face: usize) -> Rgb {
        self.entry.as_ref().map_or(Rgb::ONE, |t| t[face])
    }

    /// The carried part of `e` past the texture's entry factors (unchanged without a texture):
    /// what the subsurface solve spreads.
    pub(super) fn carried(&self, e: &[Entering]) -> Vec<Rgb> {
        match &self.entry {
            Some(f) => e.iter().zip(f).map(|(e, f)| e.carried * *f).collect(),
            None => e.iter().map(|e| e.carried).collect(),
        }
    }

    /// Adds to `b` the light an oblique beam returns at its entry face (`bssrdf::entry`): the
    /// local part of `e`, past the texture's entry factors, times the profile's total diffuse
    /// reflectance.
    pub(super) fn add_local(&self, f: &Frame, b: &mut [Rgb], e: &[Entering]) {
        if !f.profile.entry.has_local() {
            return;
        }
        let r = Rgb::from_array(f.profile.total_diffuse_reflectance().map(|v| v as f32));
        for (face, (b, e)) in b.iter_mut().zip(e).enumerate() {
            let texture = self.entry.as_ref().map_or(Rgb::ONE, |t| t[face]);
            *b += e.local * texture * r;
        }
    }

    /// Adds to `b` the exitance of the light of `e` scattered once at each face, past the
    /// texture's entry factors, where single scattering is not in the profile but along the
    /// view ray (else it is in `B` already, or left out). For bounced light, which no view ray
    /// follows: without it a bounce lost the quarter of its light a half-space scatters once.
    pub(super) fn add_single(&self, f: &Frame, b: &mut [Rgb], e: &[Entering]) {
        if !f.transport.single_scattering_along_view() {
            return;
        }
        for (face, (b, e)) in b.iter_mut().zip(e).enumerate() {
            *b += e.single * self.entry.as_ref().map_or(Rgb::ONE, |t| t[face]);
        }
    }
}
