//! The viewer's editable state: everything the UI panel changes and the solve depends on, in
//! plain structs. The UI edits a [`ViewState`]; when it differs from the last one sent, the app
//! sends a snapshot to the worker (Mertens §5.5: lighting, material and geometry may all change
//! between frames).

use glam::Vec3;
use lucent_core::bssrdf::Material;
use lucent_core::irradiance::Light;
use lucent_core::mesh::deform::{self, Bump, Noise};
pub use lucent_core::session::SolveMode;
use lucent_core::session::{FrameSettings, Method, Transport};

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

/// Geometry edits, applied in order to the undeformed mesh (Mertens figures 6.5–6.8), in the
/// core's deformation types and units (`lucent_core::mesh::deform`), as `--deform` takes them.
#[derive(Clone, Debug, PartialEq)]
pub struct Deformations {
    /// Dents (bumps of negative height along the vertex normal, mesh units), in the order they
    /// were made.
    pub dents: Vec<Bump>,
    /// Twist about the vertical axis through the centre of the mesh's bounding box, degrees
    /// from its bottom to its top (`lucent_core::mesh::deform::Deformation::Twist`, as
    /// `--deform twist:DEG`); 0 = none.
    pub twist_degrees: f32,
    /// Perlin-noise displacement along the normal ([`Noise`]: amplitude in mesh units, 0 =
    /// none; frequency in noise cells per mesh unit, default 4; `offset` advanced by the app
    /// when `noise_animated`).
    pub noise: Noise,
    /// Whether the noise offset advances every frame (figure 6.6).
    pub noise_animated: bool,
}

impl Default for Deformations {
    fn default() -> Self {
        Deformations {
            dents: Vec::new(),
            twist_degrees: 0.0,
            noise: deform::noise(0.0, NOISE_FREQUENCY, Vec3::ZERO),
            noise_animated: false,
        }
    }
}

/// Spatial frequency of the panel's noise deformation, noise cells per mesh unit (the viewer's
/// mesh has extent 1).
pub const NOISE_FREQUENCY: f32 = 4.0;

impl Deformations {
    /// True when the mesh is the undeformed input.
    pub fn is_identity(&self) -> bool {
        self.dents.is_empty() && self.twist_degrees == 0.0 && self.noise.amplitude == 0.0
    }
}

/// Everything the solve depends on except the geometry itself: the frame session's own
/// [`Transport`] and [`FrameSettings`], and what the viewer turns into its lights, environment
/// and eye.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveParams {
    /// Material (scattering coefficients in mm^-1 and eta; `name` is the preset it started
    /// from), model scale (metres), diffusion profile and single scattering.
    pub transport: Transport,
    /// Always the hierarchical method (the HTSM view draws on the GPU without a solve); the
    /// mode (Mertens §5.5), the oracle (always set: the profile's own at start), the bounces
    /// (0..=4, default [`crate::ranges::DEFAULT_BOUNCES`]) and `environment_shadows`, which is
    /// the panel's "shadows" box: the lights follow it too.
    pub settings: FrameSettings,
    /// The lights, in the viewer's normalised mesh units (the mesh centred with a bounding-box
    /// side of 1).
    pub lights: Vec<Light>,
    /// Environment map.
    pub env: EnvChoice,
    /// Environment rotation about the vertical axis, degrees.
    pub env_rotation_deg: f32,
    /// Environment strength multiplier (>= 0).
    pub env_strength: f32,
    /// The eye (normalised mesh units) that view-ray single scattering is seen from; set from
    /// the camera before each sync (`None` until the first frame).
    pub eye: Option<glam::Vec3>,
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
    /// Where "save material" writes, and what the last save said.
    pub save: SaveTarget,
}

/// Where the panel's "save material" writes a scene file (see `lucent::scene::save`).
#[derive(Clone, Debug, PartialEq)]
pub struct SaveTarget {
    /// The file name to write; an existing file is never overwritten: the next free
    /// `NAME_2.toml`, `NAME_3.toml`, ... is taken instead. Default `lucent_material.toml` in
    /// the working folder, or `SCENE_material.toml` beside a scene file.
    pub path: std::path::PathBuf,
    /// The `mesh` key written (valid relative to `path`'s folder), if known.
    pub mesh: Option<String>,
    /// Times every face of the viewer's mesh was split into four at start (the `refine` key
    /// written, 0..=3), so that the file reads back to the mesh on screen rather than to
    /// whatever `auto` decides for the saved material and scale. Default 0.
    pub refine: u32,
    /// The last save: the path written, or why it failed.
    pub message: Option<Result<String, String>>,
}

impl Default for SaveTarget {
    fn default() -> Self {
        SaveTarget { path: "lucent_material.toml".into(), mesh: None, refine: 0, message: None }
    }
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
    /// The initial state for a material and model scale under `lights` (normalised mesh
    /// units), solved in refit mode (a light move re-gathers as in render mode; a deformation
    /// or a material change refits the links instead of linking again).
    pub fn new(material: Material, scale_m: f64, lights: Vec<Light>) -> Self {
        let htsm = super::htsm::HtsmSettings::for_material(&material, scale_m);
        let transport = Transport::new(material, scale_m);
        let settings = FrameSettings {
            method: Method::Hierarchical,
            mode: SolveMode::Refit,
            // The profile's default thresholds (transport oracle), which meet 1% of the
            // exact solve on the bunny.
            oracle: Some(lucent_core::solver::Oracle::for_profile(transport.profile)),
            environment_shadows: true,
            bounces: crate::ranges::DEFAULT_BOUNCES,
            ablate: Default::default(),
        };
        ViewState {
            params: SolveParams {
                transport,
                settings,
                lights,
                env: EnvChoice::None,
                env_rotation_deg: 0.0,
                env_strength: 1.0,
                eye: None,
                cluster_face: None,
            },
            deform: Deformations::default(),
            exposure: 1.0,
            show_clusters: false,
            picked_face: None,
            tool: Tool::Orbit,
            method: ViewMethod::Mertens,
            htsm,
            by_colour: ByColour::default(),
            save: SaveTarget::default(),
        }
    }
}
