//! The keyword arguments `vcm.render` and `vcm.Session` share, parsed from their `**kwargs` by
//! one table, and their translation into a [`session::Request`] (the command line's defaults
//! where an argument is absent or `None`).
//!
//! Both functions take `(scene, **kwargs)`: one parser instead of two 20-parameter signatures
//! that had to be kept in step (and a 21-parameter `#[new]` that pyo3 0.27 turned into an
//! aborting "invalid PyErr" on any error). An unknown keyword is a `TypeError` naming the
//! keywords the function accepts, as Python's own functions report it; a value of the wrong
//! type is a `TypeError` naming the keyword.

use std::time::Duration;

use anyhow::{Result, anyhow, bail};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use render::Algorithm;
use render::driver::Budget;
use render::path_tracer::{Heuristic, LightSampler, RussianRoulette};
use render::primary_samples::PrimarySamples;
use session::{Request, SceneSource};

/// The settings of a render, as the Python functions receive them.
pub struct Options {
    pub algorithm: String,
    pub iterations: Option<u64>,
    pub time: Option<f64>,
    pub resolution: Option<(u32, u32)>,
    pub seed: u64,
    pub threads: Option<usize>,
    pub max_length: Option<u32>,
    pub spectral: bool,
    pub radius_factor: Option<f32>,
    pub radius_alpha: Option<f32>,
    /// The medium vertices' merging radius as a fraction of the volume scale (`None`: the
    /// command line's default, [`render::vcm::DEFAULT_VOLUME_RADIUS_FACTOR`]).
    pub volume_radius_factor: Option<f32>,
    pub radius_mode: String,
    pub memory_efficient: bool,
    /// `None`: the library's default (albedo); `file`: the scene file's rule
    /// ([`session::resolve_russian_roulette`]).
    pub rr_depth: Option<String>,
    pub heuristic: String,
    pub light_sampler: String,
    /// MIS compensation for image environments (`--mis-compensation`).
    pub mis_compensation: bool,
    pub sampler: String,
    /// How the threads share the work (`--parallelism`): `auto`, `pixels` or `iterations`.
    pub parallelism: String,
    pub max_memory: Option<u64>,
    pub permissive: bool,
    /// `vcm.Session` only: record per-technique images.
    pub techniques: bool,
    /// `vcm.Session` only: the longest (s, t) technique with an image of its own (1-8).
    pub technique_length: u32,
}

impl Default for Options {
    /// The defaults of the Python signatures (documented in `python/vcm/__init__.pyi`).
    fn default() -> Self {
        // The enumerated defaults are the command line's (`session::Request::new`), by name.
        let request = session::Request::new(session::SceneSource::Builtin(0));
        Self {
            algorithm: "vcm".to_string(),
            iterations: None,
            time: None,
            resolution: None,
            seed: 0,
            threads: None,
            max_length: None,
            spectral: false,
            radius_factor: None,
            radius_alpha: None,
            volume_radius_factor: None,
            radius_mode: session::radius_mode_name(request.radius_mode).to_string(),
            memory_efficient: false,
            rr_depth: None,
            heuristic: request.heuristic.name().to_string(),
            light_sampler: request.light_sampler.name().to_string(),
            mis_compensation: request.mis_compensation,
            sampler: request.sampler.name().to_string(),
            parallelism: request.parallelism.name().to_string(),
            max_memory: None,
            permissive: false,
            techniques: false,
            technique_length: request.technique_length,
        }
    }
}

/// The keywords both functions accept.
const COMMON: [&str; 19] = [
    "algorithm",
    "resolution",
    "seed",
    "threads",
    "max_length",
    "spectral",
    "radius_factor",
    "radius_alpha",
    "volume_radius_factor",
    "radius_mode",
    "memory_efficient",
    "rr_depth",
    "heuristic",
    "light_sampler",
    "mis_compensation",
    "sampler",
    "parallelism",
    "max_memory",
    "permissive",
];

