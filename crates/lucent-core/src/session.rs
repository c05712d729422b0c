//! One frame after another (Mertens §5.5): a [`FrameSession`] owns everything that outlives a
//! frame on the CPU (the mesh and its current pose, the hierarchy and its links, the shadow BVH,
//! the lights and environment, the diffusion profile, the method and mode) and turns "this
//! changed" into the least work:
//!
//! | change                         | work on the next [`FrameSession::solve`]                     |
//! |--------------------------------|--------------------------------------------------------------|
//! | camera only                    | view-ray single scattering and chord (`shading::single_scattering`, `exit_chord`) |
//! | lights or environment          | irradiance, then pull/gather/push on the stored links        |
//! | material, scale or profile     | profile tables; render mode relinks, incremental re-evaluates |
//! | deformation (positions)        | BVH refit, irradiance; render relinks, incremental updates   |
//! | oracle thresholds              | relink                                                       |
//!
//! The CLI (`lucent render`, `--frames`), the benches and the viewer's worker all drive this
//! one session; the GPU side (rasterising `B/π`, or Shopf's HTSM for [`Method::Htsm`], which has
//! no per-face solve) reads [`FrameSession::mesh`], [`FrameSession::lights`] and
//! [`FrameSession::environment`] from it.

use crate::Rgb;
use crate::bssrdf::Profile;
use crate::clock::ms_since;
use crate::formfactor::FormFactorOptions;
use crate::hierarchy::{Hierarchy, face_cluster};
use crate::irradiance::{Entering, Environment, SceneLight, ShadowCaster, face_entering, interreflection};
use crate::mesh::Mesh;
use crate::shading;
use crate::solver::finite_body::FiniteBody;
use crate::solver::{self, HierarchicalSolver, Oracle, Progress};
use glam::Vec3;
use std::sync::Arc;
use std::time::Instant;

mod extras;
mod transport;
pub use transport::Transport;

/// How the subsurface transport is computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// Mertens 2003's hierarchical boundary element solve (§3.2, §5). Default.
    #[default]
    Hierarchical,
    /// The O(N²) reference: every face pair by the semi-analytic form factor.
    Exact,
    /// Shopf 2007's Heterogeneous Translucent Shadow Maps, on the GPU: no per-face solve here;
    /// the session keeps the mesh pose, lights and environment the GPU renders from.
    Htsm,
}

impl Method {
    /// Every method, in the order the CLI and the viewer list them.
    pub const ALL: [Method; 3] = [Method::Hierarchical, Method::Exact, Method::Htsm];

    /// The name the CLI and scene files use.
    pub fn name(self) -> &'static str {
        match self {
            Method::Hierarchical => "hierarchical",
            Method::Exact => "exact",
            Method::Htsm => "htsm",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_name(s, &Method::ALL, Method::name, "method")
    }
}

/// Mertens §5.5: what the hierarchical solve keeps between frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SolveMode {
    /// Links made once and stored; a light change only re-gathers. Relinks after a deformation
    /// or material change.
    Render,
    /// Links stored and updated after a deformation or material change: only the links that
    /// the change touched are re-evaluated, promoted or demoted.
    Incremental,
    /// No stored links: refine from the root and gather while traversing, every solve. Default
    /// for single images (nothing to reuse).
    #[default]
    OnTheFly,
}

impl SolveMode {
    /// Every mode, in the order the CLI and the viewer list them.
    pub const ALL: [SolveMode; 3] = [SolveMode::Render, SolveMode::Incremental, SolveMode::OnTheFly];

    /// The name the CLI and the viewer use.
    pub fn name(self) -> &'static str {
        match self {
            SolveMode::Render => "render",
            SolveMode::Incremental => "incremental",
            SolveMode::OnTheFly => "on-the-fly",
        }
    }
}

impl std::str::FromStr for SolveMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_name(s, &SolveMode::ALL, SolveMode::name, "mode")
    }
}

