//! One translucent body's state between frames: its frame session (Mertens §5.5, lucent-core's
//! `session`), the solve running on Bevy's async compute pool (its work on the plugin's
//! [`crate::SolvePool`]), and what the session was last given, so that only a real change
//! starts a solve.

use crate::convert::Weld;
use crate::lights::MappedLight;
use bevy::asset::AssetId;
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task};
use lucent_core::irradiance::SceneLight;
use lucent_core::session::{FrameSession, FrameSettings, Solved, Transport};
use std::time::Instant;

/// What one solve is asked: the session's inputs in the body's local (mesh) frame, and the
/// world lights the highlight draws with it.
#[derive(Clone, Debug, PartialEq)]
pub struct Inputs {
    /// lucent's (welded) vertex positions, mesh units.
    pub positions: Vec<glam::Vec3>,
    /// The lights in the mesh frame.
    pub lights: Vec<SceneLight>,
    /// The same lights in the world, for the highlight.
    pub world_lights: Vec<MappedLight>,
    /// Material, model scale and profile.
    pub transport: Transport,
    /// Method, mode and bounces.
    pub settings: FrameSettings,
    /// The camera in the mesh frame (view-ray single scattering and the chord follow it).
    pub eye: Option<glam::Vec3>,
}

/// What a finished solve hands back to the main thread.
pub struct Finished {
    /// The session, to be given the next change.
    pub session: FrameSession,
    /// Its result.
    pub solved: Solved,
    /// What it solved.
    pub inputs: Inputs,
    /// Wall-clock time of the solve on the pool, milliseconds.
    pub ms: f32,
    /// When it finished.
    pub done: Instant,
}

/// A body's solve state (the plugin adds it next to [`crate::Translucent`]).
#[derive(Component)]
pub struct LucentBody {
    /// The mesh asset the session was made from.
    pub(crate) mesh: AssetId<Mesh>,
    /// Bevy vertices to lucent's and back.
    pub(crate) weld: Weld,
    /// The session while no solve runs (a running solve owns it).
    pub(crate) session: Option<FrameSession>,
    /// The welded mesh, until the first solve makes the session from it on the solve pool (a new
    /// session's profile tables would stall the frame).
    pub(crate) rest: Option<lucent_core::mesh::Mesh>,
    /// The running solve.
    pub(crate) task: Option<Task<Finished>>,
    /// What the session was last given (a solve runs only when this differs).
    pub(crate) sent: Option<Inputs>,
    /// The model scale in metres, fixed at the first solve.
    pub(crate) scale_m: f32,
    /// The [`crate::Translucent`] the transport was last made from, and that transport.
    pub(crate) transport: Option<(crate::Translucent, Transport)>,
    /// The material showing this body.
    pub(crate) material: Handle<crate::LucentMaterial>,
    /// The material's per-vertex buffer.
    pub(crate) buffer: Handle<bevy::render::storage::ShaderBuffer>,
}

/// What the plugin reports about a body's solves (read it; the plugin writes it).
#[derive(Component, Clone, Debug, Default)]
pub struct SolveStatus {
    /// Solves finished and shown since the body appeared.
    pub solves: u64,
    /// Wall-clock time of the last finished solve (off the frame, on the solve pool), milliseconds.
    pub last_ms: f32,
    /// Whether a solve is running now (the last result is shown meanwhile).
    pub solving: bool,
    /// When the last shown solve finished on the pool (`None` before the first). The plugin
    /// shows it in the first frame whose `PostUpdate` runs after this instant.
    pub last_done: Option<Instant>,
    /// Why the body cannot be solved, if it cannot (the mesh or the material); logged once.
    pub error: Option<String>,
}

impl LucentBody {
    /// Gives the session `inputs` (only what changed) and starts its solve on the async compute
    /// pool, its work on `pool` (the first solve makes the session). Does nothing while a solve
    /// runs.
    pub(crate) fn start(&mut self, inputs: Inputs, pool: &crate::SolvePool) {
        let session = match (self.session.take(), self.rest.take()) {
            (Some(session), _) => Ok(session),
            (None, Some(mesh)) => Err(mesh),
            (None, None) => return,
        };
        let old = self.sent.as_ref();
        let moved = old.is_none_or(|o| o.positions != inputs.positions);
        let relit = old.is_none_or(|o| o.lights != inputs.lights);
        self.sent = Some(inputs.clone());
        let pool = pool.pool();
        // Everything the session does with the change happens on the pool, not in the frame: a
        // new material's profile tables take long enough to stall it.
        self.task = Some(AsyncComputeTaskPool::get().spawn(async move {
            let started = Instant::now();
            // The async compute thread waits; the session's work runs on the pool's threads.
            let (session, solved) = pool.install(|| {
                let mut session = session.unwrap_or_else(|mesh| {
                    FrameSession::new(mesh, None, inputs.transport.clone(), inputs.settings)
                });
                if moved {
                    session.set_positions(&inputs.positions);
                }
                if relit {
                    session.set_lights(inputs.lights.clone());
                }
                session.set_transport(inputs.transport.clone());
                session.set_settings(inputs.settings);
                session.set_eye(inputs.eye);
                let solved = session.solve().clone();
                (session, solved)
            });
            let done = Instant::now();
            Finished { session, solved, inputs, ms: (done - started).as_secs_f32() * 1e3, done }
        }));
    }
}
