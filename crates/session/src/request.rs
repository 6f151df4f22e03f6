//! What a front end asks a session for.

use render::path_tracer::{Heuristic, LightSampler, RussianRoulette};
use render::primary_samples::PrimarySamples;
use scene::Summation;
use scene::filter::FilmMode;
use std::path::PathBuf;
use std::time::Duration;

use render::driver::Budget;
use render::vcm::RadiusMode;
use render::{Algorithm, Parallelism, RenderSettings};

use crate::slice::SliceSpec;
use crate::source::SceneSource;

/// The front ends' `pt` sampler (`--sampler`, `sampler=`): the stratified sequence, which has
/// less noise per sample. Not the engine's default (`render::RenderSettings`: independent
/// numbers, which its statistical tests need).
pub const DEFAULT_SAMPLER: PrimarySamples = PrimarySamples::Sobol;

/// Everything a render session needs. [`Request::new`] gives the command line's defaults.
#[derive(Clone, Debug)]
pub struct Request {
    /// The scene.
    pub scene: SceneSource,
    /// Image size in pixels (default: the scene file's film, 512×512 for built-in scenes).
    pub resolution: Option<(u32, u32)>,
    /// The algorithm.
    pub algorithm: Algorithm,
    /// When to stop; `Iterations` counts a resumed checkpoint's iterations too. `None`: as many
    /// iterations as the scene file's samples per pixel (Mitsuba's `<sampler>` `sample_count`,
    /// pbrt's `pixelsamples`; one sample per pixel per iteration), otherwise 64.
    pub budget: Option<Budget>,
    /// Unsupported scene-file parameters that would change the image are warnings instead of
    /// errors.
    pub permissive: bool,
    /// Maximum path length in segments (default: the scene file's, 10 for built-in scenes).
    pub max_length: Option<u32>,
    /// Seed of the random streams.
    pub seed: u64,
    /// Initial merging radius as a fraction of the scene's merging scale
    /// (`render::vcm::radius::MergingScale`).
    pub radius_factor: f32,
    /// Merging radius reduction α, in (0, 1].
    pub radius_alpha: f32,
    /// Initial merging radius at medium vertices as a fraction of the scene's merging scale
    /// (scenes with media; `render::vcm::VcmSettings::volume_radius_factor`).
    pub volume_radius_factor: f32,
    /// Global or per-pixel merging radius.
    pub radius_mode: RadiusMode,
    /// Memory-efficient progressive VCM (tech report §6.2).
    pub memory_efficient: bool,
    /// Spectral rendering.
    pub spectral: bool,
    /// Worker threads (0: all cores).
    pub threads: usize,
    /// Bytes the light vertices and merging grid may use (default: half the physical memory).
    pub max_memory: Option<u64>,
    /// Draw a progress bar (on a terminal).
    pub progress: bool,
    /// The image file (format by extension; linear formats get a `.png` preview beside them).
    /// `None`: write no image (the film is in [`crate::Outcome`]).
    pub output: Option<PathBuf>,
    /// Exposure of PNG outputs in stops.
    pub exposure: f32,
    /// Per-pixel variance of the mean, to this linear image file.
    pub variance: Option<PathBuf>,
    /// Keep the film's sums of squares (24 bytes per pixel) even without a variance file or a
    /// checkpoint, for a front end that reads [`scene::Film::variance_of_mean`] from the
    /// outcome. The session keeps them anyway when `variance` or `checkpoint` is set.
    pub keep_variance: bool,
    /// Per-technique images into this directory (VCM engine algorithms only), with per-(s, t)
    /// images up to `technique_length` segments.
    pub techniques: Option<PathBuf>,
    /// See `techniques` (1 to 8).
    pub technique_length: u32,
    /// Save the render's state to this file every `checkpoint_every` and at the end.
    pub checkpoint: Option<PathBuf>,
    /// Wall-clock time between checkpoints (zero: after every iteration).
    pub checkpoint_every: Duration,
    /// Continue the render saved in this file: scene, algorithm, resolution, seed, path
    /// length, radius, memory-efficient and spectral settings come from it (those fields are
    /// ignored), and it is checkpointed to again unless `checkpoint` is set.
    pub resume: Option<PathBuf>,
    /// Russian roulette of the path tracer (`pt`); by default the albedo rule. `None`: the scene
    /// file's rule ([`crate::resolve_russian_roulette`]: Mitsuba 3's throughput rule from the
    /// file's `rr_depth`, default 5, for Mitsuba files; the albedo rule for pbrt files and
    /// built-in scenes). A resumed render keeps its checkpoint's.
    pub russian_roulette: Option<RussianRoulette>,
    /// MIS heuristic of the path tracer (`pt`).
    pub heuristic: Heuristic,
    /// Light sampler of the path tracer's next-event estimation (`pt`).
    pub light_sampler: LightSampler,
    /// MIS compensation for image environments in `pt` and the VCM engine's algorithms
    /// (`--mis-compensation`, [`RenderSettings::mis_compensation`]). A resumed render keeps its
    /// checkpoint's.
    pub mis_compensation: bool,
    /// Where the path tracer (`pt`) takes its first vertices' numbers from (`--sampler`).
    pub sampler: PrimarySamples,
    /// How camera samples reach the pixels (`--film`). `None`: the scene's choice, splatting
    /// for scene files (which name a reconstruction filter), filter importance sampling for the
    /// built-in scenes. A resumed render keeps its checkpoint's mode (asking for another one is
    /// an error).
    pub film: Option<FilmMode>,
    /// How the film adds iterations (`--sums`). `None`: f64 sums, or fixed-point sums for a
    /// slice (which needs them). A resumed render keeps its checkpoint's.
    pub summation: Option<Summation>,
    /// Render only this slice of the iterations into the checkpoint (`--slice K/N`), for
    /// `vcm merge` ([`crate::slice`]). A resumed slice keeps its checkpoint's.
    pub slice: Option<SliceSpec>,
    /// How the threads share the work (`--parallelism`): the image is the same either way.
    pub parallelism: Parallelism,
}

