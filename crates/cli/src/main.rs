//! `vcm`: the command-line front end. Parses arguments and translates them into a render
//! session ([`session`], which loads the scene, renders, checkpoints and writes the images),
//! then prints. The command line's defaults and help texts live here.

mod bench;
mod bench_accel;
mod compare;
mod conformance;
mod huge_pages;
mod merge;
#[cfg(feature = "mpi")]
mod mpi;
mod report;

use render::path_tracer::{Heuristic, LightSampler, RussianRoulette};
use render::primary_samples::PrimarySamples;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::{Result, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};
use render::Algorithm;
use render::driver::Budget;
use render::vcm::RadiusMode;
use scene::Summation;
use scene::cornell;
use scene::filter::FilmMode;
use session::slice::SliceSpec;
use session::{LoadedScene, Notice, SceneSource};
// The per-entry Z-test of `compare` and `conformance`.
use image_metrics::ztest;

#[derive(Parser)]
#[command(name = "vcm", version, about = "A physically based renderer built around vertex connection and merging")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image.
    Render(RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// Time iterations of the algorithms on the reference scenes.
    Bench(bench::BenchArgs),
    /// Compare two images (RMSE, relative MSE, means, optional per-pixel Z-test).
    Compare(compare::CompareArgs),
    /// Render scenes with several algorithms at equal time and write an HTML comparison.
    Report(report::ReportArgs),
    /// Render Mitsuba 3's render test suite and judge every scene against its reference.
    Conformance(conformance::ConformanceArgs),
    /// Merge the checkpoints of a render's slices (`vcm render --slice K/N`) into its image.
    Merge(merge::MergeArgs),
}

/// Algorithm names as the command line spells them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum AlgorithmName {
    /// Path tracing (BSDF sampling + next-event estimation, MIS).
    Pt,
    /// Eye light: |cos| shading preview.
    El,
    /// Light tracing.
    Lt,
    /// Progressive photon mapping.
    Ppm,
    /// Bidirectional photon mapping.
    Bpm,
    /// Bidirectional path tracing.
    Bpt,
    /// Vertex connection and merging.
    Vcm,
}

impl AlgorithmName {
    fn algorithm(self) -> Algorithm {
        let name = self.to_possible_value().map(|v| v.get_name().to_string()).unwrap_or_default();
        Algorithm::from_name(&name).expect("every command-line algorithm name is implemented")
    }
}

/// `--radius-mode` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum RadiusModeName {
    /// `--radius-factor` times the scene's merging scale (its bounding-sphere radius, or the
    /// visible part's when the camera sees much less), shrunk by √(512² / pixels) above 512²
    /// pixels: merging costs the same per pixel at every resolution.
    Global,
    /// `--radius-factor` times the scene's merging scale at every resolution.
    Fixed,
    /// The pixel's footprint at the first surface it sees.
    PerPixel,
}

impl RadiusModeName {
    /// The engine's mode.
    pub(crate) fn mode(self) -> RadiusMode {
        match self {
            Self::Global => RadiusMode::Global,
            Self::Fixed => RadiusMode::Fixed,
            Self::PerPixel => RadiusMode::PerPixel,
        }
    }

    /// The command line's name (and the checkpoints').
    pub(crate) fn name(self) -> &'static str {
        session::radius_mode_name(self.mode())
    }
}

