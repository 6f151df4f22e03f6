//! The `vcm` Python module (its native part `vcm._vcm`, re-exported by `python/vcm/__init__.py`): a front end of the render session ([`session`]) like the `vcm`
//! command line. It translates keyword arguments into a [`session::Request`], runs it with the
//! interpreter's lock released, and hands images over as numpy `float32` arrays of shape
//! `(height, width, 3)`, top row first, linear sRGB.
//!
//! - [`loading`]: `load_file`, `scenes`, the `Scene` class;
//! - [`options`]: the keyword arguments shared by `render` and `Session`;
//! - [`progressive`]: `render` and the `Session` class;
//! - [`images`]: `read`, `write`, `compare` and the array conversions;
//! - [`interrupt`]: running work off the interpreter's lock, stoppable by Ctrl-C.

mod images;
mod interrupt;
mod loading;
mod options;
mod progressive;

use pyo3::prelude::*;

/// Errors of a session (bad settings, scene files) as Python `ValueError`s with the whole
/// cause chain (`file:line:column: message` for scene files).
fn value_error(error: anyhow::Error) -> PyErr {
    pyo3::exceptions::PyValueError::new_err(format!("{error:#}"))
}

/// A physically based renderer (vertex connection and merging and its family: pt, lt, ppm,
/// bpm, bpt, vcm; RGB and spectral).
#[pymodule]
#[pyo3(name = "_vcm")]
fn vcm(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    module.add("ALGORITHMS", render::Algorithm::ALL.map(|(_, name)| name).to_vec())?;
    module.add_class::<loading::Scene>()?;
    module.add_class::<progressive::Session>()?;
    module.add_function(wrap_pyfunction!(loading::load_file, module)?)?;
    module.add_function(wrap_pyfunction!(loading::scenes, module)?)?;
    module.add_function(wrap_pyfunction!(progressive::render, module)?)?;
    module.add_function(wrap_pyfunction!(images::read, module)?)?;
    module.add_function(wrap_pyfunction!(images::write, module)?)?;
    module.add_function(wrap_pyfunction!(images::compare, module)?)?;
    Ok(())
}