/// `s` (case-insensitive) among `all` by `name`, or a one-line error listing the accepted names.
fn parse_name<T: Copy>(s: &str, all: &[T], name: fn(T) -> &'static str, what: &str) -> Result<T, String> {
    let s = s.trim().to_ascii_lowercase();
    all.iter().copied().find(|&v| name(v) == s).ok_or_else(|| {
        let names: Vec<_> = all.iter().map(|&v| name(v)).collect();
        format!("unknown {what} {s:?}; expected one of {}", names.join(", "))
    })
}

/// How much looser the oracle's thresholds are for a bounce solved on the fly than for the
/// direct light's solve. The bounce is a few percent of `B` (up to a third in a crevice), so its
/// share of the error stays below the direct solve's: on the 48K Stanford dragon (marble,
/// 10 cm) the image moved by 0.03% at the median pixel, 0.18% at the 99th percentile.
const BOUNCE_ORACLE_SLACK: f32 = 4.0;

/// How the session solves, besides the material and the light.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameSettings {
    /// Hierarchical, exact or HTSM.
    pub method: Method,
    /// What the hierarchical solve keeps between frames.
    pub mode: SolveMode,
    /// Refinement thresholds; `None`: the profile's defaults ([`Oracle::for_profile`]).
    pub oracle: Option<Oracle>,
    /// Whether the mesh shadows the environment (64 rays per face,
    /// [`crate::irradiance::occlusion`]). Lights say for themselves ([`SceneLight::shadows`]).
    pub environment_shadows: bool,
    /// Bounces of subsurface light between facing parts through the air
    /// ([`interreflection`]), 0..=4; 0 (this struct's default) switches them off. The `lucent`
    /// command line, scenes and viewer default to 3 (`ranges::DEFAULT_BOUNCES` there).
    pub bounces: u32,
}

/// Wall-clock times of one solve's stages, milliseconds. Stages that did not run are 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Irradiance at the leaves: lights, shadow rays, environment (and the BVH refit), the
    /// body's thickness rays and, on a new mesh's first hierarchical solve, the solver's
    /// making (its hierarchy's build), which runs beside them.
    pub irradiance_ms: f64,
    /// Profile tables, link creation, refinement or incremental update.
    pub link_ms: f64,
    /// Pulling irradiance up the hierarchy.
    pub pull_ms: f64,
    /// Gathering along the links (the whole O(N²) sum for the exact solver).
    pub gather_ms: f64,
    /// What depends on the eye: single scattering along the view ray
    /// (`shading::single_scattering`) and the body's chord factor (`shading::exit_chord`).
    pub single_scattering_ms: f64,
    /// Pushing `B` down to the leaves and the per-vertex average.
    pub push_ms: f64,
    /// Bounces between parts: their rays and solves ([`interreflection`]).
    pub bounces_ms: f64,
}

impl Timings {
    /// Sum of the stages, milliseconds.
    pub fn total_ms(&self) -> f64 {
        self.irradiance_ms
            + self.link_ms
            + self.pull_ms
            + self.gather_ms
            + self.push_ms
            + self.bounces_ms
            + self.single_scattering_ms
    }
}

/// What one solve produced.
#[derive(Clone, Debug, Default)]
pub struct Solved {
    /// Radiosity `B` per face (empty for [`Method::Htsm`]).
    pub face_b: Vec<Rgb>,
    /// Diffuse exitant radiance `B / (c π)` per vertex, area-weighted (§3.2), before the exit
    /// Fresnel factor and lobe, times the body's chord factor along the view ray where an eye is
    /// set and the profile's lobe is not flat ([`shading::exit_chord`]; empty for
    /// [`Method::Htsm`]).
    pub vertex_radiance: Vec<Rgb>,
    /// Single-scattered radiance along the view ray per vertex, before the exit Fresnel factor
    /// (empty without it: see [`Transport::single_scattering_along_view`] and
    /// [`FrameSession::set_eye`]). Shading adds it to `vertex_radiance`, blended geometrically
    /// across a face ([`shading::single_scattering`]).
    pub vertex_single: Vec<Rgb>,
    /// How `vertex_radiance` leaves over exit angles: the mesh pass multiplies it by
    /// `T(μ_o)` besides `F_t` ([`crate::bssrdf::ExitLobe`]; flat for Mertens' profile and HTSM).
    pub exit_lobe: crate::bssrdf::ExitLobe,
    /// Per-stage times of the solve that made this (zero when it was reused).
    pub timings: Timings,
    /// Links of the hierarchical solve (`None` for the exact solver and HTSM).
    pub links: Option<usize>,
    /// Whether anything was computed (false: nothing changed since the last solve).
    pub fresh: bool,
}

