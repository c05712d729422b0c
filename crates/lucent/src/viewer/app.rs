//! The winit application: owns the window, the GPU state, the egui integration, the worker and
//! the scene, and runs one frame per redraw: take worker replies, run the UI, send the new state
//! to the worker, draw, take screenshots, advance the script.

use super::core_adapter::EnvCache;
use super::draw::{self, DrawParams, ViewDrawer};
use super::framing::Framing;
use super::gfx::Gfx;
use super::htsm::HtsmPanel;
use super::input::{self, Input, ViewportRect};
use super::model::ViewModel;
use super::present::{EguiFrame, Surface, encode_and_submit, save_screenshot, upload_scene};
use super::screenshot;
use super::script::{Action, Automation, Step};
use super::state::{EnvChoice, ViewMethod, ViewState};
use super::ui::{self, Status};
use super::worker::{MeshOrigin, Request, Worker};
use anyhow::Context as _;
use glam::Vec2;
use lucent_core::bssrdf::Material;
use lucent_core::camera::OrbitCamera;
use lucent_gpu::mesh_pass::Shading;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoopProxy};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// Wakes the event loop when the worker has a reply.
#[derive(Clone, Copy, Debug)]
pub struct WorkerWake;

/// How the viewer starts.
pub struct Options {
    /// Where the mesh comes from.
    pub mesh: MeshOrigin,
    /// The mesh's colour texture, if it has one (drawn by the mesh pass; HTSM stays untextured).
    pub texture: Option<lucent_core::mesh::texture::Texture>,
    /// Initial state (material, scale, lights...).
    pub state: ViewState,
    /// The scene file's camera (degrees, radii of the mesh's bounding sphere), framed as
    /// `lucent render` frames it; `None`: the viewer's home view ([`super::framing::home`]).
    pub camera: Option<OrbitCamera>,
    /// Scripted run, if any.
    pub automation: Option<Automation>,
    /// Window inner size, logical pixels.
    pub size: (u32, u32),
}

/// Frame pacing for continuous redraws (animations, scripted runs): about 60 Hz.
const FRAME_INTERVAL: Duration = Duration::from_millis(16);
/// A scripted run fails if it makes no progress for this long.
const SCRIPT_TIMEOUT: Duration = Duration::from_secs(300);

/// Smoothed frame statistics.
#[derive(Debug)]
struct FrameStats {
    last_frame: Instant,
    fps: f64,
    draw_ms: f64,
}

/// The application.
pub struct App {
    mesh_origin: Option<MeshOrigin>,
    texture: Option<lucent_core::mesh::texture::Texture>,
    size: (u32, u32),
    proxy: EventLoopProxy<WorkerWake>,
    worker: Option<Worker>,
    scene: ViewModel,
    framing: Framing,
    input: Input,
    automation: Option<Automation>,
    last_progress: Instant,
    surface: Option<Surface>,
    viewport: ViewportRect,
    stats: FrameStats,
    pending_shot: Option<PathBuf>,
    exit_after_shot: bool,
    /// A scripted `animate:SECONDS` runs until then (noise flowing, the first light orbiting).
    animate_until: Option<Instant>,
    /// The environment HTSM draws with (the worker keeps its own for the solve).
    environment: EnvCache,
    /// The first error that ends the run (returned by [`super::run`]).
    pub error: Option<anyhow::Error>,
}

