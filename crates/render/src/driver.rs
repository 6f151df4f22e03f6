//! The progressive driver: runs iterations of an integrator over the whole image until an
//! iteration count or a wall-clock budget is reached, on a chosen number of threads.
//!
//! Determinism: every pixel of every iteration draws from its own random stream
//! `Rng::for_stream(seed, iteration, pixel)`, and each pixel's iterations are summed in order,
//! so the image does not depend on the number of threads.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use math::Rng;
use rayon::prelude::*;
use scene::{Film, FrameBuffer, Scene, Summation};
use spectrum::Rgb;

use crate::eye_light;
use crate::parallelism::Parallelism;
use crate::path_tracer::PathTracer;
use crate::primary_samples::{PathDims, PrimarySamples};
use crate::progressive::{Progressive, run_budget};
use crate::splat_frame;
use crate::vcm::technique_images::{TechniqueImages, TechniqueLayout};
use crate::vcm::{RadiusMode, VcmAlgorithm, VcmEngine, VcmSettings};

/// The rendering algorithms. The names are the command-line spellings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    /// Path tracing with next-event estimation and MIS.
    PathTracing,
    /// Eye light: `|cos|` shading preview.
    EyeLight,
    /// An algorithm of the VCM engine.
    Vcm(VcmAlgorithm),
}

impl Algorithm {
    /// Every algorithm with its command-line name.
    pub const ALL: [(Algorithm, &'static str); 7] = [
        (Algorithm::PathTracing, "pt"),
        (Algorithm::EyeLight, "el"),
        (Algorithm::Vcm(VcmAlgorithm::LightTracing), "lt"),
        (Algorithm::Vcm(VcmAlgorithm::ProgressivePhotonMapping), "ppm"),
        (Algorithm::Vcm(VcmAlgorithm::BidirectionalPhotonMapping), "bpm"),
        (Algorithm::Vcm(VcmAlgorithm::BidirectionalPathTracing), "bpt"),
        (Algorithm::Vcm(VcmAlgorithm::VertexConnectionMerging), "vcm"),
    ];

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
    /// Initial merging radius as a fraction of the scene's merging scale
    /// ([`crate::vcm::radius::MergingScale`]).
    pub radius_factor: f32,
    /// Merging radius reduction α.
    pub radius_alpha: f32,
    /// Initial merging radius at medium vertices as a fraction of the scene's merging scale
    /// ([`crate::vcm::VcmSettings::volume_radius_factor`]; scenes with media only).
    pub volume_radius_factor: f32,
    /// Global or per-pixel merging radius.
    pub radius_mode: RadiusMode,
    /// Memory-efficient progressive mode of the VCM engine (tech report §6.2).
    pub memory_efficient: bool,
    /// Spectral mode: hero wavelength sampling with four wavelengths per path
    /// ([`spectrum::Hero4`]); RGB otherwise.
    pub spectral: bool,
    /// Russian roulette of the path tracer (`pt`); the VCM engine always uses the BSDF's
    /// continuation probability.
    pub russian_roulette: crate::path_tracer::RussianRoulette,
    /// MIS heuristic of the path tracer (`pt`).
    pub heuristic: crate::path_tracer::Heuristic,
    /// How the path tracer (`pt`) picks lights for next-event estimation.
    pub light_sampler: crate::path_tracer::LightSampler,
    /// MIS compensation for image environments in `pt` and the VCM engine's algorithms
    /// ([`PathTracer::mis_compensation`], [`VcmSettings::mis_compensation`]). Default: on.
    pub mis_compensation: bool,
    /// Where the path tracer (`pt`) takes its first vertices' numbers from
    /// ([`crate::primary_samples`]). Default: independent numbers (the front ends' default,
    /// `session::Request`, is the stratified sequence).
    pub primary_samples: PrimarySamples,
    /// Spectral mode with merging: wavelength groups per iteration
    /// ([`crate::vcm::VcmSettings::wavelength_groups`]).
    pub wavelength_groups: u32,
    /// The film keeps the per-pixel sums of squares of the iterations (24 bytes per pixel) for
    /// [`Film::variance_of_mean`] and checkpoints; without them the render's peak memory is
    /// lower. Default: on.
    pub variance: bool,
    /// How the film adds iterations ([`Summation::Float`] by default; [`Summation::Fixed`]
    /// makes films of disjoint iteration ranges mergeable bit for bit).
    pub summation: Summation,
    /// How the threads share the work: the pixels of one iteration, or whole iterations side by
    /// side ([`Parallelism`]). The image is the same bit for bit either way.
    pub parallelism: Parallelism,
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
            radius_factor: 0.003,
            radius_alpha: 0.75,
            volume_radius_factor: crate::vcm::DEFAULT_VOLUME_RADIUS_FACTOR,
            radius_mode: RadiusMode::Global,
            memory_efficient: false,
            spectral: false,
            russian_roulette: crate::path_tracer::RussianRoulette::default(),
            heuristic: crate::path_tracer::Heuristic::Balance,
            light_sampler: crate::path_tracer::LightSampler::default(),
            mis_compensation: true,
            primary_samples: PrimarySamples::default(),
            wavelength_groups: crate::vcm::wavelengths::DEFAULT_WAVELENGTH_GROUPS,
            variance: true,
            summation: Summation::Float,
            parallelism: Parallelism::Auto,
        }
    }
}

