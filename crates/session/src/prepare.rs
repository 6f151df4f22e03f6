//! Everything a render session settles before its first iteration: the request with a
//! resumed checkpoint's settings applied, the checked settings and outputs, the loaded scene,
//! the memory guard's decision and what a checkpoint records. [`crate::render`] and
//! [`crate::Live`] (the Python module's sessions) both start from it.

use std::path::PathBuf;

use anyhow::{Result, bail};
use render::driver::Budget;
use render::path_tracer::RussianRoulette;
use render::vcm::technique_images::TechniqueLayout;
use render::{Algorithm, RenderSettings};
use scene::filter::FilmMode;
use scene::{Film, Scene, Summation};

use crate::Notice;
use crate::checkpoint::{self, Recorded};
use crate::guard::{self, Guard};
use crate::outputs::{check_writable, output_paths};
use crate::request::{Request, radius_mode_from_name, radius_mode_name};
use crate::run::{DEFAULT_ITERATIONS, Observer, validate};
use crate::slice::SliceSpec;
use crate::source::{LoadedScene, SceneSource, load_scene, scene_source};

/// The path tracer's Russian roulette: the one `asked` for (the command line's `--rr-depth`,
/// Python's `rr_depth=`, a resumed checkpoint's), else the scene file's: Mitsuba 3's rule
/// ([`RussianRoulette::Throughput`], survival `min(max throughput component, 0.95)`) from the
/// file's `rr_depth` (`file_rr_depth`, [`io::RenderSettings::rr_depth`]; Mitsuba's default 5
/// when its integrator does not say), else (pbrt files, built-in scenes) the albedo rule
/// ([`RussianRoulette::Albedo`]).
pub fn resolve_russian_roulette(asked: Option<RussianRoulette>, file_rr_depth: Option<u32>) -> RussianRoulette {
    asked.unwrap_or(match file_rr_depth {
        Some(start) => RussianRoulette::Throughput { start },
        None => RussianRoulette::Albedo,
    })
}

/// A render session ready for its first iteration.
pub struct Prepared {
    /// The request, with a resumed checkpoint's settings in place of the given ones.
    pub request: Request,
    /// The loaded scene.
    pub scene: Scene,
    /// The driver's settings (the memory guard may have switched on the memory-efficient mode).
    pub settings: RenderSettings,
    /// What checkpoints of this render record.
    pub recorded: Recorded,
    /// The film of the resumed checkpoint, taken by the first [`crate::Progressive`].
    pub resumed: Option<Film>,
    /// Iterations in the resumed checkpoint.
    pub resumed_iterations: Option<u64>,
    /// The image files to write, with their formats.
    pub outputs: Vec<(PathBuf, io::ImageFormat)>,
    /// Per-(s, t) technique images to record (`request.techniques`; the Python module sets it
    /// without a directory).
    pub layout: Option<TechniqueLayout>,
    /// Per-family films to record.
    pub record_families: bool,
}

