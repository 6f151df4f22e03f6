//! `vcm report`: renders every scene × algorithm combination with the same budget (seconds of
//! render time, or iterations) and writes an HTML page comparing them.
//!
//! Output directory layout (`-o DIR`):
//!
//! - `DIR/<scene>/<algorithm>.exr`: the final linear image of each combination, and
//!   `DIR/<scene>/<algorithm>.png` its sRGB preview;
//! - `DIR/<scene>/reference.png`: the preview of the scene's reference, when one is given;
//! - `DIR/<scene>/convergence.svg`: relative MSE against render time (log–log, one line per
//!   algorithm), when a reference is given;
//! - `DIR/index.html`: the page; `DIR/report.json`: every number of the page.
//!
//! Timing: only rendering counts (the iterations and their accumulation into the film). With a
//! reference, the error of the running image is measured after iterations 1, 2, 4, 8, … and
//! after the last one; those measurements are not part of the render time. The errors are
//! [`compare::metrics`](crate::compare::metrics): RMSE and relative MSE (`ε = 1e-2`).
//!
//! `<scene>` is the built-in scene's name, or the stem of a scene file's name with characters
//! other than ASCII letters, digits, `-`, `_` and `.` replaced by `_`.

mod html;
mod plot;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail, ensure};
use render::RenderSettings;
use render::driver::Renderer;
use scene::Film;
use scene::cornell;

use session::{LoadedScene, SceneSource};

use crate::AlgorithmName;

/// Arguments of `vcm report`.
#[derive(clap::Args, Debug, Clone)]
#[command(group = clap::ArgGroup::new("budget").required(true).args(["time", "iterations"]))]
pub struct ReportArgs {
    /// Scenes: built-in ids (0-3) or names (see `vcm scenes`), or scene files; comma- or
    /// space-separated.
    #[arg(long, required = true, num_args = 1.., value_delimiter = ',', value_name = "SCENE")]
    pub scenes: Vec<String>,
    /// Algorithms, comma- or space-separated [default: pt, lt, ppm, bpm, bpt, vcm].
    #[arg(long, num_args = 1.., value_enum, value_delimiter = ',', value_name = "ALGORITHM")]
    pub algorithms: Vec<AlgorithmName>,
    /// Render time per combination in seconds (setup and error measurements excluded).
    #[arg(long, short, value_name = "SECONDS")]
    pub time: Option<f64>,
    /// Iterations per combination instead of a time budget (an equal-sample comparison).
    #[arg(long, short, value_name = "N")]
    pub iterations: Option<u64>,
    /// Reference image of a scene (EXR, PFM or HDR; PNG is read as sRGB): NAME is the scene as
    /// given to --scenes (or its built-in name or id). Repeatable.
    #[arg(long, value_name = "NAME=FILE")]
    pub reference: Vec<String>,
    /// Image size in pixels [default: the scene file's film, 512x512 for built-in scenes].
    #[arg(long, short, value_name = "WxH", value_parser = crate::parse_resolution)]
    pub resolution: Option<(u32, u32)>,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub threads: usize,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Exposure of the PNG previews in stops (the EXR images are never scaled).
    #[arg(long, value_name = "STOPS", default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Output directory (created if needed).
    #[arg(long, short, value_name = "DIR")]
    pub output: PathBuf,
}

/// How long each combination renders.
#[derive(Clone, Copy, Debug, PartialEq)]
enum ReportBudget {
    /// Render time (iterations until it is reached; at least one).
    Time(Duration),
    /// A fixed number of iterations.
    Iterations(u64),
}

impl ReportBudget {
    fn describe(self) -> String {
        match self {
            Self::Time(t) => format!("{} s of render time", t.as_secs_f64()),
            Self::Iterations(n) => format!("{n} iterations"),
        }
    }
}

/// One measurement of the running image against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ErrorPoint {
    /// Iterations rendered so far.
    iterations: u64,
    /// Render time so far in seconds.
    seconds: f64,
    /// Root-mean-square error against the reference.
    rmse: f64,
    /// Relative MSE against the reference.
    relative_mse: f64,
}