impl RenderSettings {
    /// The VCM engine's settings, when the algorithm is one of its.
    pub fn vcm_settings(&self) -> Option<VcmSettings> {
        match self.algorithm {
            Algorithm::Vcm(algorithm) => Some(VcmSettings {
                algorithm,
                max_length: self.max_length,
                radius_factor: self.radius_factor,
                radius_alpha: self.radius_alpha,
                volume_radius_factor: self.volume_radius_factor,
                radius_mode: self.radius_mode,
                memory_efficient: self.memory_efficient,
                spectral: self.spectral,
                wavelength_groups: self.wavelength_groups,
                film_variance: self.variance,
                mis_compensation: self.mis_compensation,
            }),
            _ => None,
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
    /// Iterations rendered at a time ([`RenderSettings::lanes`]; 1: all threads on one).
    pub lanes: usize,
    /// Light vertices stored in the last iteration and bytes per vertex (VCM engine only).
    pub light_vertices: Option<(usize, usize)>,
    /// Statistics of the last iteration of the VCM engine.
    pub vcm_stats: Option<crate::vcm::IterationStats>,
    /// The render was stopped early through [`Control::stop`].
    pub interrupted: bool,
    /// Per technique family ([`crate::vcm::Family::ALL`] order), when [`Control::record_families`] was set
    /// and the algorithm is one of the VCM engine's.
    pub family_films: Option<[Film; 5]>,
    /// Per (s, t) technique, when [`Control::record_techniques`] was set and the algorithm is
    /// one of the VCM engine's.
    pub technique_images: Option<TechniqueImages>,
    /// Discarded non-finite estimates of this render's iterations per technique family
    /// ([`crate::vcm::Family::ALL`] order; VCM engine only).
    pub rejected_by_family: Option<crate::vcm::RejectedCounts>,
}

/// The integrator of a render, with its state across iterations.
enum Integrator {
    PathTracing(PathTracer),
    EyeLight,
    Vcm(Box<VcmEngine>),
}

/// Renders iterations one at a time: the building block of [`render`], also used by tests
/// that need every iteration's frame.
pub struct Renderer<'a> {
    scene: &'a Scene,
    settings: RenderSettings,
    /// In an `Arc` so that [`Renderer::in_pool`] can hold it while lending `self` to its closure.
    pool: Arc<rayon::ThreadPool>,
    integrator: Integrator,
    frame: FrameBuffer,
    iteration: u64,
    /// The per-pixel integrators' splatting buffers, kept across iterations.
    spread: splat_frame::SpreadScratch,
}

impl<'a> Renderer<'a> {
    /// Prepares a render of `scene` (the budget in `settings` is not used here).
    pub fn new(scene: &'a Scene, settings: &RenderSettings) -> Result<Self, String> {
        Self::starting_at(scene, settings, 0)
    }