impl Prepared {
    /// Resolves, checks and loads what `request` asks for; notices go to `observer`.
    pub fn new(request: &Request, observer: &mut dyn Observer) -> Result<Self> {
        let mut request = request.clone();
        // A resumed render takes its settings from the checkpoint.
        let resumed = match &request.resume {
            Some(path) => {
                let (recorded, film) = checkpoint::load(path)?;
                request.scene = match &recorded.scene_file {
                    Some((file, defines)) => scene_source(&file.display().to_string(), defines)?,
                    None => SceneSource::Builtin(recorded.mask),
                };
                request.algorithm = Algorithm::from_name(&recorded.algorithm).ok_or_else(|| {
                    anyhow::anyhow!("unknown algorithm '{}' in '{}'", recorded.algorithm, path.display())
                })?;
                request.resolution = Some(recorded.resolution);
                request.max_length = Some(recorded.max_length);
                request.seed = recorded.seed;
                request.radius_factor = recorded.radius_factor;
                request.radius_alpha = recorded.radius_alpha;
                request.volume_radius_factor = recorded.volume_radius_factor;
                request.radius_mode = radius_mode_from_name(&recorded.radius_mode).ok_or_else(|| {
                    anyhow::anyhow!("unknown radius mode '{}' in '{}'", recorded.radius_mode, path.display())
                })?;
                request.memory_efficient = recorded.memory_efficient;
                request.spectral = recorded.spectral;
                request.russian_roulette = Some(recorded.russian_roulette);
                request.heuristic = recorded.heuristic;
                request.light_sampler = recorded.light_sampler;
                request.mis_compensation = recorded.mis_compensation;
                request.sampler = recorded.sampler;
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
                if let Some(asked) = request.summation.filter(|asked| *asked != recorded.sums) {
                    bail!(
                        "cannot resume '{}' with --sums {}: it was rendered with --sums {}",
                        path.display(),
                        asked.name(),
                        recorded.sums.name()
                    );
                }
                request.summation = Some(recorded.sums);
                if let Some(slice) = recorded.slice {
                    let asked = request.slice.map(|s| (s.index, s.count));
                    if asked.is_some_and(|asked| asked != (slice.index, slice.count)) {
                        bail!("cannot resume '{}' as another slice: it holds slice {}", path.display(), slice.name());
                    }
                    if request.budget.is_some_and(|b| b != Budget::Iterations(slice.iterations)) {
                        bail!(
                            "cannot resume slice '{}' with another budget: its render has {} iterations",
                            path.display(),
                            slice.iterations
                        );
                    }
                    request.slice = Some(SliceSpec { index: slice.index, count: slice.count });
                    request.budget = Some(Budget::Iterations(slice.iterations));
                } else if request.slice.is_some() {
                    bail!("cannot resume '{}' as a slice: it holds a whole render", path.display());
                }
                if request.checkpoint.is_none() {
                    request.checkpoint = Some(path.clone());
                }
                Some((film, recorded.fingerprint, path.clone()))
            }
            None => None,
        };
        if let Some(spec) = request.slice {
            let name = spec.name();
            if request.summation == Some(Summation::Float) {
                bail!("--slice {name} needs --sums fixed (slices are merged exactly), not --sums float");
            }
            request.summation = Some(Summation::Fixed);
            if matches!(request.budget, Some(Budget::Time(_))) {
                bail!(
                    "--slice {name} needs an iteration count (--iterations), not --time: every slice must know its iterations"
                );
            }
            if request.checkpoint.is_none() {
                bail!("--slice {name} needs --checkpoint FILE: the slice's film is what `vcm merge` reads");
            }
            if request.techniques.is_some() {
                bail!("--slice cannot be combined with --techniques (technique images are not merged)");
            }
        }
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
        let LoadedScene { mut scene, file_max_length, file_samples, file_rr_depth, fingerprint, .. } = loaded;
        let russian_roulette = resolve_russian_roulette(r.russian_roulette, file_rr_depth);
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
            volume_radius_factor: r.volume_radius_factor,
            radius_mode: r.radius_mode,
            memory_efficient: r.memory_efficient,
            spectral: r.spectral,
            russian_roulette,
            heuristic: r.heuristic,
            light_sampler: r.light_sampler,
            mis_compensation: r.mis_compensation,
            primary_samples: r.sampler,
            // Checkpoints always carry the sums of squares, so that any resume can ask for a
            // variance image.
            variance: r.keep_variance || r.variance.is_some() || r.checkpoint.is_some(),
            summation: r.summation.unwrap_or_default(),
            parallelism: r.parallelism,
            ..RenderSettings::default()
        };
        let slice = match r.slice {
            Some(spec) => {
                let Budget::Iterations(n) = settings.budget else { unreachable!("checked above") };
                let slice = spec.of(n)?;
                // The slice ends where its range does; an unfinished slice resumes in place.
                settings.budget = Budget::Iterations(slice.range().end);
                Some(slice)
            }
            None => None,
        };
        let resumed = match (resumed, slice) {
            (None, Some(slice)) => {
                let film = Film::with_summation(scene.camera.width, scene.camera.height, true, settings.summation)
                    .starting_at(slice.range().start);
                Some((film, None))
            }
            (resumed, _) => resumed.map(|(film, _, path)| (film, Some(path))),
        };
        if let Some(vcm_settings) = settings.vcm_settings()
            && !settings.memory_efficient
        {
            let lanes = settings.lanes(render::worker_threads(settings.threads), scene.camera.pixel_count());
            match guard::check(&scene, &vcm_settings, r.seed, r.max_memory, lanes)? {
                Guard::Fits => {}
                // Each lane holds its own buffers: within the limit only one at a time.
                Guard::OneIterationAtATime => {
                    if r.parallelism == render::Parallelism::Iterations {
                        observer.notice(Notice::Note(format!(
                            "{lanes} iterations side by side would need more than --max-memory allows; rendering \
                             one at a time with all threads (--parallelism pixels, the same image)"
                        )));
                    }
                    settings.parallelism = render::Parallelism::Pixels;
                }
                Guard::SwitchToMemoryEfficient(message) => {
                    observer.notice(Notice::Note(message));
                    settings.memory_efficient = true;
                    settings.parallelism = render::Parallelism::Pixels;
                }
            }
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
            volume_radius_factor: r.volume_radius_factor,
            radius_mode: radius_mode_name(r.radius_mode).to_string(),
            memory_efficient: settings.memory_efficient,
            spectral: r.spectral,
            russian_roulette,
            heuristic: r.heuristic,
            light_sampler: r.light_sampler,
            mis_compensation: r.mis_compensation,
            sampler: r.sampler,
            film: scene.camera.film.name().to_string(),
            fingerprint,
            sums: settings.summation,
            slice,
        };

        // The request states the policy used (the summary line names it).
        request.russian_roulette = Some(russian_roulette);
        Ok(Self {
            resumed_iterations: resumed.as_ref().filter(|(_, path)| path.is_some()).map(|(film, _)| film.iterations()),
            resumed: resumed.map(|(film, _)| film),
            record_families: request.techniques.is_some(),
            request,
            scene,
            settings,
            recorded,
            outputs,
            layout,
        })
    }
}
