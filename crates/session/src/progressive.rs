//! A progressive render advanced one iteration at a time: the loop body of every front end.
//! [`crate::render`] (the command line) steps it until its budget, the Python module's
//! `Session` steps it when asked; both add every iteration to the film (and to the technique
//! images, when recorded) through [`Progressive::step`], so they produce the same images.
//!
//! It owns no scene (it borrows one: see [`crate::Live`] for a render that owns its scene), no
//! budget, no stop flag and no files: the caller decides when to stop and what to write.

use std::time::{Duration, Instant};

use anyhow::{Result, bail};
use render::RenderSettings;
use render::driver::Renderer;
use render::vcm::technique_images::{TechniqueImages, TechniqueLayout};
use render::vcm::{Family, RejectedCounts};
use scene::{Film, FrameBuffer, Scene};

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
    elapsed: Duration,
}

impl<'a> Progressive<'a> {
    /// Prepares a render of `scene` as `settings` say (their budget and progress flag are not
    /// used here). `resume` continues a film: its iteration count is the index of the next
    /// iteration. `record_families` / `record_techniques` accumulate one film per technique
    /// family and one image per (s, t) technique (VCM engine algorithms; ignored by the others
    /// and when resuming, since a checkpoint does not hold them).
    pub fn new(
        scene: &'a Scene,
        settings: &RenderSettings,
        resume: Option<Film>,
        record_families: bool,
        record_techniques: Option<TechniqueLayout>,
    ) -> Result<Self> {
        let (width, height) = (scene.camera.width, scene.camera.height);
        let film = match resume {
            Some(film) if (film.width(), film.height()) != (width, height) => {
                bail!("the film to resume is {}x{}, the render {width}x{height}", film.width(), film.height())
            }
            Some(film) => film,
            None => Film::with_variance(width, height, settings.variance),
        };
        let mut renderer = Renderer::starting_at(scene, settings, film.iterations()).map_err(anyhow::Error::msg)?;
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
        Ok(Self {
            renderer,
            film,
            family_films,
            family_frame: FrameBuffer::new(0, 0),
            technique_images,
            rejected_by_family: None,
            elapsed: Duration::ZERO,
        })
    }

    /// Renders the next iteration and adds it to the film (and the technique images).
    pub fn step(&mut self) -> Result<()> {
        let start = Instant::now();
        let rejected = self.renderer.step();
        self.film.add_iteration(self.renderer.frame(), rejected);
        let engine = self.renderer.vcm_engine();
        if let Some(engine) = engine {
            let counts = self.rejected_by_family.get_or_insert_with(Default::default);
            for (total, r) in counts.iter_mut().zip(engine.stats().rejected_by_family) {
                *total += r;
            }
        }
        if let (Some(films), Some(values)) = (&mut self.family_films, engine.and_then(|e| e.family_frames())) {
            if self.family_frame.pixels.is_empty() {
                self.family_frame = FrameBuffer::new(self.film.width(), self.film.height());
            }
            for (index, family_film) in films.iter_mut().enumerate() {
                for (pixel, value) in self.family_frame.pixels.iter_mut().zip(values) {
                    *pixel = value.0[index];
                }
                family_film.add_iteration(&self.family_frame, 0);
            }
        }
        if let (Some(images), Some(values)) = (&mut self.technique_images, engine.and_then(|e| e.technique_frame())) {
            images.add_iteration(values).map_err(anyhow::Error::msg)?;
        }
        self.elapsed += start.elapsed();
        Ok(())
    }

    /// The accumulated film (a resumed film's iterations included).
    pub fn film(&self) -> &Film {
        &self.film
    }

    /// Iterations in the film (a resumed film's included).
    pub fn iterations(&self) -> u64 {
        self.film.iterations()
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

    /// The driver's result, as [`render::driver::render_with`] returns it.
    pub fn into_output(self, interrupted: bool) -> render::driver::RenderOutput {
        let vcm_stats = self.renderer.vcm_engine().map(|e| e.stats());
        render::driver::RenderOutput {
            threads: self.renderer.threads(),
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
