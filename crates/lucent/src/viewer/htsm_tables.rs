//! The HTSM diffusion model's tables (`lucent_gpu::htsm::diffusion`: the half-space's albedo and
//! the slab's transmittance over nine densities, exact transport, up to seconds for a new
//! medium) made on a thread of their own, so that a slider drag over the medium never blocks a
//! frame. Requests are coalesced as the solve worker's are ([`super::worker`]): the thread
//! always makes the newest medium's tables, never a stale one's. Until they arrive the panel
//! draws with the last tables made (the kernel's shape and attenuation follow the new medium at
//! once; only the kernel's totals lag), then draws again.

use lucent_gpu::htsm::diffusion::{DiffusionKey, DiffusionUniforms};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;

/// Tables made by the thread, with the key they were made for.
pub type Tables = (DiffusionKey, Box<DiffusionUniforms>);

/// The table thread (started at the first request) and the newest tables it made.
#[derive(Default)]
pub struct TableBuilder {
    thread: Option<Channels>,
    /// The key last asked for and not yet made.
    pending: Option<DiffusionKey>,
    /// The newest tables made.
    ready: Option<Tables>,
}

struct Channels {
    requests: Sender<DiffusionKey>,
    replies: Receiver<Tables>,
    _handle: JoinHandle<()>,
}

impl TableBuilder {
    /// The newest tables made, after taking the thread's replies; asks for `key`'s when these
    /// are not `key`'s (once per key). Never waits.
    pub fn get(&mut self, key: DiffusionKey) -> Option<&Tables> {
        self.take_replies();
        let made = self.ready.as_ref().is_some_and(|(k, _)| *k == key);
        if !made && self.pending != Some(key) {
            self.pending = Some(key);
            let c = self.thread.get_or_insert_with(spawn);
            // A send fails only when the thread panicked; the next request starts another.
            if c.requests.send(key).is_err() {
                self.thread = None;
                self.pending = None;
            }
        }
        self.ready.as_ref()
    }

    /// Whether tables were asked for and not made yet (the caller draws again when they come).
    pub fn building(&mut self) -> bool {
        self.take_replies();
        self.pending.is_some()
    }

    /// Takes the thread's replies: the newest becomes `ready`.
    fn take_replies(&mut self) {
        if let Some(c) = &self.thread {
            while let Ok(tables) = c.replies.try_recv() {
                if self.pending == Some(tables.0) {
                    self.pending = None;
                }
                self.ready = Some(tables);
            }
        }
    }
}

/// Starts the thread: it makes the newest key's tables of those queued, and ends when the
/// [`TableBuilder`] (its request sender) is dropped.
fn spawn() -> Channels {
    let (requests, inbox) = channel::<DiffusionKey>();
    let (outbox, replies) = channel();
    let _handle = std::thread::Builder::new()
        .name("htsm tables".into())
        .spawn(move || {
            while let Ok(mut key) = inbox.recv() {
                while let Ok(newer) = inbox.try_recv() {
                    key = newer;
                }
                if outbox.send((key, Box::new(DiffusionUniforms::new(&key)))).is_err() {
                    return;
                }
            }
        })
        .expect("spawning the HTSM table thread");
    Channels { requests, replies, _handle }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use lucent_gpu::htsm::medium::HtsmCoefficients;
    use std::time::{Duration, Instant};

    fn key(sigma_a: f32) -> DiffusionKey {
        DiffusionKey {
            coefficients: HtsmCoefficients {
                sigma_a: Vec3::splat(sigma_a),
                sigma_s_prime: Vec3::new(35.0, 61.0, 95.0),
                density_sigma_a: Vec3::splat(25.0),
            },
            eta: 1.0,
            kernel_radius: 0.04,
            samples: 9,
        }
    }

    /// Polls until the builder holds `k`'s tables (the thread's work takes under a minute).
    fn wait_for(b: &mut TableBuilder, k: DiffusionKey) -> Tables {
        let start = Instant::now();
        loop {
            if let Some((made, u)) = b.get(k)
                && *made == k
            {
                return (*made, u.clone());
            }
            assert!(start.elapsed() < Duration::from_secs(120), "no tables for the key");
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    #[test]
    fn tables_are_made_on_another_thread_and_are_the_same_tables() {
        let mut b = TableBuilder::default();
        let k = key(0.07);
        // The first request returns at once with nothing: the tables are not made on this
        // thread (made here, they would be returned now).
        assert!(b.get(k).is_none());
        assert!(b.building());
        let (made, u) = wait_for(&mut b, k);
        assert!(!b.building());
        assert_eq!(made, k);
        assert!(*u == DiffusionUniforms::new(&k), "the thread's tables are DiffusionUniforms::new's");
    }

    #[test]
    fn a_new_medium_keeps_the_last_tables_until_its_own_come() {
        let mut b = TableBuilder::default();
        let (first, second) = (key(0.07), key(0.5));
        wait_for(&mut b, first);
        // Asking for another medium hands back the first's tables meanwhile, never nothing.
        let meanwhile = b.get(second).expect("the last tables").0;
        assert!(meanwhile == first || meanwhile == second);
        let (made, u) = wait_for(&mut b, second);
        assert_eq!(made, second);
        assert!(*u == DiffusionUniforms::new(&second));
    }
}
