//! A glTF material's subsurface extensions mapped onto lucent's material (issue 18, part 4).
//!
//! Precedence: a material given explicitly (`--material`, `--albedo`/`--mfp`, or a scene file's
//! `material` key) wins over the glTF file's extensions, which win over the default material
//! (skim milk). A glTF material with none of `KHR_materials_volume`,
//! `KHR_materials_diffuse_transmission` or `KHR_materials_volume_scatter` leaves the default.
//!
//! The mapping, per RGB channel (lucent takes a slab albedo and a reduced mean free path, and
//! inverts them with [`Material::from_albedo_mfp`]):
//!
//! - **albedo**: `KHR_materials_volume_scatter`'s `multiscatterColor` (the multi-scatter albedo
//!   of Kulla and Conty 2017, the colour the medium shows after many bounces: what lucent's slab
//!   albedo means); without it, `baseColorFactor` (the colour the lit side shows). Clamped into
//!   0.001..=0.999.
//! - **distance**: `KHR_materials_volume`'s attenuation, `sigma_t = -ln(attenuationColor) /
//!   attenuationDistance` per mesh unit. With `KHR_materials_volume_scatter`, the
//!   single-scatter albedo `rho_ss` follows from `multiscatterColor` by the draft's formula
//!   and the reduced extinction is `sigma_t (1 - g rho_ss)` (`g` = `scatterAnisotropy`);
//!   without it the whole attenuation is taken as extinction (`KHR_materials_volume` alone
//!   declares no scattering, which a subsurface renderer cannot draw). The mean free path is its
//!   inverse, converted to mm with the model's scale (so the look stays the same at any
//!   `--scale`), clamped into 0.0001..=1000 mm. Without a finite `attenuationDistance` the
//!   default material's mean free path is kept.
//! - **eta**: `KHR_materials_ior`'s `ior`, else glTF's default 1.5, clamped into 1..=3.
//! - Not modelled, and said so: `diffuseTransmissionFactor` and `diffuseTransmissionColorFactor`
//!   (and their textures: how translucent an object looks follows from the distance and the
//!   scale), `thicknessFactor` (lucent has the mesh itself), and materials after the first.

use anyhow::Result;
use lucent_core::bssrdf::{ALBEDO, MEAN_FREE_PATH_MM, Material};
use lucent_core::mesh::GltfMaterial;

/// glTF's default index of refraction (core specification, `KHR_materials_ior`).
pub const GLTF_DEFAULT_IOR: f64 = 1.5;

/// What a glTF material became.
#[derive(Clone, Debug, PartialEq)]
pub struct MappedMaterial {
    /// The material (named `glTF material N`).
    pub material: Material,
    /// Slab albedo per linear RGB channel (unitless, 0.001..=0.999), as requested of
    /// [`Material::from_albedo_mfp`].
    pub albedo: [f64; 3],
    /// Reduced mean free path `1 / sigma_t'` per channel, mm (0.0001..=1000).
    pub mfp_mm: [f64; 3],
    /// One line: where each value came from and what was approximated.
    pub note: String,
}

/// The draft `KHR_materials_volume_scatter`'s single-scatter albedo for a multi-scatter albedo
/// (Kulla and Conty 2017), clamped to 0..=1.
pub fn single_scatter_albedo(multiscatter: f64) -> f64 {
    let a = multiscatter;
    let root = (9.59217 + 41.6808 * a + 17.7126 * a * a).sqrt();
    (1.0 - (4.09712 + 4.20863 * a - root).powi(2)).clamp(0.0, 1.0)
}

