//! The viewer's model side, independent of the window: the mesh (undeformed and deformed), the
//! editable state, and the bookkeeping that keeps the worker solving the latest state.
//!
//! Generations: every state sent to the worker gets a new number. The image is *settled* when
//! the newest solution received is for the newest state sent and has been drawn.

use super::core_adapter::{self, Solution};
use super::state::{Deformations, SolveParams, ViewState};
use super::worker::{Reply, Request, Worker};
use crate::progress::{StageClock, StageView};
use lucent_core::mesh::Mesh;
use std::sync::Arc;
use std::time::Instant;

/// Mesh, state and solve bookkeeping.
pub struct ViewModel {
    /// The state the UI edits.
    pub state: ViewState,
    /// The loaded, normalised, undeformed mesh (`None` while loading).
    pub base: Option<Arc<Mesh>>,
    /// `base` with `state.deform` applied (what is drawn and solved).
    pub mesh: Option<Arc<Mesh>>,
    /// Why the mesh could not be loaded.
    pub load_error: Option<String>,
    /// The latest solution received.
    pub solution: Solution,
    /// True when `mesh` changed since the renderer last uploaded it.
    pub geometry_dirty: bool,
    /// True when `solution` changed since the renderer last uploaded it.
    pub radiance_dirty: bool,
    deform_of_mesh: Option<Deformations>,
    sent: Option<SolveParams>,
    sent_generation: u64,
    received_generation: u64,
    drawn_generation: u64,
    solve_started: Instant,
    stages: StageClock,
}

impl ViewModel {
    /// A scene that starts with `state` and no mesh yet.
    pub fn new(state: ViewState) -> Self {
        ViewModel {
            state,
            base: None,
            mesh: None,
            load_error: None,
            solution: Solution::default(),
            geometry_dirty: false,
            radiance_dirty: false,
            deform_of_mesh: None,
            sent: None,
            sent_generation: 0,
            received_generation: 0,
            drawn_generation: 0,
            solve_started: Instant::now(),
            stages: StageClock::default(),
        }
    }

    /// Takes the worker's replies; returns true if anything arrived.
    pub fn receive(&mut self, worker: &Worker) -> bool {
        self.stages.observe(worker.progress());
        let mut any = false;
        while let Some(reply) = worker.try_recv() {
            any = true;
            match reply {
                Reply::Loaded(Ok(mesh)) => {
                    self.base = Some(Arc::new(mesh));
                    self.deform_of_mesh = None;
                }
                Reply::Loaded(Err(e)) => self.load_error = Some(e),
                Reply::Solved { generation, solution } => {
                    // Replies arrive in order; an older one is still better than nothing.
                    self.received_generation = generation;
                    self.solution = solution;
                    self.radiance_dirty = true;
                }
            }
        }
        any
    }

    /// Rebuilds the deformed mesh if the deformations changed, and sends the worker a solve
    /// when the mesh or the parameters changed. Cheap when nothing changed.
    pub fn sync(&mut self, worker: &Worker) {
        let Some(base) = &self.base else { return };
        let st = &mut self.state;
        st.params.cluster_face = if st.show_clusters { st.picked_face } else { None };
        let mut changed = false;
        if self.deform_of_mesh.as_ref() != Some(&self.state.deform) {
            let mesh = if self.state.deform.is_identity() {
                base.clone()
            } else {
                Arc::new(core_adapter::deform(base, &self.state.deform))
            };
            self.mesh = Some(mesh);
            self.deform_of_mesh = Some(self.state.deform.clone());
            self.geometry_dirty = true;
            changed = true;
        }
        if self.sent.as_ref() != Some(&self.state.params) {
            changed = true;
        }
        if changed {
            self.sent_generation += 1;
            self.sent = Some(self.state.params.clone());
            if self.received_generation + 1 == self.sent_generation {
                // The worker was idle: a new solve starts now.
                self.solve_started = Instant::now();
            }
            worker.send(Request::Solve {
                generation: self.sent_generation,
                mesh: self.mesh.clone().expect("set above or earlier"),
                params: self.state.params.clone(),
            });
        }
    }