#[derive(Args)]
struct RenderArgs {
    /// Scene: a built-in id (0-3) or name (see `vcm scenes`), or a scene file: Mitsuba 3 XML
    /// (.xml) or pbrt-v4 (.pbrt).
    #[arg(long, default_value = "cornell-sun")]
    scene: String,
    /// Set a scene-file parameter, overriding its `<default>` (Mitsuba: `$NAME`); repeatable.
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE")]
    defines: Vec<String>,
    /// Build the Cornell box from a bit mask instead (0-1023, see `vcm scenes`); overrides --scene.
    #[arg(long, value_name = "N")]
    scene_mask: Option<u32>,
    /// Rendering algorithm.
    #[arg(long, short, value_enum, default_value_t = AlgorithmName::Vcm)]
    algorithm: AlgorithmName,
    /// Number of iterations, one sample per pixel each [default: the scene file's sample count,
    /// else 64].
    #[arg(long, short, value_name = "N", conflicts_with = "time")]
    iterations: Option<u64>,
    /// Render for this many seconds of wall-clock time instead.
    #[arg(long, short, value_name = "SECONDS")]
    time: Option<f64>,
    /// Image size in pixels [default: the scene file's film, 512x512 for built-in scenes].
    #[arg(long, short, value_name = "WxH", value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Maximum path length in segments (camera segment included; 2 = direct lighting)
    /// [default: the scene file's max_depth, 10 for built-in scenes].
    #[arg(long, value_name = "N")]
    max_length: Option<u32>,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Initial merging radius as a fraction of the scene's merging scale: its bounding-sphere
    /// radius, or the visible part's when the camera sees less than a quarter of it.
    #[arg(long, value_name = "F", default_value_t = 0.003)]
    radius_factor: f32,
    /// Merging radius reduction: r_i = r_0 * (i+1)^((alpha-1)/2), 0 < alpha <= 1.
    #[arg(long, value_name = "ALPHA", default_value_t = 0.75)]
    radius_alpha: f32,
    /// Initial merging radius at medium vertices (the 3-D kernel of volumetric photon points),
    /// as a fraction of the scene's merging scale; it shrinks as (i+1)^((alpha-1)/3) and, above
    /// 512² pixels, as the cube root of the pixel count (scenes with media only).
    #[arg(long, value_name = "F", default_value_t = render::vcm::DEFAULT_VOLUME_RADIUS_FACTOR)]
    volume_radius_factor: f32,
    /// Merging radius: one for the image (scaled with the resolution above 512², or fixed), or
    /// per pixel from its footprint (tech report §6.1).
    #[arg(long, value_enum, default_value_t = RadiusModeName::Global)]
    radius_mode: RadiusModeName,
    /// Memory-efficient progressive VCM (tech report §6.2): merge with the previous
    /// iteration's light vertices, keeping only their 64-byte merging data.
    #[arg(long)]
    memory_efficient: bool,
    /// Spectral rendering: four hero-rotated wavelengths per path (360-830 nm), RGB colours
    /// upsampled to spectra, dispersion; the image is still written in linear sRGB.
    #[arg(long)]
    spectral: bool,
    /// Scene-file parameters that would change the image and are not supported become
    /// warnings instead of errors (the render then differs from what the file describes).
    #[arg(long)]
    permissive: bool,
    /// Russian roulette of the path tracer (pt): N = Mitsuba 3's rule from bounce N on
    /// (survival min(max throughput, 0.95)), or `albedo` = the BSDF's continuation probability at
    /// every bounce (the VCM engine's rule, which the other algorithms always use), or `file` =
    /// the scene file's: Mitsuba's rule from the file's integrator rr_depth (Mitsuba's default
    /// 5) for Mitsuba files, albedo for pbrt files and built-in scenes. The default, albedo,
    /// measured more efficient (docs/performance.md, "Russian roulette from the scene file").
    #[arg(long, default_value = "albedo", value_name = "N|albedo|file", value_parser = parse_russian_roulette)]
    rr_depth: RouletteArg,
    /// MIS heuristic of the path tracer (pt): balance or power (exponent 2).
    #[arg(long, default_value = "balance", value_name = "balance|power", value_parser = parse_heuristic)]
    heuristic: Heuristic,
    /// How the path tracer (pt) picks a light for next-event estimation: `tree` conditions on
    /// the shading point (a light BVH, pbrt-v4's), `power` is the scene-global selection (half
    /// power, half uniform over emitters) that the VCM engine always uses. See
    /// docs/lights-suite.md.
    #[arg(long, default_value = "tree", value_name = "tree|power", value_parser = parse_light_sampler)]
    light_sampler: LightSampler,
    /// MIS compensation for image environment maps (pt, bpt and vcm): next-event estimation
    /// samples only the map's directions brighter than its mean, and leaves the rest to BSDF
    /// sampling; both settings estimate the same image, `on` with less noise (0.80x of `off`'s
    /// variance for pt, 0.85x for vcm and bpt on Mitsuba's matpreview; docs/performance.md, "MIS
    /// compensation for environment maps"). `off` is Mitsuba 3's estimator. Other lights and
    /// scenes with media are unaffected.
    #[arg(long, default_value = "on", value_name = "on|off", value_parser = parse_on_off, action = clap::ArgAction::Set)]
    mis_compensation: bool,
    /// Where the path tracer (pt) takes the numbers of its first surface hit from: `sobol`, one
    /// Sobol sequence per pixel over the iterations, Owen-scrambled (less noise per sample:
    /// 0.80x Mitsuba's variance on matpreview at 16 spp against 1.21x, see docs/performance.md,
    /// "Stratified first vertices"), or `independent` numbers. With `sobol` the iterations of a
    /// pixel are not independent, so a --variance image over-estimates the variance of the mean.
    /// Other algorithms draw independent numbers.
    #[arg(long, default_value = "sobol", value_name = "sobol|independent", value_parser = parse_sampler)]
    sampler: PrimarySamples,
    /// How camera samples reach the pixels: `splat` spreads each over the pixels its
    /// reconstruction filter covers (Mitsuba's and pbrt's film), `fis` places it around its
    /// pixel's centre by importance-sampling the filter [default: splat for scene files, fis for
    /// the built-in scenes]. The same for the box filter. See docs/film.md.
    #[arg(long, value_name = "splat|fis", value_parser = parse_film)]
    film: Option<FilmMode>,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", default_value_t = 0)]
    threads: usize,
    /// How the threads share the work: `pixels` (all threads on one iteration), `iterations`
    /// (one iteration per thread, as many at a time as threads: no waiting between an
    /// iteration's phases, one set of buffers per thread), or `auto`: iterations for lt, ppm,
    /// bpm, bpt and vcm on images of at least 256x256 pixels when the memory guard allows
    /// it, pixels otherwise. The image is the same bit for bit. See docs/performance.md,
    /// "Iterations side by side".
    #[arg(long, default_value = "auto", value_name = "auto|pixels|iterations", value_parser = parse_parallelism)]
    parallelism: render::Parallelism,
    /// Memory the light vertices and merging grid may use, e.g. 8G or 512M [default: half of
    /// the physical memory]. A render that needs more switches to --memory-efficient, or stops
    /// with a message when that does not fit either.
    #[arg(long, value_name = "SIZE", value_parser = render::vcm::memory::parse_size)]
    max_memory: Option<u64>,
    /// Output image; the format follows the extension (.exr, .pfm, .hdr, .png). A linear
    /// output also gets a .png preview beside it.
    #[arg(long, short, value_name = "FILE", default_value = "render.exr")]
    output: PathBuf,
    /// Exposure of the PNG preview in stops (the linear outputs are never scaled).
    #[arg(long, value_name = "STOPS", default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Do not draw a progress bar.
    #[arg(long)]
    quiet: bool,
    /// Save the render's state to FILE (atomically) every --checkpoint-every seconds and at
    /// the end, so that `--resume FILE` can continue it.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints (0: after every iteration).
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0)]
    checkpoint_every: f64,
    /// Also write the per-pixel variance of the mean (the squared standard error, estimated
    /// from the spread of the iterations) to FILE (.exr, .pfm or .hdr), for
    /// `vcm compare --variance-a/--variance-b`. Exact for independent iterations: with pt's
    /// default `--sampler sobol` it over-estimates the variance (give `--sampler independent`).
    #[arg(long, value_name = "FILE")]
    variance: Option<PathBuf>,
    /// Write one linear image per technique family (emitter-hit, next-event, light-tracing,
    /// connection, merging; they sum to the image), a false-colour `vc-vm-share.png` (red:
    /// share of vertex connection, green: share of vertex merging) and one linear image per
    /// (s, t) technique up to --technique-length (`s0-t2.exr`, …, `merge-s2-t2.exr`, …, and
    /// `longer-<family>.exr` for the rest; they also sum to the image) into DIR. VCM engine
    /// algorithms only.
    #[arg(long, value_name = "DIR")]
    techniques: Option<PathBuf>,
    /// Longest path (in segments, 1 to 8) with its own per-(s, t) image in --techniques; longer
    /// paths go to one `longer-<family>.exr` per family. Each image costs 36 bytes per pixel.
    #[arg(long, value_name = "N", default_value_t = 4, requires = "techniques")]
    technique_length: u32,
    /// Continue the render saved in FILE: scene, algorithm, resolution, seed, path length and
    /// radius settings come from the checkpoint (those options are ignored); --iterations
    /// counts the checkpoint's iterations too. Keeps checkpointing to FILE.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// How the film adds iterations: `float` (f64 sums, 24 bytes per pixel) or `fixed` (exact
    /// fixed-point sums, 48 bytes per pixel; the image differs from float's in the last bits
    /// only) [default: float; fixed with --slice]. See docs/distributed.md.
    #[arg(long, value_name = "float|fixed", value_parser = parse_summation)]
    sums: Option<Summation>,
    /// Render only slice K of N (0-based) of the iterations into --checkpoint FILE, for a
    /// batch scheduler's array job; `vcm merge` adds the N slices into the image of one
    /// `vcm render --sums fixed`, bit for bit. See docs/distributed.md.
    #[arg(long, value_name = "K/N", value_parser = parse_slice)]
    slice: Option<SliceSpec>,
}

