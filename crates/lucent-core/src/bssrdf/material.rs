//! Measured scattering materials (Jensen et al. 2001, table in lucent's REFERENCE notes; the
//! same numbers as pbrt-v4's `media.cpp`) and user-defined ones.

use super::beam_diffusion::EffectiveAlbedo;

/// A homogeneous scattering material for the dipole model.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Display name (matching is case-insensitive).
    pub name: String,
    /// Reduced scattering coefficient `sigma_s'` per RGB channel, in mm^-1 (> 0).
    pub sigma_s_prime: [f64; 3],
    /// Absorption coefficient `sigma_a` per RGB channel, in mm^-1 (> 0; a material that absorbs
    /// nothing has no finite diffusion length).
    pub sigma_a: [f64; 3],
    /// Relative index of refraction (unitless, 1..2 for the Fresnel fits; 1.3 for the table).
    pub eta: f64,
}

/// Why a material was rejected.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MaterialError {
    #[error("unknown material '{name}'; known materials: {known}")]
    Unknown { name: String, known: String },
    #[error(
        "material '{name}': {what} must be within {MIN_SIGMA}..={MAX_SIGMA} mm^-1 in every channel, got {values:?}"
    )]
    OutOfRange { name: String, what: &'static str, values: [f64; 3] },
    #[error("material '{name}': eta must be finite and within 1.0..=3.0, got {eta}")]
    BadEta { name: String, eta: f64 },
    #[error("material '{name}': albedo {value} is outside the accepted range {min}..={max} at eta {eta}")]
    Albedo { name: String, value: f64, min: f64, max: f64, eta: f64 },
    #[error("material '{name}': mean free path {value} mm is outside the accepted range {min}..={max} mm")]
    MeanFreePath { name: String, value: f64, min: f64, max: f64 },
}

/// Slab albedos [`Material::from_albedo_mfp`] accepts (unitless). Below 0.001 a channel is
/// black to any display; 0.999 is as white as a slab that absorbs gets.
pub const ALBEDO: std::ops::RangeInclusive<f64> = 1e-3..=0.999;
/// Reduced mean free paths [`Material::from_albedo_mfp`] accepts, mm: from 0.1 micrometre
/// (`sigma_t' =` `MAX_SIGMA`) to a metre, where both coefficients of any accepted albedo stay
/// at or above `MIN_SIGMA` for every `eta` up to 3 (albedo 0.999 at eta 3 needs
/// `1 - rho' = 1e-9`).
pub const MEAN_FREE_PATH_MM: std::ops::RangeInclusive<f64> = 1e-4..=1e3;

/// The smallest coefficient accepted, mm^-1 (a mean free path of a million km: no absorption
/// or scattering, for any object lucent renders).
pub const MIN_SIGMA: f64 = 1e-12;
/// The largest coefficient accepted, mm^-1: a mean free path of 0.1 micrometre, below the
/// wavelength of light, where diffusion (and this renderer) has nothing left to show.
pub const MAX_SIGMA: f64 = 1e4;

