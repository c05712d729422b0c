//! The view terms of a [`super::FrameSession`]: what depends on the eye. The diffuse radiance
//! `B / (c π)` per vertex as it leaves towards the eye, times the body's chord factor where the
//! profile has one (`shading::exit_chord`) and the transmitted light's exit lobe where light
//! crossed the body (`shading::transmitted_exit`), and single scattering along the view ray
//! where the transport asks for it (`shading::single_scattering`). An eye-only change redoes
//! only these.

use super::Frame;
use super::body::Body;
use super::irradiance::Irradiance;
use crate::Rgb;
use crate::irradiance::ShadowCaster;
use crate::mesh::Mesh;
use crate::shading::diffuse_radiance;
use crate::shading::exit_chord::ExitChord;
use crate::shading::single_scattering::{
    ViewRay, ViewRayScene, face_view_rays, view_ray_radiance_along, view_rays,
};
use crate::shading::transmitted_exit::{self, ExitShares, Transmitted};
use crate::shading::view_basis::{DrawTerms, ViewBasis, ViewTerms};
use crate::solver::transmission::Tilt;
use glam::Vec3;

/// The eye and the last solve's diffuse radiance, which an eye-only change sees again.
#[derive(Default)]
pub(super) struct View {
    /// The eye, mesh units, for view-ray single scattering (`None`: not added).
    eye: Option<Vec3>,
    /// The last solve's diffuse radiance `B / (c π)` per vertex, before the chord factor.
    diffuse: Vec<Rgb>,
    /// How the view terms are evaluated: traced per eye, or split (`shading::view_basis`).
    terms: ViewTerms,
    /// The split's eye-independent part for the last solve (made on the first eye after it),
    /// and the one before, whose chords serve while the mesh has not moved.
    basis: Option<ViewBasis>,
    stale: Option<ViewBasis>,
    /// The last solve's `B` per face and the transmitted light it holds
    /// (`Body::add_transmission`), for the transmitted light's exit lobe; empty where no light
    /// crossed the body.
    transmitted: Transmitted,
    /// What the transmitted light's exit needs that no eye changes, for the last solve (made on
    /// its first view, traced or split, and kept for every eye until the next solve).
    exit_shares: Option<ExitShares>,
    /// The view rays of the last eye, pose and refractive index, which a light move keeps.
    rays: RayCache,
}

/// View rays kept while the eye, the pose and the refractive index stay: per vertex (the
/// chord factor's) and per face (the single scattering's), each made when first asked for.
#[derive(Default)]
struct RayCache {
    key: Option<(Vec3, f32, Vec<Vec3>, usize)>,
    vertex: Option<Vec<Option<ViewRay>>>,
    face: Option<Vec<Option<ViewRay>>>,
}

impl RayCache {
    /// Empties the cache unless it was made for `eye` and `scene`'s pose and material.
    fn keep_if_current(&mut self, scene: &ViewRayScene, eye: Vec3) {
        let (eta, mesh) = (scene.profile.eta as f32, scene.mesh);
        let current = self.key.as_ref().is_some_and(|(e, n, p, t)| {
            *e == eye && *n == eta && *t == mesh.triangles.len() && *p == mesh.positions
        });
        if !current {
            *self = RayCache {
                key: Some((eye, eta, mesh.positions.clone(), mesh.triangles.len())),
                ..Default::default()
            };
        }
    }
}

impl View {
    /// Sets the eye; whether it moved.
    pub(super) fn set_eye(&mut self, eye: Option<Vec3>) -> bool {
        let changed = self.eye != eye;
        if changed {
            self.eye = eye;
        }
        changed
    }

    /// Whether a solve's diffuse radiance is kept for every vertex of `mesh` (HTSM keeps none).
    pub(super) fn has_solve(&self, mesh: &Mesh) -> bool {
        self.diffuse.len() == mesh.positions.len()
    }

    /// Sets how the view terms are evaluated; whether that changed.
    pub(super) fn set_terms(&mut self, terms: ViewTerms) -> bool {
        let changed = self.terms != terms;
        self.terms = terms;
        changed
    }

    /// Keeps the diffuse radiance `B / (c π)` per vertex of the solve's `face_b` (plus
    /// `vertex_change`, the local limit's change at the vertices, `super::local_limit`), and
    /// the transmitted light `sent` per face that `face_b` holds (empty: none) and how the
    /// sphere's share of it leaves (`tilts`, `Body::tilts`; empty: normal-centred); the split's
    /// eye-independent part is made again on the next eye.
    pub(super) fn keep_solve(
        &mut self,
        f: &Frame,
        face_b: &[Rgb],
        sent: Vec<Rgb>,
        tilts: Vec<Tilt>,
        vertex_change: Option<&[Rgb]>,
    ) {
        let mut b = f.mesh.face_to_vertex(face_b);
        if let Some(change) = vertex_change {
            b.iter_mut().zip(change).for_each(|(b, c)| *b = (*b + *c).max(Rgb::ZERO));
        }
        self.diffuse = diffuse_radiance(&b, &f.profile);
        self.stale = self.basis.take().or(self.stale.take());
        self.exit_shares = None;
        self.transmitted = if sent.is_empty() {
            Default::default()
        } else {
            Transmitted { face_b: face_b.to_vec(), sent, tilts }
        };
    }

