//! The viewer's second method: Heterogeneous Translucent Shadow Maps (Shopf 2007, chapter 4),
//! switchable with the homogeneous Mertens solve in the panel.
//!
//! HTSM needs no CPU solve: [`HtsmPanel::update`] renders the current (deformed) mesh with a
//! density volume through [`lucent_gpu::htsm::HtsmRenderer`] on the viewer's device, from every
//! light and the environment, straight into a GPU texture of the 3D viewport's size that egui
//! draws as a native texture (no read-back). The renderer is made once per mesh topology and
//! volume; a deformation only moves its vertices (the density follows through the rest pose).
//! It re-renders only when something it depends on changed (camera, lights, environment, mesh,
//! settings, viewport size), so an idle window costs nothing.

use super::htsm_tables::{TableBuilder, Tables};
use glam::Vec3;
use lucent_core::bssrdf::Material;
use lucent_core::camera::CameraView;
use lucent_core::irradiance::{Environment, Light};
use lucent_core::mesh::Mesh;
use lucent_core::volume::VolumeSpec;
use lucent_gpu::GpuContext;
use lucent_gpu::htsm::diffusion::DiffusionKey;
use lucent_gpu::htsm::medium::DEFAULT_DENSITY_SIGMA_A;
use lucent_gpu::htsm::{HtsmMedium, HtsmParams, HtsmRenderer, HtsmView, TransportModel, volume_dims_for};
use lucent_gpu::tonemap::ToneMap;
use std::sync::Arc;
use std::time::Instant;

/// Side of the light-view reference images, texels (Shopf §5.2 uses 256^2 maps too).
const REFERENCE_SIZE: u32 = 256;
/// Voxels along the mesh's largest side of the procedural volume.
const VOLUME_RES: u32 = 64;

/// The HTSM settings the panel edits (see [`HtsmParams`] and [`HtsmMedium`] for meanings,
/// units and ranges).
#[derive(Clone, Debug, PartialEq)]
pub struct HtsmSettings {
    /// Density volume spec, as for `lucent render --volume` (`veins`, `cube:0.5`, ...).
    pub volume: String,
    /// The medium HTSM renders (issue 55): the base material's `sigma_s'` and `sigma_a`, the
    /// absorption the density adds, and the object's size. Default: the viewer's material at
    /// its scale with `sigma_d` = [`DEFAULT_DENSITY_SIGMA_A`] mm^-1.
    pub medium: HtsmMedium,
    /// Sampling, transport model and surface parameters; the attenuation comes from `medium`
    /// ([`HtsmMedium::apply`]), `tone` from the viewer's exposure. Default: the `diffusion`
    /// model, phase g 0 (the medium's `sigma_s'` is isotropic).
    pub params: HtsmParams,
    /// The viewer's material and scale (metres) `medium` and `params.eta` were last taken from:
    /// [`HtsmSettings::follow`] takes them again when the viewer's change.
    pub source: (Material, f64),
}

impl HtsmSettings {
    /// The settings for the viewer's material (`sigma_s'`, `sigma_a` in mm^-1) at `scale_m`
    /// metres.
    pub fn for_material(material: &Material, scale_m: f64) -> Self {
        let f = |v: [f64; 3]| Vec3::from(v.map(|x| x as f32));
        HtsmSettings {
            volume: "veins".into(),
            medium: HtsmMedium {
                sigma_s_prime: f(material.sigma_s_prime),
                sigma_a: f(material.sigma_a),
                density_sigma_a: Vec3::splat(DEFAULT_DENSITY_SIGMA_A),
                scale_m: scale_m as f32,
            },
            params: HtsmParams {
                model: TransportModel::Diffusion,
                phase_g: 0.0,
                eta: material.eta as f32,
                ..HtsmParams::default()
            },
            source: (material.clone(), scale_m),
        }
    }

