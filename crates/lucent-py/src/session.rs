//! `lucent.Session`: a `lucent_core::session::FrameSession` (Mertens 2003 §5.5) on a resolved
//! scene, kept across solves: new poses (the incremental update of the links by default), new
//! lights and new materials re-solve only what they change. `Session.render` draws the last
//! solve through the same GPU frame as `lucent render` (`lucent::still::draw`).

use crate::options::{SceneArgs, positions_of, resolve};
use crate::render::{hdr_array, image_size};
use glam::Vec3;
use lucent::output::Frame;
use lucent::scene::Scene;
use lucent_core::Rgb;
use lucent_core::irradiance::SceneLight;
use lucent_core::mesh::deform::Deformation;
use lucent_core::session::{FrameSession, SolveMode, Solved, Transport};
use lucent_gpu::GpuContext;
use lucent_gpu::tonemap::ToneMap;
use numpy::{AllowTypeChange, PyArray2, PyArray3, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

/// What one ``Session.solve()`` produced.
#[pyclass(module = "lucent", frozen)]
pub struct Solution {
    /// Radiosity B per face, (faces, 3) float32 RGB: the light leaving each face after
    /// subsurface transport, in the lights' irradiance units.
    #[pyo3(get)]
    face_b: Py<PyArray2<f32>>,
    /// Diffuse exitant radiance per vertex, (vertices, 3) float32 RGB: B / (c pi)
    /// area-weighted over the faces around the vertex (Mertens §3.2), before the exit Fresnel
    /// factor, times the body's chord factor along the view ray.
    #[pyo3(get)]
    vertex_radiance: Py<PyArray2<f32>>,
    /// Single-scattered radiance along the view ray per vertex, (vertices, 3) float32, before
    /// the exit Fresnel factor; (0, 3) when single scattering is not along the view ray.
    #[pyo3(get)]
    vertex_single: Py<PyArray2<f32>>,
    /// Wall-clock milliseconds of the solve's stages (irradiance_ms, body_ms, link_ms, pull_ms,
    /// gather_ms, single_scattering_ms, push_ms, bounces_ms; 0 for a stage that did not run),
    /// their sum total_ms, and wall_ms, the whole call as Python waited for it.
    #[pyo3(get)]
    timings: Py<PyDict>,
    /// Links of the hierarchical solve (None for the exact solver).
    #[pyo3(get)]
    links: Option<usize>,
    /// False when nothing changed since the last solve (the last result, timings 0).
    #[pyo3(get)]
    fresh: bool,
}

fn rgb_array<'py>(py: Python<'py>, v: &[Rgb]) -> Bound<'py, PyArray2<f32>> {
    let flat: Vec<f32> = v.iter().flat_map(|c| c.to_array()).collect();
    let array = numpy::ndarray::Array2::from_shape_vec((v.len(), 3), flat).expect("three per row");
    PyArray2::from_owned_array(py, array)
}

impl Solution {
    fn new(py: Python<'_>, s: &Solved, wall_ms: f64) -> PyResult<Self> {
        let t = &s.timings;
        let timings = PyDict::new(py);
        for (k, v) in [
            ("irradiance_ms", t.irradiance_ms),
            ("body_ms", t.body_ms),
            ("link_ms", t.link_ms),
            ("pull_ms", t.pull_ms),
            ("gather_ms", t.gather_ms),
            ("single_scattering_ms", t.single_scattering_ms),
            ("push_ms", t.push_ms),
            ("bounces_ms", t.bounces_ms),
            ("total_ms", t.total_ms()),
            ("wall_ms", wall_ms),
        ] {
            timings.set_item(k, v)?;
        }
        Ok(Solution {
            face_b: rgb_array(py, &s.face_b).unbind(),
            vertex_radiance: rgb_array(py, &s.vertex_radiance).unbind(),
            vertex_single: rgb_array(py, &s.vertex_single).unbind(),
            timings: timings.unbind(),
            links: s.links,
            fresh: s.fresh,
        })
    }
}

#[pymethods]
impl Solution {
    fn __repr__(&self, py: Python<'_>) -> String {
        let faces = self.face_b.bind(py).shape()[0];
        let vertices = self.vertex_radiance.bind(py).shape()[0];
        format!("Solution({faces} faces, {vertices} vertices, links={:?}, fresh={})", self.links, self.fresh)
    }
}

/// A translucent object kept across solves: the CPU side of lucent's frames. See the type
/// stubs for the arguments (the same as ``lucent.render``'s).
#[pyclass(module = "lucent")]
pub struct Session {
    scene: Scene,
    session: FrameSession,
    /// The image size the eye is framed for (view-ray single scattering) and `render` draws.
    size: (u32, u32),
    /// The last solve, for `render`.
    last: Option<Solved>,
}