/// Maps `g` onto a material (see the module docs). `mm_per_unit`: millimetres per mesh unit at
/// the scene's scale; `fallback`: the default material, whose mean free path is kept when the
/// file gives no distance. `None` when the material has no subsurface extension.
pub fn map(g: &GltfMaterial, mm_per_unit: f64, fallback: &Material) -> Result<Option<MappedMaterial>> {
    if !g.has_subsurface_extension() {
        return Ok(None);
    }
    let mut notes: Vec<String> = Vec::new();
    let (albedo_in, albedo_from) = match &g.volume_scatter {
        Some(s) => (s.multiscatter_color, "KHR_materials_volume_scatter multiscatterColor"),
        None => (g.base_color, "baseColorFactor"),
    };
    let albedo = albedo_in.map(|a| a.clamp(*ALBEDO.start(), *ALBEDO.end()));
    notes.push(format!("albedo {} from {albedo_from}{}", join3(albedo), clamped(albedo_in, albedo)));

    let attenuation = g.volume.as_ref().filter(|v| v.attenuation_distance.is_finite());
    let mfp_mm = match attenuation {
        Some(v) => {
            let g_aniso = g.volume_scatter.as_ref().map_or(0.0, |s| s.anisotropy);
            let reduced: [f64; 3] = std::array::from_fn(|c| {
                let sigma_t = -v.attenuation_color[c].ln() / v.attenuation_distance;
                let rho_ss =
                    g.volume_scatter.as_ref().map_or(0.0, |s| single_scatter_albedo(s.multiscatter_color[c]));
                sigma_t * (1.0 - g_aniso * rho_ss)
            });
            let raw = reduced.map(|s| mm_per_unit / s);
            let mfp = raw.map(|d| {
                if d.is_nan() {
                    *MEAN_FREE_PATH_MM.end()
                } else {
                    d.clamp(*MEAN_FREE_PATH_MM.start(), *MEAN_FREE_PATH_MM.end())
                }
            });
            let how = match &g.volume_scatter {
                Some(s) => format!("reduced by scatterAnisotropy {}", s.anisotropy),
                None => "all attenuation taken as extinction (no KHR_materials_volume_scatter)".to_string(),
            };
            notes.push(format!(
                "mfp {} mm from KHR_materials_volume attenuationColor {} over attenuationDistance {} units ({how}){}",
                join3(mfp),
                join3(v.attenuation_color),
                num(v.attenuation_distance),
                clamped(raw, mfp)
            ));
            mfp
        }
        None => {
            let (_, mfp) = fallback.albedo_mfp();
            notes.push(format!(
                "mfp {} mm kept from the default {} (no finite KHR_materials_volume attenuationDistance)",
                join3(mfp),
                fallback.name
            ));
            mfp
        }
    };

    let ior = g.ior.unwrap_or(GLTF_DEFAULT_IOR);
    let eta = if ior == 0.0 { 3.0 } else { ior.clamp(1.0, 3.0) };
    let from = if g.ior.is_some() { "KHR_materials_ior" } else { "glTF's default" };
    notes.push(format!(
        "eta {eta} from {from}{}",
        if eta != ior { format!(" (ior {ior} clamped to 1..=3)") } else { String::new() }
    ));

    if let Some(dt) = &g.diffuse_transmission {
        notes.push(format!(
            "diffuseTransmissionFactor {} and color {}{} not modelled (translucency follows from mfp and scale)",
            dt.factor,
            join3(dt.color),
            if dt.textured { " and their textures" } else { "" }
        ));
    }
    if let Some(v) = g.volume.as_ref().filter(|v| v.thickness > 0.0) {
        notes.push(format!("thicknessFactor {} ignored (the mesh is the volume)", num(v.thickness)));
    }
    if g.count > 1 {
        notes.push(format!("first of {} materials used for the whole mesh", g.count));
    }
    let name = format!("glTF material {}", g.index);
    let material = Material::from_albedo_mfp(&name, albedo, mfp_mm, eta)?;
    let note = format!("{name}: {}", notes.join("; "));
    Ok(Some(MappedMaterial { material, albedo, mfp_mm, note }))
}

/// A number for the note: four decimals, or two significant figures below 0.01 (glTF's numbers
/// are `f32`: `0.1` arrives as `0.10000000149...`).
fn num(x: f64) -> String {
    match x {
        x if x != 0.0 && x.abs() < 0.01 => format!("{x:.1e}"),
        x => format!("{}", (x * 1e4).round() / 1e4),
    }
}

/// Three numbers as [`num`] writes them.
fn join3(v: [f64; 3]) -> String {
    v.map(num).join(",")
}

fn clamped(before: [f64; 3], after: [f64; 3]) -> String {
    if before == after { String::new() } else { format!(" (clamped from {})", join3(before)) }
}
