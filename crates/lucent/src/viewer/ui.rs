//! The egui side panel: material, scale, lights, environment, solver, deformation tools,
//! timings and the figure 6.9 view. It edits a [`ViewState`] in place and reports one-off
//! requests (screenshot, resets) in [`UiRequests`]; it never touches the GPU or the worker.

use super::core_adapter::level_colour;
use super::htsm::HtsmPanel;
use super::state::{EnvChoice, SolveMode, Tool, ViewMethod, ViewState};
use crate::progress::StageView;
use egui::{Color32, ComboBox, Slider, SliderClamping, Ui};
use glam::{Vec2, Vec3};
use lucent_core::bssrdf::ProfileKind;
use lucent_core::bssrdf::{Material, PRESETS};
use lucent_core::camera::CameraView;
use lucent_core::irradiance::{Light, LightKind};
use lucent_core::session::Timings;
use lucent_core::solver::Oracle;
use lucent_core::solver::oracle::OracleMode;

/// Read-only facts the panel displays.
#[derive(Clone, Debug, Default)]
pub struct Status {
    /// Adapter name and backend.
    pub adapter: String,
    /// Vertex and triangle counts of the current mesh (`None` while loading).
    pub mesh_size: Option<(usize, usize)>,
    /// A loading error to show instead of the mesh.
    pub load_error: Option<String>,
    /// True while the worker is solving a state newer than the one shown.
    pub solving: bool,
    /// Seconds the current solve has been running.
    pub solving_for_s: f64,
    /// The current solve's stage, once it has run a second.
    pub progress: Option<StageView>,
    /// Timings of the solve shown.
    pub timings: Timings,
    /// Link count of the solve shown (hierarchical solver only).
    pub links: Option<usize>,
    /// Method that produced the solve shown.
    pub method: lucent_core::session::Method,
    /// CPU time to record and submit the last frame, milliseconds.
    pub draw_ms: f64,
    /// Frames per second, smoothed.
    pub fps: f64,
}

/// One-off requests from the panel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UiRequests {
    /// Save a screenshot.
    pub screenshot: bool,
    /// Reset the camera.
    pub reset_camera: bool,
    /// Save the material to a new scene file ([`ViewState::save`]).
    pub save_material: bool,
}

/// Width of the side panel, points.
pub const PANEL_WIDTH: f32 = 300.0;

/// Draws the side panel inside `ui` (the root) and returns the requests made this frame.
pub fn side_panel(ui: &mut Ui, state: &mut ViewState, status: &Status, htsm: &HtsmPanel) -> UiRequests {
    let mut req = UiRequests::default();
    egui::Panel::left("lucent-panel").resizable(false).exact_size(PANEL_WIDTH).show(ui, |ui| {
        egui::ScrollArea::vertical().show(ui, |ui| {
            header(ui, status, &mut req);
            section(ui, "Method", true, |ui| method(ui, state, htsm));
            section(ui, "Material", true, |ui| req.save_material = material(ui, state));
            section(ui, "Lights", true, |ui| lights(ui, &mut state.params.lights));
            section(ui, "Environment", false, |ui| environment(ui, state));
            section(ui, "Solver", true, |ui| solver(ui, state));
            section(ui, "Deformation", true, |ui| deformation(ui, state));
            section(ui, "Timings", true, |ui| timings(ui, status));
        });
    });
    req
}

/// The homogeneous (Mertens) or heterogeneous (HTSM) method, and HTSM's settings.
fn method(ui: &mut Ui, state: &mut ViewState, htsm: &HtsmPanel) {
    ui.horizontal(|ui| {
        ui.radio_value(&mut state.method, ViewMethod::Mertens, "homogeneous (Mertens)");
        ui.radio_value(&mut state.method, ViewMethod::Htsm, "HTSM (Shopf)");
    });
    if state.method == ViewMethod::Htsm {
        super::htsm::controls(ui, &mut state.htsm, htsm);
    }
}

fn section(ui: &mut Ui, title: &str, open: bool, body: impl FnOnce(&mut Ui)) {
    egui::CollapsingHeader::new(title).default_open(open).show(ui, body);
}

fn header(ui: &mut Ui, status: &Status, req: &mut UiRequests) {
    ui.heading("lucent");
    ui.small(&status.adapter);
    match (&status.load_error, status.mesh_size) {
        (Some(e), _) => {
            ui.colored_label(Color32::LIGHT_RED, e);
        }
        (None, None) => {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("loading mesh…");
            });
        }
        (None, Some((v, t))) => {
            ui.horizontal(|ui| {
                ui.label(format!("{v} vertices, {t} triangles"));
                if status.solving {
                    ui.spinner();
                    ui.small(format!("solving {:.1} s", status.solving_for_s));
                }
            });
            if let Some(p) = &status.progress {
                let text = format!("{} {}/{} faces ({:.0}/s)", p.stage, p.done, p.total, p.per_s);
                ui.add(egui::ProgressBar::new(p.done as f32 / p.total as f32).text(text));
            }
        }
    }
    ui.horizontal(|ui| {
        req.screenshot = ui.button("Screenshot (F12)").clicked();
        req.reset_camera = ui.button("Reset view").clicked();
    });
}