/// What changed since the last solve.
#[derive(Clone, Copy, Debug, Default)]
struct Changes {
    geometry: bool,
    transport: bool,
    light: bool,
    oracle: bool,
    method: bool,
    /// The eye moved (only view-ray single scattering depends on it).
    view: bool,
}

impl Changes {
    fn all() -> Self {
        Changes { geometry: true, transport: true, light: true, oracle: true, method: true, view: true }
    }
    fn any(&self) -> bool {
        self.solve() || self.view
    }
    /// Whether the per-face solve must run.
    fn solve(&self) -> bool {
        self.geometry || self.transport || self.light || self.oracle || self.method
    }

    /// Both sets of changes.
    fn union(self, o: Changes) -> Changes {
        Changes {
            geometry: self.geometry || o.geometry,
            transport: self.transport || o.transport,
            light: self.light || o.light,
            oracle: self.oracle || o.oracle,
            method: self.method || o.method,
            view: self.view || o.view,
        }
    }
}

/// The CPU side of a translucent object across frames. See the module documentation.
pub struct FrameSession {
    /// The mesh in its current pose (topology fixed for the session's life).
    mesh: Mesh,
    /// Vertex positions of the rest pose: the hierarchical solver links there first, so that
    /// a deformed pose is an incremental update.
    rest: Vec<Vec3>,
    /// The mesh's largest bounding-box side in its rest pose, mesh units: the profile's scale
    /// does not follow a deformation.
    rest_extent: f32,
    transport: Transport,
    profile: Profile,
    settings: FrameSettings,
    lights: Vec<SceneLight>,
    environment: Option<Environment>,
    /// The hierarchy a front end built (shrink-wrap), until the solver takes it.
    hierarchy: Option<Hierarchy>,
    solver: Option<HierarchicalSolver>,
    caster: Option<ShadowCaster>,
    /// The bounce's rays between parts, traced on the first bounce, refitted after small
    /// deformations and traced again after large ones (`BounceRays::fits`).
    bounce_rays: Option<interreflection::BounceRays>,
    /// Whether the mesh moved since `bounce_rays` were traced or last refitted.
    bounce_rays_moved: bool,
    /// Irradiance at the faces as last computed (reused when only the solver changed).
    irradiance: Vec<Entering>,
    /// Per-face entry factors of a texture (`sqrt` of its colour over the face), if any.
    entry: Option<Vec<Rgb>>,
    /// The eye, mesh units, for view-ray single scattering (`None`: not added).
    eye: Option<Vec3>,
    /// The finite-body gain per face and its table (`solver::finite_body`), for the profiles
    /// that bound energy; remade when the mesh moves or the transport changes.
    face_gain: Option<Arc<Vec<Rgb>>>,
    finite_body: Option<FiniteBody>,
    /// The exit lobe's weights and the mean chord factor `N` per vertex (`shading::exit_chord`),
    /// made with the gain from the same rays; `None` for a flat exit lobe.
    exit_chord: Option<(crate::shading::exit_chord::ExitChord, Vec<Rgb>)>,
    /// The last solve's diffuse radiance `B / (c π)` per vertex, before the chord factor (an
    /// eye-only change reuses it).
    diffuse: Vec<Rgb>,
    /// The rays under each face that the gain measures the body with, traced once, followed
    /// through small deformations (`ThicknessRays::fits`).
    thickness_rays: Option<crate::solver::finite_body::ThicknessRays>,
    /// The slab transmission of every face across the body (`solver::transmission`), made
    /// with the gain from the same rays; `None` for [`Transmission::HalfSpace`] or without a gain.
    cross_body: Option<Arc<crate::solver::transmission::CrossBody>>,
    /// The last solve's `B` per face and the transmitted light it holds (`cross_body`), for
    /// the transmitted light's exit lobe; empty without `cross_body`.
    transmitted: (Vec<Rgb>, Vec<Rgb>),
    /// `cross_body`'s terms under uniform irradiance 1, for the energy bound.
    face_terms: Option<Arc<Vec<Rgb>>>,
    changes: Changes,
    /// Changes the CPU solve has not seen yet (made while HTSM, which has none, was chosen).
    unsolved: Changes,
    last: Solved,
    /// Where long refinements and exact solves count their progress, if a front end watches.
    progress: Option<Arc<Progress>>,
}

