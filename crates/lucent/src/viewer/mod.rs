//! The interactive viewer (`lucent view`): Mertens et al. 2003 §5.5 ("Interactivity") and the
//! interactive results of figure 6: lighting, material, scale and geometry change while the
//! per-vertex solution is recomputed on a worker thread, and the window stays responsive.
//!
//! * [`app`]: the winit application and the per-frame sequence; [`present`]: one frame's GPU
//!   work (uploads, passes, submit, screenshot).
//! * [`gfx`]: adapter, device and window surface (format, present mode, resize, minimise).
//! * [`draw`]: the 3D view with `lucent-gpu`'s mesh and tone-map passes.
//! * [`ui`]: the egui side panel.
//! * [`framing`], [`input`], [`pick`]: what the orbit camera (`lucent_core::camera`) frames,
//!   mouse handling, ray picking through the mesh's BVH.
//! * [`state`], [`model`]: the editable state and the solve bookkeeping.
//! * [`worker`]: the solve thread (coalesced requests); [`htsm_tables`]: HTSM's table thread.
//! * [`core_adapter`]: the panel's state mapped onto `lucent-core`'s frame session.
//! * [`script`], [`screenshot`]: scripted runs and PNG screenshots.
//! * [`scene_file`]: start-up state from the resolved scene (flags and a TOML scene file).

pub mod app;
pub mod core_adapter;
pub mod draw;
pub mod framing;
pub mod gfx;
pub mod htsm;
pub mod htsm_tables;
pub mod input;
pub mod model;
pub mod pick;
pub mod present;
pub mod scene_file;
pub mod screenshot;
pub mod script;
pub mod state;
pub mod ui;
pub mod worker;