/// The material editor; true when "save material" was clicked.
fn material(ui: &mut Ui, state: &mut ViewState) -> bool {
    let m = &mut state.params.transport.material;
    ComboBox::from_label("preset").selected_text(m.name.clone()).show_ui(ui, |ui| {
        for (name, _, _) in PRESETS {
            if ui.selectable_label(m.name == *name, *name).clicked()
                && let Ok(preset) = Material::by_name(name)
            {
                *m = preset;
            }
        }
    });
    let before = m.clone();
    ui.label("reduced scattering σs' (1/mm)");
    for (v, c) in m.sigma_s_prime.iter_mut().zip(["R", "G", "B"]) {
        ui.add(Slider::new(v, 0.01..=50.0).logarithmic(true).text(c).clamping(SliderClamping::Edits));
    }
    ui.label("absorption σa (1/mm)");
    for (v, c) in m.sigma_a.iter_mut().zip(["R", "G", "B"]) {
        ui.add(Slider::new(v, 1e-4..=10.0).logarithmic(true).text(c).clamping(SliderClamping::Edits));
    }
    ui.add(Slider::new(&mut m.eta, 1.0..=2.0).text("η").clamping(SliderClamping::Edits));
    if *m != before && !m.name.ends_with(" (edited)") {
        m.name = format!("{} (edited)", m.name);
    }
    by_colour(ui, state);
    ui.add(
        Slider::new(&mut state.params.transport.scale_m, 0.001..=2.0)
            .logarithmic(true)
            .text("scale (m)")
            .clamping(SliderClamping::Edits),
    );
    ui.add(
        Slider::new(&mut state.exposure, 0.05..=50.0)
            .logarithmic(true)
            .text("exposure")
            .clamping(SliderClamping::Edits),
    );
    save_button(ui, state)
}

/// "save material": writes the material, scale, profile and exposure to a new scene file
/// (never over an existing one) and shows where, or why not.
fn save_button(ui: &mut Ui, state: &ViewState) -> bool {
    let clicked = ui
        .button("save material")
        .on_hover_text(format!(
            "writes a scene file that lucent render --scene reads back: {} (or the next free name)",
            state.save.path.display()
        ))
        .clicked();
    match &state.save.message {
        Some(Ok(path)) => {
            ui.small(format!("saved to {path}"));
        }
        Some(Err(e)) => {
            ui.colored_label(Color32::LIGHT_RED, e);
        }
        None => {}
    }
    clicked
}

/// The material by colour and distance: a colour picker for the slab albedo, distance sliders,
/// and "apply", which inverts the pbd profile's albedo at the current η (about a second the first
/// time at an η, while its effective-albedo table is built; instant after).
fn by_colour(ui: &mut Ui, state: &mut ViewState) {
    ui.collapsing("by colour and distance", |ui| {
        let c = &mut state.by_colour;
        ui.horizontal(|ui| {
            ui.color_edit_button_rgb(&mut c.albedo);
            ui.label("slab albedo");
        });
        ui.label("mean free path (mm)");
        for (v, name) in c.mfp_mm.iter_mut().zip(["R", "G", "B"]) {
            ui.add(Slider::new(v, 0.01..=100.0).logarithmic(true).text(name).clamping(SliderClamping::Edits));
        }
        if ui.button("apply").clicked() {
            let (albedo, mfp) = (c.albedo.map(f64::from), c.mfp_mm.map(f64::from));
            match Material::from_albedo_mfp("colour", albedo, mfp, state.params.transport.material.eta) {
                Ok(m) => {
                    state.params.transport.material = m;
                    c.error = None;
                }
                Err(e) => c.error = Some(e.to_string()),
            }
        }
        if let Some(e) = &c.error {
            ui.colored_label(Color32::LIGHT_RED, e);
        }
    });
}

/// A white point light at `position` (normalised mesh units) giving irradiance 1 at the origin.
pub fn point_light(position: Vec3) -> Light {
    Light::Point { position, intensity: Vec3::splat(position.length_squared().max(0.01)) }
}