impl FrameSession {
    /// A session for `mesh` in its rest pose; `hierarchy`, when given, was built with `mesh`
    /// (Mertens §5.1.2 subdivision), else the face-cluster hierarchy (§5.1.1) is built on first
    /// use. Nothing is solved until [`FrameSession::solve`].
    pub fn new(
        mesh: Mesh,
        hierarchy: Option<Hierarchy>,
        transport: Transport,
        settings: FrameSettings,
    ) -> Self {
        let rest_extent = mesh.extent();
        let profile = transport.profile_at(rest_extent);
        FrameSession {
            rest: mesh.positions.clone(),
            mesh,
            rest_extent,
            transport,
            profile,
            settings,
            lights: Vec::new(),
            environment: None,
            hierarchy,
            solver: None,
            caster: None,
            bounce_rays: None,
            bounce_rays_moved: false,
            irradiance: Vec::new(),
            entry: None,
            eye: None,
            face_gain: None,
            finite_body: None,
            exit_chord: None,
            diffuse: Vec::new(),
            thickness_rays: None,
            cross_body: None,
            transmitted: Default::default(),
            face_terms: None,
            changes: Changes::all(),
            unsolved: Changes::default(),
            last: Solved::default(),
            progress: None,
        }
    }

    /// The mesh in its current pose.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The diffusion profile in mesh units.
    pub fn profile(&self) -> &Profile {
        &self.profile
    }

    /// The material at its size.
    pub fn transport(&self) -> &Transport {
        &self.transport
    }

    /// Method, mode, oracle, environment shadows and bounces.
    pub fn settings(&self) -> &FrameSettings {
        &self.settings
    }

    /// The lights, mesh units.
    pub fn lights(&self) -> &[SceneLight] {
        &self.lights
    }

    /// The distant environment, if any.
    pub fn environment(&self) -> Option<&Environment> {
        self.environment.as_ref()
    }

    /// The hierarchical solver with its hierarchy and links, once a hierarchical solve made it.
    pub fn hierarchical(&self) -> Option<&HierarchicalSolver> {
        self.solver.as_ref()
    }

    /// The oracle in use: the settings' thresholds, else the profile's defaults.
    pub fn oracle(&self) -> Oracle {
        self.settings.oracle.unwrap_or_else(|| Oracle::for_profile(self.profile.kind))
    }

    /// Moves the mesh to `positions` (a deformation of the rest pose: same vertex count).
    ///
    /// # Panics
    /// If the vertex count differs (the topology is fixed for a session).
    pub fn set_positions(&mut self, positions: &[Vec3]) {
        assert_eq!(positions.len(), self.mesh.positions.len(), "a session's topology is fixed");
        if self.mesh.positions != positions {
            self.mesh.positions.copy_from_slice(positions);
            self.changes.geometry = true;
            self.bounce_rays_moved = true;
        }
    }

    /// Changes the material, scale or profile (the profile is rebuilt only if one of them
    /// changed).
    pub fn set_transport(&mut self, transport: Transport) {
        if self.transport != transport {
            self.profile = transport.profile_at(self.rest_extent);
            self.transport = transport;
            self.finite_body = None;
            self.changes.transport = true;
        }
    }

    /// Changes the method, mode, oracle, environment shadows or bounces.
    pub fn set_settings(&mut self, settings: FrameSettings) {
        let s = &self.settings;
        self.changes.oracle |= s.oracle != settings.oracle;
        self.changes.method |= s.method != settings.method || s.mode != settings.mode;
        self.changes.light |=
            s.environment_shadows != settings.environment_shadows || s.bounces != settings.bounces;
        self.settings = settings;
    }

    /// Replaces the lights.
    pub fn set_lights(&mut self, lights: Vec<SceneLight>) {
        if self.lights != lights {
            self.lights = lights;
            self.changes.light = true;
        }
    }

