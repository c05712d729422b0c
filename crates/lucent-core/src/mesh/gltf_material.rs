//! What a glTF material says about light under its surface (issue 18), read and checked:
//! `pbrMetallicRoughness.baseColorFactor`, `KHR_materials_volume`,
//! `KHR_materials_diffuse_transmission`, the draft `KHR_materials_volume_scatter` and
//! `KHR_materials_ior`. Mapping these onto a scattering material is the caller's business
//! (`lucent::scene`, which says what it approximated); this module only reports the values the
//! file gives, with the extensions' defaults for absent properties.
//!
//! A value outside its extension's range (a negative distance, a colour component outside
//! 0..=1, an anisotropy outside -1..1, anything not a number) is a one-line error naming the
//! file, the material, the property and the value. JSON has no NaN or infinity, so a file
//! holding one is not valid JSON and fails as such.

use super::MeshError;
use super::error::guard;
use gltf::json::Value;
use std::path::Path;

/// `KHR_materials_volume` of a material.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfVolume {
    /// `attenuationColor`: the colour (linear RGB, each 0..=1) white light becomes after
    /// travelling `attenuation_distance` through the medium. Default `[1, 1, 1]`.
    pub attenuation_color: [f64; 3],
    /// `attenuationDistance`: mesh units (glTF: metres before the node transforms), > 0;
    /// `+inf` when absent (the extension's default: no attenuation).
    pub attenuation_distance: f64,
    /// `thicknessFactor`: thickness of the volume under the surface, mesh units, >= 0
    /// (0: thin-walled). Default 0.
    pub thickness: f64,
}

/// `KHR_materials_diffuse_transmission` of a material.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfDiffuseTransmission {
    /// `diffuseTransmissionFactor`: share of the diffuse light transmitted through the
    /// surface, 0..=1. Default 0.
    pub factor: f64,
    /// `diffuseTransmissionColorFactor`: colour of the transmitted light, linear RGB, each
    /// 0..=1. Default `[1, 1, 1]`.
    pub color: [f64; 3],
    /// Whether `diffuseTransmissionTexture` or `diffuseTransmissionColorTexture` is given.
    pub textured: bool,
}

/// The draft `KHR_materials_volume_scatter` of a material.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfVolumeScatter {
    /// `multiscatterColor`: the multi-scatter albedo (Kulla and Conty 2017), the colour the
    /// medium shows after many bounces, linear RGB, each 0..=1. Default `[0, 0, 0]`.
    pub multiscatter_color: [f64; 3],
    /// `scatterAnisotropy`: Henyey-Greenstein `g`, -1 < g < 1. Default 0.
    pub anisotropy: f64,
}

/// The subsurface-related parts of one glTF material.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfMaterial {
    /// Which material of the file this is (its index in `materials`).
    pub index: usize,
    /// How many materials the file has.
    pub count: usize,
    /// `pbrMetallicRoughness.baseColorFactor`, RGB (linear, each 0..=1). Default `[1, 1, 1]`.
    pub base_color: [f64; 3],
    /// `KHR_materials_volume`, when present.
    pub volume: Option<GltfVolume>,
    /// `KHR_materials_diffuse_transmission`, when present.
    pub diffuse_transmission: Option<GltfDiffuseTransmission>,
    /// `KHR_materials_volume_scatter` (draft), when present.
    pub volume_scatter: Option<GltfVolumeScatter>,
    /// `KHR_materials_ior`'s `ior` (glTF: 1 or more, or 0 for an infinite index), when present.
    pub ior: Option<f64>,
}

impl GltfMaterial {
    /// Whether any extension that describes light under the surface is present.
    pub fn has_subsurface_extension(&self) -> bool {
        self.volume.is_some() || self.diffuse_transmission.is_some() || self.volume_scatter.is_some()
    }
}

/// The first material of a glTF/GLB file (the one lucent renders the whole mesh with), or
/// `None` when the file has no material. Errors are one line naming the file.
pub fn load_gltf_material(path: &Path) -> Result<Option<GltfMaterial>, MeshError> {
    let name = path.display().to_string();
    let bytes = crate::limits::read_input(path).map_err(|reason| MeshError::invalid(&name, reason))?;
    parse_gltf_material(&bytes, &name)
}

/// [`load_gltf_material`] on glTF JSON or GLB bytes held in memory; `name` stands for the file
/// in messages.
pub fn parse_gltf_material(bytes: &[u8], name: &str) -> Result<Option<GltfMaterial>, MeshError> {
    guard(name, || {
        let gltf = super::io_gltf::read_gltf(bytes).map_err(|reason| MeshError::invalid(name, reason))?;
        let count = gltf.document.materials().len();
        match gltf.document.materials().next() {
            Some(m) => read_material(&m, count).map(Some).map_err(|reason| MeshError::invalid(name, reason)),
            None => Ok(None),
        }
    })?
}