/// The outcome of one scene × algorithm combination.
#[derive(Clone, Debug)]
struct AlgorithmResult {
    /// Command-line name of the algorithm.
    algorithm: &'static str,
    /// Iterations rendered.
    iterations: u64,
    /// Render time in seconds.
    seconds: f64,
    /// Non-finite samples replaced by zero.
    rejected_samples: u64,
    /// The final image, relative to the output directory.
    image: String,
    /// Its PNG preview, relative to the output directory.
    preview: String,
    /// Errors against the reference during the render, the last one being the final image's.
    convergence: Vec<ErrorPoint>,
}

impl AlgorithmResult {
    fn ms_per_iteration(&self) -> f64 {
        1e3 * self.seconds / self.iterations.max(1) as f64
    }

    /// The final image's error, when there is a reference.
    fn final_error(&self) -> Option<ErrorPoint> {
        self.convergence.last().copied()
    }
}

/// A scene's reference image.
struct Reference {
    /// The file as given.
    path: PathBuf,
    image: io::Image,
}

/// Everything the page shows of one scene.
struct SceneReport {
    /// Directory name and heading.
    label: String,
    width: u32,
    height: u32,
    /// The reference file and its preview (relative to the output directory).
    reference: Option<(String, String)>,
    results: Vec<AlgorithmResult>,
    /// The convergence plot, relative to the output directory.
    plot: Option<String>,
}

/// A scene to render, resolved but not yet loaded.
struct SceneEntry {
    /// As given on the command line.
    given: String,
    /// Directory name and heading.
    label: String,
    source: SceneSource,
}

/// Resolves a `--scenes` entry: where it comes from and its label. The one place that knows
/// how scene names are resolved.
fn resolve_scene(name: &str) -> Result<(SceneSource, String)> {
    let source = session::scene_source(name, &[])?;
    let label = match &source {
        SceneSource::Builtin(mask) => cornell::builtin_scenes()
            .find(|s| s.mask == *mask)
            .map_or_else(|| format!("cornell-mask-{mask}"), |s| s.name.to_string()),
        SceneSource::File(path, _) => {
            let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let clean: String = stem
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') { c } else { '_' })
                .collect();
            if clean.is_empty() || clean.starts_with('.') { format!("scene{clean}") } else { clean }
        }
    };
    Ok((source, label))
}

/// Loads a resolved scene at `resolution` (default: the scene's own).
fn load_scene(source: &SceneSource, resolution: Option<(u32, u32)>) -> Result<LoadedScene> {
    crate::load_scene(source, resolution, false)
}

