//! The window's GPU side: an adapter that can present to the window's surface, the device, and
//! the surface configuration (a format and present mode the surface really offers), kept in
//! step with resizes and minimisation.

use anyhow::Context as _;
use lucent_gpu::GpuContext;
use std::sync::Arc;
use winit::window::Window;

/// Device, queue and the configured window surface.
pub struct Gfx {
    /// The window's surface (owns an `Arc` of the window, so it lives as long as needed).
    pub surface: wgpu::Surface<'static>,
    /// Device, queue and adapter description, shared with `lucent-gpu`'s passes.
    pub ctx: GpuContext,
    /// Current surface configuration; `width`/`height` are never 0.
    pub config: wgpu::SurfaceConfiguration,
    /// False while the window is minimised (size 0): nothing is drawn then.
    pub visible: bool,
}

/// Backends tried in order unless `WGPU_BACKEND` names some: Vulkan (lavapipe under Xvfb),
/// then GL (llvmpipe through EGL), then the native APIs of other platforms.
const BACKEND_ORDER: [wgpu::Backends; 4] =
    [wgpu::Backends::VULKAN, wgpu::Backends::GL, wgpu::Backends::METAL, wgpu::Backends::DX12];

impl Gfx {
    /// Opens a device that can present to `window`. `display` is the event loop's display
    /// handle (GL on Wayland needs it at instance creation). `low_latency` prefers a present
    /// mode that does not wait for vertical blank (for scripted runs).
    pub fn new(
        window: Arc<Window>,
        display: winit::event_loop::OwnedDisplayHandle,
        low_latency: bool,
    ) -> anyhow::Result<Gfx> {
        let order = match wgpu::Backends::from_env() {
            Some(b) => vec![b],
            None => BACKEND_ORDER.to_vec(),
        };
        let compiled = wgpu::Instance::enabled_backend_features();
        let mut tried = Vec::new();
        for backends in order.into_iter().filter(|b| compiled.intersects(*b)) {
            match Self::try_backends(backends, &window, display.clone(), low_latency) {
                Ok(gfx) => return Ok(gfx),
                Err(e) => tried.push(format!("{backends:?}: {e:#}")),
            }
        }
        anyhow::bail!(
            "no GPU adapter can present to the window (tried {}); without a GPU install Mesa \
             (`apt-get install mesa-vulkan-drivers`), or pick a backend with WGPU_BACKEND=vulkan|gl",
            tried.join("; ")
        )
    }

    fn try_backends(
        backends: wgpu::Backends,
        window: &Arc<Window>,
        display: winit::event_loop::OwnedDisplayHandle,
        low_latency: bool,
    ) -> anyhow::Result<Gfx> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            flags: wgpu::InstanceFlags::from_build_config().with_env(),
            ..wgpu::InstanceDescriptor::new_with_display_handle(Box::new(display))
        });
        let surface = instance.create_surface(window.clone()).context("creating the window surface")?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .context("no adapter for this surface")?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lucent viewer"),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        }))
        .context("opening the device")?;
        let caps = surface.get_capabilities(&adapter);
        let format = choose_format(&caps.formats).context("the surface offers no format")?;
        let present_mode = choose_present_mode(&caps.present_modes, low_latency);
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            desired_maximum_frame_latency: 2,
            present_mode,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
        };
        surface.configure(&device, &config);
        let adapter_info = adapter.get_info();
        log::info!(
            "viewer: {} ({:?}), surface {format:?}, {present_mode:?}",
            adapter_info.name,
            adapter_info.backend
        );
        Ok(Gfx {
            surface,
            ctx: GpuContext::from_device(device, queue, adapter_info),
            config,
            visible: size.width > 0 && size.height > 0,
        })
    }

    /// Follows a window resize; a zero size (minimised) stops drawing until the next resize.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.visible = width > 0 && height > 0;
        if self.visible && (width, height) != (self.config.width, self.config.height) {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.ctx.device, &self.config);
        }
    }

    /// The next surface texture, reconfiguring once if the surface is outdated or lost;
    /// `None` when this frame should be skipped (minimised, occluded, timeout).
    pub fn acquire(&mut self) -> Option<wgpu::SurfaceTexture> {
        if !self.visible {
            return None;
        }
        for _ in 0..2 {
            match self.surface.get_current_texture() {
                wgpu::CurrentSurfaceTexture::Success(t) => return Some(t),
                wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                    // Present this one; the next resize event reconfigures.
                    return Some(t);
                }
                wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                    self.surface.configure(&self.ctx.device, &self.config);
                }
                wgpu::CurrentSurfaceTexture::Timeout
                | wgpu::CurrentSurfaceTexture::Occluded
                | wgpu::CurrentSurfaceTexture::Validation => return None,
            }
        }
        None
    }
}

/// A gamma-space 8-bit format when offered (egui and our tone curve write display values),
/// else whatever comes first.
fn choose_format(formats: &[wgpu::TextureFormat]) -> Option<wgpu::TextureFormat> {
    use wgpu::TextureFormat::{Bgra8Unorm, Rgba8Unorm};
    formats
        .iter()
        .copied()
        .find(|f| matches!(f, Bgra8Unorm | Rgba8Unorm))
        .or_else(|| formats.first().copied())
}

/// Fifo (vsync, always supported) for interactive use; for scripted runs the first of
/// Immediate/Mailbox offered, so frames are not paced by a display that may not exist.
fn choose_present_mode(modes: &[wgpu::PresentMode], low_latency: bool) -> wgpu::PresentMode {
    use wgpu::PresentMode::{Fifo, Immediate, Mailbox};
    if low_latency && let Some(m) = [Immediate, Mailbox].into_iter().find(|m| modes.contains(m)) {
        return m;
    }
    Fifo
}