    /// Replaces the environment.
    pub fn set_environment(&mut self, environment: Option<Environment>) {
        if self.environment != environment {
            self.environment = environment;
            self.changes.light = true;
        }
    }

    /// Sets the eye (mesh units) that view-ray single scattering is seen from; `None` leaves
    /// it out. Only that term is recomputed when the eye moves.
    pub fn set_eye(&mut self, eye: Option<Vec3>) {
        if self.eye != eye {
            self.eye = eye;
            self.changes.view = true;
        }
    }

    /// Counts the progress of long solves (hierarchical refinement: leaves of finished receiver
    /// subtrees; exact solve: receivers) on `progress`, for a front end to poll; `None` stops.
    pub fn set_progress(&mut self, progress: Option<Arc<Progress>>) {
        if let Some(s) = &mut self.solver {
            s.progress = progress.clone();
        }
        self.progress = progress;
    }

    /// Sets the texture's entry factor per face (see `mesh::texture`): the irradiance of each
    /// face is multiplied by it before the solve, which itself stays untextured.
    ///
    /// # Panics
    /// If there is not one factor per face.
    pub fn set_entry_factors(&mut self, entry: Option<Vec<Rgb>>) {
        if let Some(f) = &entry {
            assert_eq!(f.len(), self.mesh.triangles.len(), "one entry factor per face");
        }
        if self.entry != entry {
            self.entry = entry;
            self.changes.light = true;
        }
    }

    /// True when nothing the solve depends on changed since the last solve.
    pub fn is_current(&self) -> bool {
        !self.changes.any()
    }

