//! The subsurface transport of a [`super::FrameSession`] (Mertens §3.2, §5): irradiance per face
//! to radiosity `B` per face, by the hierarchical solver (its hierarchy and links kept across
//! frames as the solve mode says, §5.5) or by the exact O(N²) sum.

use super::body::Body;
use super::{Changes, Frame, Method, SolveMode, Timings};
use crate::Rgb;
use crate::clock::ms_since;
use crate::formfactor::FormFactorOptions;
use crate::hierarchy::{Hierarchy, face_cluster};
use crate::mesh::Mesh;
use crate::solver::{self, HierarchicalSolver, Oracle, Progress};
use glam::Vec3;
use std::sync::Arc;
use std::time::Instant;

/// The rest pose and the hierarchical solver made on it.
pub(super) struct Subsurface {
    /// Vertex positions of the rest pose: the hierarchical solver links there first, so that
    /// a deformed pose is an incremental update.
    rest: Vec<Vec3>,
    /// The hierarchy a front end built (shrink-wrap), until the solver takes it.
    hierarchy: Option<Hierarchy>,
    /// The hierarchical solver with its hierarchy and links, once a hierarchical solve made it.
    solver: Option<HierarchicalSolver>,
}

impl Subsurface {
    /// The stage for a mesh whose rest pose is `rest`; `hierarchy`, when given, was built on it.
    pub(super) fn new(rest: Vec<Vec3>, hierarchy: Option<Hierarchy>) -> Self {
        Subsurface { rest, hierarchy, solver: None }
    }

    /// The hierarchical solver, once made.
    pub(super) fn solver(&self) -> Option<&HierarchicalSolver> {
        self.solver.as_ref()
    }

    /// Counts the solver's progress on `progress` (`None` stops).
    pub(super) fn set_progress(&mut self, progress: Option<Arc<Progress>>) {
        if let Some(s) = &mut self.solver {
            s.progress = progress;
        }
    }

    /// What makes the hierarchical solver, where the method is hierarchical and it is not made
    /// yet: to run on any thread (its hierarchy's build is one core's greedy contraction, which
    /// the session runs beside the irradiance). Give the result to [`Subsurface::keep`].
    pub(super) fn maker_if_missing(
        &mut self,
        f: &Frame,
    ) -> Option<impl FnOnce() -> HierarchicalSolver + Send + use<>> {
        (f.settings.method == Method::Hierarchical && self.solver.is_none()).then(|| self.maker(f))
    }

    /// Keeps a solver that [`Subsurface::maker_if_missing`]'s maker made.
    pub(super) fn keep(&mut self, solver: Option<HierarchicalSolver>) {
        if solver.is_some() {
            self.solver = solver;
        }
    }

    /// What makes the hierarchical solver on the rest pose (building the hierarchy unless a
    /// front end gave one), with the session's oracle.
    fn maker(&mut self, f: &Frame) -> impl FnOnce() -> HierarchicalSolver + Send + use<> {
        let rest = Mesh::new(self.rest.clone(), f.mesh.triangles.clone());
        let given = self.hierarchy.take();
        let (profile, oracle, progress) = (f.profile.clone(), f.oracle(), f.progress.clone());
        move || {
            let h = given.unwrap_or_else(|| face_cluster::build(&rest));
            let mut s = HierarchicalSolver::new(rest, h, profile, oracle);
            s.ff_opts = FormFactorOptions::default();
            s.progress = progress;
            s
        }
    }

    /// `B` per face for irradiance `e` (times the finite-body gain per face of `body`, if any,
    /// under an energy bound that leaves room for its slab transmission term) by the settings'
    /// method, updating the hierarchical solver for `changes` first and linking with the
    /// thresholds `oracle`: `(B, links)`. Adds its stages' times to `timings`. The
    /// transmission term itself is added by the caller (`Body::add_transmission`).
    pub(super) fn solve(
        &mut self,
        f: &Frame,
        body: &Body,
        e: &[Rgb],
        changes: &Changes,
        oracle: Oracle,
        timings: &mut Timings,
    ) -> (Vec<Rgb>, Option<usize>) {
        if f.settings.method == Method::Exact {
            let t = Instant::now();
            let all: Vec<usize> = (0..f.mesh.triangles.len()).collect();
            let opts = FormFactorOptions::default();
            let p = f.progress.as_deref();
            let gain = body.face_gain().map(|g| g.as_slice());
            let term = body.face_term().map(|t| t.as_slice());
            let b =
                solver::exact::solve_receivers_with_gain(&f.mesh, &f.profile, e, &opts, &all, p, gain, term);
            timings.gather_ms += ms_since(t);
            return (b, None);
        }
        if self.solver.is_none() {
            self.solver = Some(self.maker(f)());
        }
        let s = self.solver.as_mut().expect("made above");
        s.set_face_gain(body.face_gain().cloned());
        s.set_face_term(body.face_term().cloned());
        hierarchical(s, f, e, changes, oracle, timings)
    }
}

/// `B` per face for irradiance `e` by the hierarchical solver `s` in the settings' mode:
/// relinked, updated or refined on the fly as the pose, the profile and the oracle changed.
fn hierarchical(
    s: &mut HierarchicalSolver,
    f: &Frame,
    e: &[Rgb],
    changes: &Changes,
    oracle: Oracle,
    timings: &mut Timings,
) -> (Vec<Rgb>, Option<usize>) {
    let (mode, mesh, profile) = (f.settings.mode, &f.mesh, &f.profile);
    let moved = s.mesh.positions != mesh.positions;
    let t = Instant::now();
    let profile_changed = s.profile != *profile;
    let oracle_changed = changes.oracle || s.oracle != oracle;
    let relink = moved || profile_changed || oracle_changed;
    s.oracle = oracle;
    // Only an incremental update reads the candidates.
    s.keep_candidates = !matches!(mode, SolveMode::Render | SolveMode::Refit);
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
        SolveMode::Refit => {
            if oracle_changed {
                if profile_changed {
                    s.set_profile(profile.clone());
                }
                s.link();
            }
            // A material change is refitted too (no links yet: linked there).
            let material = (s.profile != *profile).then(|| profile.clone());
            s.update_refit_with(&mesh.positions, material, solver::RefitOptions::default());
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
