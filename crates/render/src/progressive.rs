//! A progressive render advanced one iteration at a time, and the budget loop over it: the
//! loop body and the loop of every front end. [`crate::driver::render_with`], the session
//! crate's `render` (the command line) and the Python module's `Session` all add each iteration
//! to the film (and the technique images, when recorded) through [`Progressive::step`], so they
//! produce the same images bit for bit.
//!
//! [`Progressive`] owns no scene (it borrows one), no budget, no stop flag and no files: the
//! caller decides when to stop and what to write; [`run_budget`] is the usual caller.
//!
//! **Iterations side by side** ([`crate::Parallelism::Iterations`]). An iteration of the VCM
//! engine has phases that wait for each other (light pass, grid, camera pass): at each boundary
//! a thread that finishes early waits for the others, and some hand-overs are serial. With
//! several lanes, [`Progressive::step_batch`] renders that many consecutive iterations at once,
//! each on a thread of its own with its own integrator state, and adds them to the film in
//! index order: the film is the one of [`Progressive::step`] bit for bit, because an iteration
//! depends only on the seed and its index and not on the number of threads that render it.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use scene::{Film, FrameBuffer, Scene};

use crate::driver::{Budget, RenderOutput, RenderSettings, Renderer, SaveFilm};
use crate::vcm::technique_images::{TechniqueFrame, TechniqueImages, TechniqueLayout};
use crate::vcm::{Family, FamilyValues, IterationStats, RejectedCounts};
use spectrum::Rgb;

/// A progressive render of a borrowed scene: the integrator with its state, the film and the
/// optional per-technique images.
pub struct Progressive<'a> {
    renderer: Renderer<'a>,
    film: Film,
    family_films: Option<[Film; 5]>,
    /// Scratch for one family's iteration (allocated only when families are recorded).
    family_frame: FrameBuffer,
    technique_images: Option<TechniqueImages>,
    rejected_by_family: Option<RejectedCounts>,
    /// Statistics of the last added iteration (VCM engine only).
    last_stats: Option<IterationStats>,
    elapsed: Duration,
    /// Iterations rendered at a time by [`Progressive::step_batch`] (1: one at a time).
    lanes: usize,
    /// Lane 0's one-thread pool (lane 0 is `renderer`, whose own pool has all the threads) and
    /// the other lanes' renderers, each with a one-thread pool of its own; made at the first
    /// [`Progressive::step_batch`] of more than one iteration.
    lane_pool: Option<rayon::ThreadPool>,
    other_lanes: Vec<Renderer<'a>>,
}

/// One rendered iteration, not yet in the film: what [`Progressive::add_result`] adds. A
/// distributed render sends it between ranks ([`crate::distributed`]).
#[derive(Clone, Debug)]
pub struct IterationResult {
    /// The global iteration index (0-based).
    pub iteration: u64,
    /// The iteration's frame (radiance estimates per pixel, one sample per pixel).
    pub frame: FrameBuffer,
    /// Rejected (non-finite) samples of the iteration.
    pub rejected: u64,
    /// The VCM engine's statistics of the iteration (`None` for the other integrators).
    pub stats: Option<IterationStats>,
    /// Per-pixel values per technique family, when family films are recorded.
    pub family_values: Option<Vec<FamilyValues>>,
    /// Per-pixel values per (s, t) technique (`TechniqueFrame::values` layout), when technique
    /// images are recorded.
    pub technique_values: Option<Vec<Rgb>>,
}

impl<'a> Progressive<'a> {
    /// Prepares a render of `scene` as `settings` say (their budget and progress flag are not
    /// used here; [`RenderSettings::variance`] decides whether a new film keeps its sums of
    /// squares). `resume` continues a film: its iteration count is the index of the next
    /// iteration. `record_families` / `record_techniques` accumulate one film per technique
    /// family and one image per (s, t) technique (VCM engine algorithms; ignored by the others
    /// and when resuming, since a checkpoint does not hold them).
    pub fn new(
        scene: &'a Scene,
        settings: &RenderSettings,
        resume: Option<Film>,
        record_families: bool,
        record_techniques: Option<TechniqueLayout>,
    ) -> Result<Self, String> {
        let (width, height) = (scene.camera.width, scene.camera.height);
        let film = match resume {
            Some(film) if (film.width(), film.height()) != (width, height) => {
                return Err(format!(
                    "the film to resume is {}x{}, the render {width}x{height}",
                    film.width(),
                    film.height()
                ));
            }
            Some(film) => film,
            None => Film::with_summation(width, height, settings.variance, settings.summation),
        };
        let mut renderer = Renderer::starting_at(scene, settings, film.next_iteration())?;
        let fresh = film.iterations() == 0;
        let family_films = match renderer.vcm_engine_mut() {
            Some(engine) if record_families && fresh => {
                engine.record_families(true);
                Some(Family::ALL.map(|_| Film::without_variance(width, height)))
            }
            _ => None,
        };
        let technique_images = match (renderer.vcm_engine_mut(), record_techniques) {
            (Some(engine), Some(layout)) if fresh => {
                engine.record_techniques(Some(layout));
                Some(TechniqueImages::new(layout, scene.camera.pixel_count()))
            }
            _ => None,
        };
        let lanes = settings.lanes(renderer.threads(), scene.camera.pixel_count());
        Ok(Self {
            renderer,
            film,
            family_films,
            family_frame: FrameBuffer::new(0, 0),
            technique_images,
            rejected_by_family: None,
            last_stats: None,
            elapsed: Duration::ZERO,
            lanes,
            lane_pool: None,
            other_lanes: Vec::new(),
        })
    }