impl App {
    /// An app that will open its window when the event loop resumes.
    pub fn new(options: Options, proxy: EventLoopProxy<WorkerWake>) -> Self {
        App {
            mesh_origin: Some(options.mesh),
            texture: options.texture,
            size: options.size,
            proxy,
            worker: None,
            scene: ViewModel::new(options.state),
            framing: Framing::new(options.camera),
            input: Input::default(),
            automation: options.automation,
            last_progress: Instant::now(),
            surface: None,
            viewport: (Vec2::ZERO, Vec2::ONE),
            stats: FrameStats { last_frame: Instant::now(), fps: 0.0, draw_ms: 0.0 },
            pending_shot: None,
            exit_after_shot: false,
            animate_until: None,
            environment: EnvCache::default(),
            error: None,
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: anyhow::Error) {
        if self.error.is_none() {
            self.error = Some(error);
        }
        event_loop.exit();
    }

    fn open_window(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let attrs = Window::default_attributes()
            .with_title("lucent — translucent objects (Mertens et al. 2003)")
            .with_inner_size(winit::dpi::LogicalSize::new(self.size.0, self.size.1));
        let window = Arc::new(event_loop.create_window(attrs).context("creating the window")?);
        let gfx = Gfx::new(window.clone(), event_loop.owned_display_handle(), self.automation.is_some())?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            window.theme(),
            Some(gfx.ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(&gfx.ctx.device, gfx.config.format, Default::default());
        let mut drawer = ViewDrawer::new(&gfx.ctx, gfx.config.format)?;
        if let Some(texture) = &self.texture {
            drawer.set_texture(&gfx.ctx, texture)?;
        }
        let htsm = HtsmPanel::default();
        self.surface = Some(Surface { window, gfx, egui_ctx, egui_state, egui_renderer, drawer, htsm });
        Ok(())
    }

    fn start_worker(&mut self) {
        let proxy = self.proxy.clone();
        let worker = Worker::spawn(move || {
            let _ = proxy.send_event(WorkerWake);
        });
        if let Some(origin) = self.mesh_origin.take() {
            worker.send(Request::Load(origin));
        }
        self.worker = Some(worker);
    }

    fn status(&self) -> Status {
        let s = &self.scene;
        Status {
            adapter: self.surface.as_ref().map_or(String::new(), |w| {
                let i = &w.gfx.ctx.adapter_info;
                format!("{} ({:?})", i.name, i.backend)
            }),
            mesh_size: s.mesh.as_ref().map(|m| (m.positions.len(), m.triangles.len())),
            load_error: s.load_error.clone(),
            solving: s.solving(),
            solving_for_s: s.solving_for_s(),
            progress: s.solve_progress(),
            timings: s.solution.solved.timings,
            links: s.solution.solved.links,
            method: s.state.params.settings.method,
            draw_ms: self.stats.draw_ms,
            fps: self.stats.fps,
        }
    }

    /// One frame: see the module docs. Any error ends the run.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        let frame_start = Instant::now();
        if let Err(e) = self.frame() {
            return self.fail(event_loop, e);
        }
        if self.exit_after_shot && self.pending_shot.is_none() {
            return event_loop.exit();
        }
        self.update_stats(frame_start);
        self.advance_script(event_loop);
    }

    fn frame(&mut self) -> anyhow::Result<()> {
        let dt = self.stats.last_frame.elapsed().as_secs_f32();
        if let Some(until) = self.animate_until {
            self.animate_step(until, dt);
        }
        let Some(worker) = &self.worker else { return Ok(()) };
        self.scene.receive(worker);
        if let (Some(e), Some(_)) = (&self.scene.load_error, &self.automation) {
            anyhow::bail!("loading the mesh: {e}");
        }
        self.input.update(&mut self.scene.state);
        // HTSM's medium follows the material and scale however they changed (panel, script).
        let st = &mut self.scene.state;
        st.htsm.follow(&st.params.transport.material, st.params.transport.scale_m);
        let d = &mut self.scene.state.deform;
        if d.noise_animated && d.noise.amplitude != 0.0 {
            d.noise.offset += glam::Vec3::splat(dt * 0.5);
        }
        let status = self.status();
        let Some(surface) = &mut self.surface else { return Ok(()) };
        // HTSM renders at the previous frame's viewport size, before the UI that shows it.
        let state = &self.scene.state;
        if state.method == ViewMethod::Htsm
            && let Some(mesh) = &self.scene.mesh
        {
            let params = draw_params(&self.framing, state, self.viewport, false);
            let size = (self.viewport.1.x as u32, self.viewport.1.y as u32);
            let light = (&state.params.lights[..], self.environment.get(&state.params));
            let (ctx, renderer) = (&surface.gfx.ctx, &mut surface.egui_renderer);
            surface.htsm.update(ctx, renderer, mesh, &state.htsm, light, params.camera, params.tone, size);
        }
        let (output, requests, viewport) = run_ui(surface, &mut self.scene.state, &status, &self.framing);
        self.viewport = viewport;
        if requests.reset_camera {
            self.framing.reset();
        }
        if requests.screenshot {
            self.pending_shot = Some(screenshot::timestamped_path());
        }
        if requests.save_material {
            let state = &mut self.scene.state;
            let saved = super::scene_file::save_material(state, None);
            state.save.message = Some(saved.map(|p| p.display().to_string()).map_err(|e| format!("{e:#}")));
        }
        let aspect = viewport.1.x / viewport.1.y.max(1.0);
        self.scene.state.params.eye = Some(self.framing.view(aspect).eye);
        self.scene.sync(worker);
        self.framing.update(self.scene.base.as_ref(), self.scene.mesh.as_ref());
        upload_scene(surface, &mut self.scene)?;
        let ui = EguiFrame::new(surface, output);
        let false_colour = self.scene.solution.clusters.is_some();
        let mut params = draw_params(&self.framing, &self.scene.state, viewport, false_colour);
        if !false_colour {
            // The lobe of the profile that made the radiance on screen.
            params.shading.exit_lobe = self.scene.solution.solved.exit_lobe.clone();
        }
        if !surface.drawer.reflects() {
            params.shading.environment = 0.0;
        }
        if let Some(frame) = surface.gfx.acquire() {
            let view = frame.texture.create_view(&Default::default());
            encode_and_submit(surface, &view, viewport, &params, &ui)?;
            surface.gfx.ctx.queue.present(frame);
            self.scene.mark_drawn();
        }
        if let Some(path) = self.pending_shot.take() {
            save_screenshot(surface, &path, viewport, &params, &ui)?;
        }
        ui.free_textures(surface);
        Ok(())
    }

    fn update_stats(&mut self, frame_start: Instant) {
        let s = &mut self.stats;
        s.draw_ms = frame_start.elapsed().as_secs_f64() * 1e3;
        let dt = s.last_frame.elapsed().as_secs_f64().max(1e-6);
        s.fps = if s.fps == 0.0 { 1.0 / dt } else { 0.9 * s.fps + 0.1 / dt };
        s.last_frame = Instant::now();
    }

    /// One frame of a scripted `animate:SECONDS`: the first light turns about the vertical axis
    /// at half a radian per second; at the end the noise stops and the script goes on.
    fn animate_step(&mut self, until: Instant, dt: f32) {
        let state = &mut self.scene.state;
        if Instant::now() >= until {
            state.deform.noise_animated = false;
            self.animate_until = None;
            return;
        }
        if let Some(light) = state.params.lights.first_mut()
            && let Some(p) = light.position()
        {
            let p = glam::Quat::from_rotation_y(0.5 * dt) * p;
            light.set_position(p);
            light.set_direction(-p);
        }
        self.last_progress = Instant::now();
    }

    fn advance_script(&mut self, event_loop: &ActiveEventLoop) {
        if self.animate_until.is_some() {
            return;
        }
        let htsm_building = self.surface.as_mut().is_some_and(|s| s.htsm.building());
        let settled = self.scene.settled() && !htsm_building;
        let Some(auto) = &mut self.automation else { return };
        let step = auto.step(settled);
        match step {
            Step::Wait if self.last_progress.elapsed() > SCRIPT_TIMEOUT => {
                let e = anyhow::anyhow!(
                    "scripted run made no progress for {} s (the solve did not finish)",
                    SCRIPT_TIMEOUT.as_secs()
                );
                self.fail(event_loop, e)
            }
            Step::Wait => {}
            Step::Run(action) => {
                self.last_progress = Instant::now();
                if let Err(e) = self.apply(action) {
                    self.fail(event_loop, e)
                }
            }
            Step::Finish => match auto.screenshot.take() {
                Some(path) => {
                    self.pending_shot = Some(path);
                    self.exit_after_shot = true;
                }
                None => event_loop.exit(),
            },
        }
    }

    /// Applies one scripted action to the state or camera.
    fn apply(&mut self, action: Action) -> anyhow::Result<()> {
        let state = &mut self.scene.state;
        match action {
            Action::Dent(p) => {
                let mesh = self.scene.mesh.as_ref().context("dent: no mesh")?;
                let dent = input::scripted_dent(mesh, p).context("dent: the mesh has no vertices")?;
                state.deform.dents.push(dent);
            }
            Action::Light(p) => match state.params.lights.first_mut() {
                Some(l) => l.set_position(p),
                None => state.params.lights.push(super::ui::point_light(p)),
            },
            Action::Twist(degrees) => state.deform.twist_degrees = degrees,
            Action::Material(name) => {
                state.params.transport.material = Material::by_name(&name)?;
            }
            Action::Scale(m) => state.params.transport.scale_m = m,
            Action::Camera(yaw, pitch, distance) => self.framing.place(yaw, pitch, distance),
            Action::Exposure(k) => state.exposure = k,
            Action::Clusters(p) => {
                let mesh = self.scene.mesh.as_ref().context("clusters: no mesh")?;
                state.show_clusters = true;
                state.picked_face = nearest_face(mesh, p);
            }
            Action::Htsm(on) => state.method = if on { ViewMethod::Htsm } else { ViewMethod::Mertens },
            Action::Shot(path) => self.pending_shot = Some(path),
            Action::Save(path) => {
                let written = super::scene_file::save_material(state, Some(&path))?;
                println!("lucent: material saved to {}", written.display());
                state.save.message = Some(Ok(written.display().to_string()));
            }
            Action::Albedo(albedo, mfp) => {
                let (a, d) = (albedo.map(f64::from), mfp.map(f64::from));
                let eta = state.params.transport.material.eta;
                state.params.transport.material = Material::from_albedo_mfp("colour", a, d, eta)?;
                state.by_colour = super::state::ByColour { albedo, mfp_mm: mfp, error: None };
            }
            Action::Animate(seconds) => {
                if state.deform.noise.amplitude == 0.0 {
                    state.deform.noise.amplitude = 0.02;
                }
                state.deform.noise_animated = true;
                if state.params.lights.is_empty() {
                    state.params.lights.push(super::ui::point_light(glam::Vec3::new(0.0, 1.0, -2.0)));
                }
                self.animate_until = Some(Instant::now() + Duration::from_secs_f64(seconds));
            }
        }
        Ok(())
    }

    /// Whether frames must keep coming without input.
    fn animating(&self) -> bool {
        let d = &self.scene.state.deform;
        self.automation.is_some() || self.input.animating() || (d.noise_animated && d.noise.amplitude != 0.0)
    }

    fn window_input(&mut self, event: &WindowEvent) {
        let mesh = self.scene.mesh.clone();
        match event {
            WindowEvent::MouseInput { state, button, .. } => {
                let inside = self.cursor_in_viewport();
                if *state == ElementState::Released || inside {
                    let size = self.viewport.1;
                    let camera = self.framing.view(size.x / size.y.max(1.0));
                    let (view, scene) = (self.viewport, &mut self.scene.state);
                    self.input.button(*button, *state, view, &camera, scene, mesh.as_ref());
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = Vec2::new(position.x as f32, position.y as f32);
                self.input.moved(p, self.viewport, &mut self.framing.camera);
            }
            WindowEvent::MouseWheel { delta, .. } if self.cursor_in_viewport() => {
                self.input.wheel(*delta, self.viewport, &mut self.framing.camera)
            }
            WindowEvent::CursorLeft { .. } | WindowEvent::Focused(false) => self.input.release_all(),
            _ => {}
        }
    }

    fn cursor_in_viewport(&self) -> bool {
        let Some(s) = &self.surface else { return false };
        let over_ui = s.egui_ctx.is_pointer_over_egui() || s.egui_ctx.egui_wants_pointer_input();
        !over_ui
    }

    /// Keys that act on the whole app; true if handled.
    fn shortcut(&mut self, event_loop: &ActiveEventLoop, event: &WindowEvent) -> bool {
        let WindowEvent::KeyboardInput { event: key, .. } = event else {
            return false;
        };
        if key.state != ElementState::Pressed || key.repeat {
            return false;
        }
        match &key.logical_key {
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Named(NamedKey::F12) => self.pending_shot = Some(screenshot::timestamped_path()),
            Key::Character(c) if c.eq_ignore_ascii_case("p") => {
                self.pending_shot = Some(screenshot::timestamped_path())
            }
            _ => return false,
        }
        true
    }
}

/// The 3D pass's parameters for the camera, the state and the viewport's aspect ratio;
/// `false_colour` shows the uploaded colours as they are (no highlight, exposure 1).
fn draw_params(
    framing: &Framing,
    state: &ViewState,
    (_, size): ViewportRect,
    false_colour: bool,
) -> DrawParams {
    DrawParams {
        camera: framing.view(size.x / size.y.max(1.0)),
        shading: Shading {
            eta: state.params.transport.material.eta as f32,
            lights: state.params.lights.clone(),
            specular: if false_colour { 0.0 } else { 1.0 },
            environment: if false_colour || state.params.env == EnvChoice::None {
                0.0
            } else {
                state.params.env_strength
            },
            ..Default::default()
        },
        tone: draw::tone_map(if false_colour { 1.0 } else { state.exposure }),
    }
}

/// The face whose centroid is nearest to `p`.
fn nearest_face(mesh: &lucent_core::mesh::Mesh, p: glam::Vec3) -> Option<u32> {
    (0..mesh.triangles.len())
        .min_by(|&a, &b| {
            let da = (mesh.face_centroid(a) - p).length_squared();
            let db = (mesh.face_centroid(b) - p).length_squared();
            da.total_cmp(&db)
        })
        .map(|f| f as u32)
}

/// Runs the egui pass: the side panel and light markers. Returns egui's output, the panel's
/// requests and the 3D viewport in physical pixels.
fn run_ui(
    surface: &mut Surface,
    state: &mut ViewState,
    status: &Status,
    framing: &Framing,
) -> (egui::FullOutput, ui::UiRequests, ViewportRect) {
    let raw = surface.egui_state.take_egui_input(&surface.window);
    let mut requests = ui::UiRequests::default();
    let mut central = egui::Rect::NOTHING;
    let htsm = &surface.htsm;
    let output = surface.egui_ctx.run_ui(raw, |root| {
        requests = ui::side_panel(root, state, status, htsm);
        central = root.available_rect_before_wrap();
        if state.method == ViewMethod::Htsm
            && let Some(texture) = htsm.texture()
        {
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            root.painter().image(texture, central, uv, egui::Color32::WHITE);
        }
        let camera = framing.view(central.width() / central.height().max(1.0));
        ui::light_markers(root, central, &camera, &state.params.lights);
    });
    surface.egui_state.handle_platform_output(&surface.window, output.platform_output.clone());
    let ppp = output.pixels_per_point;
    let (w, h) = (surface.gfx.config.width as f32, surface.gfx.config.height as f32);
    let min = Vec2::new(central.min.x * ppp, central.min.y * ppp).clamp(Vec2::ZERO, Vec2::new(w, h));
    let max = Vec2::new(central.max.x * ppp, central.max.y * ppp).clamp(min, Vec2::new(w, h));
    (output, requests, (min, (max - min).max(Vec2::ONE)))
}

impl ApplicationHandler<WorkerWake> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.surface.is_some() {
            return;
        }
        if let Err(e) = self.open_window(event_loop) {
            return self.fail(event_loop, e);
        }
        if self.worker.is_none() {
            self.start_worker();
        }
        if let Some(s) = &self.surface {
            s.window.request_redraw();
        }
    }