fn read_material(m: &gltf::Material<'_>, count: usize) -> Result<GltfMaterial, String> {
    let index = m.index().unwrap_or(0);
    let at = |what: &str| format!("material {index} {what}");
    let [r, g, b, _] = m.pbr_metallic_roughness().base_color_factor();
    let base_color = unit_colour(&at("baseColorFactor"), [r, g, b].map(f64::from))?;
    let volume = match m.volume() {
        Some(v) => {
            let ext = "KHR_materials_volume";
            let attenuation_color =
                unit_colour(&at(&format!("{ext} attenuationColor")), v.attenuation_color().map(f64::from))?;
            let attenuation_distance = f64::from(v.attenuation_distance());
            if attenuation_distance.is_nan() || attenuation_distance <= 0.0 {
                return Err(format!(
                    "{} {attenuation_distance} must be > 0",
                    at(&format!("{ext} attenuationDistance"))
                ));
            }
            let thickness = f64::from(v.thickness_factor());
            if !(thickness >= 0.0 && thickness.is_finite()) {
                return Err(format!("{} {thickness} must be >= 0", at(&format!("{ext} thicknessFactor"))));
            }
            Some(GltfVolume { attenuation_color, attenuation_distance, thickness })
        }
        None => None,
    };
    let diffuse_transmission = match m.extension_value("KHR_materials_diffuse_transmission") {
        Some(v) => {
            let at = |p: &str| at(&format!("KHR_materials_diffuse_transmission {p}"));
            let factor = field(v, "diffuseTransmissionFactor", &at)?.unwrap_or(0.0);
            if !(0.0..=1.0).contains(&factor) {
                return Err(format!("{} {factor} must be within 0..=1", at("diffuseTransmissionFactor")));
            }
            let color = colour_field(v, "diffuseTransmissionColorFactor", &at)?.unwrap_or([1.0; 3]);
            let textured = ["diffuseTransmissionTexture", "diffuseTransmissionColorTexture"]
                .iter()
                .any(|k| v.get(k).is_some());
            Some(GltfDiffuseTransmission { factor, color, textured })
        }
        None => None,
    };
    let volume_scatter = match m.extension_value("KHR_materials_volume_scatter") {
        Some(v) => {
            let at = |p: &str| at(&format!("KHR_materials_volume_scatter {p}"));
            let multiscatter_color = colour_field(v, "multiscatterColor", &at)?.unwrap_or([0.0; 3]);
            let anisotropy = field(v, "scatterAnisotropy", &at)?.unwrap_or(0.0);
            if !(anisotropy > -1.0 && anisotropy < 1.0) {
                return Err(format!(
                    "{} {anisotropy} must be within -1..1 (exclusive)",
                    at("scatterAnisotropy")
                ));
            }
            Some(GltfVolumeScatter { multiscatter_color, anisotropy })
        }
        None => None,
    };
    let ior = match m.extension_value("KHR_materials_ior") {
        Some(v) => {
            let ior = field(v, "ior", &|p: &str| at(&format!("KHR_materials_ior {p}")))?.unwrap_or(1.5);
            if !(ior == 0.0 || ior >= 1.0) {
                return Err(format!("{} {ior} must be 0 or at least 1", at("KHR_materials_ior ior")));
            }
            Some(ior)
        }
        None => None,
    };
    Ok(GltfMaterial { index, count, base_color, volume, diffuse_transmission, volume_scatter, ior })
}

/// An extension's object, checked to be one, then its number property `key` (if present).
fn field(ext: &Value, key: &str, at: &dyn Fn(&str) -> String) -> Result<Option<f64>, String> {
    object(ext, at)?;
    match ext.get(key) {
        None => Ok(None),
        Some(v) => v.as_f64().map(Some).ok_or_else(|| format!("{} {} is not a number", at(key), short(v))),
    }
}

/// A colour property `key`: three numbers, each 0..=1.
fn colour_field(ext: &Value, key: &str, at: &dyn Fn(&str) -> String) -> Result<Option<[f64; 3]>, String> {
    object(ext, at)?;
    let Some(v) = ext.get(key) else { return Ok(None) };
    let numbers: Option<Vec<f64>> = v.as_array().map(|a| a.iter().filter_map(Value::as_f64).collect());
    match numbers {
        Some(n) if n.len() == 3 && v.as_array().is_some_and(|a| a.len() == 3) => {
            unit_colour(&at(key), [n[0], n[1], n[2]]).map(Some)
        }
        _ => Err(format!("{} {} must be an array of three numbers", at(key), short(v))),
    }
}

fn object(ext: &Value, at: &dyn Fn(&str) -> String) -> Result<(), String> {
    match ext.is_object() {
        true => Ok(()),
        false => Err(format!("{} must be a JSON object, got {}", at("(the extension)"), short(ext))),
    }
}

fn unit_colour(what: &str, c: [f64; 3]) -> Result<[f64; 3], String> {
    match c.iter().find(|x| !(0.0..=1.0).contains(*x)) {
        Some(bad) => Err(format!("{what} {c:?} has component {bad} outside 0..=1")),
        None => Ok(c),
    }
}

/// A JSON value for a message, at most 60 characters.
fn short(v: &Value) -> String {
    let s = v.to_string();
    match s.char_indices().nth(60) {
        Some((k, _)) => format!("{}...", &s[..k]),
        None => s,
    }
}
