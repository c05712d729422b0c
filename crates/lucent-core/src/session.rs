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
//!
//! The session coordinates five stages, one file each, that own their inputs, their cache and
//! when it goes stale; [`FrameSession::solve`] runs them in the order light flows:
//!
//! * `irradiance.rs`: lights, environment, the texture's entry factors and the shadow BVH that
//!   every stage traces → Fresnel-transmitted irradiance per face (§5.3);
//! * `body.rs`: thickness rays under the faces → the finite-body gain, the slab transmission
//!   across the body and the exit chord's per-vertex means;
//! * `subsurface.rs`: the hierarchical solver and its links, or the exact sum → `B` per face;
//! * `bounces.rs`: the rays between facing parts → `B` of the light they send each other;
//! * `view.rs`: the eye → `B / (c π)` per vertex seen along the view rays (the chord factor,
//!   the transmitted light's lobe) and view-ray single scattering.

use crate::Rgb;
use crate::bssrdf::Profile;
use crate::clock::ms_since;
use crate::hierarchy::Hierarchy;
use crate::irradiance::{Environment, SceneLight};
use crate::mesh::Mesh;
use crate::solver::{HierarchicalSolver, Oracle, Progress};
use glam::Vec3;
use std::sync::Arc;
use std::time::Instant;

mod body;
mod bounces;
mod irradiance;
mod subsurface;
mod transport;
mod view;
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
    /// ([`crate::irradiance::interreflection`]), 0..=4; 0 (this struct's default) switches them
    /// off. The `lucent` command line, scenes and viewer default to 3 (`ranges::DEFAULT_BOUNCES`
    /// there).
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
    /// Bounces between parts: their rays and solves ([`crate::irradiance::interreflection`]).
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
    /// set and the profile's lobe is not flat ([`crate::shading::exit_chord`]; empty for
    /// [`Method::Htsm`]).
    pub vertex_radiance: Vec<Rgb>,
    /// Single-scattered radiance along the view ray per vertex, before the exit Fresnel factor
    /// (empty without it: see [`Transport::single_scattering_along_view`] and
    /// [`FrameSession::set_eye`]). Shading adds it to `vertex_radiance`, blended geometrically
    /// across a face ([`crate::shading::single_scattering`]).
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