fn parse_resolution(text: &str) -> Result<(u32, u32), String> {
    let invalid = || format!("invalid resolution '{text}': expected WIDTHxHEIGHT, e.g. 512x512, each 1-16384");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(invalid)?;
    let w: u32 = w.trim().parse().map_err(|_| invalid())?;
    let h: u32 = h.trim().parse().map_err(|_| invalid())?;
    if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
        return Err(invalid());
    }
    Ok((w, h))
}

/// Loads a scene for the subcommands that render without a session (`bench`, `report`),
/// printing the loader's warnings and, unless `quiet`, what was loaded.
fn load_scene(source: &SceneSource, resolution: Option<(u32, u32)>, quiet: bool) -> Result<LoadedScene> {
    let loaded = session::load_scene(source, resolution, false)?;
    for warning in &loaded.warnings {
        eprintln!("{}", Notice::Warning(warning.clone()));
    }
    if let (Some(line), false) = (&loaded.loaded, quiet) {
        eprintln!("{line}");
    }
    Ok(loaded)
}

/// Set by the first Ctrl-C / SIGTERM: finish the current iteration, write the images, stop.
static STOP: AtomicBool = AtomicBool::new(false);

/// First Ctrl-C / SIGTERM sets [`STOP`] (the work in progress finishes its iteration and writes
/// what it has); a second one exits at once.
fn install_interrupt_handler() {
    let handler = ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: finishing the current iteration (press Ctrl-C again to quit at once)");
    });
    if let Err(error) = handler {
        eprintln!("warning: cannot install the Ctrl-C handler ({error}); an interrupt will lose the work");
    }
}

