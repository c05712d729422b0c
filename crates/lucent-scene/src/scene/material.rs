//! The `material` key of a scene file: a preset name, or a table of either coefficients
//! (`sigma_s_prime`, `sigma_a`) or colour and distance (`albedo`, `mfp`, inverted by
//! [`Material::from_albedo_mfp`]), each with an optional `eta` and `name`.

use anyhow::{Result, bail};
use lucent_core::bssrdf::Material;
use lucent_core::shading::{SingleScattering, UnknownSingleScattering};
use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use std::fmt;

/// A material preset name or custom coefficients.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialSpec {
    /// A preset, by name (case-insensitive).
    Preset(String),
    /// User-defined coefficients.
    Custom(CustomMaterial),
}

impl Default for MaterialSpec {
    fn default() -> Self {
        MaterialSpec::Preset(super::resolve::DEFAULT_MATERIAL.into())
    }
}

impl MaterialSpec {
    /// The slab albedo and mean free path (mm) of a material given by colour and distance.
    pub fn by_colour(&self) -> Option<([f64; 3], [f64; 3])> {
        match self {
            MaterialSpec::Custom(c) => c.albedo.zip(c.mfp),
            MaterialSpec::Preset(_) => None,
        }
    }
}

/// A custom material: either coefficients (`sigma_s_prime` and `sigma_a`) or what an artist
/// gives (`albedo` and `mfp`, see [`Material::from_albedo_mfp`]).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CustomMaterial {
    /// Display name. Default `"custom"`.
    #[serde(default = "custom_name")]
    pub name: String,
    /// Reduced scattering coefficient per RGB channel, mm^-1 (1e-12..=1e4).
    pub sigma_s_prime: Option<[f64; 3]>,
    /// Absorption coefficient per RGB channel, mm^-1 (1e-12..=1e4).
    pub sigma_a: Option<[f64; 3]>,
    /// Slab albedo per linear RGB channel: what a flat, thick slab shows under uniform light
    /// (0.001..=0.999 at every eta).
    pub albedo: Option<[f64; 3]>,
    /// Reduced mean free path (scatter distance) `1 / sigma_t'` per RGB channel, mm
    /// (0.0001..=1e3).
    pub mfp: Option<[f64; 3]>,
    /// Relative index of refraction (1..=3). Default 1.3.
    #[serde(default = "default_eta")]
    pub eta: f64,
}

impl CustomMaterial {
    /// The material, validated; exactly one of the two pairs must be given, both of its keys.
    pub fn resolve(&self) -> Result<Material> {
        Ok(match (self.sigma_s_prime, self.sigma_a, self.albedo, self.mfp) {
            (Some(s), Some(a), None, None) => Material::custom(&self.name, s, a, self.eta)?,
            (None, None, Some(albedo), Some(mfp)) => {
                Material::from_albedo_mfp(&self.name, albedo, mfp, self.eta)?
            }
            _ => bail!(
                "material '{}': give either sigma_s_prime and sigma_a (mm^-1) or albedo and mfp (mm), both keys of one pair",
                self.name
            ),
        })
    }
}

fn custom_name() -> String {
    "custom".into()
}
fn default_eta() -> f64 {
    1.3
}

// A string or a table, with the table's own field errors (serde's untagged enums would only say
// "did not match any variant").
impl<'de> Deserialize<'de> for MaterialSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = MaterialSpec;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a material preset name or a table with sigma_s_prime and sigma_a, or albedo and mfp",
                )
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<MaterialSpec, E> {
                Ok(MaterialSpec::Preset(s.to_string()))
            }
            fn visit_map<M: MapAccess<'de>>(self, m: M) -> Result<MaterialSpec, M::Error> {
                CustomMaterial::deserialize(de::value::MapAccessDeserializer::new(m))
                    .map(MaterialSpec::Custom)
            }
        }
        d.deserialize_any(V)
    }
}

/// The scene file's `single_scattering`: a mode name, or `true` (view) / `false` (off) as
/// files written before the modes existed have it.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum SingleScatteringKey {
    /// `true` or `false`.
    On(bool),
    /// `"view"`, `"profile"` or `"off"`.
    Mode(String),
}