fn to_positions(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

#[pymethods]
impl Session {
    #[new]
    #[pyo3(signature = (
        mesh = None, *, vertices = None, faces = None, scene = None, material = None, scale = None,
        lights = None, shadows = true, env = None, env_rotation = None, camera = None, width = 800,
        height = 600, profile = None, single_scattering = None, transmission = None, method = None,
        mode = None, bounces = None, refine = None, deform = None, surface = true, exposure = None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new<'py>(
        py: Python<'py>,
        mesh: Option<PathBuf>,
        vertices: Option<PyArrayLike2<'py, f32, AllowTypeChange>>,
        faces: Option<PyArrayLike2<'py, i64, AllowTypeChange>>,
        scene: Option<PathBuf>,
        material: Option<Bound<'py, PyAny>>,
        scale: Option<f64>,
        lights: Option<Vec<String>>,
        shadows: bool,
        env: Option<String>,
        env_rotation: Option<f32>,
        camera: Option<HashMap<String, f32>>,
        width: u32,
        height: u32,
        profile: Option<String>,
        single_scattering: Option<String>,
        transmission: Option<String>,
        method: Option<String>,
        mode: Option<String>,
        bounces: Option<u32>,
        refine: Option<Bound<'py, PyAny>>,
        deform: Option<String>,
        surface: bool,
        exposure: Option<f32>,
    ) -> PyResult<Self> {
        let args = SceneArgs {
            mesh,
            vertices,
            faces,
            scene,
            material,
            scale,
            lights,
            shadows,
            env,
            env_rotation,
            camera,
            profile,
            single_scattering,
            transmission,
            method,
            mode,
            bounces,
            refine,
            deform,
            surface,
            exposure,
        };
        let size = image_size(width, height)?;
        let scene = resolve(py, args.overrides()?)?;
        // Poses are the point of a session: links on the rest pose, updated to each new one as
        // a fresh link would be (`lucent render --frames` refits them instead), unless `mode`
        // says otherwise.
        let mut session = scene.session(SolveMode::Incremental);
        session.set_eye(Some(scene.camera_view(size).eye));
        if !scene.deform.is_empty() {
            session.set_positions(&scene.deformed(1.0).positions);
        }
        Ok(Session { scene, session, size, last: None })
    }

    /// Solves what changed since the last solve (everything the first time), with the GIL
    /// released, and returns the result.
    fn solve(&mut self, py: Python<'_>) -> PyResult<Solution> {
        let session = &mut self.session;
        let (solved, wall_ms) = crate::unlocked(py, move || {
            let t = Instant::now();
            let solved = session.solve().clone();
            Ok((solved, t.elapsed().as_secs_f64() * 1e3))
        })?;
        let out = Solution::new(py, &solved, wall_ms)?;
        self.last = Some(solved);
        Ok(out)
    }

    /// Moves the mesh to ``positions`` ((vertices, 3), mesh units): a pose of the same mesh
    /// (see ``vertices``). The next solve updates the links incrementally in the default mode.
    fn set_pose(&mut self, positions: PyArrayLike2<'_, f32, AllowTypeChange>) -> PyResult<()> {
        let p = positions_of(positions.as_array())?;
        let n = self.session.mesh().positions.len();
        if p.len() != n {
            return Err(crate::LucentError::new_err(format!(
                "set_pose: {} positions for a mesh of {n} vertices (a session's topology is fixed)",
                p.len()
            )));
        }
        self.session.set_positions(&p);
        Ok(())
    }

    /// Poses the mesh by a deformation of its rest pose, as ``lucent render --deform``:
    /// ``twist:DEGREES``, ``bump:x,y,z,radius,height`` (mesh units) or
    /// ``noise:amplitude,frequency``, at animation parameter ``t`` (0 rest, 1 as given).
    #[pyo3(signature = (spec, t = 1.0))]
    fn deform(&mut self, spec: &str, t: f32) -> PyResult<()> {
        let d: Deformation =
            spec.parse().map_err(|e| crate::LucentError::new_err(format!("deform {spec:?}: {e}")))?;
        if !t.is_finite() {
            return Err(crate::LucentError::new_err(format!("deform: t must be finite, got {t}")));
        }
        let mut pos = Vec::new();
        d.apply(&self.scene.mesh, t, &mut pos);
        self.session.set_positions(&pos);
        Ok(())
    }

    /// Replaces the lights: strings as ``lucent render --light`` (``point:x,y,z`` or
    /// ``dir:x,y,z``, mesh units; irradiance 1), casting shadows unless ``shadows`` is False.
    #[pyo3(signature = (lights, shadows = true))]
    fn set_lights(&mut self, lights: Vec<String>, shadows: bool) -> PyResult<()> {
        let (center, _) = lucent_core::camera::bounding_sphere(&self.scene.mesh.positions);
        let mut parsed = Vec::with_capacity(lights.len());
        for spec in &lights {
            let light = lucent::scene::parse_light(spec, center).map_err(crate::to_py)?;
            parsed.push(SceneLight { shadows, ..SceneLight::from(light) });
        }
        self.scene.lights = parsed.clone();
        self.session.set_lights(parsed);
        Ok(())
    }

    /// Replaces the material (a preset name or a ``lucent.Material``) and, if given, the
    /// model scale (the rest mesh's largest bounding-box side, metres).
    #[pyo3(signature = (material, scale = None))]
    fn set_material(&mut self, material: Bound<'_, PyAny>, scale: Option<f64>) -> PyResult<()> {
        let material = match material.cast::<crate::material::Material>() {
            Ok(m) => m.get().inner.clone(),
            Err(_) => {
                let name: String = material.extract()?;
                lucent_core::bssrdf::Material::by_name(&name)
                    .map_err(|e| crate::LucentError::new_err(e.to_string()))?
            }
        };
        let scale_m = match scale {
            Some(s) => lucent::ranges::check("scale", s, &lucent::ranges::SCALE_M)
                .map_err(crate::LucentError::new_err)?,
            None => self.scene.transport.scale_m,
        };
        let transport = Transport { material, scale_m, ..self.scene.transport.clone() };
        self.scene.transport = transport.clone();
        self.session.set_transport(transport);
        Ok(())
    }

    /// Draws the last solve (solving first if there is none) with the scene's camera, lights and
    /// environment, as ``lucent.render`` returns it: (height, width, 4) float32, RGB
    /// premultiplied by coverage. The size is the session's (``width``, ``height``).
    fn render<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        if self.last.is_none() || !self.session.is_current() {
            self.solve(py)?;
        }
        let (scene, size, mesh) = (&self.scene, self.size, self.session.mesh());
        let solved = self.last.as_ref().expect("solved above");
        let hdr = crate::unlocked(py, move || {
            let ctx = GpuContext::new()?;
            let tone = ToneMap { exposure: scene.exposure, ..Default::default() };
            match lucent::still::draw(ctx, scene, size, tone, mesh, solved, false, true)?.0 {
                Frame::Hdr(hdr) => Ok(hdr),
                Frame::Ldr(_) => anyhow::bail!("the GPU frame came back tone mapped"),
            }
        })?;
        hdr_array(py, &hdr)
    }

    /// The mesh's vertices in the current pose, (vertices, 3) float32, mesh units. With
    /// ``refine`` (auto by default) these are the split mesh's, which a pose must match.
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let flat = to_positions(&self.session.mesh().positions);
        let n = flat.len() / 3;
        Ok(PyArray2::from_owned_array(
            py,
            numpy::ndarray::Array2::from_shape_vec((n, 3), flat).expect("3 a row"),
        ))
    }

    /// The rest pose's vertices, (vertices, 3) float32, mesh units.
    #[getter]
    fn rest_vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let flat = to_positions(&self.scene.mesh.positions);
        let n = flat.len() / 3;
        Ok(PyArray2::from_owned_array(
            py,
            numpy::ndarray::Array2::from_shape_vec((n, 3), flat).expect("3 a row"),
        ))
    }

    /// The faces, (faces, 3) uint32 indices into ``vertices`` (after validation dropped
    /// degenerate and repeated faces, and after ``refine``'s splits).
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u32>>> {
        let t = &self.session.mesh().triangles;
        let flat: Vec<u32> = t.iter().flatten().copied().collect();
        Ok(PyArray2::from_owned_array(
            py,
            numpy::ndarray::Array2::from_shape_vec((t.len(), 3), flat).expect("3 a row"),
        ))
    }

    /// The material in use.
    #[getter]
    fn material(&self) -> crate::material::Material {
        crate::material::Material { inner: self.scene.transport.material.clone() }
    }

    /// Model scale: the rest mesh's largest bounding-box side, metres.
    #[getter]
    fn scale(&self) -> f64 {
        self.scene.transport.scale_m
    }

    /// Times every face of the input mesh was split into four before the solve.
    #[getter]
    fn refine_levels(&self) -> u32 {
        self.scene.refine_levels
    }

    /// The solve mode in use: ``render``, ``incremental``, ``refit`` or ``on-the-fly``.
    #[getter]
    fn mode(&self) -> &'static str {
        self.session.settings().mode.name()
    }

    fn __repr__(&self) -> String {
        let m = self.session.mesh();
        format!(
            "Session({}: {} vertices, {} faces, {} at {} m, {} {})",
            self.scene.source,
            m.positions.len(),
            m.triangles.len(),
            self.scene.transport.material.name,
            self.scene.transport.scale_m,
            self.session.settings().method.name(),
            self.session.settings().mode.name()
        )
    }
}