    /// Iterations [`Progressive::step_batch`] renders at a time ([`RenderSettings::lanes`]).
    pub fn lanes(&self) -> usize {
        self.lanes
    }

    /// Renders the next `min(at_most, lanes)` iterations ([`Progressive::lanes`]) and adds them
    /// to the film in order: side by side, one thread each, when that is more than one, else one
    /// with all threads ([`Progressive::step`]). Returns how many it rendered. The film is the
    /// same either way, bit for bit.
    pub fn step_batch(&mut self, at_most: u64) -> Result<u64, String> {
        let count = at_most.min(self.lanes as u64);
        match count {
            0 => {}
            1 => self.step()?,
            _ => self.step_lanes(count as usize)?,
        }
        Ok(count)
    }

    /// Renders iterations `next .. next + count` side by side, one per lane, and adds them.
    fn step_lanes(&mut self, count: usize) -> Result<(), String> {
        let start = Instant::now();
        self.make_lanes(count)?;
        let first = self.film.next_iteration();
        let (families, techniques) = (self.family_films.is_some(), self.technique_images.is_some());
        let Some(pool) = &self.lane_pool else { unreachable!("made by make_lanes") };
        let (main, others) = (&mut self.renderer, &mut self.other_lanes[..count - 1]);
        let results: Vec<IterationResult> = std::thread::scope(|scope| {
            let handles: Vec<_> = others
                .iter_mut()
                .zip(first + 1..)
                .map(|(lane, iteration)| {
                    scope.spawn(move || {
                        let pool = lane.pool();
                        render_in(lane, &pool, iteration, families, techniques)
                    })
                })
                .collect();
            let mut results = vec![render_in(main, pool, first, families, techniques)];
            for handle in handles {
                results.push(handle.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)));
            }
            results
        });
        for (k, result) in results.into_iter().enumerate() {
            self.add_result(&result)?;
            match k {
                0 => self.renderer.restore_frame(result.frame),
                _ => self.other_lanes[k - 1].restore_frame(result.frame),
            }
        }
        self.elapsed += start.elapsed();
        Ok(())
    }

    /// Makes lane 0's pool and the renderers of lanes 1 .. `count` that do not exist yet.
    fn make_lanes(&mut self, count: usize) -> Result<(), String> {
        if self.lane_pool.is_none() {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .map_err(|e| format!("cannot start a worker thread: {e}"))?;
            self.lane_pool = Some(pool);
        }
        while self.other_lanes.len() + 1 < count {
            let settings = RenderSettings { threads: 1, ..self.renderer.settings().clone() };
            let scene = self.renderer.scene();
            let mut lane = Renderer::starting_at(scene, &settings, self.film.next_iteration())?;
            if let Some(engine) = lane.vcm_engine_mut() {
                engine.record_families(self.family_films.is_some());
                engine.record_techniques(self.technique_images.as_ref().map(TechniqueImages::layout));
            }
            self.other_lanes.push(lane);
        }
        Ok(())
    }

    /// Renders the next iteration (index [`Progressive::next_iteration`]) and adds it to the film
    /// (and the technique images): [`Progressive::render_iteration`] then
    /// [`Progressive::add_result`].
    pub fn step(&mut self) -> Result<(), String> {
        let start = Instant::now();
        let result = self.render_iteration(self.film.next_iteration());
        self.add_result(&result)?;
        // The frame goes back to the renderer: one frame per render, not one per iteration.
        self.renderer.restore_frame(result.frame);
        self.elapsed += start.elapsed();
        Ok(())
    }

    /// Runs `f` on one of the renderer's worker threads ([`Renderer::in_pool`]): the steps
    /// inside it do not each wait for a worker to wake.
    pub fn in_pool<R: Send>(&mut self, f: impl FnOnce(&mut Self) -> R + Send) -> R {
        let pool = self.renderer.pool();
        pool.install(|| f(self))
    }

    /// Renders global iteration `iteration` (any index: a function of the seed and the index
    /// only) without touching the film; [`Progressive::add_result`] adds it.
    pub fn render_iteration(&mut self, iteration: u64) -> IterationResult {
        let pool = self.renderer.pool();
        let (families, techniques) = (self.family_films.is_some(), self.technique_images.is_some());
        render_in(&mut self.renderer, &pool, iteration, families, techniques)
    }

    /// Adds one rendered iteration to the film, the family films and the technique images, in
    /// that order (the additions of a single-process render, bit for bit). The result must be
    /// the film's next iteration; another index is an error (the film's iteration count is the
    /// index of the next iteration, so iterations are added in order without gaps).
    pub fn add_result(&mut self, result: &IterationResult) -> Result<(), String> {
        if result.iteration != self.film.next_iteration() {
            return Err(format!(
                "internal error: iteration {} added to a film whose next iteration is {}",
                result.iteration,
                self.film.next_iteration()
            ));
        }
        if !self.film.has_room() {
            return Err(format!(
                "a film with fixed-point sums holds at most {} iterations",
                Film::FIXED_MAX_ITERATIONS
            ));
        }
        if (result.frame.width, result.frame.height) != (self.film.width(), self.film.height()) {
            return Err(format!(
                "iteration {} is {}x{}, the film {}x{}",
                result.iteration,
                result.frame.width,
                result.frame.height,
                self.film.width(),
                self.film.height()
            ));
        }
        self.film.add_iteration(&result.frame, result.rejected);
        if let Some(stats) = result.stats {
            let counts = self.rejected_by_family.get_or_insert_with(Default::default);
            for (total, r) in counts.iter_mut().zip(stats.rejected_by_family) {
                *total += r;
            }
            self.last_stats = Some(stats);
        }
        if let (Some(films), Some(values)) = (&mut self.family_films, &result.family_values) {
            if self.family_frame.pixels.is_empty() {
                self.family_frame = FrameBuffer::new(self.film.width(), self.film.height());
            }
            if values.len() != self.family_frame.pixels.len() {
                return Err(format!("iteration {}: family values of another size", result.iteration));
            }
            for (index, family_film) in films.iter_mut().enumerate() {
                for (pixel, value) in self.family_frame.pixels.iter_mut().zip(values) {
                    *pixel = value.0[index];
                }
                family_film.add_iteration(&self.family_frame, 0);
            }
        }
        if let (Some(images), Some(values)) = (&mut self.technique_images, &result.technique_values) {
            let frame = TechniqueFrame { layout: images.layout(), values: values.clone() };
            images.add_iteration(&frame)?;
        }
        Ok(())
    }

    /// Adds wall-clock time to [`Progressive::elapsed`] (a distributed render counts its rounds).
    pub fn add_elapsed(&mut self, time: Duration) {
        self.elapsed += time;
    }

    /// The technique layout when technique images are recorded (decoding a result needs it).
    pub fn technique_layout(&self) -> Option<TechniqueLayout> {
        self.technique_images.as_ref().map(TechniqueImages::layout)
    }

    /// Whether family films are recorded.
    pub fn records_families(&self) -> bool {
        self.family_films.is_some()
    }

    /// The accumulated film (a resumed film's iterations included).
    pub fn film(&self) -> &Film {
        &self.film
    }

    /// Iterations in the film (a resumed film's included).
    pub fn iterations(&self) -> u64 {
        self.film.iterations()
    }

    /// Global index of the next iteration: the film's first iteration (0 unless it holds a
    /// slice of a render) plus its iteration count.
    pub fn next_iteration(&self) -> u64 {
        self.film.next_iteration()
    }

    /// One film per technique family ([`Family::ALL`] order) when recorded; they sum to the film.
    pub fn family_films(&self) -> Option<&[Film; 5]> {
        self.family_films.as_ref()
    }

    /// One image per (s, t) technique when recorded; they sum to the film.
    pub fn technique_images(&self) -> Option<&TechniqueImages> {
        self.technique_images.as_ref()
    }

    /// Wall-clock time spent in [`Progressive::step`].
    pub fn elapsed(&self) -> Duration {
        self.elapsed
    }

    /// Worker threads.
    pub fn threads(&self) -> usize {
        self.renderer.threads()
    }

    /// The render's result.
    pub fn into_output(self, interrupted: bool) -> RenderOutput {
        let vcm_stats = self.last_stats.or_else(|| self.renderer.vcm_engine().map(|e| e.stats()));
        RenderOutput {
            threads: self.renderer.threads(),
            lanes: self.lanes,
            film: self.film,
            elapsed: self.elapsed,
            light_vertices: vcm_stats.map(|s| (s.light_vertices, s.bytes_per_vertex)),
            vcm_stats,
            interrupted,
            family_films: self.family_films,
            technique_images: self.technique_images,
            rejected_by_family: self.rejected_by_family,
        }
    }
}

