//! `lucent.render`: one image as `lucent render --out x.exr` writes it (Mertens 2003: solve on
//! the CPU, raster on the GPU, `lucent::still`), as a numpy array.

use crate::options::{SceneArgs, resolve};
use lucent::output::Frame;
use lucent::ranges;
use lucent_gpu::GpuContext;
use lucent_gpu::tonemap::ToneMap;
use numpy::{AllowTypeChange, PyArray3, PyArrayLike2};
use pyo3::prelude::*;
use std::collections::HashMap;
use std::path::PathBuf;

/// Renders a translucent object and returns the linear HDR frame: a float32 array of shape
/// (height, width, 4), RGB radiance premultiplied by A, the pixel's coverage of the object
/// (nothing else is drawn: the background is 0 with alpha 0). The same image as
/// ``lucent render --out x.exr`` with the same scene. See the type stubs for every argument.
#[pyfunction]
#[pyo3(signature = (
    mesh = None, *, vertices = None, faces = None, scene = None, material = None, scale = None,
    lights = None, shadows = true, env = None, env_rotation = None, camera = None, width = 800,
    height = 600, profile = None, single_scattering = None, transmission = None, method = None,
    mode = None, bounces = None, refine = None, deform = None, surface = true, exposure = None
))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
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
) -> PyResult<Bound<'py, PyArray3<f32>>> {
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
    let hdr = crate::unlocked(py, move || {
        // As `lucent render`: the adapter first, so that no solve is wasted without one.
        let ctx = GpuContext::new()?;
        let (mesh, mut session) = lucent::still::session(&scene, size);
        let solved = session.solve();
        let tone = ToneMap { exposure: scene.exposure, ..Default::default() };
        match lucent::still::draw(ctx, &scene, size, tone, &mesh, solved, false, true)?.0 {
            Frame::Hdr(hdr) => Ok(hdr),
            Frame::Ldr(_) => anyhow::bail!("the GPU frame came back tone mapped"),
        }
    })?;
    hdr_array(py, &hdr)
}

/// `width` x `height` checked against the command line's range.
pub fn image_size(width: u32, height: u32) -> PyResult<(u32, u32)> {
    let check = |label, v| ranges::check(label, v, &ranges::IMAGE_SIDE).map_err(crate::LucentError::new_err);
    Ok((check("width", width)?, check("height", height)?))
}

/// The HDR frame as a (height, width, 4) float32 array, rows top first.
pub fn hdr_array<'py>(
    py: Python<'py>,
    hdr: &lucent::output::HdrImage,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let (w, h) = (hdr.width as usize, hdr.height as usize);
    let flat: Vec<f32> = hdr.pixels.iter().flatten().copied().collect();
    let array = numpy::ndarray::Array3::from_shape_vec((h, w, 4), flat)
        .map_err(|e| crate::LucentError::new_err(format!("the frame has the wrong size: {e}")))?;
    Ok(PyArray3::from_owned_array(py, array))
}