/// Runs `vcm report`.
pub fn run(args: ReportArgs) -> Result<()> {
    use AlgorithmName::*;
    let budget = match (args.time, args.iterations) {
        (Some(t), _) if !(t.is_finite() && t > 0.0) => bail!("--time must be a positive number of seconds, got {t}"),
        (Some(t), _) => ReportBudget::Time(Duration::from_secs_f64(t)),
        (None, Some(0)) => bail!("--iterations must be at least 1"),
        (None, Some(n)) => ReportBudget::Iterations(n),
        (None, None) => bail!("give --time SECONDS or --iterations N"),
    };
    ensure!(args.exposure.is_finite(), "--exposure must be a finite number of stops, got {}", args.exposure);
    let mut algorithms: Vec<AlgorithmName> = Vec::new();
    let requested = if args.algorithms.is_empty() { vec![Pt, Lt, Ppm, Bpm, Bpt, Vcm] } else { args.algorithms };
    for a in requested {
        if !algorithms.contains(&a) {
            algorithms.push(a);
        }
    }

    // Resolve every scene and reference before rendering anything.
    let mut entries: Vec<SceneEntry> = Vec::new();
    for given in &args.scenes {
        let (source, label) = resolve_scene(given).with_context(|| format!("--scenes '{given}'"))?;
        if let Some(other) = entries.iter().find(|e| e.label == label) {
            if other.source == source {
                continue;
            }
            bail!("--scenes: '{}' and '{given}' would both be written to '{label}/'", other.given);
        }
        entries.push(SceneEntry { given: given.clone(), label, source });
    }
    let mut references: Vec<Option<Reference>> = entries.iter().map(|_| None).collect();
    for arg in &args.reference {
        let (name, file) = match arg.split_once('=') {
            Some((name, file)) if !name.is_empty() && !file.is_empty() => (name, file),
            _ => bail!("--reference '{arg}': expected NAME=FILE"),
        };
        let index = entries
            .iter()
            .position(|e| e.given == name || e.label == name)
            .or_else(|| {
                let (source, _) = resolve_scene(name).ok()?;
                entries.iter().position(|e| e.source == source)
            })
            .with_context(|| {
                let names: Vec<&str> = entries.iter().map(|e| e.given.as_str()).collect();
                format!("--reference '{arg}': scene '{name}' is not among --scenes ({})", names.join(", "))
            })?;
        ensure!(references[index].is_none(), "--reference '{arg}': scene '{name}' already has a reference");
        let path = PathBuf::from(file);
        let image = io::read_image(&path).with_context(|| format!("--reference '{arg}'"))?;
        references[index] = Some(Reference { path, image });
    }

    // Load the scenes (this also checks the references' sizes) before rendering anything.
    let mut scenes = Vec::new();
    for (entry, reference) in entries.iter().zip(&references) {
        let loaded =
            load_scene(&entry.source, args.resolution).with_context(|| format!("--scenes '{}'", entry.given))?;
        let (width, height) = (loaded.scene.camera.width, loaded.scene.camera.height);
        if let Some(r) = reference {
            ensure!(
                (r.image.width, r.image.height) == (width as usize, height as usize),
                "--reference '{}': the image is {}x{}, but scene '{}' renders at {width}x{height} (see --resolution)",
                r.path.display(),
                r.image.width,
                r.image.height,
                entry.given
            );
        }
        scenes.push(loaded);
    }

    // Create the directories and check that the page can be written.
    let out = &args.output;
    for entry in &entries {
        let dir = out.join(&entry.label);
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create the output directory '{}'", dir.display()))?;
    }
    session::outputs::check_writable(&out.join("index.html"))?;
    session::outputs::check_writable(&out.join("report.json"))?;

    let options = io::WriteOptions { exposure_stops: args.exposure };
    crate::install_interrupt_handler();
    let total = entries.len() * algorithms.len();
    let mut done = 0;
    let mut reports: Vec<SceneReport> = Vec::new();
    for ((entry, loaded), reference) in entries.iter().zip(&scenes).zip(&references) {
        let scene = &loaded.scene;
        let (width, height) = (scene.camera.width, scene.camera.height);
        let reference_files = match reference {
            Some(r) => {
                let preview = format!("{}/reference.png", entry.label);
                io::write_image(&out.join(&preview), &r.image, &options)?;
                Some((r.path.display().to_string(), preview))
            }
            None => None,
        };
        let mut results = Vec::new();
        for name in &algorithms {
            done += 1;
            let algorithm = name.algorithm();
            eprintln!(
                "[{done}/{total}] {} with {} at {width}x{height} for {} ...",
                entry.label,
                algorithm.name(),
                budget.describe()
            );
            let settings = RenderSettings {
                algorithm,
                max_length: loaded.file_max_length.unwrap_or(RenderSettings::default().max_length),
                seed: args.seed,
                threads: args.threads,
                ..RenderSettings::default()
            };
            let (film, seconds, convergence, interrupted) =
                render_combination(scene, &settings, budget, reference.as_ref().map(|r| &r.image))?;
            let image = io::Image { width: width as usize, height: height as usize, pixels: film.mean() };
            let stem = format!("{}/{}", entry.label, algorithm.name());
            let (exr, png) = (format!("{stem}.exr"), format!("{stem}.png"));
            io::write_image(&out.join(&exr), &image, &io::WriteOptions::default())?;
            io::write_image(&out.join(&png), &image, &options)?;
            let result = AlgorithmResult {
                algorithm: algorithm.name(),
                iterations: film.iterations(),
                seconds,
                rejected_samples: film.rejected_samples(),
                image: exr,
                preview: png,
                convergence,
            };
            let error = match result.final_error() {
                Some(e) => format!(", RMSE {}, relMSE {}", html::number(e.rmse), html::number(e.relative_mse)),
                None => String::new(),
            };
            eprintln!(
                "[{done}/{total}] {} with {}: {} iterations in {:.2} s ({:.2} ms/iteration){error}",
                entry.label,
                result.algorithm,
                result.iterations,
                result.seconds,
                result.ms_per_iteration()
            );
            results.push(result);
            if interrupted {
                break;
            }
        }
        let plot = if reference.is_some() {
            let file = format!("{}/convergence.svg", entry.label);
            let series: Vec<(&str, Vec<(f64, f64)>)> = results
                .iter()
                .map(|r| (r.algorithm, r.convergence.iter().map(|p| (p.seconds, p.relative_mse)).collect()))
                .collect();
            let title = format!("{}: relative MSE vs render time", entry.label);
            plot::convergence_plot(&out.join(&file), &title, &series)?.then_some(file)
        } else {
            None
        };
        reports.push(SceneReport {
            label: entry.label.clone(),
            width,
            height,
            reference: reference_files,
            results,
            plot,
        });
        // Keep the page current, so an interrupted report still shows the finished scenes.
        html::write_outputs(out, &reports, budget, &args.reference, args.seed)?;
        if crate::STOP.load(std::sync::atomic::Ordering::Relaxed) {
            eprintln!(
                "interrupted: the report has {done} of {total} combinations (the last one stopped early: its \
                 iteration count is on the page)"
            );
            break;
        }
    }
    eprintln!("report: {}", out.join("index.html").display());
    Ok(())
}

