//! The progressive driver: runs iterations of an integrator over the whole image until an
//! iteration count or a wall-clock budget is reached, on a chosen number of threads.
//!
//! Determinism: every pixel of every iteration draws from its own random stream
//! `Rng::for_stream(seed, iteration, pixel)`, and each pixel's iterations are summed in order,
//! so the image does not depend on the number of threads.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use math::{Rng, Vec2};
use rayon::prelude::*;
use scene::{Film, FrameBuffer, Scene};
use spectrum::Rgb;

use crate::{eye_light, path_tracer};

/// The rendering algorithms. The names are the command-line spellings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    /// Path tracing with next-event estimation and MIS.
    PathTracing,
    /// Eye light: `|cos|` shading preview.
    EyeLight,
}

impl Algorithm {
    /// Every algorithm with its command-line name.
    pub const ALL: [(Algorithm, &'static str); 2] = [(Algorithm::PathTracing, "pt"), (Algorithm::EyeLight, "el")];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(a, _)| *a == self).map(|(_, n)| *n).unwrap_or("?")
    }

    /// Parses a command-line name.
    pub fn from_name(name: &str) -> Option<Algorithm> {
        Self::ALL.iter().find(|(_, n)| *n == name).map(|(a, _)| *a)
    }
}

/// When to stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// A fixed number of iterations.
    Iterations(u64),
    /// Iterations until this wall-clock time has passed (at least one iteration).
    Time(Duration),
}

/// Everything the driver needs besides the scene.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Which integrator.
    pub algorithm: Algorithm,
    /// When to stop.
    pub budget: Budget,
    /// Maximum path length in segments (camera segment included).
    pub max_length: u32,
    /// Seed of all random streams.
    pub seed: u64,
    /// Worker threads (0 = all cores).
    pub threads: usize,
    /// Draw a progress bar on stderr (only when it is a terminal).
    pub progress: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            algorithm: Algorithm::PathTracing,
            budget: Budget::Iterations(1),
            max_length: 10,
            seed: 0,
            threads: 0,
            progress: false,
        }
    }
}

/// The result of a render.
#[derive(Debug)]
pub struct RenderOutput {
    /// Accumulated image.
    pub film: Film,
    /// Wall-clock time spent in iterations.
    pub elapsed: Duration,
    /// Threads actually used.
    pub threads: usize,
}

/// Renders `scene` progressively as `settings` say.
pub fn render(scene: &Scene, settings: &RenderSettings) -> Result<RenderOutput, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| format!("cannot start {} worker threads: {e}", settings.threads))?;
    let threads = pool.current_num_threads();
    let camera = &scene.camera;
    let mut film = Film::new(camera.width, camera.height);
    let mut frame = FrameBuffer::new(camera.width, camera.height);
    let progress = make_progress_bar(settings);
    let start = Instant::now();
    let mut iteration = 0u64;
    loop {
        match settings.budget {
            Budget::Iterations(n) if iteration >= n => break,
            Budget::Time(limit) if iteration > 0 && start.elapsed() >= limit => break,
            _ => {}
        }
        let rejected = pool.install(|| render_iteration(scene, settings, iteration, &mut frame));
        film.add_iteration(&frame, rejected);
        iteration += 1;
        if let Some(bar) = &progress {
            match settings.budget {
                Budget::Iterations(_) => bar.set_position(iteration),
                Budget::Time(_) => {
                    bar.set_position(start.elapsed().as_millis() as u64);
                    bar.set_message(format!("{iteration} it"));
                }
            }
        }
    }
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    Ok(RenderOutput { film, elapsed: start.elapsed(), threads })
}

fn make_progress_bar(settings: &RenderSettings) -> Option<ProgressBar> {
    if !settings.progress || !std::io::stderr().is_terminal() {
        return None;
    }
    let (length, template) = match settings.budget {
        Budget::Iterations(n) => (n, "{bar:40} {pos}/{len} iterations, {per_sec}, ETA {eta}"),
        Budget::Time(limit) => (limit.as_millis() as u64, "{bar:40} {elapsed}/{duration} {msg}"),
    };
    let bar = ProgressBar::new(length);
    bar.set_style(ProgressStyle::with_template(template).ok()?);
    Some(bar)
}

/// Renders one iteration into `frame` (overwriting it); returns the number of rejected
/// (non-finite) samples.
fn render_iteration(scene: &Scene, settings: &RenderSettings, iteration: u64, frame: &mut FrameBuffer) -> u64 {
    let width = frame.width as usize;
    frame
        .pixels
        .par_chunks_mut(width)
        .enumerate()
        .map(|(y, row)| {
            let mut rejected = 0u64;
            for (x, pixel) in row.iter_mut().enumerate() {
                let index = (y * width + x) as u64;
                let mut rng = Rng::for_stream(settings.seed, iteration, index);
                let raster = Vec2::new(x as f32 + rng.uniform(), y as f32 + rng.uniform());
                let ray = scene.camera.generate_ray(raster);
                let value = match settings.algorithm {
                    Algorithm::PathTracing => {
                        path_tracer::PathTracer::new(settings.max_length).radiance(scene, ray, &mut rng)
                    }
                    Algorithm::EyeLight => eye_light::eye_light(scene, &ray),
                };
                *pixel = if value.is_finite() {
                    value
                } else {
                    rejected += 1;
                    Rgb::BLACK
                };
            }
            rejected
        })
        .sum()
}
