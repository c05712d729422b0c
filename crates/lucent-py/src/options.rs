//! What the Python keyword arguments say about a scene, as the command line's flags say it:
//! one `lucent::scene::Overrides`, checked against the same ranges (`lucent::ranges`) and
//! resolved by the same `Scene::resolve`.

use crate::material::Material;
use glam::Vec3;
use lucent::ranges;
use lucent::scene::{Overrides, Scene};
use lucent_core::mesh::Mesh;
use lucent_core::session::{Method, SolveMode};
use numpy::{AllowTypeChange, PyArrayLike2};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A range check's message as a [`crate::LucentError`].
fn check<T: PartialOrd + std::fmt::Display + Copy>(
    label: &str,
    value: T,
    range: &std::ops::RangeInclusive<T>,
) -> PyResult<T> {
    ranges::check(label, value, range).map_err(crate::LucentError::new_err)
}

/// Parses `text` with `T`'s `FromStr` (the command line's parser), its message as a
/// [`crate::LucentError`].
fn parse<T: std::str::FromStr>(label: &str, text: &str) -> PyResult<T>
where
    T::Err: std::fmt::Display,
{
    text.parse::<T>().map_err(|e| crate::LucentError::new_err(format!("{label}: {e}")))
}

/// The scene's keyword arguments, as `lucent.render` and `lucent.Session` take them. See the
/// type stubs (`python/lucent/_lucent.pyi`) for each one's meaning, units and default.
#[derive(Default)]
pub struct SceneArgs<'py> {
    pub mesh: Option<PathBuf>,
    pub vertices: Option<PyArrayLike2<'py, f32, AllowTypeChange>>,
    pub faces: Option<PyArrayLike2<'py, i64, AllowTypeChange>>,
    pub scene: Option<PathBuf>,
    pub material: Option<Bound<'py, PyAny>>,
    pub scale: Option<f64>,
    pub lights: Option<Vec<String>>,
    pub shadows: bool,
    pub env: Option<String>,
    pub env_rotation: Option<f32>,
    pub camera: Option<std::collections::HashMap<String, f32>>,
    pub profile: Option<String>,
    pub single_scattering: Option<String>,
    pub transmission: Option<String>,
    pub method: Option<String>,
    pub mode: Option<String>,
    pub bounces: Option<u32>,
    pub refine: Option<Bound<'py, PyAny>>,
    pub deform: Option<String>,
    pub surface: bool,
    pub exposure: Option<f32>,
}