    /// Prepares a render whose next iteration is `first_iteration` (resuming a render).
    pub fn starting_at(scene: &'a Scene, settings: &RenderSettings, first_iteration: u64) -> Result<Self, String> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(settings.threads)
            .build()
            .map(Arc::new)
            .map_err(|e| format!("cannot start {} worker threads: {e}", settings.threads))?;
        let max_materials = crate::vcm::light_vertex::MAX_MATERIAL as usize + 1;
        if settings.vcm_settings().is_some() && scene.materials.len() > max_materials {
            return Err(format!(
                "the scene has {} materials; the VCM engine's light vertices can name at most {max_materials}",
                scene.materials.len()
            ));
        }
        if settings.vcm_settings().is_some()
            && let Some(index) = (0..scene.materials.len())
                .find(|&i| scene.material_flags(i as u32).reads_mesh_attribute && scene.materials[i].reads_uv())
        {
            return Err(format!(
                "material {index} reads both a mesh attribute and a uv texture; the VCM engine's light vertices \
                 store only one of the two (the path tracer renders it)"
            ));
        }
        check_media(scene, settings.algorithm)?;
        if scene.media.is_active() && settings.vcm_settings().is_some_and(|v| v.radius_mode == RadiusMode::PerPixel) {
            // cVM of a path through a medium vertex carries the global radius (η_V/η_A = (4/3) r,
            // `vcm::mis`), so it cannot be rebased to a per-pixel radius.
            return Err("the per-pixel merging radius is not supported in scenes with media (issue #15)".to_string());
        }
        let integrator = match (settings.algorithm, settings.vcm_settings()) {
            (_, Some(vcm)) => Integrator::Vcm(Box::new(VcmEngine::new(scene, vcm))),
            (Algorithm::EyeLight, _) => Integrator::EyeLight,
            _ => Integrator::PathTracing(PathTracer {
                spectral: settings.spectral,
                russian_roulette: settings.russian_roulette,
                heuristic: settings.heuristic,
                light_sampler: settings.light_sampler,
                mis_compensation: settings.mis_compensation,
                primary_samples: settings.primary_samples,
                ..PathTracer::new(settings.max_length)
            }),
        };
        let frame = FrameBuffer::new(scene.camera.width, scene.camera.height);
        Ok(Self {
            scene,
            settings: settings.clone(),
            pool,
            integrator,
            frame,
            iteration: first_iteration,
            spread: Default::default(),
        })
    }

    /// Renders the next iteration into [`Renderer::frame`]; returns the number of rejected
    /// (non-finite) samples.
    pub fn step(&mut self) -> u64 {
        let pool = Arc::clone(&self.pool);
        self.step_in(&pool)
    }

    /// [`Renderer::step`] on the threads of `pool` instead of the renderer's own: how
    /// [`crate::progressive`] runs iterations side by side, one thread each.
    pub(crate) fn step_in(&mut self, pool: &rayon::ThreadPool) -> u64 {
        let (scene, seed, iteration) = (self.scene, self.settings.seed, self.iteration);
        if self.frame.pixels.len() != scene.camera.pixel_count() {
            // The frame was taken ([`Renderer::take_frame`]) and not given back.
            self.frame = FrameBuffer::new(scene.camera.width, scene.camera.height);
        }
        let (frame, spread) = (&mut self.frame, &mut self.spread);
        let integrator = &mut self.integrator;
        let rejected = pool.install(|| match integrator {
            Integrator::Vcm(engine) => engine.run_iteration(scene, seed, iteration, frame),
            Integrator::PathTracing(tracer) => {
                let spectral = tracer.spectral;
                render_iteration(
                    scene,
                    (seed, iteration),
                    tracer.primary_samples,
                    (frame, spread),
                    |ray, rng, index, dims| {
                        // Spectral mode: the pixel's wavelengths stratified over the iterations.
                        let u = spectral.then(|| crate::wavelength_sequence::per_index_sample(seed, iteration, index));
                        tracer.radiance_with(scene, ray, rng, u, dims)
                    },
                )
            }
            Integrator::EyeLight => {
                let independent = PrimarySamples::Independent;
                render_iteration(scene, (seed, iteration), independent, (frame, spread), |ray, _, _, _| {
                    eye_light::eye_light(scene, &ray)
                })
            }
        });
        self.iteration += 1;
        rejected
    }