/// One row of the preset table: name, `sigma_s'` (mm^-1), `sigma_a` (mm^-1).
type Row = (&'static str, [f64; 3], [f64; 3]);

/// The presets: Jensen et al. 2001 measured materials (eta 1.3) plus candle wax.
pub const PRESETS: &[Row] = &[
    ("Apple", [2.29, 2.39, 1.97], [0.0030, 0.0034, 0.046]),
    ("Chicken1", [0.15, 0.21, 0.38], [0.015, 0.077, 0.19]),
    ("Chicken2", [0.19, 0.25, 0.32], [0.018, 0.088, 0.20]),
    ("Cream", [7.38, 5.47, 3.15], [0.0002, 0.0028, 0.0163]),
    ("Ketchup", [0.18, 0.07, 0.03], [0.061, 0.97, 1.45]),
    ("Marble", [2.19, 2.62, 3.00], [0.0021, 0.0041, 0.0071]),
    ("Potato", [0.68, 0.70, 0.55], [0.0024, 0.0090, 0.12]),
    ("Skimmilk", [0.70, 1.22, 1.90], [0.0014, 0.0025, 0.0142]),
    ("Skin1", [0.74, 0.88, 1.01], [0.032, 0.17, 0.48]),
    ("Skin2", [1.09, 1.59, 1.79], [0.013, 0.070, 0.145]),
    ("Wholemilk", [2.55, 3.21, 3.77], [0.0011, 0.0024, 0.014]),
    // Candle wax is not in Jensen's table and no measured RGB dipole coefficients for it are
    // published that we could verify. These are *plausible* values, chosen so that paraffin
    // behaves as Mertens fig. 6.3 shows: a mean free path near 1 mm (sigma_s' about 1 mm^-1, in
    // the range reported for paraffin tissue phantoms in biomedical optics) and absorption
    // rising towards blue for the warm, yellowish glow of candles. Replace them with measured
    // numbers when you have them.
    ("Wax", [1.00, 0.95, 0.85], [0.0020, 0.0080, 0.0300]),
];

impl Material {
    /// A preset by name, case-insensitively (`"skimmilk"`, `"Marble"`, `"wax"`; `"candlewax"`
    /// and `"candle-wax"` are accepted for `Wax`).
    pub fn by_name(name: &str) -> Result<Material, MaterialError> {
        let wanted = name.trim().to_ascii_lowercase().replace(['-', '_', ' '], "");
        let wanted = if wanted == "candlewax" { "wax".to_string() } else { wanted };
        PRESETS
            .iter()
            .find(|(n, _, _)| n.to_ascii_lowercase() == wanted)
            .map(|&(n, s, a)| Material { name: n.to_string(), sigma_s_prime: s, sigma_a: a, eta: 1.3 })
            .ok_or_else(|| MaterialError::Unknown {
                name: name.to_string(),
                known: PRESETS.iter().map(|r| r.0).collect::<Vec<_>>().join(", "),
            })
    }

    /// A user-defined material, validated.
    pub fn custom(
        name: &str,
        sigma_s_prime: [f64; 3],
        sigma_a: [f64; 3],
        eta: f64,
    ) -> Result<Material, MaterialError> {
        let m = Material { name: name.to_string(), sigma_s_prime, sigma_a, eta };
        m.validate()?;
        Ok(m)
    }

    /// A material from what an artist gives (Blender's Principled BSDF, Unreal, Arnold): the
    /// colour a flat, thick slab of it shows under uniform light, and how far light goes in it.
    ///
    /// - `albedo`: per channel, the slab's subsurface albedo, exitant radiosity over the
    ///   irradiance that entered (the surface's own Fresnel reflection excluded), unitless, in
    ///   [`albedo_range`]`(eta)` ([`ALBEDO`], 0.001..=0.999, for `eta` up to about 1.85).
    /// - `mfp_mm`: per channel, the reduced mean free path `1 / sigma_t'`, mm, in
    ///   [`MEAN_FREE_PATH_MM`] (0.0001..=1e3).
    /// - `eta`: relative index of refraction, 1..=3 (1.3 for the presets).
    ///
    /// Each channel's single-scattering albedo `rho' = sigma_s' / sigma_t'` is the one whose
    /// effective albedo under the default profile (calibrated photon beam diffusion, multiple
    /// plus single scattering: the exact half-space albedo at normal incidence,
    /// [`super::beam_diffusion::EffectiveAlbedo`]) is `albedo`; then
    /// `sigma_s' = rho' / mfp` and `sigma_a = (1 - rho') / mfp`. (pbrt-v3's
    /// `SubsurfaceFromDiffuse` does the same with its own table.)
    pub fn from_albedo_mfp(
        name: &str,
        albedo: [f64; 3],
        mfp_mm: [f64; 3],
        eta: f64,
    ) -> Result<Material, MaterialError> {
        if !eta.is_finite() || !(1.0..=3.0).contains(&eta) {
            return Err(MaterialError::BadEta { name: name.to_string(), eta });
        }
        if let Some(&value) = mfp_mm.iter().find(|d| !MEAN_FREE_PATH_MM.contains(*d)) {
            let (min, max) = (*MEAN_FREE_PATH_MM.start(), *MEAN_FREE_PATH_MM.end());
            return Err(MaterialError::MeanFreePath { name: name.to_string(), value, min, max });
        }
        let table = effective_albedo_table(eta);
        let (lo, hi) = albedo_range_of(&table);
        let mut sigma_s_prime = [0.0; 3];
        let mut sigma_a = [0.0; 3];
        for c in 0..3 {
            let rho = Some(albedo[c])
                .filter(|a| (lo..=hi).contains(a))
                .and_then(|a| table.invert_exact(a))
                .ok_or_else(|| MaterialError::Albedo {
                name: name.to_string(),
                value: albedo[c],
                min: lo,
                max: hi,
                eta,
            })?;
            // Keep both coefficients at or above MIN_SIGMA where the profile needs a single-
            // scattering albedo within 1e-6 of 1 (eta near 1.8 and above); `max`/`min`, unlike
            // `clamp`, cannot panic, and `validate` has the last word.
            let floor = MIN_SIGMA * mfp_mm[c];
            let rho = rho.min(1.0 - floor).max(floor);
            sigma_s_prime[c] = rho / mfp_mm[c];
            sigma_a[c] = (1.0 - rho) / mfp_mm[c];
        }
        Material::custom(name, sigma_s_prime, sigma_a, eta)
    }

    /// The artist's view of this material (see [`Material::from_albedo_mfp`]): per channel the
    /// slab albedo under the default profile, and the reduced mean free path `1 / sigma_t'` in mm.
    pub fn albedo_mfp(&self) -> ([f64; 3], [f64; 3]) {
        let mut albedo = [0.0; 3];
        let mut mfp = [0.0; 3];
        for c in 0..3 {
            let sigma_t = self.sigma_s_prime[c] + self.sigma_a[c];
            albedo[c] = super::beam_diffusion::calibrated_albedo(self.sigma_s_prime[c] / sigma_t, self.eta);
            mfp[c] = 1.0 / sigma_t;
        }
        (albedo, mfp)
    }

    /// Checks that every coefficient is within `MIN_SIGMA..=MAX_SIGMA` mm^-1 and `eta` in 1..=3.
    pub fn validate(&self) -> Result<(), MaterialError> {
        let bad = |v: &[f64; 3]| v.iter().any(|x| !(MIN_SIGMA..=MAX_SIGMA).contains(x));
        if bad(&self.sigma_s_prime) {
            return Err(MaterialError::OutOfRange {
                name: self.name.clone(),
                what: "sigma_s'",
                values: self.sigma_s_prime,
            });
        }
        if bad(&self.sigma_a) {
            return Err(MaterialError::OutOfRange {
                name: self.name.clone(),
                what: "sigma_a",
                values: self.sigma_a,
            });
        }
        if !self.eta.is_finite() || !(1.0..=3.0).contains(&self.eta) {
            return Err(MaterialError::BadEta { name: self.name.clone(), eta: self.eta });
        }
        Ok(())
    }
}

/// The slab albedos [`Material::from_albedo_mfp`] accepts at `eta`: [`ALBEDO`], its top lowered
/// (to three decimals) where the profile's effective albedo at `rho' = 1` stays below 0.999.
/// The calibrated profile conserves energy at `rho' = 1` for every `eta`, so this is [`ALBEDO`]
/// itself; the check stays for tables that do not.
pub fn albedo_range(eta: f64) -> (f64, f64) {
    albedo_range_of(&effective_albedo_table(eta))
}

fn albedo_range_of(table: &EffectiveAlbedo) -> (f64, f64) {
    // No slab gives back more than it receives, hence the cap. Below the table's second row the
    // inversion brackets between rho = 0 and that row.
    let reach = (table.rho_eff.last().copied().unwrap_or(0.0) * 1e3).floor() / 1e3;
    (*ALBEDO.start(), ALBEDO.end().min(reach))
}

/// The effective-albedo table for `eta`, built once per `eta` (100 half-space albedos).
fn effective_albedo_table(eta: f64) -> std::sync::Arc<EffectiveAlbedo> {
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex, OnceLock};
    static TABLES: OnceLock<Mutex<HashMap<u64, Arc<EffectiveAlbedo>>>> = OnceLock::new();
    let tables = TABLES.get_or_init(Default::default);
    if let Some(t) = tables.lock().unwrap_or_else(|e| e.into_inner()).get(&eta.to_bits()) {
        return t.clone();
    }
    let table = Arc::new(EffectiveAlbedo::new(eta));
    tables.lock().unwrap_or_else(|e| e.into_inner()).insert(eta.to_bits(), table.clone());
    table
}