/// Prints a session's notices on stderr (progress ones unless `--quiet`) and installs the
/// interrupt handler when rendering starts.
#[cfg(not(feature = "mpi"))]
struct Terminal {
    quiet: bool,
}

#[cfg(not(feature = "mpi"))]
impl session::Observer for Terminal {
    fn notice(&mut self, notice: Notice) {
        if !(self.quiet && matches!(notice, Notice::Progress(_))) {
            eprintln!("{notice}");
        }
    }

    fn starting(&mut self) {
        install_interrupt_handler();
    }
}

/// `vcm render`: translates the arguments into a [`session::Request`], runs it, prints the
/// summary line.
fn run_render(args: RenderArgs) -> Result<()> {
    // Settings that only the command line spells as seconds (the rest is checked by the
    // session).
    if !(args.checkpoint_every.is_finite() && args.checkpoint_every >= 0.0) {
        bail!("--checkpoint-every must be a non-negative number of seconds, got {}", args.checkpoint_every);
    }
    let budget = match (args.iterations, args.time) {
        (_, Some(t)) if !(t.is_finite() && t > 0.0) => bail!("--time must be a positive number of seconds, got {t}"),
        (_, Some(t)) => Some(Budget::Time(Duration::from_secs_f64(t))),
        (Some(n), None) => Some(Budget::Iterations(n)),
        // The scene file's sample count, or 64.
        (None, None) => None,
    };
    let scene = match (&args.resume, args.scene_mask) {
        // Replaced by the checkpoint's scene.
        (Some(_), _) => SceneSource::Builtin(0),
        (None, Some(mask)) => SceneSource::Builtin(mask),
        (None, None) => session::scene_source(&args.scene, &args.defines)?,
    };
    let request = session::Request {
        scene,
        resolution: args.resolution,
        algorithm: args.algorithm.algorithm(),
        budget,
        max_length: args.max_length,
        seed: args.seed,
        radius_factor: args.radius_factor,
        radius_alpha: args.radius_alpha,
        volume_radius_factor: args.volume_radius_factor,
        radius_mode: args.radius_mode.mode(),
        memory_efficient: args.memory_efficient,
        spectral: args.spectral,
        threads: args.threads,
        max_memory: args.max_memory,
        progress: !args.quiet,
        output: Some(args.output),
        exposure: args.exposure,
        variance: args.variance,
        keep_variance: false,
        techniques: args.techniques,
        technique_length: args.technique_length,
        checkpoint: args.checkpoint,
        checkpoint_every: Duration::from_secs_f64(args.checkpoint_every),
        resume: args.resume,
        permissive: args.permissive,
        russian_roulette: args.rr_depth.0,
        heuristic: args.heuristic,
        light_sampler: args.light_sampler,
        mis_compensation: args.mis_compensation,
        sampler: args.sampler,
        film: args.film,
        summation: args.sums,
        slice: args.slice,
        parallelism: args.parallelism,
    };
    #[cfg(feature = "mpi")]
    return mpi::render(&request, &STOP, args.quiet);
    #[cfg(not(feature = "mpi"))]
    {
        let outcome = session::render(&request, Some(&STOP), &mut Terminal { quiet: args.quiet })?;
        eprintln!("{}", outcome.summary);
        Ok(())
    }
}

