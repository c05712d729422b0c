//! `lucent.Material`: a homogeneous scattering material (Jensen et al. 2001's dipole
//! parameters; lucent_core::bssrdf::Material), from a preset, from its coefficients, or from the
//! artist's slab albedo and mean free path (and back).

use lucent_core::bssrdf::Material as CoreMaterial;
use pyo3::prelude::*;

/// A homogeneous scattering material.
///
/// Make one with ``Material.preset("marble")``, ``Material(sigma_s_prime, sigma_a, eta)`` or
/// ``Material.from_albedo_mfp(albedo, mfp, eta)``. Coefficients are per RGB channel, in mm^-1.
#[pyclass(module = "lucent", frozen, from_py_object)]
#[derive(Clone)]
pub struct Material {
    pub(crate) inner: CoreMaterial,
}

fn err(e: lucent_core::bssrdf::MaterialError) -> PyErr {
    crate::LucentError::new_err(e.to_string())
}

#[pymethods]
impl Material {
    /// A material from its coefficients: reduced scattering ``sigma_s_prime`` and absorption
    /// ``sigma_a`` per RGB channel, mm^-1, each within 1e-12..=1e4; ``eta`` the relative index
    /// of refraction, 1..=3 (default 1.3, the presets' value).
    #[new]
    #[pyo3(signature = (sigma_s_prime, sigma_a, eta = 1.3, name = "custom"))]
    fn new(sigma_s_prime: [f64; 3], sigma_a: [f64; 3], eta: f64, name: &str) -> PyResult<Self> {
        CoreMaterial::custom(name, sigma_s_prime, sigma_a, eta).map(|inner| Material { inner }).map_err(err)
    }

    /// A preset by name, case-insensitively: Jensen et al. 2001's measured materials (apple,
    /// chicken1, chicken2, cream, ketchup, marble, potato, skimmilk, skin1, skin2, wholemilk)
    /// and candle wax; eta 1.3. See ``lucent.presets()``.
    #[staticmethod]
    fn preset(name: &str) -> PyResult<Self> {
        CoreMaterial::by_name(name).map(|inner| Material { inner }).map_err(err)
    }

    /// A material from what an artist gives: per channel the slab ``albedo`` (the colour a
    /// thick flat slab shows under uniform light, 0.001..=0.999) and the reduced mean free path
    /// ``mfp`` = 1/sigma_t' in mm (1e-4..=1e3), at index of refraction ``eta`` (1..=3). The
    /// inverse is ``albedo_mfp()``.
    #[staticmethod]
    #[pyo3(signature = (albedo, mfp, eta = 1.3, name = "custom"))]
    fn from_albedo_mfp(albedo: [f64; 3], mfp: [f64; 3], eta: f64, name: &str) -> PyResult<Self> {
        CoreMaterial::from_albedo_mfp(name, albedo, mfp, eta).map(|inner| Material { inner }).map_err(err)
    }

    /// ``(albedo, mfp)``: per channel the slab albedo under the default profile and the reduced
    /// mean free path 1/sigma_t' in mm (the inverse of ``from_albedo_mfp``).
    fn albedo_mfp(&self) -> ([f64; 3], [f64; 3]) {
        self.inner.albedo_mfp()
    }

    /// The name (a preset's, or the one given).
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// Reduced scattering coefficient per RGB channel, mm^-1.
    #[getter]
    fn sigma_s_prime(&self) -> [f64; 3] {
        self.inner.sigma_s_prime
    }

    /// Absorption coefficient per RGB channel, mm^-1.
    #[getter]
    fn sigma_a(&self) -> [f64; 3] {
        self.inner.sigma_a
    }

    /// Relative index of refraction (unitless).
    #[getter]
    fn eta(&self) -> f64 {
        self.inner.eta
    }

    fn __repr__(&self) -> String {
        let m = &self.inner;
        format!(
            "Material(sigma_s_prime={:?}, sigma_a={:?}, eta={}, name={:?})",
            m.sigma_s_prime, m.sigma_a, m.eta, m.name
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }
}

/// The names of the material presets, in table order.
#[pyfunction]
pub fn presets() -> Vec<String> {
    lucent_core::bssrdf::PRESETS.iter().map(|r| r.0.to_ascii_lowercase()).collect()
}
