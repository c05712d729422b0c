//! The viewer's editable state: everything the UI panel changes and the solve depends on, in
//! plain structs. The UI edits a [`ViewState`]; when it differs from the last one sent, the app
//! sends a snapshot to the worker (Mertens §5.5: lighting, material and geometry may all change
//! between frames).

use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::Material;
use lucent_core::bssrdf::ProfileKind;

/// Kind of a light in the lights list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    /// Isotropic point light.
    Point,
    /// Point light restricted to a cone around `direction`.
    Spot,
    /// Distant light travelling along `direction`.
    Directional,
}

impl LightKind {
    /// All kinds, in the order the UI lists them.
    pub const ALL: [LightKind; 3] = [LightKind::Point, LightKind::Spot, LightKind::Directional];

    /// Name shown in the UI.
    pub fn label(self) -> &'static str {
        match self {
            LightKind::Point => "point",
            LightKind::Spot => "spot",
            LightKind::Directional => "directional",
        }
    }
}

/// One light as the UI edits it. Positions are in the viewer's normalised mesh units (the mesh
/// is centred at the origin with a bounding-box extent of 1, see [`super::scene_mesh`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LightSpec {
    /// Point, spot or directional.
    pub kind: LightKind,
    /// Position (point and spot), mesh units.
    pub position: Vec3,
    /// Direction the light travels (spot axis and directional), need not be unit.
    pub direction: Vec3,
    /// Colour, linear RGB in 0..1, multiplied by `power`.
    pub color: Rgb,
    /// Strength: radiant intensity (W/sr, point/spot) or irradiance (W/m^2, directional)
    /// per unit of `color`. > 0.
    pub power: f32,
    /// Spot cone half-angle in degrees (spot only), 1..90.
    pub spot_angle_deg: f32,
}

impl LightSpec {
    /// A white point light at `position` whose irradiance on a surface at the origin facing it
    /// is 1 (so the default exposure shows it without clipping).
    pub fn point(position: Vec3) -> Self {
        LightSpec {
            kind: LightKind::Point,
            position,
            direction: -position,
            color: Rgb::ONE,
            power: position.length_squared().max(0.01),
            spot_angle_deg: 30.0,
        }
    }
}

/// Environment map choice (Mertens §5.3 lights with an HDR environment too).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvChoice {
    /// No environment light.
    None,
    /// `assets/courtyard.exr`.
    Courtyard,
    /// `assets/forest.exr`.
    Forest,
}

impl EnvChoice {
    /// All choices, in UI order.
    pub const ALL: [EnvChoice; 3] = [EnvChoice::None, EnvChoice::Courtyard, EnvChoice::Forest];

    /// Name shown in the UI.
    pub fn label(self) -> &'static str {
        match self {
            EnvChoice::None => "none",
            EnvChoice::Courtyard => "courtyard",
            EnvChoice::Forest => "forest",
        }
    }

    /// The asset file, relative to the repository root, if any (scene files name it so).
    pub fn path(self) -> Option<&'static str> {
        match self {
            EnvChoice::None => None,
            EnvChoice::Courtyard => Some("assets/courtyard.exr"),
            EnvChoice::Forest => Some("assets/forest.exr"),
        }
    }

    /// The map: the probe compiled into the binary (so the viewer works from any directory);
    /// `None` for [`EnvChoice::None`].
    pub fn load(
        self,
    ) -> Option<Result<lucent_core::irradiance::EnvMap, lucent_core::irradiance::EnvMapError>> {
        match self {
            EnvChoice::None => None,
            named => lucent_core::irradiance::EnvMap::builtin(named.label()),
        }
    }
}

/// Solver mode (Mertens §5.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverMode {
    /// Links kept; only irradiance is re-gathered when lighting changes.
    Render,
    /// Links kept and updated (demoted/promoted) after material or geometry changes.
    Incremental,
    /// Full hierarchical evaluation from scratch every solve, no stored links.
    OnTheFly,
}

impl SolverMode {
    /// All modes, in UI order.
    pub const ALL: [SolverMode; 3] = [SolverMode::Render, SolverMode::Incremental, SolverMode::OnTheFly];

    /// Name shown in the UI.
    pub fn label(self) -> &'static str {
        match self {
            SolverMode::Render => "render",
            SolverMode::Incremental => "incremental",
            SolverMode::OnTheFly => "on-the-fly",
        }
    }
}

/// A dent (a bump of negative height) applied where the user clicked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dent {
    /// Centre on the surface, mesh units.
    pub center: Vec3,
    /// Radius of the smooth falloff, mesh units (> 0).
    pub radius: f32,
    /// Displacement along the vertex normal at the centre, mesh units (negative: a dent).
    pub height: f32,
}

/// Geometry edits, applied in order to the undeformed mesh (Mertens figures 6.5–6.8).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Deformations {
    /// Dents, in the order they were made.
    pub dents: Vec<Dent>,
    /// Twist about the vertical (y) axis, radians per mesh unit of height; 0 = none.
    pub twist: f32,
    /// Perlin-noise displacement along the normal, mesh units; 0 = none.
    pub noise_amplitude: f32,
    /// Whether the noise offset advances every frame (figure 6.6).
    pub noise_animated: bool,
    /// Current noise offset (advanced by the app when `noise_animated`), mesh units.
    pub noise_offset: f32,
}

