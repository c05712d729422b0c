//! The viewer's second method: Heterogeneous Translucent Shadow Maps (Shopf 2007, chapter 4),
//! switchable with the homogeneous Mertens solve in the panel.
//!
//! HTSM needs no CPU solve: [`HtsmPanel::update`] renders the current (deformed) mesh with a
//! density volume through [`lucent_gpu::htsm::HtsmRenderer`] on the viewer's device, from the
//! first light, and keeps the image as an egui texture that the UI draws over the 3D viewport.
//! It re-renders only when something it depends on changed (camera, light, mesh, settings,
//! viewport size), so an idle window costs nothing.

use glam::Vec3;
use lucent_core::irradiance::Light;
use lucent_core::mesh::Mesh;
use lucent_core::volume::VolumeSpec;
use lucent_gpu::GpuContext;
use lucent_gpu::camera::CameraView;
use lucent_gpu::htsm::{HtsmParams, HtsmRenderer, HtsmView, TransportModel, volume_dims_for};
use lucent_gpu::tonemap::ToneMap;
use std::sync::Arc;
use std::time::Instant;

/// Side of the light-view reference images, texels (Shopf §5.2 uses 256^2 maps too).
const REFERENCE_SIZE: u32 = 256;
/// Voxels along the mesh's largest side of the procedural volume.
const VOLUME_RES: u32 = 64;

/// The HTSM settings the panel edits (see [`HtsmParams`] for meanings, units and ranges).
#[derive(Clone, Debug, PartialEq)]
pub struct HtsmSettings {
    /// Density volume spec, as for `lucent render --volume` (`veins`, `cube:0.5`, ...).
    pub volume: String,
    /// Material, sampling and surface parameters; `tone` is set from the viewer's exposure.
    pub params: HtsmParams,
}

impl Default for HtsmSettings {
    fn default() -> Self {
        HtsmSettings { volume: "veins".into(), params: HtsmParams::default() }
    }
}

/// Everything an HTSM image depends on, to know when to render again.
#[derive(Clone, Debug)]
struct Inputs {
    /// Held (not just its address) so that a freed mesh's address cannot be reused by a new
    /// one and pass for it.
    mesh: Arc<Mesh>,
    volume: String,
    params: HtsmParams,
    camera: CameraView,
    light: Light,
    size: (u32, u32),
}

impl Inputs {
    /// The same mesh (by identity) and equal everything else.
    fn same_as(&self, other: &Inputs) -> bool {
        Arc::ptr_eq(&self.mesh, &other.mesh)
            && (&self.volume, &self.params, &self.camera, &self.light, self.size)
                == (&other.volume, &other.params, &other.camera, &other.light, other.size)
    }
}

/// The HTSM renderer of the current mesh and volume, and its last image.
#[derive(Default)]
pub struct HtsmPanel {
    renderer: Option<(Arc<Mesh>, String, HtsmRenderer)>,
    last: Option<Inputs>,
    texture: Option<egui::TextureHandle>,
    /// GPU time of the last HTSM frame (encode to read-back), milliseconds.
    pub frame_ms: f64,
    /// Why the last render failed (shown in the panel instead of an image).
    pub error: Option<String>,
}