    /// Follows the viewer's material and scale: when they differ from [`HtsmSettings::source`]
    /// (a preset chosen, a coefficient edited, a colour applied, a script's `material:` or
    /// `scale:`), the medium's `sigma_s'`, `sigma_a`, size and the index become theirs; the
    /// density's absorption, the volume and the sampling stay, and so do edits made in the
    /// HTSM panel until the viewer's material or scale next changes. True when it changed.
    pub fn follow(&mut self, material: &Material, scale_m: f64) -> bool {
        if self.source.0 == *material && self.source.1 == scale_m {
            return false;
        }
        let taken = Self::for_material(material, scale_m);
        self.medium = HtsmMedium { density_sigma_a: self.medium.density_sigma_a, ..taken.medium };
        self.params.eta = taken.params.eta;
        self.source = taken.source;
        true
    }

    /// The parameters the renderer takes: `params` with the medium applied.
    pub fn render_params(&self) -> HtsmParams {
        self.medium.apply(self.params)
    }
}

impl Default for HtsmSettings {
    fn default() -> Self {
        Self::for_material(&Material::by_name("skimmilk").expect("a preset"), 0.05)
    }
}

/// HTSM's measured error against a path tracer (Mitsuba 3 `volpathmis` on the same medium),
/// the panel's reminder of how far its image is from ground truth; docs/htsm.md has the table.
pub const MEASURED_ERROR: &str = "HTSM (diffusion) vs path tracer: median error +2.3% / +1.6% \
    lit from the front, +5.8% / +6.4% lit from behind, green -46% / -24% (veined bunny, \
    5 / 2 cm; docs/htsm.md)";

/// Everything an HTSM image depends on, to know when to draw it again.
#[derive(Clone, Debug)]
struct Inputs {
    /// Held (not just its address) so that a freed mesh's address cannot be reused by a new
    /// one and pass for it.
    mesh: Arc<Mesh>,
    volume: String,
    params: HtsmParams,
    camera: CameraView,
    lights: Vec<Light>,
    environment: Option<Environment>,
    size: (u32, u32),
    /// The medium whose diffusion tables the image is drawn with (`None` for the other models).
    tables: Option<DiffusionKey>,
}

impl Inputs {
    /// The same mesh (by identity) and equal everything else.
    fn same_as(&self, other: &Inputs) -> bool {
        Arc::ptr_eq(&self.mesh, &other.mesh)
            && (
                &self.volume,
                &self.params,
                &self.camera,
                &self.lights,
                &self.environment,
                self.size,
                self.tables,
            ) == (
                &other.volume,
                &other.params,
                &other.camera,
                &other.lights,
                &other.environment,
                other.size,
                other.tables,
            )
    }
}

/// The GPU texture HTSM draws into, registered with egui.
struct Target {
    view: wgpu::TextureView,
    id: egui::TextureId,
    size: (u32, u32),
}

/// The texture's format: what egui-wgpu takes for native textures (gamma-encoded bytes,
/// sampled as they are), and what the tone map writes for a PNG.
const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The HTSM renderer of the current mesh and volume, and its last image.
#[derive(Default)]
pub struct HtsmPanel {
    /// The renderer with the topology and volume it was made for.
    renderer: Option<(Vec<[u32; 3]>, String, HtsmRenderer)>,
    /// The positions last uploaded (the renderer's mesh pose).
    positions: Option<Arc<Mesh>>,
    last: Option<Inputs>,
    target: Option<Target>,
    /// CPU time to record and submit the last HTSM frame, milliseconds.
    pub frame_ms: f64,
    /// Why the last draw failed (shown in the panel instead of an image).
    pub error: Option<String>,
    /// The diffusion model's tables, made on their own thread.
    tables: TableBuilder,
    /// Whether the current medium's diffusion tables are still being made (the panel says so:
    /// the image is the last medium's, or none before the first tables come).
    pub making_tables: bool,
}

