//! `vcm.render` (one call: the command line's session, without files) and `vcm.Session` (a
//! progressive render stepped from Python: [`session::Live`]).

use std::path::PathBuf;

use ::render::Algorithm;
use ::render::vcm::Family;
use ::render::vcm::technique_images::TechniqueLayout;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use session::{Live, Notice, Observer, Prepared, Request, SceneSource};

use crate::images::pixels_to_array;
use crate::interrupt::run_interruptible;
use crate::loading::Scene;
use crate::options::{Caller, Options};
use crate::value_error;

/// Collects a session's warnings and notes, issued as Python warnings afterwards.
#[derive(Default)]
struct Notices(Vec<String>);

impl Observer for Notices {
    fn notice(&mut self, notice: Notice) {
        if !matches!(notice, Notice::Progress(_)) {
            self.0.push(notice.to_string());
        }
    }
}

impl Notices {
    fn warn(self, py: Python<'_>) -> PyResult<()> {
        let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
        for text in self.0 {
            PyErr::warn(py, &category, &std::ffi::CString::new(text).unwrap_or_default(), 1)?;
        }
        Ok(())
    }
}

/// Renders `scene` and returns the image: numpy float32 `(height, width, 3)`, linear sRGB, top
/// row first; the same image as `vcm render` writes for the same settings. Keyword arguments
/// (all optional, see `python/vcm/__init__.pyi`): `algorithm`, `iterations` (default: the scene
/// file's sample count, else 64) or `time` (seconds), `resolution`, `seed`, `threads` (`None`:
/// all cores), `max_length`, `spectral`, `radius_factor`, `radius_alpha`,
/// `volume_radius_factor`, `radius_mode`, `memory_efficient`, `rr_depth`, `heuristic`,
/// `light_sampler`, `mis_compensation`, `sampler`, `parallelism`, `max_memory`, `permissive`. Ctrl-C stops after the current iteration and
/// raises `KeyboardInterrupt`.
#[pyfunction]
#[pyo3(signature = (scene, **kwargs))]
#[pyo3(text_signature = "(scene, *, algorithm='vcm', iterations=None, time=None, resolution=None, seed=0, \
    threads=None, max_length=None, spectral=False, radius_factor=None, radius_alpha=None, \
    volume_radius_factor=None, radius_mode='global', memory_efficient=False, rr_depth=None, \
    heuristic='balance', light_sampler='tree', mis_compensation=True, sampler='sobol', parallelism='auto', max_memory=None, \
    permissive=False)")]
pub fn render<'py>(py: Python<'py>, scene: &Scene, kwargs: Option<&Bound<'py, PyDict>>) -> PyResult<Bound<'py, PyAny>> {
    let options = Options::parse(Caller::Render, kwargs)?;
    let request = options.request(scene.source.clone()).map_err(value_error)?;
    let mut notices = Notices::default();
    let outcome = run_interruptible(py, |stop| session::render(&request, Some(stop), &mut notices))?;
    notices.warn(py)?;
    let film = outcome.map_err(value_error)?.output.film;
    pixels_to_array(py, film.mean(), film.width(), film.height())
}

/// A progressive render stepped from Python: `step(n)` renders `n` more iterations (the same
/// iterations, in the same order, as one `vcm.render` call, so stepping to N iterations gives
/// its image). Keyword arguments as `vcm.render` (no budget), plus `techniques=True` to record
/// per-technique images (VCM engine algorithms), `technique_length` (1-8) bounding the
/// per-(s, t) ones.
#[pyclass(module = "vcm")]
pub struct Session {
    live: Live,
}

impl Session {
    fn start(py: Python<'_>, request: Request, layout: Option<TechniqueLayout>) -> PyResult<Self> {
        let mut notices = Notices::default();
        let prepared = py.detach(|| Prepared::new(&request, &mut notices)).map_err(value_error)?;
        notices.warn(py)?;
        let mut prepared = prepared;
        if let Some(layout) = layout {
            if !matches!(prepared.settings.algorithm, Algorithm::Vcm(_)) {
                return Err(PyValueError::new_err(format!(
                    "techniques=True needs an algorithm of the VCM engine (lt, ppm, bpm, bpt, vcm), not {}",
                    prepared.settings.algorithm.name()
                )));
            }
            prepared.layout = Some(layout);
            prepared.record_families = true;
        }
        let live = py.detach(|| Live::start(prepared)).map_err(value_error)?;
        Ok(Self { live })
    }
}

