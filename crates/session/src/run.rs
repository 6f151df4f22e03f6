//! The session itself: request in, outputs written, outcome out.

use std::sync::atomic::AtomicBool;

use anyhow::{Result, bail};
use render::driver::{Budget, Control, RenderOutput};
use render::vcm::Family;
use render::vcm::technique_images::TechniqueLayout;
use render::{Algorithm, RenderSettings};
use scene::filter::FilmMode;

use crate::checkpoint::{self, Recorded};
use crate::guard::{self, Guard};
use crate::outputs::{check_writable, output_paths, write_st_images, write_technique_images};
use crate::request::{Request, radius_mode_from_name, radius_mode_name};
use crate::source::{LoadedScene, SceneSource, load_scene, scene_source};
use crate::{Notice, Summary};

/// Receives what a session tells the user, and when rendering starts.
pub trait Observer {
    /// A message for the user.
    fn notice(&mut self, notice: Notice);
    /// Called once, after the scene is loaded and checked, just before the first iteration
    /// (e.g. to install an interrupt handler that sets the stop flag).
    fn starting(&mut self) {}
}

/// What a finished (or interrupted) session produced.
#[derive(Debug)]
pub struct Outcome {
    /// The driver's result: the film (a resumed checkpoint's iterations included) and the
    /// statistics.
    pub output: RenderOutput,
    /// The summary line.
    pub summary: Summary,
}