/// Renders global iteration `iteration` with `renderer` on the threads of `pool`, taking its
/// frame, and the family and technique values when they are recorded.
fn render_in(
    renderer: &mut Renderer,
    pool: &rayon::ThreadPool,
    iteration: u64,
    families: bool,
    techniques: bool,
) -> IterationResult {
    renderer.seek(iteration);
    let rejected = renderer.step_in(pool);
    let frame = renderer.take_frame();
    let engine = renderer.vcm_engine();
    IterationResult {
        iteration,
        frame,
        rejected,
        stats: engine.map(|e| e.stats()),
        family_values: if families { engine.and_then(|e| e.family_frames()).map(<[_]>::to_vec) } else { None },
        technique_values: if techniques {
            engine.and_then(|e| e.technique_frame()).map(|f| f.values.clone())
        } else {
            None
        },
    }
}

/// Steps `progressive` until `settings.budget` is reached (`Iterations` counts a resumed
/// film's iterations; `Time` this call's time, at least one iteration) or `stop` is set
/// (checked before each iteration), with a progress bar when `settings.progress` is set and
/// stderr is a terminal. `checkpoint` saves the film every interval of wall-clock time (after
/// the iteration that crosses it) and once at the end; its error stops the render. Returns
/// whether the stop flag ended the render.
pub fn run_budget(
    progressive: &mut Progressive,
    settings: &RenderSettings,
    stop: Option<&AtomicBool>,
    mut checkpoint: Option<(Duration, SaveFilm)>,
) -> Result<bool, String> {
    let progress = progress_bar(settings);
    let start = Instant::now();
    let mut last_checkpoint = Instant::now();
    let first_iteration = progressive.next_iteration();
    let every = checkpoint.as_ref().map(|(every, _)| *every);
    // Wall-clock time of the last batch of iterations rendered side by side.
    let mut last_batch: Option<Duration> = None;
    // The iterations run inside the renderer's pool ([`Progressive::in_pool`]), which they
    // leave only when a checkpoint is due (the saver need not be `Send`) or at the end.
    let interrupted = loop {
        let pause = progressive.in_pool(|progressive| {
            loop {
                let iteration = progressive.next_iteration();
                match settings.budget {
                    Budget::Iterations(n) if iteration >= n => return Ok(Pause::Done),
                    Budget::Time(limit) if iteration > first_iteration && start.elapsed() >= limit => {
                        return Ok(Pause::Done);
                    }
                    _ => {}
                }
                if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
                    return Ok(Pause::Stopped);
                }
                // Side by side when lanes are on: as many as the iteration budget leaves, or,
                // under a time budget, a whole batch while the last batch's time still fits.
                let at_most = match settings.budget {
                    Budget::Iterations(n) => n - iteration,
                    Budget::Time(limit) => match last_batch {
                        Some(took) if start.elapsed() + took > limit => 1,
                        _ => u64::MAX,
                    },
                };
                let batch_start = Instant::now();
                let count = progressive.step_batch(at_most)?;
                if count > 1 {
                    last_batch = Some(batch_start.elapsed());
                }
                let done = iteration + count;
                if let Some(bar) = &progress {
                    match settings.budget {
                        Budget::Iterations(_) => bar.set_position(done),
                        Budget::Time(_) => {
                            bar.set_position(start.elapsed().as_millis() as u64);
                            bar.set_message(format!("{done} it"));
                        }
                    }
                }
                if every.is_some_and(|every| last_checkpoint.elapsed() >= every) {
                    return Ok::<_, String>(Pause::Checkpoint);
                }
            }
        })?;
        match pause {
            Pause::Done => break false,
            Pause::Stopped => break true,
            Pause::Checkpoint => {
                if let Some((_, save)) = &mut checkpoint {
                    save(progressive.film())?;
                }
                last_checkpoint = Instant::now();
            }
        }
    };
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    if let Some((_, save)) = &mut checkpoint {
        save(progressive.film())?;
    }
    Ok(interrupted)
}

/// Why [`run_budget`]'s loop left the pool.
enum Pause {
    /// The budget is spent.
    Done,
    /// The stop flag was set.
    Stopped,
    /// A checkpoint is due.
    Checkpoint,
}

/// A progress bar on stderr when asked for and stderr is a terminal.
pub(crate) fn progress_bar(settings: &RenderSettings) -> Option<ProgressBar> {
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
