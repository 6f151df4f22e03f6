//! The keyword arguments `vcm.render` and `vcm.Session` share, and their translation into a
//! [`session::Request`] (the command line's defaults where an argument is `None`).

use std::time::Duration;

use anyhow::{Result, anyhow, bail};
use render::Algorithm;
use render::driver::Budget;
use render::path_tracer::{Heuristic, LightSampler, RussianRoulette};
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
    pub radius_mode: String,
    pub memory_efficient: bool,
    /// `None`: the library's default (albedo); `file`: the scene file's rule
    /// ([`session::resolve_russian_roulette`]).
    pub rr_depth: Option<String>,
    pub heuristic: String,
    pub light_sampler: String,
    pub max_memory: Option<u64>,
    pub permissive: bool,
}

impl Options {
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
        request.max_memory = self.max_memory;
        request.permissive = self.permissive;
        // `Session.variance()` may be asked for at any time.
        request.keep_variance = true;
        Ok(request)
    }
}