impl HtsmPanel {
    /// Renders `mesh` with `settings` into the texture when an input changed. `lights` are the
    /// viewer's (normalised mesh units). Errors (a bad volume spec, a parameter out of range, no
    /// light and no environment) are kept in [`HtsmPanel::error`], not returned: the window
    /// stays.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        egui_renderer: &mut egui_wgpu::Renderer,
        mesh: &Arc<Mesh>,
        settings: &HtsmSettings,
        (lights, environment): (&[Light], Option<Environment>),
        camera: CameraView,
        tone: ToneMap,
        size: (u32, u32),
    ) {
        let params = HtsmParams { tone, ..settings.render_params() };
        // The diffusion model's tables: the newest made (drawn with until the medium's own
        // come); none made yet, nothing to draw with: the last image stays.
        let key = DiffusionKey::of(&params);
        let tables = key.and_then(|key| self.tables.get(key).cloned());
        self.making_tables = key.is_some() && self.tables.building();
        if key.is_some() && tables.is_none() {
            return;
        }
        let inputs = Inputs {
            mesh: mesh.clone(),
            volume: settings.volume.clone(),
            params,
            camera,
            lights: lights.to_vec(),
            environment,
            size: (size.0.max(1), size.1.max(1)),
            tables: tables.as_ref().map(|t| t.0),
        };
        if self.last.as_ref().is_some_and(|last| last.same_as(&inputs)) {
            return;
        }
        self.last = Some(inputs.clone());
        self.error = self.draw(ctx, egui_renderer, &inputs, tables).err().map(|e| format!("{e:#}"));
    }

    /// Whether the diffusion tables of the medium asked for are still being made (the panel
    /// then draws again when they come).
    pub fn building(&mut self) -> bool {
        self.tables.building()
    }

    fn draw(
        &mut self,
        ctx: &GpuContext,
        egui_renderer: &mut egui_wgpu::Renderer,
        inputs: &Inputs,
        tables: Option<Tables>,
    ) -> anyhow::Result<()> {
        inputs.params.validate()?;
        let mesh = &inputs.mesh;
        let stale = !matches!(&self.renderer, Some((t, v, _)) if *t == mesh.triangles && *v == inputs.volume);
        if stale {
            self.renderer = None;
            let spec: VolumeSpec = inputs.volume.parse()?;
            let volume = spec.build(volume_dims_for(mesh, VOLUME_RES))?;
            let renderer = HtsmRenderer::new(ctx, mesh, &volume, REFERENCE_SIZE)?;
            self.renderer = Some((mesh.triangles.clone(), inputs.volume.clone(), renderer));
            self.positions = Some(mesh.clone());
        }
        let (_, _, renderer) = self.renderer.as_mut().expect("made above");
        // Tables come from the table thread only: a frame never makes them.
        renderer.set_make_tables(false);
        if let Some((key, u)) = tables {
            renderer.set_diffusion_tables(key, *u);
        }
        if !self.positions.as_ref().is_some_and(|p| Arc::ptr_eq(p, mesh)) {
            renderer.set_positions(ctx, &mesh.positions)?;
            self.positions = Some(mesh.clone());
        }
        let target = ensure_target(&mut self.target, ctx, egui_renderer, inputs.size);
        let view = HtsmView {
            camera: inputs.camera,
            lights: inputs.lights.clone(),
            environment: inputs.environment,
            width: inputs.size.0,
            height: inputs.size.1,
        };
        let t = Instant::now();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        renderer.encode_into(ctx, &mut encoder, &target.view, TARGET_FORMAT, &view, &inputs.params)?;
        ctx.queue.submit([encoder.finish()]);
        self.frame_ms = t.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// The last HTSM image, if there is one.
    pub fn texture(&self) -> Option<egui::TextureId> {
        self.target.as_ref().filter(|_| self.error.is_none()).map(|t| t.id)
    }
}