    /// Runs `f` on one of the renderer's worker threads, where each [`Renderer::step`] starts
    /// its iteration on the spot. A step called from outside the pool hands the iteration to a
    /// worker and sleeps until it is done: a cross-thread round trip per iteration, which costs
    /// as much as the rendering itself on an 8 × 8 image (docs/testing.md, "Trimmed
    /// dependencies and cheaper tests"). The images are the same bit for bit.
    pub fn in_pool<R: Send>(&mut self, f: impl FnOnce(&mut Self) -> R + Send) -> R {
        let pool = self.pool();
        pool.install(|| f(self))
    }

    /// Makes `iteration` the next iteration to render (any index: an iteration is a function
    /// of the seed and its index, so a distributed render starts each rank anywhere).
    pub fn seek(&mut self, iteration: u64) {
        self.iteration = iteration;
    }

    /// The frame of the last iteration.
    pub fn frame(&self) -> &FrameBuffer {
        &self.frame
    }

    /// Takes the frame of the last iteration out without copying it (the next
    /// [`Renderer::step`] allocates a new one unless it is given back with
    /// [`Renderer::restore_frame`]).
    pub fn take_frame(&mut self) -> FrameBuffer {
        std::mem::replace(&mut self.frame, FrameBuffer::new(0, 0))
    }

    /// Gives back a frame taken by [`Renderer::take_frame`], to be reused by the next step.
    pub fn restore_frame(&mut self, frame: FrameBuffer) {
        self.frame = frame;
    }

    /// Iterations rendered so far.
    pub fn iterations(&self) -> u64 {
        self.iteration
    }

    /// The worker threads' pool (for [`Progressive::in_pool`]).
    pub(crate) fn pool(&self) -> Arc<rayon::ThreadPool> {
        Arc::clone(&self.pool)
    }

    /// Worker threads.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// The scene it renders.
    pub fn scene(&self) -> &'a Scene {
        self.scene
    }

    /// The settings the renderer was made with.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The VCM engine, when the algorithm is one of its.
    pub fn vcm_engine(&self) -> Option<&VcmEngine> {
        match &self.integrator {
            Integrator::Vcm(engine) => Some(engine),
            _ => None,
        }
    }

    /// The VCM engine, mutably (e.g. to record per-technique images).
    pub fn vcm_engine_mut(&mut self) -> Option<&mut VcmEngine> {
        match &mut self.integrator {
            Integrator::Vcm(engine) => Some(engine),
            _ => None,
        }
    }
}

/// The error for a scene with participating media or index-matched boundaries that
/// `algorithm` cannot render: the path tracer and the algorithms of the VCM engine render
/// homogeneous and grid media (`crate::vcm::medium`; the merging ones with volumetric photon
/// points, `crate::vcm::mis`), the eye-light preview does not; no algorithm renders them together with
/// fluorescent materials (issue #15).
pub fn check_media(scene: &Scene, algorithm: Algorithm) -> Result<(), String> {
    if !scene.media.is_active() {
        return Ok(());
    }
    if !matches!(algorithm, Algorithm::PathTracing | Algorithm::Vcm(_)) {
        return Err("media are rendered by pt, lt, bpt, ppm, bpm and vcm only (issue #15)".to_string());
    }
    if scene.has_fluorescence() {
        return Err("fluorescent materials in a scene with media are not supported yet (issue #15)".to_string());
    }
    Ok(())
}

