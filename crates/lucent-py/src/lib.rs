//! `lucent` from Python: the extension module `lucent._lucent` (pyo3 + numpy), built by maturin
//! (`pip install ./crates/lucent-py`). It renders, solves and makes materials through the same
//! library as the command line: one scene resolution (`lucent::scene::Scene::resolve`), one
//! `lucent_core::session::FrameSession`, one GPU frame (`lucent::still`, `lucent::frame`).
//!
//! * [`render`](render::render): `lucent render --out x.exr` as a numpy array.
//! * [`Session`](session::Session): a frame session (Mertens 2003 §5.5: render, incremental
//!   and on-the-fly modes) that solves new poses, lights and materials.
//! * [`Material`](material::Material): presets, `sigma_s'`/`sigma_a`, or albedo and mean free
//!   path (and back).
//!
//! Every error is a Python exception with lucent's one-line message ([`LucentError`]); solves
//! and renders run with the GIL released, on a thread with the command line's stack (the
//! hierarchy's traversals recurse once per level).

use pyo3::prelude::*;

mod exr_io;
mod material;
mod options;
mod render;
mod session;

pyo3::create_exception!(
    _lucent,
    LucentError,
    pyo3::exceptions::PyException,
    "An error lucent reports: a bad input (mesh, material, light, number out of range), a \
     missing file or no GPU adapter. The message is lucent's one line."
);

/// Stack of the solving thread and of rayon's workers, bytes: as the command line's
/// (`crates/lucent/src/main.rs`), since face clustering of scanned meshes nests thousands of
/// levels deep. Only what is touched is committed.
const STACK_BYTES: usize = 512 << 20;

/// The error as Python sees it: lucent's message with its chain of causes on one line.
pub(crate) fn to_py(err: anyhow::Error) -> PyErr {
    LucentError::new_err(format!("{err:#}"))
}

/// Runs `f` with the GIL released on a thread with [`STACK_BYTES`] of stack, and turns an
/// error or a panic into a [`LucentError`] (never a crash of the interpreter).
pub(crate) fn unlocked<T: Send>(py: Python<'_>, f: impl FnOnce() -> anyhow::Result<T> + Send) -> PyResult<T> {
    let result = py.detach(|| {
        std::thread::scope(|scope| {
            let worker = std::thread::Builder::new()
                .name("lucent".into())
                .stack_size(STACK_BYTES)
                .spawn_scoped(scope, f);
            match worker.map(|w| w.join()) {
                Ok(Ok(result)) => result,
                Ok(Err(panic)) => {
                    let what = panic
                        .downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| panic.downcast_ref::<String>().cloned())
                        .unwrap_or_default();
                    Err(anyhow::anyhow!("internal error (a bug in lucent, please report it): {what}"))
                }
                Err(e) => Err(anyhow::anyhow!("cannot start the solving thread: {e}")),
            }
        })
    });
    result.map_err(to_py)
}

#[pymodule]
fn _lucent(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // As the command line: rayon's workers get the deep stack (a pool someone else built first
    // is kept).
    let _ = rayon::ThreadPoolBuilder::new().stack_size(STACK_BYTES).build_global();
    m.add("LucentError", m.py().get_type::<LucentError>())?;
    m.add_class::<material::Material>()?;
    m.add_class::<session::Session>()?;
    m.add_class::<session::Solution>()?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(material::presets, m)?)?;
    m.add_function(wrap_pyfunction!(exr_io::read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(exr_io::write_exr, m)?)?;
    Ok(())
}