    fn user_event(&mut self, _: &ActiveEventLoop, _: WorkerWake) {
        if let Some(s) = &self.surface {
            s.window.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(surface) = &mut self.surface else { return };
        let response = surface.egui_state.on_window_event(&surface.window, &event);
        if response.repaint {
            surface.window.request_redraw();
        }
        match &event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => return event_loop.exit(),
            WindowEvent::Resized(size) => {
                surface.gfx.resize(size.width, size.height);
                surface.window.request_redraw();
                return;
            }
            WindowEvent::RedrawRequested => return self.redraw(event_loop),
            _ => {}
        }
        let keyboard_taken = surface.egui_ctx.egui_wants_keyboard_input();
        if !(keyboard_taken && matches!(event, WindowEvent::KeyboardInput { .. }))
            && self.shortcut(event_loop, &event)
        {
            return;
        }
        if !response.consumed {
            self.window_input(&event);
            if let Some(s) = &self.surface {
                s.window.request_redraw();
            }
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let htsm = self.scene.state.method == ViewMethod::Htsm;
        let Some(s) = &mut self.surface else { return };
        // HTSM's tables being made on their thread: wake to draw with them when they come.
        let htsm_building = htsm && s.htsm.building();
        let Some(s) = &self.surface else { return };
        if !self.animating() && !self.scene.solving() && !htsm_building {
            event_loop.set_control_flow(ControlFlow::Wait);
            return;
        }
        if !self.animating() {
            // Only waiting for the worker (its reply wakes the loop) or HTSM's tables: redraw
            // four times a second for the elapsed time, the progress bar and the tables.
            event_loop.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(250)));
            return;
        }
        let next = self.stats.last_frame + FRAME_INTERVAL;
        if Instant::now() >= next {
            s.window.request_redraw();
        } else {
            event_loop.set_control_flow(ControlFlow::WaitUntil(next));
        }
    }

    fn new_events(&mut self, _: &ActiveEventLoop, cause: winit::event::StartCause) {
        if let winit::event::StartCause::ResumeTimeReached { .. } = cause
            && let Some(s) = &self.surface
        {
            s.window.request_redraw();
        }
    }
}
