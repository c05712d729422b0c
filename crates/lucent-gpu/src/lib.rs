//! # lucent-gpu
//!
//! Everything lucent does on the GPU, through wgpu: choosing an adapter that exists (Vulkan,
//! else GL; `WGPU_BACKEND` honoured), the per-vertex radiance raster with tone mapping
//! (Mertens 2003 §5.4), and read-back of offscreen images.
//!
//! * [`context`]: [`GpuContext`] (device, queue, adapter) and the shared texture formats.
//! * [`readback`]: textures and buffers back to the CPU (row padding handled).
//! * [`mesh_pass`]: per-vertex `B / pi` times the per-pixel exit Fresnel factor, highlights and
//!   the environment-reflection hook, into an HDR target, seen through a
//!   `lucent_core::camera::CameraView`.
//! * [`surface_maps`]: the environment and albedo maps the mesh pass samples.
//! * [`tonemap`]: exposure, gamma curve or ACES fit, background.
//! * [`offscreen`]: the two passes into offscreen targets and read-back to an image.
//! * [`htsm`]: Heterogeneous Translucent Shadow Maps (Shopf 2007).
//! * [`test_support`]: tests that skip with a note where no adapter exists (and fail under CI).

pub mod context;
pub mod htsm;
pub mod mesh_pass;
pub mod offscreen;
pub mod readback;
pub mod surface_maps;
pub mod test_support;
pub mod tonemap;

pub use context::{DEPTH_FORMAT, GpuContext, GpuError, HDR_FORMAT, LDR_FORMAT};