impl SceneArgs<'_> {
    /// The overrides these arguments make, every number range-checked and every name parsed
    /// as the command line does.
    pub fn overrides(&self) -> PyResult<Overrides> {
        let mut o = Overrides {
            scene: self.scene.clone(),
            mesh: self.mesh.clone(),
            mesh_data: self.mesh_data()?,
            lights: self.lights.clone().unwrap_or_default(),
            no_shadows: !self.shadows,
            env: self.env.clone(),
            deform: self.deform.clone(),
            no_surface: !self.surface,
            ..Default::default()
        };
        if o.mesh.is_some() && o.mesh_data.is_some() {
            return Err(PyValueError::new_err("give a mesh path or vertices and faces, not both"));
        }
        match &self.material {
            None => {}
            Some(m) if m.is_instance_of::<pyo3::types::PyString>() => o.material = Some(m.extract()?),
            Some(m) => match m.cast::<Material>() {
                Ok(m) => o.material_data = Some(m.get().inner.clone()),
                Err(_) => return Err(PyTypeError::new_err("material: a preset name or a lucent.Material")),
            },
        }
        o.scale = self.scale.map(|s| check("scale", s, &ranges::SCALE_M)).transpose()?;
        o.exposure = self.exposure.map(|e| check("exposure", e, &ranges::EXPOSURE)).transpose()?;
        o.env_rotation =
            self.env_rotation.map(|r| check("env_rotation", r, &ranges::ANGLE_DEG)).transpose()?;
        o.bounces = self.bounces.map(|b| check("bounces", b, &ranges::BOUNCES)).transpose()?;
        for (key, &v) in self.camera.iter().flatten() {
            match key.as_str() {
                "yaw" => o.yaw = Some(check("camera yaw", v, &ranges::ANGLE_DEG)?),
                "pitch" => o.pitch = Some(check("camera pitch", v, &ranges::PITCH_DEG)?),
                "distance" => o.distance = Some(check("camera distance", v, &ranges::CAMERA_DISTANCE)?),
                _ => {
                    return Err(PyValueError::new_err(format!(
                        "camera: unknown key {key:?}; expected yaw, pitch, distance"
                    )));
                }
            }
        }
        o.profile = self.profile.as_deref().map(|p| parse("profile", p)).transpose()?;
        o.single_scattering =
            self.single_scattering.as_deref().map(|s| parse("single_scattering", s)).transpose()?;
        o.transmission = self.transmission.as_deref().map(|t| parse("transmission", t)).transpose()?;
        o.method = Some(self.method()?);
        o.mode = self.mode.as_deref().map(|m| parse::<SolveMode>("mode", m)).transpose()?;
        o.refine = match &self.refine {
            None => None,
            Some(r) => Some(parse("refine", &r.str()?.to_cow()?)?),
        };
        Ok(o)
    }

    /// The solver: `hierarchical` (default) or `exact`; HTSM has no per-vertex solve and its
    /// own GPU path, which the module does not offer.
    fn method(&self) -> PyResult<Method> {
        let method = match self.method.as_deref() {
            None => Method::default(),
            Some(m) => parse::<Method>("method", m)?,
        };
        if method == Method::Htsm {
            return Err(crate::LucentError::new_err(
                "method 'htsm' is not available from Python (it has no per-vertex solve); use the command line",
            ));
        }
        Ok(method)
    }

    /// The mesh of `vertices` (N, 3) and `faces` (M, 3), if given: finite coordinates and
    /// indices within the vertices (the rest of the checks are `Scene::resolve`'s).
    fn mesh_data(&self) -> PyResult<Option<(String, Mesh)>> {
        let (v, f) = match (&self.vertices, &self.faces) {
            (None, None) => return Ok(None),
            (Some(v), Some(f)) => (v.as_array(), f.as_array()),
            _ => return Err(PyValueError::new_err("vertices and faces go together")),
        };
        if v.ncols() != 3 || f.ncols() != 3 {
            return Err(PyValueError::new_err(format!(
                "vertices must be (N, 3) and faces (M, 3), got {:?} and {:?}",
                v.shape(),
                f.shape()
            )));
        }
        let positions = positions_of(v)?;
        let n = positions.len() as i64;
        let mut triangles = Vec::with_capacity(f.nrows());
        for (i, row) in f.rows().into_iter().enumerate() {
            if let Some(bad) = row.iter().find(|&&x| x < 0 || x >= n) {
                return Err(crate::LucentError::new_err(format!(
                    "faces[{i}] has index {bad}, outside the {n} vertices"
                )));
            }
            triangles.push([row[0] as u32, row[1] as u32, row[2] as u32]);
        }
        let name = format!("numpy mesh ({} vertices, {} faces)", positions.len(), triangles.len());
        Ok(Some((name, Mesh::new(positions, triangles))))
    }
}

/// Positions from an (N, 3) array, every coordinate finite.
pub fn positions_of(v: numpy::ndarray::ArrayView2<'_, f32>) -> PyResult<Vec<Vec3>> {
    if v.ncols() != 3 {
        return Err(PyValueError::new_err(format!("positions must be (N, 3), got {:?}", v.shape())));
    }
    let mut out = Vec::with_capacity(v.nrows());
    for (i, row) in v.rows().into_iter().enumerate() {
        let p = Vec3::new(row[0], row[1], row[2]);
        if !p.is_finite() {
            return Err(crate::LucentError::new_err(format!("vertex {i} is not finite: {p}")));
        }
        out.push(p);
    }
    Ok(out)
}

/// The scene these overrides resolve to (with the GIL released: it may load a large mesh).
pub fn resolve(py: Python<'_>, o: Overrides) -> PyResult<Scene> {
    crate::unlocked(py, move || Scene::resolve(&o))
}
