//! `lucent.read_exr` / `lucent.write_exr`: the RGBA OpenEXR files `lucent render --out x.exr`
//! writes and the validation references hold, as numpy arrays, so comparing images needs no
//! other package.

use lucent::output::{HdrImage, write_exr_atomically};
use numpy::{AllowTypeChange, PyArray3, PyArrayLike3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Reads the first RGBA layer of an OpenEXR file as a (height, width, 4) float32 array, rows
/// top first (a missing alpha channel reads as 1).
#[pyfunction]
pub fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let image = crate::unlocked(py, move || {
        exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res, _| HdrImage {
                width: res.width() as u32,
                height: res.height() as u32,
                pixels: vec![[0.0f32; 4]; res.width() * res.height()],
            },
            |img: &mut HdrImage, p, (r, g, b, a): (f32, f32, f32, f32)| {
                img.pixels[p.y() * img.width as usize + p.x()] = [r, g, b, a]
            },
        )
        .map(|img| img.layer_data.channel_data.pixels)
        .map_err(|e| anyhow::anyhow!("{}: cannot read the EXR: {e}", path.display()))
    })?;
    crate::render::hdr_array(py, &image)
}

/// Writes a (height, width, 4) array as a 32-bit float RGBA OpenEXR file, atomically (as
/// ``lucent render`` writes its EXR).
#[pyfunction]
pub fn write_exr(
    py: Python<'_>,
    path: PathBuf,
    image: PyArrayLike3<'_, f32, AllowTypeChange>,
) -> PyResult<()> {
    let a = image.as_array();
    let (height, width, channels) = a.dim();
    if channels != 4 || height == 0 || width == 0 {
        return Err(PyValueError::new_err(format!(
            "write_exr: expected (height, width, 4), got {:?}",
            a.shape()
        )));
    }
    let pixels: Vec<[f32; 4]> = a.rows().into_iter().map(|px| [px[0], px[1], px[2], px[3]]).collect();
    let hdr = HdrImage { width: width as u32, height: height as u32, pixels };
    crate::unlocked(py, move || write_exr_atomically(&hdr, &path))
}
