//! `vcm`: the command-line front end. Parses arguments, builds the scene, runs the progressive
//! driver and writes the images. This is the only place that makes user-facing decisions
//! (defaults, file names, messages).

mod bench_accel;
mod checkpoint;
mod compare;
mod report;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};
use render::driver::{Budget, Control};
use render::vcm::technique_images::{TechniqueImages, TechniqueLayout};
use render::vcm::{Family, RadiusMode};
use render::{Algorithm, RenderSettings};
use scene::Scene;
use scene::cornell::{self, BUILTIN_SCENES};

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
    Bench(BenchArgs),
    /// Compare two images (RMSE, relative MSE, means, optional per-pixel Z-test).
    Compare(compare::CompareArgs),
    /// Render scenes with several algorithms at equal time and write an HTML comparison.
    Report(report::ReportArgs),
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
enum RadiusModeName {
    /// `--radius-factor` times the scene's bounding-sphere radius.
    Global,
    /// The pixel's footprint at the first surface it sees.
    PerPixel,
}

#[derive(Args)]
struct RenderArgs {
    /// Scene: a built-in id (0-3) or name (see `vcm scenes`), or a scene file: Mitsuba 3 XML
    /// (.xml) or pbrt-v4 (.pbrt).
    #[arg(long, default_value = "cornell-sun")]
    scene: String,
    /// Set a scene-file parameter, overriding its <default> (Mitsuba: `$NAME`); repeatable.
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE")]
    defines: Vec<String>,
    /// Build the Cornell box from a bit mask instead (0-1023, see `vcm scenes`); overrides --scene.
    #[arg(long, value_name = "N")]
    scene_mask: Option<u32>,
    /// Rendering algorithm.
    #[arg(long, short, value_enum, default_value_t = AlgorithmName::Vcm)]
    algorithm: AlgorithmName,
    /// Number of iterations, one sample per pixel each [default: 64].
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
    /// Initial merging radius as a fraction of the scene's bounding-sphere radius.
    #[arg(long, value_name = "F", default_value_t = 0.003)]
    radius_factor: f32,
    /// Merging radius reduction: r_i = r_0 * (i+1)^((alpha-1)/2), 0 < alpha <= 1.
    #[arg(long, value_name = "ALPHA", default_value_t = 0.75)]
    radius_alpha: f32,
    /// Merging radius: one for the image, or per pixel from its footprint (tech report §6.1).
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
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", default_value_t = 0)]
    threads: usize,
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
    /// `vcm compare --variance-a/--variance-b`.
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
}