impl SingleScatteringKey {
    /// The mode it names.
    pub fn mode(&self) -> Result<SingleScattering, UnknownSingleScattering> {
        match self {
            SingleScatteringKey::On(true) => Ok(SingleScattering::ViewRay),
            SingleScatteringKey::On(false) => Ok(SingleScattering::Off),
            SingleScatteringKey::Mode(s) => s.parse(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn material(toml_value: &str) -> Result<Material> {
        #[derive(Deserialize)]
        struct One {
            material: MaterialSpec,
        }
        let one: One = toml::from_str(&format!("material = {toml_value}\n"))?;
        match one.material {
            MaterialSpec::Preset(name) => Ok(Material::by_name(&name)?),
            MaterialSpec::Custom(c) => c.resolve(),
        }
    }

    #[test]
    fn colour_and_distance_give_the_inverted_material() {
        let text = "{ albedo = [0.8, 0.6, 0.4], mfp = [1.0, 0.5, 0.25], eta = 1.3, name = \"clay\" }";
        let m = material(text).unwrap();
        let same = Material::from_albedo_mfp("clay", [0.8, 0.6, 0.4], [1.0, 0.5, 0.25], 1.3).unwrap();
        assert_eq!(m, same);
        // sigma_t' = 1 / mfp, and the slab albedo comes back.
        let (albedo, mfp) = m.albedo_mfp();
        for c in 0..3 {
            assert!((m.sigma_s_prime[c] + m.sigma_a[c] - 1.0 / [1.0, 0.5, 0.25][c]).abs() < 1e-9);
            assert!(
                (albedo[c] - [0.8, 0.6, 0.4][c]).abs() < 1e-3 && (mfp[c] - [1.0, 0.5, 0.25][c]).abs() < 1e-12
            );
        }
        // eta defaults to 1.3; the coefficient form still works.
        assert_eq!(material("{ albedo = [0.5, 0.5, 0.5], mfp = [1, 1, 1] }").unwrap().eta, 1.3);
        let m = material("{ sigma_s_prime = [1, 2, 3], sigma_a = [0.1, 0.2, 0.3], eta = 1.4 }").unwrap();
        assert_eq!((m.sigma_s_prime, m.eta), ([1.0, 2.0, 3.0], 1.4));
        assert_eq!(material("\"Marble\"").unwrap().name, "Marble");
    }

    #[test]
    fn half_pairs_mixed_pairs_and_bad_values_are_refused() {
        for text in [
            "{ albedo = [0.5, 0.5, 0.5] }",
            "{ mfp = [1, 1, 1] }",
            "{ albedo = [0.5, 0.5, 0.5], sigma_a = [1, 1, 1] }",
            "{ albedo = [0.5, 0.5, 0.5], mfp = [1, 1, 1], sigma_s_prime = [1, 1, 1], sigma_a = [1, 1, 1] }",
        ] {
            let e = format!("{:#}", material(text).unwrap_err());
            assert!(e.contains("either sigma_s_prime and sigma_a") && e.contains("albedo and mfp"), "{e}");
        }
        let e = material("{ albedo = [0.5, 1.0, 0.5], mfp = [1, 1, 1] }").unwrap_err().to_string();
        assert!(e.contains("albedo 1 ") && e.contains("0.001..=0.999"), "{e}");
        let e = material("{ albedo = [0.5, 0.5, 0.5], mfp = [1, -2, 1] }").unwrap_err().to_string();
        assert!(e.contains("mean free path -2 mm") && e.contains("0.0001..=1000"), "{e}");
        let e = material("{ albedo = [0.5, 0.5], mfp = [1, 1, 1] }").unwrap_err().to_string();
        assert!(e.contains("albedo") || e.contains("length 3"), "{e}");
        // The calibrated profile reaches the whole range at any eta; past it, the error names eta.
        assert!(material("{ albedo = [0.98, 0.5, 0.5], mfp = [1, 1, 1], eta = 3.0 }").is_ok());
        let e =
            material("{ albedo = [0.9995, 0.5, 0.5], mfp = [1, 1, 1], eta = 3.0 }").unwrap_err().to_string();
        assert!(e.contains("albedo 0.9995 ") && e.contains("0.001..=0.999 at eta 3"), "{e}");
    }
}