/// The lights list: each core [`Light`] edited in place (kind, colour and power, position,
/// direction, spot cone).
fn lights(ui: &mut Ui, lights: &mut Vec<Light>) {
    let mut remove = None;
    for (i, l) in lights.iter_mut().enumerate() {
        ui.push_id(i, |ui| {
            // Strength shown as a colour (its largest channel 1) times a power.
            let power = l.power().max_element().max(1e-6);
            let mut colour = (l.power() / power).to_array();
            let mut new_power = power;
            ui.horizontal(|ui| {
                let mut kind = l.kind();
                ComboBox::from_id_salt("kind").selected_text(kind.name()).width(100.0).show_ui(ui, |ui| {
                    for k in LightKind::ALL {
                        ui.selectable_value(&mut kind, k, k.name());
                    }
                });
                if kind != l.kind() {
                    *l = l.with_kind(kind, 2.0);
                }
                ui.color_edit_button_rgb(&mut colour);
                if ui.small_button("remove").clicked() {
                    remove = Some(i);
                }
            });
            if let Some(mut p) = l.position() {
                vec3_sliders(ui, &mut p, -3.0..=3.0, "pos");
                l.set_position(p);
            }
            if let Some(mut d) = l.direction() {
                vec3_sliders(ui, &mut d, -1.0..=1.0, "dir");
                l.set_direction(d);
            }
            if let Light::Spot { cone_angle, .. } = l {
                let mut deg = cone_angle.to_degrees();
                ui.add(Slider::new(&mut deg, 1.0..=90.0).text("cone (°)"));
                *cone_angle = deg.to_radians();
            }
            ui.add(
                Slider::new(&mut new_power, 0.01..=100.0)
                    .logarithmic(true)
                    .text("power")
                    .clamping(SliderClamping::Edits),
            );
            l.set_power(Vec3::from_array(colour) * new_power);
            ui.separator();
        });
    }
    if let Some(i) = remove {
        lights.remove(i);
    }
    if ui.button("Add light").clicked() {
        lights.push(point_light(Vec3::new(0.0, 1.2, 1.2)));
    }
}

fn vec3_sliders(ui: &mut Ui, v: &mut Vec3, range: std::ops::RangeInclusive<f32>, label: &str) {
    ui.horizontal(|ui| {
        ui.label(label);
        for c in [&mut v.x, &mut v.y, &mut v.z] {
            ui.add(egui::DragValue::new(c).speed(0.01).range(range.clone()));
        }
    });
}

/// The refinement oracle (Mertens §5.2): its mode, its thresholds, and a reset to the profile's
/// defaults. Smaller thresholds refine more.
fn oracle(ui: &mut Ui, o: &mut Oracle, profile: ProfileKind) {
    ui.horizontal(|ui| {
        ui.label("oracle");
        ui.radio_value(&mut o.mode, OracleMode::Transport, "transport");
        ui.radio_value(&mut o.mode, OracleMode::SolidAngle, "solid angle");
        if ui.small_button("defaults").clicked() {
            *o = Oracle { mode: o.mode, ..Oracle::for_profile(profile) };
        }
    });
    let (unit, range) = match o.mode {
        OracleMode::Transport => ("", 1e-3..=1.0),
        OracleMode::SolidAngle => (" (sr)", 1e-4..=1.0),
    };
    ui.add(Slider::new(&mut o.eps1, range.clone()).logarithmic(true).text(format!("ε1 receiver{unit}")));
    ui.add(Slider::new(&mut o.eps2, range).logarithmic(true).text(format!("ε2 emitter{unit}")));
    if o.mode == OracleMode::Transport {
        ui.add(Slider::new(&mut o.eps_abs, 1e-6..=1e-1).logarithmic(true).text("ε_abs (of R_d total)"));
    }
}

fn environment(ui: &mut Ui, state: &mut ViewState) {
    let p = &mut state.params;
    ComboBox::from_label("map").selected_text(p.env.label()).show_ui(ui, |ui| {
        for e in EnvChoice::ALL {
            ui.selectable_value(&mut p.env, e, e.label());
        }
    });
    ui.add(Slider::new(&mut p.env_rotation_deg, 0.0..=360.0).text("rotation (°)"));
    ui.add(Slider::new(&mut p.env_strength, 0.0..=10.0).text("strength"));
    if let Some(path) = p.env.path()
        && !std::path::Path::new(path).is_file()
    {
        ui.weak(format!("{path} not found (run from the repository root)"));
    }
    ui.checkbox(&mut p.settings.environment_shadows, "shadows");
}