/// Which function's keywords are parsed: each has two of its own besides [`COMMON`].
#[derive(Clone, Copy)]
pub enum Caller {
    /// `vcm.render(scene, **kwargs)`: a budget (`iterations` or `time`).
    Render,
    /// `vcm.Session(scene, **kwargs)`: technique images (`techniques`, `technique_length`).
    Session,
}

impl Caller {
    fn name(self) -> &'static str {
        match self {
            Caller::Render => "render",
            Caller::Session => "Session",
        }
    }

    fn own(self) -> [&'static str; 2] {
        match self {
            Caller::Render => ["iterations", "time"],
            Caller::Session => ["techniques", "technique_length"],
        }
    }

    /// Every keyword the function accepts, in the order of its documented signature.
    fn keywords(self) -> Vec<&'static str> {
        let mut all = COMMON.to_vec();
        let at = if matches!(self, Caller::Render) { 1 } else { all.len() };
        for (i, own) in self.own().into_iter().enumerate() {
            all.insert(at + i, own);
        }
        all
    }
}

/// `value` converted to `T`, or a `TypeError` naming the function and the keyword.
fn extract<'a, 'py, T: FromPyObject<'a, 'py>>(
    caller: Caller,
    key: &str,
    value: &'a Bound<'py, PyAny>,
    expected: &str,
) -> PyResult<T> {
    value.extract::<T>().map_err(|_| {
        let shown = value.repr().map(|r| r.to_string()).unwrap_or_else(|_| "?".to_string());
        PyTypeError::new_err(format!("{}(): {key} expects {expected}, got {shown}", caller.name()))
    })
}

impl Options {
    /// Parses the keyword arguments of `caller` (`None`: none given). Unknown keywords and
    /// values of the wrong type are `TypeError`s; values are checked later, by
    /// [`Options::request`].
    pub fn parse(caller: Caller, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut o = Options::default();
        let Some(kwargs) = kwargs else { return Ok(o) };
        let accepted = caller.keywords();
        for (key, value) in kwargs.iter() {
            let key: String = key.extract()?;
            if !accepted.contains(&key.as_str()) {
                return Err(PyTypeError::new_err(format!(
                    "{}() got an unexpected keyword argument '{key}'; it accepts: {}",
                    caller.name(),
                    accepted.join(", ")
                )));
            }
            let v = &value;
            match key.as_str() {
                "algorithm" => o.algorithm = extract(caller, &key, v, "a str")?,
                "iterations" => o.iterations = extract(caller, &key, v, "an int >= 0 or None")?,
                "time" => o.time = extract(caller, &key, v, "a float (seconds) or None")?,
                "resolution" => o.resolution = extract(caller, &key, v, "(width, height) or None")?,
                "seed" => o.seed = extract(caller, &key, v, "an int >= 0")?,
                "threads" => o.threads = extract(caller, &key, v, "an int >= 0 or None")?,
                "max_length" => o.max_length = extract(caller, &key, v, "an int >= 0 or None")?,
                "spectral" => o.spectral = extract(caller, &key, v, "a bool")?,
                "radius_factor" => o.radius_factor = extract(caller, &key, v, "a float or None")?,
                "radius_alpha" => o.radius_alpha = extract(caller, &key, v, "a float or None")?,
                "volume_radius_factor" => o.volume_radius_factor = extract(caller, &key, v, "a float or None")?,
                "radius_mode" => o.radius_mode = extract(caller, &key, v, "a str")?,
                "memory_efficient" => o.memory_efficient = extract(caller, &key, v, "a bool")?,
                "rr_depth" => o.rr_depth = extract_rr_depth(caller, v)?,
                "heuristic" => o.heuristic = extract(caller, &key, v, "a str")?,
                "light_sampler" => o.light_sampler = extract(caller, &key, v, "a str")?,
                "mis_compensation" => o.mis_compensation = extract(caller, &key, v, "a bool")?,
                "sampler" => o.sampler = extract(caller, &key, v, "a str")?,
                "parallelism" => o.parallelism = extract(caller, &key, v, "a str")?,
                "max_memory" => o.max_memory = extract(caller, &key, v, "an int (bytes) or None")?,
                "permissive" => o.permissive = extract(caller, &key, v, "a bool")?,
                "techniques" => o.techniques = extract(caller, &key, v, "a bool")?,
                "technique_length" => o.technique_length = extract(caller, &key, v, "an int (1-8)")?,
                _ => unreachable!("every accepted keyword has a branch: {key}"),
            }
        }
        Ok(o)
    }

