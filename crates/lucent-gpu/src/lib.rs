//! # lucent-gpu
//!
//! Everything lucent does on the GPU, through wgpu: choosing an adapter that exists (Vulkan,
//! else GL; `WGPU_BACKEND` honoured), the per-vertex radiance raster with tone mapping, and
//! read-back of offscreen images.
//!
//! * [`context`]: [`GpuContext`] (device, queue, adapter) and the shared texture formats.
//! * [`readback`]: textures and buffers back to the CPU (row padding handled).

pub mod context;
pub mod readback;

pub use context::{DEPTH_FORMAT, GpuContext, GpuError, HDR_FORMAT, LDR_FORMAT};