    /// Solves the current state, doing only what the changes since the last solve need (see
    /// the module documentation); returns the last result, marked not fresh, when nothing
    /// changed.
    pub fn solve(&mut self) -> &Solved {
        if !self.changes.any() {
            self.last.fresh = false;
            self.last.timings = Timings::default();
            return &self.last;
        }
        let changes = std::mem::take(&mut self.changes).union(std::mem::take(&mut self.unsolved));
        if self.settings.method == Method::Htsm {
            // Kept for when a CPU method is chosen again.
            self.unsolved = changes;
            self.last = Solved { fresh: true, ..Solved::default() };
            return &self.last;
        }
        let mut timings = Timings::default();
        // Only the eye moved: the last solve's `B / (c π)` stands, seen along new view rays
        // (HTSM leaves it empty, but leaving HTSM is a method change, which solves).
        if !changes.solve() && self.diffuse.len() == self.mesh.positions.len() {
            let t = Instant::now();
            (self.last.vertex_radiance, self.last.vertex_single) = self.seen_from_eye();
            timings.single_scattering_ms = ms_since(t);
            self.last.timings = timings;
            self.last.fresh = true;
            return &self.last;
        }
        // A new mesh's solver needs its hierarchy, built on one core (a greedy contraction):
        // make it beside the irradiance and the body's rays, which do not need it (871K
        // dragon: 4.4 s alone).
        let make = (self.settings.method == Method::Hierarchical && self.solver.is_none())
            .then(|| self.solver_maker());
        let t = Instant::now();
        let (solver, ()) = rayon::join(
            || make.map(|make| make()),
            || {
                if changes.geometry || changes.light || changes.transport || self.irradiance.is_empty() {
                    self.irradiance = self.face_irradiance(changes.geometry);
                }
                if changes.geometry || changes.transport || self.face_gain.is_none() {
                    self.measure_body();
                }
            },
        );
        if solver.is_some() {
            self.solver = solver;
        }
        timings.irradiance_ms = ms_since(t);

        let e = std::mem::take(&mut self.irradiance);
        let oracle = self.oracle();
        let carried = self.entered_carried(&e);
        let (mut face_b, links) = self.transport_once(&carried, &changes, oracle, &mut timings);
        let t = Instant::now();
        let mut sent = Vec::new();
        self.add_transmission(&mut face_b, &mut sent, &carried);
        self.add_local(&mut face_b, &e);
        // Each bounce: the light the last solve sent out, caught by facing parts, solved again
        // (the solve is linear in the irradiance; stored links are reused).
        // The direct light's single scattering leaves too, but is not bounced: with it the
        // dragon read +6.5% against the path tracer (validation/README.md, "Single scattering
        // of bounced light").
        let mut last = face_b.clone();
        let t_bounces = Instant::now();
        // The rays between parts, made current once for all the bounces of this solve.
        if self.settings.bounces > 0
            && let Some(caster) = &self.caster
        {
            match &mut self.bounce_rays {
                Some(rays) if rays.fits(&self.mesh, &self.profile) => {
                    if self.bounce_rays_moved {
                        rays.refit(&self.mesh, caster);
                    }
                }
                _ => {
                    let progress = self.progress.as_deref();
                    self.bounce_rays =
                        Some(interreflection::BounceRays::trace(&self.mesh, caster, &self.profile, progress));
                }
            }
            self.bounce_rays_moved = false;
        }
        for _ in 0..self.settings.bounces {
            let Some(rays) = &self.bounce_rays else { break };
            let e2 = interreflection::bounced_irradiance(rays, &last, &self.profile);
            let unchanged = Changes::default();
            // On the fly, a bounce links anew; its light is a small part of `B`, so its links
            // may err more (stored links are reused as they are).
            let mut bounce_oracle = oracle;
            if self.settings.mode == SolveMode::OnTheFly {
                bounce_oracle.eps1 *= BOUNCE_ORACLE_SLACK;
                bounce_oracle.eps2 *= BOUNCE_ORACLE_SLACK;
                bounce_oracle.eps_abs *= BOUNCE_ORACLE_SLACK;
            }
            let carried = self.entered_carried(&e2);
            last = self.transport_once(&carried, &unchanged, bounce_oracle, &mut Timings::default()).0;
            self.add_transmission(&mut last, &mut sent, &carried);
            self.add_local(&mut last, &e2);
            // No view ray follows the bounced light: its single scattering joins `B`.
            self.add_single(&mut last, &e2);
            face_b.iter_mut().zip(&last).for_each(|(b, l)| *b += *l);
        }
        timings.bounces_ms = ms_since(t_bounces);
        self.irradiance = e;
        self.transmitted = if sent.is_empty() { Default::default() } else { (face_b.clone(), sent) };
        self.diffuse = shading::diffuse_radiance(&self.mesh.face_to_vertex(&face_b), &self.profile);
        timings.push_ms += ms_since(t) - timings.bounces_ms;
        let t = Instant::now();
        let (vertex_radiance, vertex_single) = self.seen_from_eye();
        timings.single_scattering_ms = ms_since(t);
        let exit_lobe = self.profile.exit_lobe.clone();
        self.last = Solved { face_b, vertex_radiance, vertex_single, exit_lobe, timings, links, fresh: true };
        &self.last
    }

    /// Fresnel-transmitted irradiance at the faces (§5.3), refitting the shadow BVH first when
    /// the mesh `moved`.
    fn face_irradiance(&mut self, moved: bool) -> Vec<Entering> {
        let shadows = self.lights.iter().any(|l| l.shadows)
            || (self.environment.is_some() && self.settings.environment_shadows);
        let need_caster = shadows
            || self.settings.bounces > 0
            || self.transport.single_scattering_along_view()
            || self.profile.bounds_energy();
        match &mut self.caster {
            Some(c) if moved => {
                c.update(&self.mesh);
            }
            None if need_caster => self.caster = Some(ShadowCaster::new(&self.mesh)),
            _ => {}
        }
        // Lights shadow per their own flag; the environment only when asked.
        let caster = self.caster.as_ref().filter(|_| shadows);
        let env = self.environment.filter(|_| caster.is_none() || self.settings.environment_shadows);
        let mut e = face_entering(&self.mesh, &self.lights, env.as_ref(), &self.profile.entry, caster);
        if caster.is_some()
            && !self.settings.environment_shadows
            && let Some(env) = &self.environment
        {
            // Shadowed lights with an unshadowed environment: add the open environment.
            let open = face_entering(&self.mesh, &[], Some(env), &self.profile.entry, None);
            e.iter_mut().zip(open).for_each(|(e, o)| *e += o);
        }
        e
    }