/// Runs a render session. `stop`, when set (e.g. by a Ctrl-C handler), makes the render
/// finish its current iteration, write what it has and return (`summary.interrupted`).
pub fn render(request: &Request, stop: Option<&AtomicBool>, observer: &mut dyn Observer) -> Result<Outcome> {
    let mut request = request.clone();
    // A resumed render takes its settings from the checkpoint.
    let resumed = match &request.resume {
        Some(path) => {
            let (recorded, film) = checkpoint::load(path)?;
            request.scene = match &recorded.scene_file {
                Some((file, defines)) => scene_source(&file.display().to_string(), defines)?,
                None => SceneSource::Builtin(recorded.mask),
            };
            request.algorithm = Algorithm::from_name(&recorded.algorithm)
                .ok_or_else(|| anyhow::anyhow!("unknown algorithm '{}' in '{}'", recorded.algorithm, path.display()))?;
            request.resolution = Some(recorded.resolution);
            request.max_length = Some(recorded.max_length);
            request.seed = recorded.seed;
            request.radius_factor = recorded.radius_factor;
            request.radius_alpha = recorded.radius_alpha;
            request.radius_mode = radius_mode_from_name(&recorded.radius_mode).ok_or_else(|| {
                anyhow::anyhow!("unknown radius mode '{}' in '{}'", recorded.radius_mode, path.display())
            })?;
            request.memory_efficient = recorded.memory_efficient;
            request.spectral = recorded.spectral;
            request.russian_roulette = recorded.russian_roulette;
            request.heuristic = recorded.heuristic;
            let mode = FilmMode::from_name(&recorded.film)
                .ok_or_else(|| anyhow::anyhow!("unknown film mode '{}' in '{}'", recorded.film, path.display()))?;
            if let Some(asked) = request.film.filter(|asked| *asked != mode) {
                bail!(
                    "cannot resume '{}' with --film {}: it was rendered with --film {}",
                    path.display(),
                    asked.name(),
                    mode.name()
                );
            }
            request.film = Some(mode);
            if request.checkpoint.is_none() {
                request.checkpoint = Some(path.clone());
            }
            Some((film, recorded.fingerprint, path.clone()))
        }
        None => None,
    };
    let r = &request;
    validate(r, resumed.is_some())?;
    let outputs = match &r.output {
        Some(path) => output_paths(path)?,
        None => Vec::new(),
    };
    for (path, _) in &outputs {
        check_writable(path)?;
    }
    if let Some(path) = &r.checkpoint {
        check_writable(path)?;
    }
    if let Some(path) = &r.variance {
        if io::ImageFormat::from_path(path)? == io::ImageFormat::Png {
            bail!("--variance '{}': use a linear format (.exr, .pfm or .hdr), not PNG", path.display());
        }
        check_writable(path)?;
    }
    let layout = match &r.techniques {
        Some(dir) => {
            let layout =
                TechniqueLayout::new(r.technique_length).map_err(|e| anyhow::anyhow!("--technique-length: {e}"))?;
            std::fs::create_dir_all(dir)
                .map_err(|e| anyhow::anyhow!("cannot create technique directory '{}': {e}", dir.display()))?;
            Some(layout)
        }
        None => None,
    };

    let loaded = load_scene(&r.scene, r.resolution, r.permissive)?;
    for warning in &loaded.warnings {
        observer.notice(Notice::Warning(warning.clone()));
    }
    if let Some(line) = &loaded.loaded {
        observer.notice(Notice::Progress(line.clone()));
    }
    let LoadedScene { mut scene, file_max_length, file_samples, fingerprint, .. } = loaded;
    if let Some((_, recorded, path)) = &resumed
        && let Some(difference) = fingerprint.difference(recorded)
    {
        bail!(
            "cannot resume '{}': {difference}; resuming would mix renders of two different scenes (restore the \
             scene, or start a new render)",
            path.display()
        );
    }
    if let Some(film) = r.film {
        scene.camera.film = film;
    }
    let mut settings = RenderSettings {
        algorithm: r.algorithm,
        budget: r.budget.unwrap_or(Budget::Iterations(file_samples.unwrap_or(DEFAULT_ITERATIONS))),
        max_length: r.max_length.or(file_max_length).unwrap_or(10),
        seed: r.seed,
        threads: r.threads,
        progress: r.progress,
        radius_factor: r.radius_factor,
        radius_alpha: r.radius_alpha,
        radius_mode: r.radius_mode,
        memory_efficient: r.memory_efficient,
        spectral: r.spectral,
        russian_roulette: r.russian_roulette,
        heuristic: r.heuristic,
        ..RenderSettings::default()
    };
    if let Some(vcm_settings) = settings.vcm_settings()
        && !settings.memory_efficient
        && let Guard::SwitchToMemoryEfficient(message) = guard::check(&scene, &vcm_settings, r.seed, r.max_memory)?
    {
        observer.notice(Notice::Note(message));
        settings.memory_efficient = true;
    }
    let recorded = Recorded {
        mask: match r.scene {
            SceneSource::Builtin(mask) => mask,
            SceneSource::File(..) => 0,
        },
        scene_file: match &r.scene {
            SceneSource::Builtin(_) => None,
            SceneSource::File(path, defines) => Some((path.clone(), defines.clone())),
        },
        algorithm: r.algorithm.name().to_string(),
        resolution: (scene.camera.width, scene.camera.height),
        max_length: settings.max_length,
        seed: r.seed,
        radius_factor: r.radius_factor,
        radius_alpha: r.radius_alpha,
        radius_mode: radius_mode_name(r.radius_mode).to_string(),
        memory_efficient: settings.memory_efficient,
        spectral: r.spectral,
        russian_roulette: r.russian_roulette,
        heuristic: r.heuristic,
        film: scene.camera.film.name().to_string(),
        fingerprint,
    };

    observer.starting();
    let resumed_iterations = resumed.as_ref().map(|(film, ..)| film.iterations());
    let checkpoint_path = r.checkpoint.clone();
    let save = move |film: &scene::Film| {
        let path = checkpoint_path.as_deref().expect("only set with a path");
        checkpoint::save(path, &recorded, film).map_err(|e| format!("{e:#}"))
    };
    let control = Control {
        resume: resumed.map(|(film, ..)| film),
        stop,
        checkpoint: r.checkpoint.as_ref().map(|_| (r.checkpoint_every, Box::new(save) as Box<dyn FnMut(&_) -> _>)),
        record_families: r.techniques.is_some(),
        record_techniques: layout,
    };
    let result = render::driver::render_with(&scene, &settings, control).map_err(anyhow::Error::msg)?;

    let film = &result.film;
    let (width, height) = (film.width() as usize, film.height() as usize);
    let image = io::Image { width, height, pixels: film.mean() };
    let options = io::WriteOptions { exposure_stops: r.exposure };
    for (path, _) in &outputs {
        io::write_image(path, &image, &options)?;
    }
    if let (Some(dir), Some(families)) = (&r.techniques, &result.family_films) {
        write_technique_images(dir, families, &options)?;
    }
    if let (Some(dir), Some(images)) = (&r.techniques, &result.technique_images) {
        write_st_images(dir, images, width, height, &options)?;
    }
    if let Some(path) = &r.variance {
        let variance = io::Image { width, height, pixels: film.variance_of_mean() };
        io::write_image(path, &variance, &options)?;
    }
    let mut written: Vec<String> = outputs.iter().map(|(p, _)| p.display().to_string()).collect();
    if let Some(path) = &r.variance {
        written.push(format!("variance {}", path.display()));
    }
    if let Some(path) = &r.checkpoint {
        written.push(format!("checkpoint {}", path.display()));
    }
    let summary = Summary {
        scene: scene.name.clone(),
        algorithm: r.algorithm.name(),
        spectral: settings.spectral,
        resolution: (film.width(), film.height()),
        iterations: film.iterations(),
        resumed_after: resumed_iterations,
        seconds: result.elapsed.as_secs_f64(),
        threads: result.threads,
        light_vertices: result.light_vertices,
        rejected: film.rejected_samples(),
        rejected_by_family: match result.rejected_by_family {
            Some(counts) => {
                Family::ALL.iter().zip(counts).filter(|(_, c)| *c > 0).map(|(f, c)| (f.name(), c)).collect()
            }
            None => Vec::new(),
        },
        interrupted: result.interrupted,
        written,
    };
    Ok(Outcome { output: result, summary })
}

/// Checks the settings that do not need the scene; messages name them as the command line
/// does.
/// Iterations of a render whose request and scene name no budget.
pub const DEFAULT_ITERATIONS: u64 = 64;

fn validate(r: &Request, resumed: bool) -> Result<()> {
    if !(r.radius_factor.is_finite() && r.radius_factor > 0.0) {
        bail!("--radius-factor must be a positive number, got {}", r.radius_factor);
    }
    if !(r.radius_alpha > 0.0 && r.radius_alpha <= 1.0) {
        bail!("--radius-alpha must be in (0, 1], got {}", r.radius_alpha);
    }
    if r.max_length == Some(0) {
        bail!("--max-length must be at least 1");
    }
    match r.budget {
        Some(Budget::Iterations(0)) => bail!("--iterations must be at least 1"),
        Some(Budget::Time(t)) if t.is_zero() => bail!("--time must be a positive number of seconds, got 0"),
        _ => {}
    }
    if r.techniques.is_some() {
        if !matches!(r.algorithm, Algorithm::Vcm(_)) {
            bail!(
                "--techniques needs an algorithm of the VCM engine (lt, ppm, bpm, bpt, vcm), not {}",
                r.algorithm.name()
            );
        }
        if resumed {
            bail!("--techniques cannot be combined with --resume (checkpoints do not keep the technique images)");
        }
    }
    Ok(())
}