impl Request {
    /// A request for `scene` with the command line's defaults: VCM, 64 iterations, seed 0,
    /// radius factor 0.003, α 0.75, global radius, RGB, all cores, no outputs, checkpoints
    /// every 60 s when a checkpoint file is set.
    pub fn new(scene: SceneSource) -> Self {
        let defaults = RenderSettings::default();
        Self {
            scene,
            resolution: None,
            algorithm: Algorithm::from_name("vcm").expect("vcm is an algorithm"),
            budget: None,
            permissive: false,
            max_length: None,
            seed: 0,
            radius_factor: defaults.radius_factor,
            radius_alpha: defaults.radius_alpha,
            volume_radius_factor: defaults.volume_radius_factor,
            radius_mode: RadiusMode::Global,
            memory_efficient: false,
            spectral: false,
            threads: 0,
            max_memory: None,
            progress: false,
            output: None,
            exposure: 0.0,
            variance: None,
            keep_variance: false,
            techniques: None,
            technique_length: 4,
            checkpoint: None,
            checkpoint_every: Duration::from_secs(60),
            resume: None,
            russian_roulette: Some(RussianRoulette::Albedo),
            heuristic: defaults.heuristic,
            light_sampler: defaults.light_sampler,
            mis_compensation: defaults.mis_compensation,
            sampler: DEFAULT_SAMPLER,
            film: None,
            summation: None,
            slice: None,
            parallelism: Parallelism::Auto,
        }
    }
}

/// The command line's name of a radius mode (`global`, `fixed`, `per-pixel`), as checkpoints
/// record it.
pub fn radius_mode_name(mode: RadiusMode) -> &'static str {
    match mode {
        RadiusMode::Global => "global",
        RadiusMode::Fixed => "fixed",
        RadiusMode::PerPixel => "per-pixel",
    }
}

/// Parses [`radius_mode_name`]'s names.
pub fn radius_mode_from_name(name: &str) -> Option<RadiusMode> {
    match name {
        "global" => Some(RadiusMode::Global),
        "fixed" => Some(RadiusMode::Fixed),
        "per-pixel" => Some(RadiusMode::PerPixel),
        _ => None,
    }
}
