//! One frame's GPU work in the viewer: the window's surface and what draws into it, the scene's
//! uploads, the 3D and egui passes recorded and submitted, and the screenshot (the same frame
//! drawn again offscreen).

use super::draw::{DrawParams, ViewDrawer, Viewport};
use super::gfx::Gfx;
use super::htsm::HtsmPanel;
use super::input::ViewportRect;
use super::model::ViewModel;
use super::screenshot::Offscreen;
use std::sync::Arc;
use winit::window::Window;

/// Window, GPU and egui state, created on `resumed`.
pub(super) struct Surface {
    pub(super) window: Arc<Window>,
    pub(super) gfx: Gfx,
    pub(super) egui_ctx: egui::Context,
    pub(super) egui_state: egui_winit::State,
    pub(super) egui_renderer: egui_wgpu::Renderer,
    pub(super) drawer: ViewDrawer,
    /// The HTSM image of the 3D view when that method is chosen.
    pub(super) htsm: HtsmPanel,
}

/// egui's tessellated output for one frame, with its textures uploaded.
pub(super) struct EguiFrame {
    jobs: Vec<egui::ClippedPrimitive>,
    screen: egui_wgpu::ScreenDescriptor,
    free: Vec<egui::TextureId>,
}

impl EguiFrame {
    /// Tessellates `output` and uploads the textures it sets.
    pub(super) fn new(surface: &mut Surface, mut output: egui::FullOutput) -> Self {
        let ppp = output.pixels_per_point;
        let gfx = &surface.gfx;
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                surface.egui_renderer.update_texture(&gfx.ctx.device, &gfx.ctx.queue, *id, delta);
            }
        }
        EguiFrame {
            jobs: surface.egui_ctx.tessellate(output.shapes, ppp),
            screen: egui_wgpu::ScreenDescriptor {
                size_in_pixels: [gfx.config.width, gfx.config.height],
                pixels_per_point: ppp,
            },
            free: std::mem::take(&mut output.textures_delta.free).into_iter().collect(),
        }
    }

    /// Frees the textures egui no longer needs (after the frame's draws).
    pub(super) fn free_textures(self, surface: &mut Surface) {
        for id in &self.free {
            surface.egui_renderer.free_texture(id);
        }
    }
}

/// Uploads geometry and radiance that changed since the last frame.
pub(super) fn upload_scene(surface: &mut Surface, scene: &mut ViewModel) -> anyhow::Result<()> {
    let ctx = &surface.gfx.ctx;
    if scene.geometry_dirty {
        if let Some(mesh) = &scene.mesh {
            surface.drawer.set_geometry(ctx, mesh)?;
            // Radiance of the previous geometry still matches vertex for vertex.
            scene.radiance_dirty = true;
        }
        scene.geometry_dirty = false;
    }
    let p = &scene.state.params;
    surface.drawer.set_environment(ctx, p.env, p.env_rotation_deg);
    if scene.radiance_dirty {
        // The figure 6.9 false colours replace the radiance while that view is on.
        let solution = &scene.solution;
        match &solution.clusters {
            Some(colours) => surface.drawer.set_radiance(ctx, colours, &[])?,
            None => surface.drawer.set_radiance(
                ctx,
                &solution.solved.vertex_radiance,
                &solution.solved.vertex_single,
            )?,
        }
        scene.radiance_dirty = false;
    }
    Ok(())
}

/// Records the 3D pass and the egui pass into `target` and submits them.
pub(super) fn encode_and_submit(
    surface: &mut Surface,
    target: &wgpu::TextureView,
    (origin, size): ViewportRect,
    params: &DrawParams,
    ui: &EguiFrame,
) -> anyhow::Result<()> {
    let (jobs, screen) = (&ui.jobs, &ui.screen);
    let gfx = &surface.gfx;
    let mut encoder = gfx.ctx.device.create_command_encoder(&Default::default());
    let viewport = Viewport { x: origin.x, y: origin.y, width: size.x, height: size.y };
    let target_size = (gfx.config.width, gfx.config.height);
    surface.drawer.draw(&gfx.ctx, &mut encoder, target, target_size, viewport, params)?;
    let extra =
        surface.egui_renderer.update_buffers(&gfx.ctx.device, &gfx.ctx.queue, &mut encoder, jobs, screen);
    {
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })],
                ..Default::default()
            })
            .forget_lifetime();
        surface.egui_renderer.render(&mut pass, jobs, screen);
    }
    gfx.ctx.queue.submit(extra.into_iter().chain(std::iter::once(encoder.finish())));
    gfx.ctx.check("drawing the frame")?;
    Ok(())
}

/// Draws the frame again into an offscreen texture and writes it to `path` as a PNG.
pub(super) fn save_screenshot(
    surface: &mut Surface,
    path: &std::path::Path,
    viewport: ViewportRect,
    params: &DrawParams,
    ui: &EguiFrame,
) -> anyhow::Result<()> {
    let gfx = &surface.gfx;
    let offscreen = Offscreen::new(&gfx.ctx.device, gfx.config.format, gfx.config.width, gfx.config.height);
    encode_and_submit(surface, &offscreen.view, viewport, params, ui)?;
    offscreen.save_png(&surface.gfx.ctx.device, &surface.gfx.ctx.queue, path)?;
    let (o, s) = viewport;
    println!(
        "lucent view: saved {} ({}x{}, 3D viewport {} {} {} {})",
        path.display(),
        surface.gfx.config.width,
        surface.gfx.config.height,
        o.x as u32,
        o.y as u32,
        s.x as u32,
        s.y as u32
    );
    Ok(())
}
