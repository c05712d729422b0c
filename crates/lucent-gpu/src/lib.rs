//! # lucent-gpu
//!
//! Everything lucent does on the GPU, through wgpu: choosing an adapter that exists (Vulkan,
//! else GL; `WGPU_BACKEND` honoured), the per-vertex radiance raster with tone mapping, and
//! read-back of offscreen images.