fn solver(ui: &mut Ui, state: &mut ViewState) {
    let (t, s) = (&mut state.params.transport, &mut state.params.settings);
    ui.horizontal(|ui| {
        for m in SolveMode::ALL {
            ui.radio_value(&mut s.mode, m, m.name());
        }
    });
    let before = t.profile;
    ui.horizontal(|ui| {
        ui.label("profile");
        for k in lucent_core::bssrdf::ProfileKind::ALL {
            ui.radio_value(&mut t.profile, k, k.name());
        }
    });
    // As on the command line: `mertens` takes no bounces unless asked.
    s.bounces = crate::ranges::bounces_after_profile_change(s.bounces, before, t.profile);
    if t.profile.has_single_scattering() {
        ui.horizontal(|ui| {
            use lucent_core::shading::SingleScattering as S;
            ui.label("single scattering");
            for k in [S::ViewRay, S::Profile, S::Off] {
                ui.radio_value(&mut t.single_scattering, k, k.name());
            }
        });
    }
    ui.add(Slider::new(&mut s.bounces, crate::ranges::BOUNCES).text("bounces")).on_hover_text(
        "light one part sends through the air to another: up to 64 rays a face, traced once (refitted as the mesh deforms), and a gather each; none by default for mertens",
    );
    // Transport-oracle thresholds (relative errors): smaller refines more.
    let profile = t.profile;
    oracle(ui, s.oracle.get_or_insert_with(|| Oracle::for_profile(profile)), profile);
    ui.checkbox(&mut state.show_clusters, "figure 6.9: clusters gathered by a triangle");
    if state.show_clusters {
        state.tool = Tool::PickTriangle;
        match state.picked_face {
            Some(f) => ui.label(format!("triangle {f}; colour = level of the emitter cluster:")),
            None => ui.label("click a triangle"),
        };
        level_legend(ui);
    }
}

/// Swatches of the level colours of the figure 6.9 view (level 0 is the root).
fn level_legend(ui: &mut Ui) {
    ui.horizontal_wrapped(|ui| {
        for level in 0..8 {
            let c = (level_colour(level) * 255.0).to_array().map(|v| v as u8);
            ui.colored_label(Color32::from_rgb(c[0], c[1], c[2]), format!("■ {level}"));
        }
    });
}

fn deformation(ui: &mut Ui, state: &mut ViewState) {
    ui.horizontal(|ui| {
        ui.label("left drag:");
        ui.radio_value(&mut state.tool, Tool::Orbit, "orbit");
        ui.radio_value(&mut state.tool, Tool::Dent, "dent");
        ui.radio_value(&mut state.tool, Tool::PickTriangle, "pick");
    });
    let d = &mut state.deform;
    ui.add(Slider::new(&mut d.twist_degrees, -360.0..=360.0).text("twist (°, bottom to top)"));
    ui.add(Slider::new(&mut d.noise.amplitude, 0.0..=0.1).text("noise"));
    ui.checkbox(&mut d.noise_animated, "animate noise");
    ui.horizontal(|ui| {
        ui.label(format!("{} dents", d.dents.len()));
        if ui.button("Undo dent").clicked() {
            d.dents.pop();
        }
        if ui.button("Reset geometry").clicked() {
            *d = Default::default();
        }
    });
}

fn timings(ui: &mut Ui, status: &Status) {
    let t = &status.timings;
    egui::Grid::new("timings").num_columns(2).show(ui, |ui| {
        let total = ("CPU total", t.cpu_ms());
        for (name, ms) in t
            .stages()
            .into_iter()
            .filter(|(n, _)| !matches!(*n, "raster" | "write"))
            .chain([total, ("draw (CPU)", status.draw_ms)])
        {
            ui.label(name);
            ui.label(format!("{ms:8.2} ms"));
            ui.end_row();
        }
        ui.label("links");
        ui.label(status.links.map_or("–".to_string(), |l| l.to_string()));
        ui.end_row();
        ui.label("frame rate");
        ui.label(format!("{:.1} fps", status.fps));
        ui.end_row();
    });
    ui.small(format!("method: {}", status.method.name()));
}

/// Draws a marker for every positional light over the 3D view (`rect`, points; `camera`
/// framed for its aspect ratio).
pub fn light_markers(ui: &Ui, rect: egui::Rect, camera: &CameraView, lights: &[Light]) {
    let painter = ui.ctx().layer_painter(egui::LayerId::background());
    let size = Vec2::new(rect.width(), rect.height());
    for l in lights {
        let Some(position) = l.position() else { continue };
        let Some(p) = camera.to_pixel(position, size) else { continue };
        let pos = egui::pos2(rect.left() + p.x, rect.top() + p.y);
        let c = (l.power().normalize_or_zero() * 255.0).to_array().map(|v| v as u8);
        painter.circle(pos, 5.0, Color32::from_rgb(c[0], c[1], c[2]), (1.0, Color32::WHITE));
    }
}