    /// Records that a frame showing the latest received solution was drawn.
    pub fn mark_drawn(&mut self) {
        self.drawn_generation = self.received_generation;
    }

    /// True while the worker owes a solution for the newest state.
    pub fn solving(&self) -> bool {
        self.received_generation < self.sent_generation
    }

    /// Seconds since the oldest outstanding solve was requested (0 when idle).
    pub fn solving_for_s(&self) -> f64 {
        if self.solving() { self.solve_started.elapsed().as_secs_f64() } else { 0.0 }
    }

    /// The stage of the solve in progress (link, on-the-fly, exact) once it has run a second.
    pub fn solve_progress(&self) -> Option<StageView> {
        self.solving().then(|| self.stages.shown()).flatten()
    }

    /// True when the image on screen is the solution of the current state.
    pub fn settled(&self) -> bool {
        self.mesh.is_some()
            && self.sent_generation > 0
            && !self.solving()
            && self.drawn_generation == self.sent_generation
            && self.deform_of_mesh.as_ref() == Some(&self.state.deform)
            && self.sent.as_ref() == Some(&self.state.params)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::worker::MeshOrigin;
    use lucent_core::bssrdf::Material;
    use std::time::Duration;

    /// Polls `scene` until `done` holds (the worker runs on its own thread).
    fn wait_for(scene: &mut ViewModel, worker: &Worker, done: impl Fn(&ViewModel) -> bool) {
        let start = Instant::now();
        while !done(scene) {
            assert!(start.elapsed() < Duration::from_secs(120), "the worker did not reply");
            scene.receive(worker);
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// The image is settled only once the solution for the newest state is drawn, and any edit
    /// unsettles it until the worker delivers again.
    #[test]
    fn settles_after_the_latest_state_is_solved_and_drawn() {
        let worker = Worker::spawn(|| {});
        let lights = vec![crate::viewer::ui::point_light(glam::Vec3::new(1.0, 1.1, 1.8))];
        let mut scene = ViewModel::new(ViewState::new(Material::by_name("marble").unwrap(), 0.05, lights));
        // No bounces: their rays would be the last stage counted, after the link.
        scene.state.params.settings.bounces = 0;
        let bunny = crate::viewer::core_adapter::normalise(lucent_core::mesh::embedded::bunny());
        worker.send(Request::Load(MeshOrigin::Loaded(Box::new(bunny), None)));
        wait_for(&mut scene, &worker, |s| s.base.is_some());
        scene.sync(&worker);
        assert!(scene.solving() && !scene.settled());
        wait_for(&mut scene, &worker, |s| !s.solving());
        let n = scene.mesh.as_ref().unwrap().positions.len();
        assert_eq!(scene.solution.solved.vertex_radiance.len(), n);
        // The first solve links every face, counted where the panel's progress bar reads it.
        let (stage, done, total) = worker.progress().snapshot();
        assert_eq!((stage, done), ("link", total), "the link stage counted to its end");
        assert_eq!(total, scene.mesh.as_ref().unwrap().triangles.len());
        assert_eq!(scene.solve_progress(), None, "nothing shown once solved");
        assert!(!scene.settled(), "not drawn yet");
        scene.mark_drawn();
        assert!(scene.settled());

        // Two quick edits: only the newest needs to arrive for the image to settle.
        let p = scene.state.params.lights[0].position().unwrap();
        scene.state.params.lights[0].set_position(p + glam::Vec3::X * 0.5);
        scene.sync(&worker);
        scene.state.deform.twist_degrees = 60.0;
        scene.sync(&worker);
        assert!(!scene.settled());
        wait_for(&mut scene, &worker, |s| !s.solving());
        scene.mark_drawn();
        assert!(scene.settled());
    }
}