/// The target texture of `size`, made (or remade, keeping its egui id) when the size changed.
fn ensure_target<'a>(
    target: &'a mut Option<Target>,
    ctx: &GpuContext,
    egui_renderer: &mut egui_wgpu::Renderer,
    size: (u32, u32),
) -> &'a Target {
    if target.as_ref().is_none_or(|t| t.size != size) {
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("lucent viewer htsm"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TARGET_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let filter = wgpu::FilterMode::Linear;
        let id = match target.take() {
            Some(old) => {
                egui_renderer.update_egui_texture_from_wgpu_texture(&ctx.device, &view, filter, old.id);
                old.id
            }
            None => egui_renderer.register_native_texture(&ctx.device, &view, filter),
        };
        *target = Some(Target { view, id, size });
    }
    target.as_ref().expect("made above")
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
    let m = &mut s.medium;
    coefficient_row(ui, "sigma_s' (mm^-1)", &mut m.sigma_s_prime, 0.01..=10.0);
    coefficient_row(ui, "sigma_a (mm^-1)", &mut m.sigma_a, 0.0..=10.0);
    let mut d = m.density_sigma_a.max_element();
    if ui
        .add(Slider::new(&mut d, 0.0..=10.0).logarithmic(true).text("density sigma_a (mm^-1)"))
        .on_hover_text("absorption the density volume adds at density 1: sigma_a + density x this")
        .changed()
    {
        m.density_sigma_a = Vec3::splat(d);
    }
    ui.add(Slider::new(&mut m.scale_m, 0.005..=1.0).logarithmic(true).text("size (m)"));
    ui.add(Slider::new(&mut p.phase_g, -0.9..=0.9).text("phase g"));
    ui.horizontal(|ui| {
        ui.radio_value(&mut p.model, TransportModel::Diffusion, "diffusion");
        ui.radio_value(&mut p.model, TransportModel::BeerLambert, "beer-lambert");
        ui.radio_value(&mut p.model, TransportModel::Thesis, "thesis (table 4.1)");
    });
    ui.label(MEASURED_ERROR);
    if panel.making_tables {
        ui.label("making the diffusion tables of this medium (a few seconds): the last ones draw until then");
    }
    match &panel.error {
        Some(e) => {
            ui.colored_label(egui::Color32::LIGHT_RED, e);
        }
        None => {
            ui.label(format!("HTSM frame {:.1} ms (every light and the environment)", panel.frame_ms));
        }
    }
}

/// One medium coefficient per RGB channel, mm^-1, in `range` (logarithmic drag values).
fn coefficient_row(ui: &mut egui::Ui, label: &str, v: &mut Vec3, range: std::ops::RangeInclusive<f32>) {
    ui.horizontal(|ui| {
        let mut c = v.to_array();
        for x in &mut c {
            ui.add(egui::DragValue::new(x).range(range.clone()).speed(0.001).max_decimals(4));
        }
        *v = Vec3::from(c);
        ui.label(label);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_medium_follows_a_later_material_and_scale() {
        let skim = Material::by_name("skimmilk").unwrap();
        let marble = Material::by_name("marble").unwrap();
        let mut s = HtsmSettings::for_material(&skim, 0.05);
        assert!(!s.follow(&skim, 0.05), "nothing changed");
        // An edit in the HTSM panel stays while the viewer's material does not change.
        s.medium.density_sigma_a = Vec3::splat(2.0);
        s.medium.sigma_a.x = 1.0;
        assert!(!s.follow(&skim, 0.05));
        assert_eq!(s.medium.sigma_a.x, 1.0);
        // A new preset: its coefficients and index; the density's absorption stays.
        assert!(s.follow(&marble, 0.05));
        let want = HtsmSettings::for_material(&marble, 0.05);
        assert_eq!(s.medium.sigma_s_prime, want.medium.sigma_s_prime);
        assert_eq!(s.medium.sigma_a, want.medium.sigma_a);
        assert_eq!(s.params.eta, marble.eta as f32);
        assert_eq!(s.medium.density_sigma_a, Vec3::splat(2.0));
        // A new scale: the medium's size.
        assert!(s.follow(&marble, 0.2));
        assert_eq!(s.medium.scale_m, 0.2);
        assert_eq!(s.render_params(), HtsmSettings { medium: s.medium, ..want.clone() }.render_params());
    }
}
