//! The solve thread. The UI thread never waits on it: it sends requests over a channel and picks
//! up results when the worker wakes the event loop. Solve requests are coalesced: the worker
//! always drains its queue and solves only the newest state (Mertens §5.5 interactivity: a
//! stale solution is never worth finishing when a newer one is wanted).

use super::core_adapter::{Solution, SolverSession};
use super::state::SolveParams;
use lucent_core::mesh::Mesh;
use lucent_core::solver::Progress;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::thread::JoinHandle;

/// A request to the worker.
pub enum Request {
    /// Load the mesh and normalise it.
    Load(MeshOrigin),
    /// Solve `mesh` under `params`; `generation` identifies the state it was made from.
    Solve {
        /// Increasing number of the UI state this request was made from.
        generation: u64,
        /// The (deformed) mesh, shared with the UI thread.
        mesh: Arc<Mesh>,
        /// Material, lights, solver settings.
        params: SolveParams,
    },
}

/// Where the mesh comes from.
pub enum MeshOrigin {
    /// A mesh already loaded (by the resolved scene) and normalised, with its texture's entry
    /// factor per face (`lucent_core::mesh::texture`), if it has a texture.
    Loaded(Box<Mesh>, Option<Vec<lucent_core::Rgb>>),
}

/// A reply from the worker.
pub enum Reply {
    /// The loaded mesh, or why it could not be loaded.
    Loaded(Result<Mesh, String>),
    /// The solution for the state numbered `generation`.
    Solved {
        /// Generation of the request this solves.
        generation: u64,
        /// Per-vertex radiance and timings.
        solution: Solution,
    },
}

/// Handle to the worker thread. Dropping it closes the request channel: the thread ends after
/// the solve in progress, without being waited for (so closing the window is immediate).
pub struct Worker {
    requests: Sender<Request>,
    replies: Receiver<Reply>,
    progress: Arc<Progress>,
    _thread: JoinHandle<()>,
}

impl Worker {
    /// Starts the thread; `wake` is called after every reply (to wake the event loop).
    pub fn spawn(wake: impl Fn() + Send + 'static) -> Self {
        let (req_tx, req_rx) = channel();
        let (rep_tx, rep_rx) = channel();
        let progress = Arc::new(Progress::new());
        let session = SolverSession::with_progress(progress.clone());
        let thread = std::thread::Builder::new()
            .name("lucent-solve".into())
            .stack_size(crate::STACK_BYTES)
            .spawn(move || run(session, req_rx, rep_tx, wake))
            .expect("spawning the solve thread");
        Worker { requests: req_tx, replies: rep_rx, progress, _thread: thread }
    }

    /// The counter the solve in progress adds to (the panel's progress bar reads it).
    pub fn progress(&self) -> &Progress {
        &self.progress
    }

    /// Queues a request (never blocks).
    pub fn send(&self, request: Request) {
        // The thread only ends when this handle drops (or it panicked: then nothing more
        // will be solved, and the UI shows the last solution).
        let _ = self.requests.send(request);
    }

    /// The next reply, if one is ready (never blocks).
    pub fn try_recv(&self) -> Option<Reply> {
        self.replies.try_recv().ok()
    }
}

fn run(mut session: SolverSession, requests: Receiver<Request>, replies: Sender<Reply>, wake: impl Fn()) {
    while let Some(request) = next_coalesced(&requests) {
        let reply = match request {
            Request::Load(origin) => Reply::Loaded(load(origin, &mut session)),
            Request::Solve { generation, mesh, params } => {
                let solution = session.solve(&mesh, &params);
                let t = &solution.solved.timings;
                log::info!("solve {generation}: {} faces, {}", mesh.triangles.len(), t.line());
                Reply::Solved { generation, solution }
            }
        };
        if replies.send(reply).is_err() {
            return;
        }
        wake();
    }
}

/// Blocks for the next request, then drains the queue keeping the newest solve; a load is never
/// dropped (it is handled before any later solve).
fn next_coalesced(requests: &Receiver<Request>) -> Option<Request> {
    let mut next = requests.recv().ok()?;
    loop {
        if matches!(next, Request::Load(_)) {
            return Some(next);
        }
        match requests.try_recv() {
            Ok(newer) => next = newer,
            Err(TryRecvError::Empty) => return Some(next),
            Err(TryRecvError::Disconnected) => return None,
        }
    }
}

fn load(origin: MeshOrigin, session: &mut SolverSession) -> Result<Mesh, String> {
    let MeshOrigin::Loaded(mesh, entry) = origin;
    if mesh.triangles.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    session.set_entry_factors(entry.filter(|e| e.len() == mesh.triangles.len()));
    Ok(*mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::state::ViewState;
    use lucent_core::bssrdf::Material;

    /// Requests queued while the worker is busy collapse to the newest one.
    #[test]
    fn queued_solves_coalesce_to_the_newest() {
        let (tx, rx) = channel();
        let mesh = Arc::new(lucent_core::mesh::generate::icosphere(1));
        let params = ViewState::new(Material::by_name("marble").unwrap(), 0.05, Vec::new()).params;
        for generation in 1..=5 {
            tx.send(Request::Solve { generation, mesh: mesh.clone(), params: params.clone() }).unwrap();
        }
        match next_coalesced(&rx) {
            Some(Request::Solve { generation, .. }) => assert_eq!(generation, 5),
            _ => panic!("expected the newest solve"),
        }
        drop(tx);
        assert!(next_coalesced(&rx).is_none());
    }
}