impl Deformations {
    /// True when the mesh is the undeformed input.
    pub fn is_identity(&self) -> bool {
        self.dents.is_empty() && self.twist == 0.0 && self.noise_amplitude == 0.0
    }
}

/// Everything the solve depends on except the geometry itself.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveParams {
    /// Scattering coefficients (mm^-1) and eta; `name` is the preset it started from.
    pub material: Material,
    /// Model scale: the mesh's largest bounding-box side, in metres (> 0).
    pub scale_m: f64,
    /// The lights.
    pub lights: Vec<LightSpec>,
    /// Environment map.
    pub env: EnvChoice,
    /// Environment rotation about the vertical axis, degrees.
    pub env_rotation_deg: f32,
    /// Environment strength multiplier (>= 0).
    pub env_strength: f32,
    /// Solver mode.
    pub mode: SolverMode,
    /// Diffusion profile (default [`ProfileKind::default`]: photon beam diffusion).
    pub profile: ProfileKind,
    /// Whether the single-scattering term is included (pbd, dipole).
    pub single_scattering: bool,
    /// Refinement oracle threshold ε1 at the receiver (`Oracle::eps1`, transport mode: largest
    /// relative change of the transport over a receiver cluster; smaller refines more).
    pub epsilon1: f64,
    /// Refinement oracle threshold ε2 at the emitter (`Oracle::eps2`, transport mode: largest
    /// relative disagreement of an emitter's one-point estimate; smaller refines more).
    pub epsilon2: f64,
    /// Whether lights are shadowed by the mesh.
    pub shadows: bool,
    /// Figure 6.9: the face whose gathered-from clusters are shown, if that view is on (set
    /// from [`ViewState::show_clusters`] and [`ViewState::picked_face`]).
    pub cluster_face: Option<u32>,
}

/// The whole editable state of the viewer.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewState {
    /// Parameters sent with every solve request.
    pub params: SolveParams,
    /// Geometry edits.
    pub deform: Deformations,
    /// Exposure multiplier applied to radiance before the gamma tone curve (> 0).
    pub exposure: f32,
    /// Figure 6.9 view: colour the clusters the picked triangle gathers from by level.
    pub show_clusters: bool,
    /// The triangle picked for the figure 6.9 view.
    pub picked_face: Option<u32>,
    /// What a left-drag on the mesh does.
    pub tool: Tool,
    /// Which method draws the 3D view.
    pub method: ViewMethod,
    /// Settings of the HTSM method.
    pub htsm: super::htsm::HtsmSettings,
    /// The panel's colour-and-distance material editor.
    pub by_colour: ByColour,
}

/// A material as colour and distance, being edited (`Material::from_albedo_mfp`).
#[derive(Clone, Debug, PartialEq)]
pub struct ByColour {
    /// Slab albedo per channel, linear RGB (0.001..=0.999). Default 0.8,
    /// 0.6, 0.4.
    pub albedo: [f32; 3],
    /// Reduced mean free path per channel, mm. Default 1, 0.5, 0.25.
    pub mfp_mm: [f32; 3],
    /// Why the last "apply" was refused.
    pub error: Option<String>,
}

impl Default for ByColour {
    fn default() -> Self {
        ByColour { albedo: [0.8, 0.6, 0.4], mfp_mm: [1.0, 0.5, 0.25], error: None }
    }
}

/// The rendering method of the 3D view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewMethod {
    /// Homogeneous: the hierarchical dipole solve on the CPU (Mertens et al. 2003).
    Mertens,
    /// Heterogeneous: Translucent Shadow Maps with a density volume on the GPU (Shopf 2007).
    Htsm,
}

/// What a left-button drag does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tool {
    /// Orbit the camera.
    Orbit,
    /// Dent the surface under the cursor, deeper the longer the drag.
    Dent,
    /// Pick a triangle for the figure 6.9 view.
    PickTriangle,
}

impl ViewState {
    /// The initial state for a material and model scale, with a key light in front-above and a
    /// back light (translucency shows best lit from behind, Mertens fig. 6.3).
    pub fn new(material: Material, scale_m: f64) -> Self {
        ViewState {
            params: SolveParams {
                material,
                scale_m,
                lights: vec![
                    LightSpec::point(Vec3::new(1.0, 1.1, 1.8)),
                    LightSpec::point(Vec3::new(-0.3, 0.4, -1.5)),
                ],
                env: EnvChoice::None,
                env_rotation_deg: 0.0,
                env_strength: 1.0,
                mode: SolverMode::Render,
                profile: ProfileKind::default(),
                single_scattering: ProfileKind::default().single_scattering_by_default(),
                // The profile's default thresholds (transport oracle), which meet 1% of the
                // exact solve on the bunny.
                epsilon1: lucent_core::solver::Oracle::for_profile(ProfileKind::default()).eps1 as f64,
                epsilon2: lucent_core::solver::Oracle::for_profile(ProfileKind::default()).eps2 as f64,
                shadows: true,
                cluster_face: None,
            },
            deform: Deformations::default(),
            exposure: 1.0,
            show_clusters: false,
            picked_face: None,
            tool: Tool::Orbit,
            method: ViewMethod::Mertens,
            htsm: Default::default(),
            by_colour: ByColour::default(),
        }
    }
}