    /// The request for `scene`, checked as the command line checks its arguments.
    pub fn request(&self, scene: SceneSource) -> Result<Request> {
        let algorithm = Algorithm::from_name(&self.algorithm).ok_or_else(|| {
            let names: Vec<&str> = Algorithm::ALL.iter().map(|(_, n)| *n).collect();
            anyhow!("unknown algorithm '{}': expected one of {}", self.algorithm, names.join(", "))
        })?;
        let budget = match (self.iterations, self.time) {
            (Some(_), Some(_)) => bail!("give iterations or time, not both"),
            (_, Some(t)) if !(t.is_finite() && t > 0.0) => bail!("time must be a positive number of seconds, got {t}"),
            (_, Some(t)) => Some(Budget::Time(Duration::from_secs_f64(t))),
            (Some(n), None) => Some(Budget::Iterations(n)),
            (None, None) => None,
        };
        if let Some((w, h)) = self.resolution
            && !((1..=16384).contains(&w) && (1..=16384).contains(&h))
        {
            bail!("invalid resolution ({w}, {h}): expected (width, height), each 1-16384");
        }
        let mut request = Request::new(scene);
        request.algorithm = algorithm;
        request.budget = budget;
        request.resolution = self.resolution;
        request.seed = self.seed;
        request.threads = self.threads.unwrap_or(0);
        request.max_length = self.max_length;
        request.spectral = self.spectral;
        request.radius_factor = self.radius_factor.unwrap_or(request.radius_factor);
        request.radius_alpha = self.radius_alpha.unwrap_or(request.radius_alpha);
        request.volume_radius_factor = self.volume_radius_factor.unwrap_or(request.volume_radius_factor);
        request.radius_mode = session::radius_mode_from_name(&self.radius_mode).ok_or_else(|| {
            anyhow!("unknown radius_mode '{}': expected 'global', 'fixed' or 'per-pixel'", self.radius_mode)
        })?;
        request.memory_efficient = self.memory_efficient;
        request.russian_roulette =
            match self.rr_depth.as_deref() {
                None => request.russian_roulette,
                Some("file") => None,
                Some(name) => Some(RussianRoulette::from_name(name).ok_or_else(|| {
                    anyhow!("rr_depth: expected a bounce number >= 1, 'albedo' or 'file', got '{name}'")
                })?),
            };
        request.heuristic = Heuristic::from_name(&self.heuristic)
            .ok_or_else(|| anyhow!("heuristic: expected 'balance' or 'power', got '{}'", self.heuristic))?;
        request.light_sampler = LightSampler::from_name(&self.light_sampler)
            .ok_or_else(|| anyhow!("light_sampler: expected 'tree' or 'power', got '{}'", self.light_sampler))?;
        request.mis_compensation = self.mis_compensation;
        request.sampler = PrimarySamples::from_name(&self.sampler)
            .ok_or_else(|| anyhow!("sampler: expected 'sobol' or 'independent', got '{}'", self.sampler))?;
        request.parallelism = render::Parallelism::from_name(&self.parallelism).ok_or_else(|| {
            anyhow!("parallelism: expected 'auto', 'pixels' or 'iterations', got '{}'", self.parallelism)
        })?;
        request.max_memory = self.max_memory;
        request.permissive = self.permissive;
        // `Session.variance()` may be asked for at any time.
        request.keep_variance = true;
        Ok(request)
    }
}

/// `rr_depth`: a bounce number (int or str), `'albedo'`, `'file'` or `None`.
fn extract_rr_depth(caller: Caller, value: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    if let Ok(n) = value.extract::<u32>() {
        return Ok(Some(n.to_string()));
    }
    extract(caller, "rr_depth", value, "an int >= 1, 'albedo', 'file' or None")
}
