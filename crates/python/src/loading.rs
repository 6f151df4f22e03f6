//! `vcm.load_file`, `vcm.scenes` and the `Scene` class: where a scene comes from, checked when
//! it is named.

use std::path::Path;

use pyo3::exceptions::PyFileNotFoundError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};
use session::SceneSource;

use crate::value_error;

/// A scene: a built-in Cornell box or a scene file (Mitsuba 3 XML, pbrt-v4) with its
/// parameters. Loaded (and checked) by `vcm.load_file`; every render loads it again with the
/// render's resolution, as the command line does.
#[pyclass(module = "vcm", frozen)]
pub struct Scene {
    pub source: SceneSource,
    name: String,
    resolution: (u32, u32),
    warnings: Vec<String>,
}

#[pymethods]
impl Scene {
    /// The scene's name (built-in name or file stem).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// `(width, height)` in pixels of the scene's own film (512x512 for built-in scenes).
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        self.resolution
    }

    /// Loader warnings: parameters the renderer skips (a render with `permissive=False`
    /// refuses those that would change the image).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    fn __repr__(&self) -> String {
        let (w, h) = self.resolution;
        match &self.source {
            SceneSource::Builtin(mask) => format!("vcm.Scene('{}', mask={mask}, {w}x{h})", self.name),
            SceneSource::File(path, defines) => {
                format!("vcm.Scene('{}', params={defines:?}, {w}x{h})", path.display())
            }
        }
    }
}

/// Loads a scene: a built-in name or id (see `vcm.scenes()`) or a scene file (`.xml` Mitsuba 3,
/// `.pbrt` pbrt-v4). Keyword arguments set the file's parameters (Mitsuba `$name`, as `-D
/// name=value` on the command line). Raises `FileNotFoundError` for a missing file and
/// `ValueError` (with `file:line:column`) for an invalid one.
#[pyfunction]
#[pyo3(signature = (path_or_builtin, **params))]
pub fn load_file(
    py: Python<'_>,
    path_or_builtin: std::path::PathBuf,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Scene> {
    let mut defines = Vec::new();
    for (key, value) in params.into_iter().flatten() {
        let value = if value.is_instance_of::<PyBool>() {
            if value.extract::<bool>()? { "true".to_string() } else { "false".to_string() }
        } else {
            value.str()?.to_string()
        };
        defines.push(format!("{}={value}", key.str()?));
    }
    let name = path_or_builtin.display().to_string();
    let looks_like_file = path_or_builtin.extension().is_some() || name.contains('/');
    if looks_like_file && !path_or_builtin.exists() {
        return Err(PyFileNotFoundError::new_err(format!("scene file '{name}' does not exist")));
    }
    let source = session::scene_source(&name, &defines).map_err(value_error)?;
    // Checked permissively: syntax and references fail here, unsupported parameters when a
    // render that is not permissive loads it.
    let loaded = py.detach(|| session::load_scene(&source, None, true)).map_err(value_error)?;
    let stem = Path::new(&name).file_stem().map(|s| s.to_string_lossy().into_owned());
    Ok(Scene {
        name: match &source {
            SceneSource::Builtin(_) => loaded.scene.name.clone(),
            SceneSource::File(..) => stem.unwrap_or(name),
        },
        resolution: (loaded.scene.camera.width, loaded.scene.camera.height),
        warnings: loaded.warnings,
        source,
    })
}

/// The built-in scenes: a list of dicts with `id`, `name`, `mask` and `description`.
#[pyfunction]
pub fn scenes(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    scene::cornell::builtin_scenes()
        .map(|s| {
            let entry = PyDict::new(py);
            entry.set_item("id", s.id)?;
            entry.set_item("name", s.name)?;
            entry.set_item("mask", s.mask)?;
            entry.set_item("description", s.description)?;
            Ok(entry)
        })
        .collect()
}