    /// `B` per face for irradiance `e` by the settings' method, updating the hierarchical
    /// solver for `changes` first and linking with the thresholds `oracle`: `(B, links)`.
    fn transport_once(
        &mut self,
        e: &[Rgb],
        changes: &Changes,
        oracle: Oracle,
        timings: &mut Timings,
    ) -> (Vec<Rgb>, Option<usize>) {
        if self.settings.method == Method::Exact {
            let t = Instant::now();
            let all: Vec<usize> = (0..self.mesh.triangles.len()).collect();
            let opts = FormFactorOptions::default();
            let p = self.progress.as_deref();
            let gain = self.face_gain.as_deref().map(|g| g.as_slice());
            let terms = self.cross_body.as_ref().map(|c| c.uniform_terms());
            let b = solver::exact::solve_receivers_with_gain(
                &self.mesh,
                &self.profile,
                e,
                &opts,
                &all,
                p,
                gain,
                terms.as_deref(),
            );
            timings.gather_ms += ms_since(t);
            return (b, None);
        }
        let mode = self.settings.mode;
        self.make_solver();
        let Self { solver, mesh, profile, face_gain, cross_body, face_terms, .. } = self;
        let s = solver.as_mut().expect("made above");
        s.set_face_gain(face_gain.clone());
        if face_terms.as_ref().map(|t| t.len()) != cross_body.as_ref().map(|c| c.len()) {
            *face_terms = cross_body.as_ref().map(|c| Arc::new(c.uniform_terms()));
        }
        s.set_face_term(face_terms.clone());
        let moved = s.mesh.positions != mesh.positions;
        let t = Instant::now();
        let profile_changed = s.profile != *profile;
        let oracle_changed = changes.oracle || s.oracle != oracle;
        let relink = moved || profile_changed || oracle_changed;
        s.oracle = oracle;
        // Render mode never updates its links incrementally: it stores no candidates.
        s.keep_candidates = mode != SolveMode::Render;
        let solution = match mode {
            SolveMode::OnTheFly => {
                if moved {
                    s.set_positions(&mesh.positions);
                }
                s.profile = profile.clone();
                s.solve_on_the_fly(e)
            }
            SolveMode::Render => {
                if relink || s.links().is_none() {
                    if moved {
                        s.set_positions(&mesh.positions);
                    }
                    s.profile = profile.clone();
                    s.link();
                    timings.link_ms += ms_since(t);
                }
                s.solve_render(e)
            }
            SolveMode::Incremental => {
                if profile_changed {
                    s.set_profile(profile.clone());
                }
                if oracle_changed || s.links().is_none() {
                    // Links on the pose they were asked for first, so that later updates are
                    // incremental.
                    s.link();
                }
                s.update_incremental(&mesh.positions, None);
                timings.link_ms += ms_since(t);
                s.solve_render(e)
            }
        };
        let st = solution.stats;
        timings.link_ms += if mode == SolveMode::OnTheFly { st.link_ms } else { 0.0 };
        timings.pull_ms += st.pull_ms;
        timings.gather_ms += st.gather_ms;
        timings.push_ms += st.push_ms;
        (solution.face_b, Some(st.links))
    }

    /// Makes the hierarchical solver on first use, on the rest pose.
    fn make_solver(&mut self) {
        if self.solver.is_none() {
            self.solver = Some(self.solver_maker()());
        }
    }

    /// What makes the hierarchical solver on the rest pose (building the hierarchy unless a
    /// front end gave one), to run on any thread.
    fn solver_maker(&mut self) -> impl FnOnce() -> HierarchicalSolver + Send + use<> {
        let rest = Mesh::new(self.rest.clone(), self.mesh.triangles.clone());
        let given = self.hierarchy.take();
        let (profile, oracle, progress) = (self.profile.clone(), self.oracle(), self.progress.clone());
        move || {
            let h = given.unwrap_or_else(|| face_cluster::build(&rest));
            let mut s = HierarchicalSolver::new(rest, h, profile, oracle);
            s.ff_opts = FormFactorOptions::default();
            s.progress = progress;
            s
        }
    }
}

#[cfg(test)]
mod tests;
