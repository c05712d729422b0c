//! The GPU context: one wgpu device and queue, on an adapter that exists.
//!
//! lucent must run on machines with no GPU (CI, servers), so the adapter search is explicit and
//! ordered: the backends named in `WGPU_BACKEND` when it is set (wgpu's own variable, e.g.
//! `vulkan`, `gl`, `vulkan,gl`), otherwise Vulkan, Metal, DX12 and then GL, each first with a
//! hardware adapter and then with `force_fallback_adapter`. On Linux without a GPU this finds
//! Mesa's lavapipe (Vulkan, package `mesa-vulkan-drivers`) or llvmpipe (GL through EGL).
//! Rendering is headless: no surface is needed. The viewer, which owns a surface, builds its own
//! device and wraps it with [`GpuContext::from_device`].
//!
//! Formats used throughout lucent are ones both lavapipe and GL support as render targets:
//! [`HDR_FORMAT`], [`LDR_FORMAT`] and [`DEPTH_FORMAT`].

use std::sync::{Arc, Mutex};

/// High-dynamic-range render targets (radiance before tone mapping). `Rgba16Float` is
/// renderable, blendable, multisampled and filterable on every backend, unlike `Rgba32Float`.
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The final 8-bit image. Not an sRGB format: the tone-map pass applies its own display curve
/// (the paper's gamma curve), so the stored bytes are exactly what the shader wrote.
pub const LDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Depth buffers (reverse-Z is not used: depth 0 is the near plane).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// What can go wrong on the GPU side. Every message says what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No backend gave an adapter (or none gave a usable device).
    #[error(
        "no usable GPU adapter (tried {tried}); on Linux without a GPU install Mesa's software \
         drivers: `apt-get install mesa-vulkan-drivers` (lavapipe, Vulkan) or libegl1 with \
         libgl1-mesa-dri (llvmpipe, GL), or choose a backend with WGPU_BACKEND=vulkan|gl"
    )]
    NoAdapter {
        /// Each attempt, e.g. `Vulkan: no adapter; GL (fallback): device request failed: ...`.
        tried: String,
    },
    /// `WGPU_BACKEND` named no backend this build supports.
    #[error("WGPU_BACKEND={value:?} names no backend this build supports (use vulkan, gl, metal or dx12)")]
    BadBackendEnv {
        /// The variable's value.
        value: String,
    },
    /// The caller asked for something the device cannot do (size 0, over the limits, ...).
    #[error("{0}")]
    InvalidInput(String),
    /// wgpu reported a validation or out-of-memory error for an operation of lucent's.
    #[error("GPU error during {during}: {message}")]
    Device {
        /// What lucent was doing.
        during: String,
        /// wgpu's message.
        message: String,
    },
    /// Mapping a read-back buffer failed.
    #[error("GPU read-back failed: {0}")]
    Readback(String),
}

/// A wgpu device and queue with the adapter's description.
///
/// Cheap to share by reference; `wgpu::Device` and `wgpu::Queue` are themselves reference
/// counted, so cloning them out of the context is fine too.
pub struct GpuContext {
    /// The logical device: creates every resource.
    pub device: wgpu::Device,
    /// The queue that submissions and buffer writes go to.
    pub queue: wgpu::Queue,
    /// Name, backend, driver of the adapter in use (for logs and reports).
    pub adapter_info: wgpu::AdapterInfo,
    /// The adapter when this context chose it ([`GpuContext::new`]); `None` when it wraps a
    /// device made elsewhere ([`GpuContext::from_device`]).
    pub adapter: Option<wgpu::Adapter>,
    /// Kept alive with the adapter it produced.
    _instance: Option<wgpu::Instance>,
    /// Errors wgpu raised outside an error scope, collected instead of panicking (wgpu's default
    /// handler panics, and the CLI must never panic on a GPU error).
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.adapter_info.name)
            .field("backend", &self.adapter_info.backend)
            .finish_non_exhaustive()
    }
}

/// Backends tried in order when `WGPU_BACKEND` is unset. Those not compiled in for the
/// platform yield no adapter and cost nothing.
const DEFAULT_ORDER: [wgpu::Backends; 4] =
    [wgpu::Backends::VULKAN, wgpu::Backends::METAL, wgpu::Backends::DX12, wgpu::Backends::GL];

impl GpuContext {
    /// Finds an adapter (see the module docs for the order) and opens a device on it with the
    /// adapter's full limits and, where supported, `FLOAT32_FILTERABLE`.
    pub fn new() -> Result<GpuContext, GpuError> {
        Self::with_features(wgpu::Features::FLOAT32_FILTERABLE)
    }