/// What changed since the last solve; each stage reads the flags its cache depends on.
#[derive(Clone, Copy, Debug, Default)]
struct Changes {
    /// The mesh moved (`set_positions`).
    geometry: bool,
    /// The material, scale or profile changed (`set_transport`).
    transport: bool,
    /// Lights, environment, entry factors, environment shadows or bounces changed.
    light: bool,
    /// The oracle's thresholds changed.
    oracle: bool,
    /// The method or the solve mode changed.
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

/// What every stage reads and none owns: the mesh's pose, the material and its profile, the
/// settings and the progress counter.
struct Frame {
    /// The mesh in its current pose (topology fixed for the session's life).
    mesh: Mesh,
    /// The mesh's largest bounding-box side in its rest pose, mesh units: the profile's scale
    /// does not follow a deformation.
    rest_extent: f32,
    transport: Transport,
    /// The diffusion profile of `transport` at `rest_extent`.
    profile: Profile,
    settings: FrameSettings,
    /// Where long refinements, exact solves and ray tracing count their progress, if a front
    /// end watches.
    progress: Option<Arc<Progress>>,
}

impl Frame {
    /// The oracle in use: the settings' thresholds, else the profile's defaults.
    fn oracle(&self) -> Oracle {
        self.settings.oracle.unwrap_or_else(|| Oracle::for_profile(self.profile.kind))
    }
}

/// The CPU side of a translucent object across frames. See the module documentation.
pub struct FrameSession {
    frame: Frame,
    irradiance: irradiance::Irradiance,
    body: body::Body,
    subsurface: subsurface::Subsurface,
    bounces: bounces::Bounces,
    view: view::View,
    changes: Changes,
    /// Changes the CPU solve has not seen yet (made while HTSM, which has none, was chosen).
    unsolved: Changes,
    last: Solved,
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
            subsurface: subsurface::Subsurface::new(mesh.positions.clone(), hierarchy),
            frame: Frame { mesh, rest_extent, transport, profile, settings, progress: None },
            irradiance: irradiance::Irradiance::default(),
            body: body::Body::default(),
            bounces: bounces::Bounces::default(),
            view: view::View::default(),
            changes: Changes::all(),
            unsolved: Changes::default(),
            last: Solved::default(),
        }
    }

    /// The mesh in its current pose.
    pub fn mesh(&self) -> &Mesh {
        &self.frame.mesh
    }

    /// The diffusion profile in mesh units.
    pub fn profile(&self) -> &Profile {
        &self.frame.profile
    }

    /// The material at its size.
    pub fn transport(&self) -> &Transport {
        &self.frame.transport
    }

    /// Method, mode, oracle, environment shadows and bounces.
    pub fn settings(&self) -> &FrameSettings {
        &self.frame.settings
    }

    /// The lights, mesh units.
    pub fn lights(&self) -> &[SceneLight] {
        self.irradiance.lights()
    }

    /// The distant environment, if any.
    pub fn environment(&self) -> Option<&Environment> {
        self.irradiance.environment()
    }

    /// The hierarchical solver with its hierarchy and links, once a hierarchical solve made it.
    pub fn hierarchical(&self) -> Option<&HierarchicalSolver> {
        self.subsurface.solver()
    }

    /// The oracle in use: the settings' thresholds, else the profile's defaults.
    pub fn oracle(&self) -> Oracle {
        self.frame.oracle()
    }

    /// Moves the mesh to `positions` (a deformation of the rest pose: same vertex count).
    ///
    /// # Panics
    /// If the vertex count differs (the topology is fixed for a session).
    pub fn set_positions(&mut self, positions: &[Vec3]) {
        let mesh = &mut self.frame.mesh;
        assert_eq!(positions.len(), mesh.positions.len(), "a session's topology is fixed");
        if mesh.positions != positions {
            mesh.positions.copy_from_slice(positions);
            self.changes.geometry = true;
        }
    }

    /// Changes the material, scale or profile (the profile is rebuilt only if one of them
    /// changed).
    pub fn set_transport(&mut self, transport: Transport) {
        if self.frame.transport != transport {
            self.frame.profile = transport.profile_at(self.frame.rest_extent);
            self.frame.transport = transport;
            self.changes.transport = true;
        }
    }

    /// Changes the method, mode, oracle, environment shadows or bounces.
    pub fn set_settings(&mut self, settings: FrameSettings) {
        let s = &self.frame.settings;
        self.changes.oracle |= s.oracle != settings.oracle;
        self.changes.method |= s.method != settings.method || s.mode != settings.mode;
        self.changes.light |=
            s.environment_shadows != settings.environment_shadows || s.bounces != settings.bounces;
        self.frame.settings = settings;
    }

    /// Replaces the lights.
    pub fn set_lights(&mut self, lights: Vec<SceneLight>) {
        self.changes.light |= self.irradiance.set_lights(lights);
    }

    /// Replaces the environment.
    pub fn set_environment(&mut self, environment: Option<Environment>) {
        self.changes.light |= self.irradiance.set_environment(environment);
    }

    /// Sets the eye (mesh units) that view-ray single scattering is seen from; `None` leaves
    /// it out. Only that term is recomputed when the eye moves.
    pub fn set_eye(&mut self, eye: Option<Vec3>) {
        self.changes.view |= self.view.set_eye(eye);
    }

    /// Counts the progress of long solves (hierarchical refinement: leaves of finished receiver
    /// subtrees; exact solve: receivers) on `progress`, for a front end to poll; `None` stops.
    pub fn set_progress(&mut self, progress: Option<Arc<Progress>>) {
        self.subsurface.set_progress(progress.clone());
        self.frame.progress = progress;
    }

    /// Sets the texture's entry factor per face (see `mesh::texture`): the irradiance of each
    /// face is multiplied by it before the solve, which itself stays untextured.
    ///
    /// # Panics
    /// If there is not one factor per face.
    pub fn set_entry_factors(&mut self, entry: Option<Vec<Rgb>>) {
        if let Some(f) = &entry {
            assert_eq!(f.len(), self.frame.mesh.triangles.len(), "one entry factor per face");
        }
        self.changes.light |= self.irradiance.set_entry_factors(entry);
    }

    /// True when nothing the solve depends on changed since the last solve.
    pub fn is_current(&self) -> bool {
        !self.changes.any()
    }

    /// Solves the current state, doing only what the changes since the last solve need (see
    /// the module documentation); returns the last result, marked not fresh, when nothing
    /// changed.
    pub fn solve(&mut self) -> &Solved {
        let Some(changes) = self.take_changes() else { return &self.last };
        let mut timings = Timings::default();
        if !changes.solve() && self.view.has_solve(&self.frame.mesh) {
            return self.see_again(timings);
        }
        let f = &self.frame;
        // Light and body; a new mesh's solver (one core's greedy contraction) is made beside.
        let make = self.subsurface.maker_if_missing(f);
        let t = Instant::now();
        let (irradiance, body) = (&mut self.irradiance, &mut self.body);
        let (solver, ()) = rayon::join(
            || make.map(|make| make()),
            || {
                irradiance.update(f, &changes);
                body.update(f, irradiance.caster(), &changes);
            },
        );
        self.subsurface.keep(solver);
        timings.irradiance_ms = ms_since(t);
        let (irradiance, e, body) = (&self.irradiance, self.irradiance.faces(), &self.body);
        let carried = irradiance.carried(e);
        let (mut face_b, links) =
            self.subsurface.solve(f, body, &carried, &changes, f.oracle(), &mut timings);
        let t = Instant::now();
        // Light that crossed the body, and what of `B` it is (the transmitted exit lobe's share).
        let mut sent = Vec::new();
        body.add_transmission(&mut face_b, &mut sent, &carried);
        irradiance.add_local(f, &mut face_b, e);
        let t_bounces = Instant::now();
        self.bounces.add(f, &changes, irradiance, &mut self.subsurface, body, (&mut face_b, &mut sent));
        timings.bounces_ms = ms_since(t_bounces);
        self.view.keep_solve(f, &face_b, sent);
        timings.push_ms += ms_since(t) - timings.bounces_ms;
        let t = Instant::now();
        let (vertex_radiance, vertex_single) = self.view.seen(f, irradiance, &self.body);
        timings.single_scattering_ms = ms_since(t);
        let exit_lobe = f.profile.exit_lobe.clone();
        self.last = Solved { face_b, vertex_radiance, vertex_single, exit_lobe, timings, links, fresh: true };
        &self.last
    }

    /// The changes the next solve must follow, or `None` where it has nothing to compute: nothing
    /// changed (the last result stands, marked not fresh) or HTSM is chosen (no per-face solve:
    /// an empty result; the changes wait for a CPU method).
    fn take_changes(&mut self) -> Option<Changes> {
        if !self.changes.any() {
            self.last.fresh = false;
            self.last.timings = Timings::default();
            return None;
        }
        let changes = std::mem::take(&mut self.changes).union(std::mem::take(&mut self.unsolved));
        if self.frame.settings.method == Method::Htsm {
            self.unsolved = changes;
            self.last = Solved { fresh: true, ..Solved::default() };
            return None;
        }
        Some(changes)
    }

    /// Only the eye moved: the last solve's `B / (c π)` stands, seen along new view rays (HTSM
    /// leaves none, but leaving HTSM is a method change, which solves).
    fn see_again(&mut self, mut timings: Timings) -> &Solved {
        let t = Instant::now();
        let seen = self.view.seen(&self.frame, &self.irradiance, &self.body);
        (self.last.vertex_radiance, self.last.vertex_single) = seen;
        timings.single_scattering_ms = ms_since(t);
        self.last.timings = timings;
        self.last.fresh = true;
        &self.last
    }
}

#[cfg(test)]
mod tests;