/// The value of `--rr-depth`: a rule, or `file` (`None`: the scene file's rule,
/// `session::resolve_russian_roulette`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RouletteArg(pub Option<RussianRoulette>);

/// Parses `--rr-depth`.
pub(crate) fn parse_russian_roulette(text: &str) -> Result<RouletteArg, String> {
    if text == "file" {
        return Ok(RouletteArg(None));
    }
    RussianRoulette::from_name(text)
        .map(|rule| RouletteArg(Some(rule)))
        .ok_or_else(|| format!("expected a bounce number ≥ 1, 'albedo' or 'file', got '{text}'"))
}

/// Parses `--film`.
pub(crate) fn parse_film(text: &str) -> Result<FilmMode, String> {
    FilmMode::from_name(text).ok_or_else(|| format!("expected 'splat' or 'fis', got '{text}'"))
}

/// Parses `--sums`.
fn parse_summation(text: &str) -> Result<Summation, String> {
    Summation::from_name(text).ok_or_else(|| format!("expected 'float' or 'fixed', got '{text}'"))
}

/// Parses `--slice`.
fn parse_slice(text: &str) -> Result<SliceSpec, String> {
    SliceSpec::parse(text).map_err(|e| format!("{e:#}"))
}

/// Parses `--parallelism`.
pub(crate) fn parse_parallelism(text: &str) -> Result<render::Parallelism, String> {
    render::Parallelism::from_name(text)
        .ok_or_else(|| format!("expected 'auto', 'pixels' or 'iterations', got '{text}'"))
}

/// Parses `--light-sampler`.
pub(crate) fn parse_light_sampler(text: &str) -> Result<LightSampler, String> {
    LightSampler::from_name(text).ok_or_else(|| format!("expected 'tree' or 'power', got '{text}'"))
}

/// Parses an `on|off` switch.
pub(crate) fn parse_on_off(text: &str) -> Result<bool, String> {
    match text {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("expected 'on' or 'off', got '{text}'")),
    }
}

/// Parses `--sampler`.
fn parse_sampler(text: &str) -> Result<PrimarySamples, String> {
    PrimarySamples::from_name(text).ok_or_else(|| format!("expected 'sobol' or 'independent', got '{text}'"))
}

/// Parses `--heuristic`.
fn parse_heuristic(text: &str) -> Result<Heuristic, String> {
    Heuristic::from_name(text).ok_or_else(|| format!("expected 'balance' or 'power', got '{text}'"))
}

fn run_scenes() {
    println!("{:<4} {:<22} {:<6} description", "id", "name", "mask");
    for s in cornell::builtin_scenes() {
        println!("{:<4} {:<22} {:<6} {}", s.id, s.name, s.mask, s.description);
    }
    for f in session::builtin_files::BUILTIN_FILES {
        println!("{:<4} {:<22} {:<6} {}", "", f.name, "file", f.description);
    }
    println!();
    println!("--scene-mask N builds other variants: ceiling light 1, sun 2, point 4, background 8,");
    println!("large mirror 16, large glass 32, small mirror 64, small glass 128, glossy floor 256,");
    println!("fluorescent large sphere and blue-ish light 512.");
}

fn main() -> ExitCode {
    // First of all, before the heap holds anything: start again with huge pages for the heap
    // (`huge_pages.rs`; `VCM_HUGE_PAGES=0` turns it off).
    if let Err(error) = huge_pages::restart_with_huge_pages() {
        eprintln!("error: {error}");
        return ExitCode::from(2);
    }
    let cli = Cli::parse();
    // The instruction-set limit is read where the queries first run; a value it does not know
    // is an error here rather than silently the default.
    if let Err(error) = math::Isa::limit_from_env() {
        eprintln!("error: {error}");
        return ExitCode::from(2);
    }
    let outcome = match cli.command {
        Command::Render(args) => run_render(args).map(|()| ExitCode::SUCCESS),
        Command::Scenes => {
            run_scenes();
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench(args) => bench::run(args).map(|()| ExitCode::SUCCESS),
        Command::Compare(args) => compare::run(args),
        Command::Report(args) => report::run(args).map(|()| ExitCode::SUCCESS),
        Command::Conformance(args) => conformance::run(args).map(|()| ExitCode::SUCCESS),
        Command::Merge(args) => merge::run(args).map(|()| ExitCode::SUCCESS),
    };
    match outcome {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::from(2)
        }
    }
}