    /// As [`GpuContext::new`], also enabling those of `optional_features` the adapter supports
    /// (check `device.features()` before relying on one).
    pub fn with_features(optional_features: wgpu::Features) -> Result<GpuContext, GpuError> {
        let from_env = wgpu::Backends::from_env();
        let order: Vec<wgpu::Backends> = match from_env {
            Some(b) if b.is_empty() => {
                return Err(GpuError::BadBackendEnv {
                    value: std::env::var("WGPU_BACKEND").unwrap_or_default(),
                });
            }
            Some(b) => vec![b],
            None => DEFAULT_ORDER.to_vec(),
        };
        let compiled = wgpu::Instance::enabled_backend_features();
        let mut tried = Vec::new();
        for backends in order {
            if !compiled.intersects(backends) {
                if from_env.is_some() {
                    tried.push(format!(
                        "{}: not built into this binary, which has {}",
                        backend_names(backends),
                        backend_names(compiled)
                    ));
                }
                continue;
            }
            let name = backend_names(backends);
            let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
                backends,
                flags: wgpu::InstanceFlags::from_build_config().with_env(),
                ..wgpu::InstanceDescriptor::new_without_display_handle()
            });
            for fallback in [false, true] {
                let label = if fallback { format!("{name} (fallback)") } else { name.clone() };
                let adapter =
                    match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                        power_preference: wgpu::PowerPreference::HighPerformance,
                        force_fallback_adapter: fallback,
                        compatible_surface: None,
                        ..Default::default()
                    })) {
                        Ok(a) => a,
                        Err(e) => {
                            tried.push(format!("{label}: no adapter ({e})"));
                            continue;
                        }
                    };
                match open_device(&adapter, optional_features) {
                    Ok((device, queue)) => {
                        let info = adapter.get_info();
                        log::info!(
                            "GPU adapter: {} ({:?}, {:?}, driver {} {})",
                            info.name,
                            info.backend,
                            info.device_type,
                            info.driver,
                            info.driver_info
                        );
                        let mut ctx = Self::from_device(device, queue, info);
                        ctx.adapter = Some(adapter);
                        ctx._instance = Some(instance);
                        return Ok(ctx);
                    }
                    Err(e) => tried.push(format!("{label}: device request failed ({e})")),
                }
            }
        }
        if tried.is_empty() {
            tried.push(format!("no backend of {} is built into this binary", backend_names(compiled)));
        }
        Err(GpuError::NoAdapter { tried: tried.join("; ") })
    }

    /// Wraps a device and queue created elsewhere (the viewer's, which must be compatible with
    /// its window surface). Installs lucent's uncaptured-error collector on the device.
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        adapter_info: wgpu::AdapterInfo,
    ) -> GpuContext {
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            log::error!("wgpu: {e}");
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        GpuContext { device, queue, adapter_info, adapter: None, _instance: None, uncaptured }
    }

    /// `"llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)"`: the adapter name and backend, for logs
    /// and summaries.
    pub fn describe(&self) -> String {
        format!("{} ({})", self.adapter_info.name, backend_names(self.adapter_info.backend.into()))
    }

    /// Returns (and clears) the errors wgpu raised outside error scopes since the last call, as
    /// a [`GpuError::Device`] naming `during`. Call after submitting lucent's work.
    pub fn check(&self, during: &str) -> Result<(), GpuError> {
        let mut v = self.uncaptured.lock().unwrap_or_else(|p| p.into_inner());
        if v.is_empty() {
            return Ok(());
        }
        let message = v.join("; ");
        v.clear();
        Err(GpuError::Device { during: during.to_string(), message })
    }

    /// Blocks until all submitted work is done, then reports any uncaptured error.
    pub fn wait(&self, during: &str) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device { during: during.to_string(), message: e.to_string() })?;
        self.check(during)
    }

    /// Checks that a `width` x `height` 2D target fits this device.
    pub fn check_size(&self, width: u32, height: u32) -> Result<(), GpuError> {
        let max = self.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(GpuError::InvalidInput(format!(
                "image size {width}x{height} is not supported: each side must be 1..={max} on {}",
                self.describe()
            )));
        }
        Ok(())
    }
}

fn open_device(
    adapter: &wgpu::Adapter,
    optional_features: wgpu::Features,
) -> Result<(wgpu::Device, wgpu::Queue), wgpu::RequestDeviceError> {
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("lucent"),
        required_features: optional_features & adapter.features(),
        // Everything the adapter offers: HTSM wants large 3D textures and storage buffers.
        required_limits: adapter.limits(),
        ..Default::default()
    }))
}

/// `"Vulkan"`, `"GL"`, `"Vulkan, GL"`.
fn backend_names(b: wgpu::Backends) -> String {
    let names: Vec<&str> = [
        (wgpu::Backends::VULKAN, "Vulkan"),
        (wgpu::Backends::METAL, "Metal"),
        (wgpu::Backends::DX12, "DX12"),
        (wgpu::Backends::GL, "GL"),
        (wgpu::Backends::BROWSER_WEBGPU, "WebGPU"),
        (wgpu::Backends::NOOP, "noop"),
    ]
    .iter()
    .filter(|(f, _)| b.contains(*f))
    .map(|(_, n)| *n)
    .collect();
    names.join(", ")
}
