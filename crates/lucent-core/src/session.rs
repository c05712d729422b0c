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

mod ablate;
mod body;
mod bounces;
mod irradiance;
mod local_limit;
mod subsurface;
mod timings;
mod transport;
mod view;
pub use crate::shading::view_basis::ViewTerms;
pub use ablate::Ablations;
pub use timings::Timings;
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
    /// Links stored and kept after a deformation or material change: the changed links'
    /// coefficients are re-evaluated at the new pose and material, and the oracle decides a
    /// sample of receivers again (all of them where the sample's error exceeds its tolerance),
    /// refining only where it opens a link
    /// ([`crate::solver::HierarchicalSolver::update_refit_with`]).
    Refit,
    /// No stored links: refine from the root and gather while traversing, every solve. Default
    /// for single images (nothing to reuse).
    #[default]
    OnTheFly,
}

impl SolveMode {
    /// Every mode, in the order the CLI and the viewer list them.
    pub const ALL: [SolveMode; 4] =
        [SolveMode::Render, SolveMode::Incremental, SolveMode::Refit, SolveMode::OnTheFly];

    /// The name the CLI and the viewer use.
    pub fn name(self) -> &'static str {
        match self {
            SolveMode::Render => "render",
            SolveMode::Incremental => "incremental",
            SolveMode::Refit => "refit",
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
    /// Corrections left out, for measuring each (none by default: `lucent render --ablate`,
    /// docs/corrections.md).
    pub ablate: Ablations,
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
    /// Whether the mesh pass blends `vertex_single` linearly across a face rather than
    /// geometrically: only under the ablation [`Ablations::single_blend`].
    pub linear_single: bool,
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
        let profile = settings.ablate.applied(transport.profile_at(rest_extent));
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
            self.frame.profile =
                self.frame.settings.ablate.applied(transport.profile_at(self.frame.rest_extent));
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
        let view_only = Ablations {
            light_paths: settings.ablate.light_paths,
            view_exp: settings.ablate.view_exp,
            ..s.ablate
        } == settings.ablate;
        if s.ablate != settings.ablate && view_only {
            // Only how the view terms trace their light paths or take their exponentials.
            self.changes.view = true;
        } else if s.ablate != settings.ablate {
            // The entry term is the profile's, and the gain's terms the body's.
            self.frame.profile =
                settings.ablate.applied(self.frame.transport.profile_at(self.frame.rest_extent));
            self.changes.transport = true;
        }
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

    /// How the view terms (chord factor, view-ray single scattering) are evaluated: traced per
    /// eye (the reference, default) or split so that an eye-only change traces no ray
    /// ([`crate::shading::view_basis`]).
    pub fn set_view_terms(&mut self, terms: ViewTerms) {
        self.changes.view |= self.view.set_terms(terms);
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
        let started = Instant::now();
        if !changes.solve() && self.view.has_solve(&self.frame.mesh) {
            self.see_again(Timings::default());
        } else {
            self.solve_changes(changes);
        }
        let t = &mut self.last.timings;
        t.other_ms = (ms_since(started) - t.cpu_ms()).max(0.0);
        &self.last
    }

    /// [`FrameSession::solve`] after `changes` that the per-face solve depends on.
    fn solve_changes(&mut self, changes: Changes) {
        let mut timings = Timings::default();
        let f = &self.frame;
        // Light and body; a new mesh's solver (one core's greedy contraction) is made beside.
        let make = self.subsurface.maker_if_missing(f);
        let t = Instant::now();
        let (irradiance, body) = (&mut self.irradiance, &mut self.body);
        let (solver, body_ms) = rayon::join(
            || make.map(|make| make()),
            || {
                irradiance.update(f, &changes);
                let t = Instant::now();
                body.update(f, irradiance.caster(), &changes);
                ms_since(t)
            },
        );
        self.subsurface.keep(solver);
        timings.body_ms = body_ms;
        timings.irradiance_ms = ms_since(t) - body_ms;
        let (irradiance, e, body) = (&self.irradiance, self.irradiance.faces(), &self.body);
        let carried = irradiance.carried(e);
        let (mut face_b, links) =
            self.subsurface.solve(f, body, &carried, &changes, f.oracle(), &mut timings);
        let t = Instant::now();
        // Light that crossed the body, and what of `B` it is (the transmitted exit lobe's share).
        let mut sent = Vec::new();
        body.add_transmission(&mut face_b, &mut sent, &carried, e);
        let tilts = if sent.is_empty() { Vec::new() } else { body.tilts(f, &carried, e) };
        irradiance.add_local(f, &mut face_b, e);
        let t_bounces = Instant::now();
        self.bounces.add(f, &changes, irradiance, &mut self.subsurface, body, (&mut face_b, &mut sent));
        timings.bounces_ms = ms_since(t_bounces);
        let t_local = Instant::now();
        let local_change = local_limit::vertex_change(f, irradiance, self.subsurface.solver());
        let local_ms = ms_since(t_local);
        timings.irradiance_ms += local_ms;
        self.view.keep_solve(f, &face_b, sent, tilts, local_change.as_deref());
        timings.push_ms += ms_since(t) - timings.bounces_ms - local_ms;
        let t = Instant::now();
        let (vertex_radiance, vertex_single) = self.view.seen(f, irradiance, &self.body, None);
        timings.single_scattering_ms = ms_since(t);
        let exit_lobe = if f.settings.ablate.exit_lobe {
            crate::bssrdf::ExitLobe::flat()
        } else {
            f.profile.exit_lobe.clone()
        };
        let linear_single = f.settings.ablate.single_blend;
        self.last = Solved {
            face_b,
            vertex_radiance,
            vertex_single,
            exit_lobe,
            linear_single,
            timings,
            links,
            fresh: true,
        };
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
    fn see_again(&mut self, mut timings: Timings) {
        let t = Instant::now();
        // The last image's buffers, which the split's camera move overwrites.
        let last = &mut self.last;
        let buffers = (std::mem::take(&mut last.vertex_radiance), std::mem::take(&mut last.vertex_single));
        let seen = self.view.seen(&self.frame, &self.irradiance, &self.body, Some(buffers));
        (self.last.vertex_radiance, self.last.vertex_single) = seen;
        timings.single_scattering_ms = ms_since(t);
        self.last.timings = timings;
        self.last.fresh = true;
    }
}

#[cfg(test)]
mod tests;