/// Renders one combination until `budget` is used up or Ctrl-C ([`crate::STOP`]); with a
/// reference, measures the error of the running image after iterations 1, 2, 4, … and after the
/// last one. Returns the film, the render time in seconds, the measurements and whether it was
/// interrupted.
fn render_combination(
    scene: &scene::Scene,
    settings: &RenderSettings,
    budget: ReportBudget,
    reference: Option<&io::Image>,
) -> Result<(Film, f64, Vec<ErrorPoint>, bool)> {
    let mut renderer = Renderer::new(scene, settings).map_err(anyhow::Error::msg)?;
    let mut film = Film::new(scene.camera.width, scene.camera.height);
    let mut elapsed = Duration::ZERO;
    let mut convergence = Vec::new();
    loop {
        let start = Instant::now();
        let rejected = renderer.step();
        film.add_iteration(renderer.frame(), rejected);
        elapsed += start.elapsed();
        let iterations = film.iterations();
        let interrupted = crate::STOP.load(std::sync::atomic::Ordering::Relaxed);
        let finished = interrupted
            || match budget {
                ReportBudget::Time(limit) => elapsed >= limit,
                ReportBudget::Iterations(n) => iterations >= n,
            };
        if let Some(reference) = reference
            && (iterations.is_power_of_two() || finished)
        {
            let image = io::Image { width: reference.width, height: reference.height, pixels: film.mean() };
            let m = crate::compare::metrics(&image, reference, None, 1e-3)
                .context("cannot compare the render with the reference")?;
            convergence.push(ErrorPoint {
                iterations,
                seconds: elapsed.as_secs_f64(),
                rmse: m.rmse,
                relative_mse: m.relative_mse,
            });
        }
        if finished {
            return Ok((film, elapsed.as_secs_f64(), convergence, interrupted));
        }
    }
}