impl HtsmPanel {
    /// Renders `mesh` with `settings` into the texture when an input changed. `lights` are the
    /// viewer's (normalised mesh units); HTSM uses the first. Errors (a bad volume spec, a
    /// parameter out of range) are kept in [`HtsmPanel::error`], not returned: the window stays.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        egui_ctx: &egui::Context,
        mesh: &Arc<Mesh>,
        settings: &HtsmSettings,
        lights: &[lucent_core::irradiance::Light],
        camera: CameraView,
        tone: ToneMap,
        size: (u32, u32),
    ) {
        let light = lights
            .first()
            .copied()
            .unwrap_or(Light::Directional { direction: Vec3::NEG_Z, irradiance: Vec3::ONE });
        let inputs = Inputs {
            mesh: mesh.clone(),
            volume: settings.volume.clone(),
            params: HtsmParams { tone, ..settings.params },
            camera,
            light,
            size: (size.0.max(1), size.1.max(1)),
        };
        if self.last.as_ref().is_some_and(|last| last.same_as(&inputs)) {
            return;
        }
        self.last = Some(inputs.clone());
        match self.render(ctx, &inputs) {
            Ok(image) => {
                let pixels = egui::ColorImage::from_rgba_unmultiplied(
                    [image.width() as usize, image.height() as usize],
                    image.as_raw(),
                );
                match &mut self.texture {
                    Some(t) => t.set(pixels, egui::TextureOptions::LINEAR),
                    None => {
                        self.texture =
                            Some(egui_ctx.load_texture("htsm", pixels, egui::TextureOptions::LINEAR))
                    }
                }
                self.error = None;
            }
            Err(e) => self.error = Some(format!("{e:#}")),
        }
    }

    fn render(&mut self, ctx: &GpuContext, inputs: &Inputs) -> anyhow::Result<image::RgbaImage> {
        inputs.params.validate()?;
        let stale =
            !matches!(&self.renderer, Some((m, v, _)) if Arc::ptr_eq(m, &inputs.mesh) && *v == inputs.volume);
        if stale {
            self.renderer = None;
            let spec: VolumeSpec = inputs.volume.parse()?;
            let volume = spec.build(volume_dims_for(&inputs.mesh, VOLUME_RES))?;
            let renderer = HtsmRenderer::new(ctx, &inputs.mesh, &volume, REFERENCE_SIZE)?;
            self.renderer = Some((inputs.mesh.clone(), inputs.volume.clone(), renderer));
        }
        let (_, _, renderer) = self.renderer.as_mut().expect("made above");
        let view = HtsmView {
            camera: inputs.camera,
            lights: vec![inputs.light],
            environment: None,
            width: inputs.size.0,
            height: inputs.size.1,
        };
        let t = Instant::now();
        let image = renderer.render(ctx, &view, &inputs.params)?;
        self.frame_ms = t.elapsed().as_secs_f64() * 1e3;
        Ok(image)
    }

    /// The last HTSM image, if there is one.
    pub fn texture(&self) -> Option<egui::TextureId> {
        self.texture.as_ref().map(|t| t.id())
    }
}

/// The panel's HTSM controls.
pub fn controls(ui: &mut egui::Ui, s: &mut HtsmSettings, panel: &HtsmPanel) {
    use egui::Slider;
    let p = &mut s.params;
    ui.horizontal(|ui| {
        ui.label("volume");
        ui.text_edit_singleline(&mut s.volume).on_hover_text(
            "veins[:SEED[:SCALE]], cube[:SIZE], uniform:D, raw:PATH:NXxNYxNZ:u8|u16|f32, file:PATH",
        );
    });
    ui.horizontal(|ui| {
        ui.label("samples n");
        for n in [1, 5, 9, 13] {
            ui.radio_value(&mut p.samples, n, n.to_string());
        }
    });
    ui.add(Slider::new(&mut p.steps, 1..=64).text("steps K"));
    ui.horizontal(|ui| {
        let mut c = p.transport_colour.to_array();
        ui.color_edit_button_rgb(&mut c);
        // The model needs every channel in (0, 1].
        p.transport_colour = Vec3::from(c).clamp(Vec3::splat(0.01), Vec3::ONE);
        ui.label("transport colour T_c");
    });
    ui.add(Slider::new(&mut p.transport_distance, 0.02..=2.0).logarithmic(true).text("T_d (object units)"));
    ui.add(Slider::new(&mut p.phase_g, -0.9..=0.9).text("phase g"));
    ui.add(Slider::new(&mut p.density_scale, 0.0..=100.0).text("density scale"));
    ui.horizontal(|ui| {
        ui.radio_value(&mut p.model, TransportModel::BeerLambert, "beer-lambert");
        ui.radio_value(&mut p.model, TransportModel::Thesis, "thesis (table 4.1)");
    });
    match &panel.error {
        Some(e) => {
            ui.colored_label(egui::Color32::LIGHT_RED, e);
        }
        None => {
            ui.label(format!("HTSM frame {:.1} ms (from the first light)", panel.frame_ms));
        }
    }
}