#[pymethods]
impl Session {
    #[new]
    #[pyo3(signature = (scene, **kwargs))]
    #[pyo3(text_signature = "(scene, *, algorithm='vcm', resolution=None, seed=0, threads=None, \
        max_length=None, spectral=False, radius_factor=None, radius_alpha=None, volume_radius_factor=None, \
        radius_mode='global', memory_efficient=False, rr_depth=None, heuristic='balance', \
        light_sampler='tree', mis_compensation=True, sampler='sobol', parallelism='auto', max_memory=None, permissive=False, \
        techniques=False, \
        technique_length=4)")]
    fn new(py: Python<'_>, scene: &Scene, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let options = Options::parse(Caller::Session, kwargs)?;
        let request = options.request(scene.source.clone()).map_err(value_error)?;
        let layout = match options.techniques {
            true => Some(
                TechniqueLayout::new(options.technique_length)
                    .map_err(|e| PyValueError::new_err(format!("technique_length: {e}")))?,
            ),
            false => None,
        };
        Self::start(py, request, layout)
    }

    /// Continues the render saved by `checkpoint(path)` (or `vcm render --checkpoint`): its
    /// scene and settings come from the file; `threads` as in the constructor.
    #[staticmethod]
    #[pyo3(signature = (path, threads = None))]
    fn resume(py: Python<'_>, path: PathBuf, threads: Option<usize>) -> PyResult<Self> {
        let mut request = Request::new(SceneSource::Builtin(0));
        request.resume = Some(path);
        request.threads = threads.unwrap_or(0);
        Self::start(py, request, None)
    }

    /// Renders `n` more iterations; returns the iteration count. Ctrl-C stops after the current
    /// iteration and raises `KeyboardInterrupt`; the session stays usable.
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, py: Python<'_>, n: u64) -> PyResult<u64> {
        let live = &mut self.live;
        run_interruptible(py, |stop| live.step(n, Some(stop)))?.map_err(value_error)?;
        Ok(self.live.with_render(|p| p.iterations()))
    }

    /// Iterations rendered (a resumed checkpoint's included).
    #[getter]
    fn iterations(&self) -> u64 {
        self.live.with_render(|p| p.iterations())
    }

    /// Seconds spent rendering in this process (wall clock, summed over `step` calls).
    #[getter]
    fn seconds(&self) -> f64 {
        self.live.with_render(|p| p.elapsed().as_secs_f64())
    }

    /// `(width, height)` in pixels.
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        let camera = &self.live.prepared().scene.camera;
        (camera.width, camera.height)
    }

    /// The image: the mean of the iterations, float32 `(height, width, 3)`, top row first.
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (pixels, (w, h)) = self.live.with_render(|p| (p.film().mean(), (p.film().width(), p.film().height())));
        pixels_to_array(py, pixels, w, h)
    }

    /// Per-pixel variance of the image (of the mean), estimated from the spread of the
    /// iterations: float32 `(height, width, 3)`; for `vcm.compare(variance_a=...)`.
    fn variance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (pixels, (w, h)) =
            self.live.with_render(|p| (p.film().variance_of_mean(), (p.film().width(), p.film().height())));
        let pixels = pixels.ok_or_else(|| PyValueError::new_err("this session's film keeps no variance"))?;
        pixels_to_array(py, pixels, w, h)
    }

    /// Per-technique images (a session made with `techniques=True`): a dict of float32
    /// `(height, width, 3)` arrays, the five families (`emitter-hit`, `next-event`,
    /// `light-tracing`, `connection`, `merging`) and the (s, t) images (`s0-t2`, ...,
    /// `merge-s2-t2`, ..., `longer-<family>`). The families sum to the image, and so do the
    /// (s, t) images.
    fn techniques<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (w, h) = self.resolution();
        let images: Option<Vec<(String, Vec<[f32; 3]>)>> = self.live.with_render(|p| {
            let families = p.family_films()?;
            let techniques = p.technique_images()?;
            let mut images: Vec<_> =
                Family::ALL.iter().zip(families).map(|(f, film)| (f.name().to_string(), film.mean())).collect();
            for (index, technique) in techniques.layout().images().iter().enumerate() {
                images.push((technique.name(), techniques.mean(index)));
            }
            Some(images)
        });
        let images = images.ok_or_else(|| {
            PyValueError::new_err("this session records no technique images: create it with techniques=True")
        })?;
        let dict = PyDict::new(py);
        for (name, pixels) in images {
            dict.set_item(name, pixels_to_array(py, pixels, w, h)?)?;
        }
        Ok(dict)
    }

    /// Saves the render's state to `path`; `vcm.Session.resume(path)` (or `vcm render --resume`)
    /// continues it.
    fn checkpoint(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let live = &self.live;
        py.detach(|| live.checkpoint(&path)).map_err(value_error)
    }

    fn __repr__(&self) -> String {
        let prepared = self.live.prepared();
        let (w, h) = self.resolution();
        format!(
            "vcm.Session('{}', algorithm='{}', {w}x{h}, iterations={})",
            prepared.scene.name,
            prepared.settings.algorithm.name(),
            self.iterations()
        )
    }
}