#[derive(Args)]
struct BenchArgs {
    /// Algorithms to time (default: pt, lt, ppm, bpm, bpt, vcm).
    #[arg(long, short, value_enum, value_delimiter = ',')]
    algorithm: Vec<AlgorithmName>,
    /// Scenes to time (ids or names; default: all four).
    #[arg(long, short, value_delimiter = ',')]
    scene: Vec<String>,
    /// Iterations per scene (after one warm-up iteration).
    #[arg(long, short, default_value_t = 8)]
    iterations: u64,
    /// Image size in pixels.
    #[arg(long, short, value_name = "WxH", default_value = "512x512", value_parser = parse_resolution)]
    resolution: (u32, u32),
    /// Worker threads (default: all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Time the acceleration structure instead: BVH build and Mrays/s (closest hit and shadow
    /// rays, one thread and all) on each scene's geometry.
    #[arg(long)]
    accel: bool,
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

/// Where a scene comes from.
#[derive(Clone, Debug, PartialEq)]
enum SceneSource {
    /// A built-in Cornell box.
    Builtin(u32),
    /// A scene file with its `-D NAME=VALUE` parameters.
    File(PathBuf, Vec<String>),
}

/// Resolves `--scene`: a built-in id or name, or a scene file.
fn scene_source(name: &str, defines: &[String]) -> Result<SceneSource> {
    if let Some(s) = cornell::builtin_scenes().find(|s| s.name == name || s.id.to_string() == name) {
        if let Some(define) = defines.first() {
            bail!("-D {define}: parameters apply to scene files, not to the built-in scene '{name}'");
        }
        return Ok(SceneSource::Builtin(s.mask));
    }
    let valid: Vec<String> = cornell::builtin_scenes().map(|s| format!("{} ({})", s.id, s.name)).collect();
    if Path::new(name).extension().is_some() || name.contains('/') {
        if !Path::new(name).exists() {
            bail!("scene file '{name}' does not exist (built-in scenes: {})", valid.join(", "));
        }
        return Ok(SceneSource::File(PathBuf::from(name), defines.to_vec()));
    }
    bail!("unknown scene '{name}'; valid scenes: {}", valid.join(", "))
}

/// A loaded scene with the defaults its source implies.
struct LoadedScene {
    scene: Scene,
    /// Path length from the file's integrator (`None`: not given or unlimited).
    file_max_length: Option<u32>,
}

/// Path length used when a scene file asks for unlimited paths (Russian roulette ends them
/// long before).
const UNLIMITED_PATH_LENGTH: u32 = 100;

/// Loads or builds the scene; `resolution` overrides the file's film.
fn load_scene(source: &SceneSource, resolution: Option<(u32, u32)>, quiet: bool) -> Result<LoadedScene> {
    match source {
        SceneSource::Builtin(mask) => {
            Ok(LoadedScene { scene: build_scene(*mask, resolution.unwrap_or((512, 512)))?, file_max_length: None })
        }
        SceneSource::File(path, defines) => {
            let pairs = defines
                .iter()
                .map(|d| match d.split_once('=') {
                    Some((name, value)) if !name.is_empty() => Ok((name.to_string(), value.to_string())),
                    _ => bail!("-D '{d}': expected NAME=VALUE"),
                })
                .collect::<Result<Vec<_>>>()?;
            let start = Instant::now();
            let desc = io::load_scene(path, &pairs)?;
            for warning in &desc.warnings {
                eprintln!("warning: {warning}");
            }
            let (scene, report) =
                Scene::from_description(&desc, resolution).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            if !quiet {
                eprintln!(
                    "loaded {} in {:.2} s: {} triangles, {} analytic shapes, {} lights{}",
                    path.display(),
                    start.elapsed().as_secs_f64(),
                    report.triangles,
                    report.analytic_shapes,
                    report.lights,
                    if report.degenerate_triangles > 0 {
                        format!(", {} degenerate triangles dropped", report.degenerate_triangles)
                    } else {
                        String::new()
                    }
                );
            }
            Ok(LoadedScene { scene, file_max_length: Some(desc.max_path_length.unwrap_or(UNLIMITED_PATH_LENGTH)) })
        }
    }
}

fn build_scene(mask: u32, (width, height): (u32, u32)) -> Result<Scene> {
    cornell::build(mask, width, height)
        .with_context(|| format!("invalid scene mask {mask}: expected 0-{}", cornell::MAX_MASK))
}

/// Checks the estimated memory of the VCM engine's buffers against `--max-memory` (default:
/// half of the physical memory). Returns whether to switch to the memory-efficient mode; fails
/// when even that does not fit.
fn memory_guard(scene: &Scene, settings: &render::vcm::VcmSettings, args: &RenderArgs) -> Result<bool> {
    use render::vcm::memory::{self, format_size};
    let Some(limit) = args.max_memory.or_else(|| memory::physical_memory().map(|m| m / 2)) else {
        return Ok(false);
    };
    if memory::upper_bound(scene, settings) <= limit {
        return Ok(false);
    }
    let estimate = memory::estimate(scene, settings, args.seed);
    if estimate.two_stage_bytes <= limit {
        return Ok(false);
    }
    let need = format!(
        "{} light sub-paths x {:.2} stored vertices each need about {}",
        estimate.light_paths,
        estimate.vertices_per_path,
        format_size(estimate.two_stage_bytes)
    );
    if settings.spectral && render::vcm::Techniques::of(settings.algorithm).merge {
        bail!(
            "{need}, more than --max-memory {}; spectral mode cannot switch to --memory-efficient with {} \
             (its merges would pair different wavelengths): lower the resolution or --max-length, or raise \
             --max-memory",
            format_size(limit),
            Algorithm::Vcm(settings.algorithm).name()
        );
    }
    if estimate.memory_efficient_bytes <= limit {
        eprintln!(
            "note: {need}, more than --max-memory {}; switching to --memory-efficient (about {})",
            format_size(limit),
            format_size(estimate.memory_efficient_bytes)
        );
        return Ok(true);
    }
    bail!(
        "{need} ({} in the memory-efficient mode), more than --max-memory {}: lower the resolution or \
         --max-length, or raise --max-memory",
        format_size(estimate.memory_efficient_bytes),
        format_size(limit)
    )
}

/// The files a render writes: the requested one and, for linear formats, a PNG preview.
fn output_paths(output: &Path) -> Result<Vec<(PathBuf, io::ImageFormat)>> {
    let format = io::ImageFormat::from_path(output)?;
    let mut paths = vec![(output.to_path_buf(), format)];
    if format != io::ImageFormat::Png {
        paths.push((output.with_extension("png"), io::ImageFormat::Png));
    }
    Ok(paths)
}

/// Fails early, before any rendering, if an output cannot be created.
fn check_writable(path: &Path) -> Result<()> {
    let existed = path.exists();
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| format!("cannot write output '{}'", path.display()))?;
    if !existed {
        let _ = std::fs::remove_file(path);
    }
    Ok(())
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

fn run_render(mut args: RenderArgs) -> Result<()> {
    // A resumed render takes its settings from the checkpoint.
    let resumed = match &args.resume {
        Some(path) => {
            let (recorded, film) = checkpoint::load(path)?;
            match &recorded.scene_file {
                Some((file, defines)) => {
                    args.scene = file.display().to_string();
                    args.defines = defines.clone();
                    args.scene_mask = None;
                }
                None => args.scene_mask = Some(recorded.mask),
            }
            args.algorithm = AlgorithmName::from_str(&recorded.algorithm, false)
                .map_err(|_| anyhow::anyhow!("unknown algorithm '{}' in '{}'", recorded.algorithm, path.display()))?;
            args.resolution = Some(recorded.resolution);
            args.max_length = Some(recorded.max_length);
            args.seed = recorded.seed;
            args.radius_factor = recorded.radius_factor;
            args.radius_alpha = recorded.radius_alpha;
            args.radius_mode = RadiusModeName::from_str(&recorded.radius_mode, false).map_err(|_| {
                anyhow::anyhow!("unknown radius mode '{}' in '{}'", recorded.radius_mode, path.display())
            })?;
            args.memory_efficient = recorded.memory_efficient;
            args.spectral = recorded.spectral;
            if args.checkpoint.is_none() {
                args.checkpoint = Some(path.clone());
            }
            Some(film)
        }
        None => None,
    };
    let algorithm = args.algorithm.algorithm();
    if !(args.radius_factor.is_finite() && args.radius_factor > 0.0) {
        bail!("--radius-factor must be a positive number, got {}", args.radius_factor);
    }
    if !(args.radius_alpha > 0.0 && args.radius_alpha <= 1.0) {
        bail!("--radius-alpha must be in (0, 1], got {}", args.radius_alpha);
    }
    let source = match args.scene_mask {
        Some(mask) => SceneSource::Builtin(mask),
        None => scene_source(&args.scene, &args.defines)?,
    };
    if args.max_length == Some(0) {
        bail!("--max-length must be at least 1");
    }
    if !(args.checkpoint_every.is_finite() && args.checkpoint_every >= 0.0) {
        bail!("--checkpoint-every must be a non-negative number of seconds, got {}", args.checkpoint_every);
    }
    let budget = match (args.iterations, args.time) {
        (_, Some(t)) if !(t.is_finite() && t > 0.0) => bail!("--time must be a positive number of seconds, got {t}"),
        (_, Some(t)) => Budget::Time(Duration::from_secs_f64(t)),
        (Some(0), _) => bail!("--iterations must be at least 1"),
        (Some(n), None) => Budget::Iterations(n),
        (None, None) => Budget::Iterations(64),
    };
    let outputs = output_paths(&args.output)?;
    for (path, _) in &outputs {
        check_writable(path)?;
    }
    if let Some(path) = &args.checkpoint {
        check_writable(path)?;
    }
    if let Some(path) = &args.variance {
        if io::ImageFormat::from_path(path)? == io::ImageFormat::Png {
            bail!("--variance '{}': use a linear format (.exr, .pfm or .hdr), not PNG", path.display());
        }
        check_writable(path)?;
    }
    if let Some(dir) = &args.techniques {
        if !matches!(algorithm, Algorithm::Vcm(_)) {
            bail!(
                "--techniques needs an algorithm of the VCM engine (lt, ppm, bpm, bpt, vcm), not {}",
                algorithm.name()
            );
        }
        if resumed.is_some() {
            bail!("--techniques cannot be combined with --resume (checkpoints do not keep the technique images)");
        }
        TechniqueLayout::new(args.technique_length).map_err(|e| anyhow::anyhow!("--technique-length: {e}"))?;
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create technique directory '{}'", dir.display()))?;
    }
    let LoadedScene { scene, file_max_length } = load_scene(&source, args.resolution, args.quiet)?;
    let max_length = args.max_length.or(file_max_length).unwrap_or(10);
    let resolution = (scene.camera.width, scene.camera.height);
    let mut settings = RenderSettings {
        algorithm,
        budget,
        max_length,
        seed: args.seed,
        threads: args.threads,
        progress: !args.quiet,
        radius_factor: args.radius_factor,
        radius_alpha: args.radius_alpha,
        radius_mode: match args.radius_mode {
            RadiusModeName::Global => RadiusMode::Global,
            RadiusModeName::PerPixel => RadiusMode::PerPixel,
        },
        memory_efficient: args.memory_efficient,
        spectral: args.spectral,
        wavelength_groups: render::vcm::wavelengths::DEFAULT_WAVELENGTH_GROUPS,
    };
    if let Some(vcm_settings) = settings.vcm_settings()
        && !settings.memory_efficient
    {
        settings.memory_efficient = memory_guard(&scene, &vcm_settings, &args)?;
        args.memory_efficient = settings.memory_efficient;
    }
    let recorded = checkpoint::Recorded {
        mask: match source {
            SceneSource::Builtin(mask) => mask,
            SceneSource::File(..) => 0,
        },
        scene_file: match &source {
            SceneSource::Builtin(_) => None,
            SceneSource::File(path, defines) => Some((path.clone(), defines.clone())),
        },
        algorithm: algorithm.name().to_string(),
        resolution,
        max_length,
        seed: args.seed,
        radius_factor: args.radius_factor,
        radius_alpha: args.radius_alpha,
        radius_mode: args.radius_mode.to_possible_value().map(|v| v.get_name().to_string()).unwrap_or_default(),
        memory_efficient: args.memory_efficient,
        spectral: args.spectral,
    };
    install_interrupt_handler();
    let resumed_iterations = resumed.as_ref().map(|f| f.iterations());
    let checkpoint_path = args.checkpoint.clone();
    let save = move |film: &scene::Film| {
        checkpoint::save(checkpoint_path.as_deref().expect("only set with a path"), &recorded, film)
            .map_err(|e| format!("{e:#}"))
    };
    let control = Control {
        resume: resumed,
        stop: Some(&STOP),
        checkpoint: args
            .checkpoint
            .as_ref()
            .map(|_| (Duration::from_secs_f64(args.checkpoint_every), Box::new(save) as Box<dyn FnMut(&_) -> _>)),
        record_families: args.techniques.is_some(),
        record_techniques: args.techniques.as_ref().and_then(|_| TechniqueLayout::new(args.technique_length).ok()),
    };
    let result = render::driver::render_with(&scene, &settings, control).map_err(anyhow::Error::msg)?;
    let film = &result.film;
    let image = io::Image { width: film.width() as usize, height: film.height() as usize, pixels: film.mean() };
    let options = io::WriteOptions { exposure_stops: args.exposure };
    for (path, _) in &outputs {
        io::write_image(path, &image, &options)?;
    }
    if let (Some(dir), Some(families)) = (&args.techniques, &result.family_films) {
        write_technique_images(dir, families, &options)?;
    }
    if let (Some(dir), Some(images)) = (&args.techniques, &result.technique_images) {
        write_st_images(dir, images, film.width() as usize, film.height() as usize, &options)?;
    }
    if let Some(path) = &args.variance {
        let variance = io::Image { width: image.width, height: image.height, pixels: film.variance_of_mean() };
        io::write_image(path, &variance, &options)?;
    }
    let seconds = result.elapsed.as_secs_f64();
    let iterations = film.iterations();
    let here = iterations - resumed_iterations.unwrap_or(0);
    let mut names: Vec<String> = outputs.iter().map(|(p, _)| p.display().to_string()).collect();
    if let Some(path) = &args.variance {
        names.push(format!("variance {}", path.display()));
    }
    if let Some(path) = &args.checkpoint {
        names.push(format!("checkpoint {}", path.display()));
    }
    let vertices = match result.light_vertices {
        Some((count, bytes)) => format!(", {count} light vertices x {bytes} B"),
        None => String::new(),
    };
    let resumed_note = match resumed_iterations {
        Some(n) => format!(" (resumed after {n})"),
        None => String::new(),
    };
    let interrupted_note = if result.interrupted { "interrupted: " } else { "" };
    // Which techniques produced the discarded (NaN/infinite) estimates of this run.
    let rejected_note = match result.rejected_by_family {
        Some(counts) if counts.iter().any(|c| *c > 0) => {
            let parts: Vec<String> = Family::ALL
                .iter()
                .zip(counts)
                .filter(|(_, c)| *c > 0)
                .map(|(f, c)| format!("{} {c}", f.name()))
                .collect();
            format!(" ({})", parts.join(", "))
        }
        _ => String::new(),
    };
    eprintln!(
        "{interrupted_note}{} with {}{} at {}x{}: {} iterations{resumed_note} in {:.2} s ({:.1} ms/iteration, {} threads{vertices}), {} rejected samples{rejected_note} -> {}",
        scene.name,
        algorithm.name(),
        if settings.spectral { " (spectral)" } else { "" },
        film.width(),
        film.height(),
        iterations,
        seconds,
        1e3 * seconds / here.max(1) as f64,
        result.threads,
        film.rejected_samples(),
        names.join(", ")
    );
    Ok(())
}

/// Writes the per-family images and the false-colour VC/VM share image into `dir`.
fn write_technique_images(dir: &Path, families: &[scene::Film; 5], options: &io::WriteOptions) -> Result<()> {
    let means: Vec<Vec<[f32; 3]>> = families.iter().map(|f| f.mean()).collect();
    let (width, height) = (families[0].width() as usize, families[0].height() as usize);
    for (family, pixels) in Family::ALL.iter().zip(&means) {
        let image = io::Image { width, height, pixels: pixels.clone() };
        io::write_image(&dir.join(format!("{}.exr", family.name())), &image, options)?;
        // A preview to browse, exposed like the render's.
        io::write_image(&dir.join(format!("{}.png", family.name())), &image, options)?;
    }
    // Share of vertex merging against all connection techniques, by luminance.
    let luminance = |p: [f32; 3]| spectrum::Rgb::from_array(p).luminance().max(0.0);
    let share = (0..width * height)
        .map(|i| {
            let merging = luminance(means[Family::Merging as usize][i]);
            let total: f32 = means.iter().map(|m| luminance(m[i])).sum();
            if total > 0.0 { [1.0 - merging / total, merging / total, 0.0] } else { [0.0; 3] }
        })
        .collect();
    let image = io::Image { width, height, pixels: share };
    io::write_image(&dir.join("vc-vm-share.png"), &image, &io::WriteOptions::default())?;
    Ok(())
}

/// Writes one image per (s, t) technique into `dir`, named as
/// [`render::vcm::technique_images::TechniqueImage::name`] says.
fn write_st_images(
    dir: &Path,
    images: &TechniqueImages,
    width: usize,
    height: usize,
    options: &io::WriteOptions,
) -> Result<()> {
    for (index, technique) in images.layout().images().iter().enumerate() {
        let image = io::Image { width, height, pixels: images.mean(index) };
        io::write_image(&dir.join(format!("{}.exr", technique.name())), &image, options)?;
    }
    Ok(())
}

fn run_scenes() {
    println!("{:<4} {:<22} {:<6} description", "id", "name", "mask");
    for s in cornell::builtin_scenes() {
        println!("{:<4} {:<22} {:<6} {}", s.id, s.name, s.mask, s.description);
    }
    println!();
    println!("--scene-mask N builds other variants: ceiling light 1, sun 2, point 4, background 8,");
    println!("large mirror 16, large glass 32, small mirror 64, small glass 128, glossy floor 256,");
    println!("fluorescent large sphere and blue-ish light 512.");
}

fn run_bench(args: BenchArgs) -> Result<()> {
    use AlgorithmName::*;
    let algorithms = if args.algorithm.is_empty() { vec![Pt, Lt, Ppm, Bpm, Bpt, Vcm] } else { args.algorithm };
    let sources: Vec<SceneSource> = if args.scene.is_empty() {
        BUILTIN_SCENES.iter().map(|s| SceneSource::Builtin(s.mask)).collect()
    } else {
        args.scene.iter().map(|s| scene_source(s, &[])).collect::<Result<_>>()?
    };
    if args.accel {
        bench_accel::header();
        for source in &sources {
            let LoadedScene { scene, .. } = load_scene(source, Some(args.resolution), true)?;
            bench_accel::run(&scene, args.threads);
        }
        return Ok(());
    }
    println!(
        "{:<22} {:>9} {:>13} {:>11} {:>15} {:>9} {:>8}  phases of the last iteration (ms)",
        "scene", "algorithm", "ms/iteration", "CPU-s/iter", "light vertices", "B/vertex", "threads"
    );
    for source in sources {
        let LoadedScene { scene, file_max_length } = load_scene(&source, Some(args.resolution), true)?;
        for name in &algorithms {
            let algorithm = name.algorithm();
            let settings = |budget| RenderSettings {
                algorithm,
                budget,
                threads: args.threads,
                max_length: file_max_length.unwrap_or(RenderSettings::default().max_length),
                ..RenderSettings::default()
            };
            render::render(&scene, &settings(Budget::Iterations(1))).map_err(anyhow::Error::msg)?;
            let cpu_before = process_cpu_seconds();
            let result =
                render::render(&scene, &settings(Budget::Iterations(args.iterations))).map_err(anyhow::Error::msg)?;
            let ms = 1e3 * result.elapsed.as_secs_f64() / args.iterations as f64;
            let cpu = match (cpu_before, process_cpu_seconds()) {
                (Some(a), Some(b)) => format!("{:.3}", (b - a) / args.iterations as f64),
                _ => "-".to_string(),
            };
            let (vertices, bytes) = match result.light_vertices {
                Some((count, bytes)) => (count.to_string(), bytes.to_string()),
                None => ("-".to_string(), "-".to_string()),
            };
            let phases = match result.vcm_stats {
                Some(s) => format!(
                    "  light {:.0}, grid {:.0}, camera {:.0}",
                    s.phases.light_pass.as_secs_f64() * 1e3,
                    s.phases.grid_build.as_secs_f64() * 1e3,
                    s.phases.camera_pass.as_secs_f64() * 1e3
                ),
                None => String::new(),
            };
            println!(
                "{:<22} {:>9} {:>13.1} {:>11} {:>15} {:>9} {:>8}{phases}",
                scene.name,
                algorithm.name(),
                ms,
                cpu,
                vertices,
                bytes,
                result.threads
            );
        }
    }
    Ok(())
}

/// CPU time (user + system, all threads) of this process in seconds, from `/proc/self/stat`
/// (Linux; clock ticks of 1/100 s, the kernel's fixed USER_HZ). `None` elsewhere.
fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let user: f64 = fields.get(11)?.parse().ok()?;
    let system: f64 = fields.get(12)?.parse().ok()?;
    Some((user + system) / 100.0)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Render(args) => run_render(args).map(|()| ExitCode::SUCCESS),
        Command::Scenes => {
            run_scenes();
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench(args) => run_bench(args).map(|()| ExitCode::SUCCESS),
        Command::Compare(args) => compare::run(args),
        Command::Report(args) => report::run(args).map(|()| ExitCode::SUCCESS),
    };
    match outcome {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::from(2)
        }
    }
}