/// How a progressive render can be continued, stopped and saved, beyond its settings.
#[derive(Default)]
pub struct Control<'a> {
    /// Continue this film (a resumed render): its iteration count is the index of the next
    /// iteration, so the result equals an uninterrupted render with the same settings.
    pub resume: Option<Film>,
    /// When set (e.g. by a Ctrl-C handler), the render finishes the current iteration and
    /// stops.
    pub stop: Option<&'a AtomicBool>,
    /// Called with the film every `checkpoint_every` of wall-clock time (after the iteration
    /// that crosses the interval) and once at the end; a returned error stops the render.
    pub checkpoint: Option<(Duration, SaveFilm<'a>)>,
    /// Accumulate one film per technique family of the VCM engine ([`crate::vcm::Family`]), returned in
    /// [`RenderOutput::family_films`]; they sum to the film. Ignored by the other integrators
    /// and when resuming (the families of earlier iterations are not in a checkpoint).
    pub record_families: bool,
    /// Accumulate one image per (s, t) technique of the VCM engine, laid out as given
    /// ([`crate::vcm::technique_images`]), returned in [`RenderOutput::technique_images`]; they
    /// sum to the film. Ignored like `record_families`.
    pub record_techniques: Option<TechniqueLayout>,
}

/// A callback that saves the film (a checkpoint); an error stops the render.
pub type SaveFilm<'a> = Box<dyn FnMut(&Film) -> Result<(), String> + 'a>;

/// Renders `scene` progressively as `settings` say.
pub fn render(scene: &Scene, settings: &RenderSettings) -> Result<RenderOutput, String> {
    render_with(scene, settings, Control::default())
}

/// Renders `scene` progressively as `settings` say, resumable, stoppable and checkpointed as
/// `control` says. `Budget::Iterations(n)` counts the iterations of the resumed film too;
/// `Budget::Time` counts this call's time only.
pub fn render_with(scene: &Scene, settings: &RenderSettings, control: Control) -> Result<RenderOutput, String> {
    let Control { resume, stop, checkpoint, record_families, record_techniques } = control;
    let mut progressive = Progressive::new(scene, settings, resume, record_families, record_techniques)?;
    let interrupted = run_budget(&mut progressive, settings, stop, checkpoint)?;
    Ok(progressive.into_output(interrupted))
}

/// Renders one iteration of a per-pixel integrator into `frame` (overwriting it); returns the
/// number of rejected (non-finite) samples. Under [`scene::filter::FilmMode::Splat`] the
/// samples are then spread over the pixels their filter reaches ([`crate::splat_frame`]).
fn render_iteration(
    scene: &Scene,
    (seed, iteration): (u64, u64),
    samples: PrimarySamples,
    (frame, spread): (&mut FrameBuffer, &mut splat_frame::SpreadScratch),
    radiance: impl Fn(math::Ray, &mut Rng, u64, PathDims) -> Rgb + Sync,
) -> u64 {
    let width = frame.width as usize;
    // Independent numbers also with the sequence: drawing the offset from dimensions of its own
    // did not lower the noise (docs/performance.md, "Stratified first vertices").
    let film_offset = splat_frame::film_offset(seed, iteration);
    let rejected = frame
        .pixels
        .par_chunks_mut(width)
        .enumerate()
        .map(|(y, row)| {
            let mut rejected = 0u64;
            for (x, pixel) in row.iter_mut().enumerate() {
                let flat = y * width + x;
                let index = flat as u64;
                let mut rng = splat_frame::camera_stream(seed, iteration, flat);
                let dims = PathDims::new(samples, seed, index, iteration);
                // Raster position through the filter (weight 1 for the box and when
                // splatting), then the lens.
                let primary = scene.camera.sample_primary(x as u32, y as u32, film_offset, &mut rng);
                let value = radiance(primary.ray, &mut rng, index, dims) * primary.weight;
                *pixel = if value.is_finite() {
                    value
                } else {
                    rejected += 1;
                    Rgb::BLACK
                };
            }
            rejected
        })
        .sum();
    splat_frame::spread_camera_pass(&scene.camera, seed, iteration, &mut frame.pixels, None, None, spread);
    rejected
}