    /// `(radiance, single)` per vertex as seen from the eye (the shadow BVH of `irradiance` is
    /// current: the solve refits it first): the kept diffuse radiance times the chord factor
    /// of `body`'s exit chord (the lobe's weights and mean factors, if the lobe is not flat)
    /// with the transmitted share's own lobe (`shading::transmitted_exit`, where light crossed
    /// the body), and view-ray single scattering where the transport asks for it (else empty).
    /// Without an eye: `B / (c π)` as solved, and no single scattering. With the split view
    /// terms a solve is still seen per eye (its image is the reference's); the split's
    /// eye-independent part is made on the first eye-only change after it and serves until
    /// the next solve (the transmitted share's lobe from the eye direction alone: no rays).
    /// `eye_only`: an eye-only change, with the last image's two buffers, which the split
    /// overwrites (`None`: a solve's).
    pub(super) fn seen(
        &mut self,
        f: &Frame,
        irradiance: &Irradiance,
        body: &Body,
        eye_only: Option<(Vec<Rgb>, Vec<Rgb>)>,
    ) -> (Vec<Rgb>, Vec<Rgb>) {
        let (Some(eye), Some(caster)) = (self.eye, irradiance.caster()) else {
            return (self.diffuse.clone(), Vec::new());
        };
        let single = f.transport.single_scattering_along_view();
        let exit_chord = body.exit_chord().filter(|_| !f.settings.ablate.chord);
        if exit_chord.is_none() && !single {
            return (self.diffuse.clone(), Vec::new());
        }
        if self.terms == ViewTerms::Split && (eye_only.is_some() || self.basis.is_some()) {
            let (mut radiance, single) =
                self.seen_split(f, irradiance, exit_chord, (eye, single), eye_only.unwrap_or_default());
            if exit_chord.is_some() {
                self.transmitted_exit_split(f, body, eye, &mut radiance);
            }
            return (radiance, single);
        }
        let normals = f.mesh.vertex_normals();
        let scene = view_ray_scene(f, irradiance, caster, &normals);
        self.rays.keep_if_current(&scene, eye);
        let diffuse = match exit_chord {
            Some((chord, means)) => {
                let rays = &*self.rays.vertex.get_or_insert_with(|| view_rays(&scene, eye));
                let mut factors = chord.vertex_factors(rays, means);
                let transmitted = &self.transmitted;
                if let Some(cross) = body.cross_body().filter(|c| c.len() == transmitted.sent.len()) {
                    let shares = self.exit_shares.get_or_insert_with(|| {
                        ExitShares::new(cross, &f.mesh, &normals, transmitted, &f.profile)
                    });
                    factors = transmitted_exit::exit_factors(cross, shares, rays, f.profile.eta, &factors);
                }
                self.diffuse.iter().zip(factors).map(|(d, c)| *d * c).collect()
            }
            None => self.diffuse.clone(),
        };
        let single = if single {
            // The drawn diffuse radiance sets what a light path may leave out.
            let diffuse = Some(self.diffuse.as_slice()).filter(|_| !f.settings.ablate.light_paths);
            let rays = self.rays.face.get_or_insert_with(|| face_view_rays(&scene, eye));
            view_ray_radiance_along(&scene, rays, diffuse)
        } else {
            Vec::new()
        };
        (diffuse, single)
    }
}

impl View {
    /// [`View::seen`] by the split evaluation (`shading::view_basis`), making its
    /// eye-independent part first where the last solve left none.
    fn seen_split(
        &mut self,
        f: &Frame,
        irradiance: &Irradiance,
        exit_chord: Option<&(ExitChord, Vec<Rgb>)>,
        (eye, single): (Vec3, bool),
        (mut radiance, mut single_out): (Vec<Rgb>, Vec<Rgb>),
    ) -> (Vec<Rgb>, Vec<Rgb>) {
        let caster = irradiance.caster().expect("checked by seen");
        let mut basis = match self.basis.take() {
            Some(b) => b,
            None => {
                let normals = f.mesh.vertex_normals();
                let scene = view_ray_scene(f, irradiance, caster, &normals);
                ViewBasis::new(&scene, single, self.stale.take())
            }
        };
        let terms = DrawTerms {
            diffuse: Some(&self.diffuse),
            chord_means: exit_chord.map(|(_, n)| n.as_slice()),
            exact_exp: f.settings.ablate.view_exp,
        };
        basis.draw(&f.mesh, eye, terms, &mut radiance, &mut single_out);
        self.basis = Some(basis);
        (radiance, single_out)
    }

    /// The transmitted light's exit lobe on the split's `radiance` (the diffuse radiance times
    /// the chord factor), per vertex from the eye's direction: what
    /// `transmitted_exit::exit_factors` gives the traced view terms, without their rays.
    fn transmitted_exit_split(&mut self, f: &Frame, body: &Body, eye: Vec3, radiance: &mut [Rgb]) {
        let transmitted = &self.transmitted;
        let Some(cross) = body.cross_body().filter(|c| c.len() == transmitted.sent.len()) else { return };
        let shares = self.exit_shares.get_or_insert_with(|| {
            ExitShares::new(cross, &f.mesh, &f.mesh.vertex_normals(), transmitted, &f.profile)
        });
        shares.draw_split(crate::simd::Isa::best(), eye, cross, &self.diffuse, radiance);
    }
}

/// What the view rays see of frame `f`: its posed mesh with `normals`, the shadow BVH of
/// `caster`, its material and the lights and environment of `irradiance`.
fn view_ray_scene<'a>(
    f: &'a Frame,
    irradiance: &'a Irradiance,
    caster: &'a ShadowCaster,
    normals: &'a [Vec3],
) -> ViewRayScene<'a> {
    ViewRayScene {
        mesh: &f.mesh,
        normals,
        bvh: caster.bvh(),
        offset: caster.offset(),
        profile: &f.profile,
        lights: irradiance.lights(),
        environment: irradiance.environment(),
        lit: Some(irradiance.lit()),
    }
}
