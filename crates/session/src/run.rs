//! The session itself: request in, outputs written, outcome out.

use std::sync::atomic::AtomicBool;

use anyhow::{Result, bail};
use render::Algorithm;
use render::driver::{Budget, RenderOutput};
use render::vcm::Family;

use crate::budget::{checkpoint_saver, run_budget};
use crate::outputs::{write_st_images, write_technique_images};
use crate::prepare::Prepared;
use crate::request::Request;
use crate::{Notice, Summary};
use render::distributed::{Collective, agree, run_distributed};
use render::progressive::Progressive;

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
    render_on(request, stop, observer, None)
}

/// [`render()`], spread over the ranks of `ranks` when given ([`render::distributed`]): every
/// rank calls it with the same request (all ranks parse the same command line, so their
/// settings cannot differ). Every rank loads the scene; a load error on any rank is every
/// rank's error. Rank 0 keeps the film, writes the outputs and checkpoints and composes the
/// summary; on the other ranks the outcome's film is empty and nothing is written. `stop` on
/// any rank stops every rank after the current round. The image equals [`render()`]'s bit for
/// bit.
pub fn render_on(
    request: &Request,
    stop: Option<&AtomicBool>,
    observer: &mut dyn Observer,
    ranks: Option<&dyn Collective>,
) -> Result<Outcome> {
    let prepared = Prepared::new(request, observer);
    let prepared = match ranks {
        Some(comm) => agree(comm, prepared.map_err(|e| format!("{e:#}"))).map_err(anyhow::Error::msg)?,
        None => prepared?,
    };
    let root = ranks.is_none_or(|comm| comm.rank() == 0);
    observer.starting();
    let Prepared {
        request: r,
        scene,
        settings,
        recorded,
        resumed,
        resumed_iterations,
        outputs,
        layout,
        record_families,
    } = prepared;
    // Rank 0 continues the resumed film; the others only need its iteration count, which the
    // distributed loop broadcasts.
    let resumed = if root { resumed } else { None };
    let progressive = Progressive::new(&scene, &settings, resumed, record_families, layout);
    let mut progressive = match ranks {
        Some(comm) => agree(comm, progressive),
        None => progressive,
    }
    .map_err(anyhow::Error::msg)?;
    let checkpoint = r.checkpoint.as_deref().map(|path| (path, r.checkpoint_every, &recorded));
    let interrupted = match ranks {
        Some(comm) => {
            let checkpoint = checkpoint.filter(|_| root).map(checkpoint_saver);
            run_distributed(&mut progressive, &settings, stop, checkpoint, comm).map_err(anyhow::Error::msg)?
        }
        None => run_budget(&mut progressive, &settings, stop, checkpoint)?,
    };
    let result = progressive.into_output(interrupted);
    if !root {
        let summary = summary(&scene.name, &r, &result, resumed_iterations, Vec::new(), ranks, recorded.slice);
        return Ok(Outcome { output: result, summary });
    }

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
        let Some(pixels) = film.variance_of_mean() else {
            bail!("internal error: the film kept no sums of squares for the variance image {}", path.display())
        };
        io::write_image(path, &io::Image { width, height, pixels }, &options)?;
    }
    let mut written: Vec<String> = outputs.iter().map(|(p, _)| p.display().to_string()).collect();
    if let Some(path) = &r.variance {
        written.push(format!("variance {}", path.display()));
    }
    if let Some(path) = &r.checkpoint {
        written.push(format!("checkpoint {}", path.display()));
    }
    let summary = summary(&scene.name, &r, &result, resumed_iterations, written, ranks, recorded.slice);
    Ok(Outcome { output: result, summary })
}

/// The summary line of a finished session.
fn summary(
    scene: &str,
    r: &Request,
    result: &RenderOutput,
    resumed_iterations: Option<u64>,
    written: Vec<String>,
    ranks: Option<&dyn Collective>,
    slice: Option<crate::slice::Slice>,
) -> Summary {
    let film = &result.film;
    Summary {
        scene: scene.to_string(),
        algorithm: r.algorithm.name(),
        spectral: r.spectral,
        russian_roulette: r.russian_roulette.filter(|_| r.algorithm == Algorithm::PathTracing),
        resolution: (film.width(), film.height()),
        iterations: film.iterations(),
        resumed_after: resumed_iterations,
        seconds: result.elapsed.as_secs_f64(),
        threads: result.threads,
        ranks: ranks.map(|comm| comm.size()),
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
        slice,
    }
}

/// Iterations of a render whose request and scene name no budget.
pub const DEFAULT_ITERATIONS: u64 = 64;

/// Checks the settings that do not need the scene; messages name them as the command line
/// does.
pub(crate) fn validate(r: &Request, resumed: bool) -> Result<()> {
    if !(r.radius_factor.is_finite() && r.radius_factor > 0.0) {
        bail!("--radius-factor must be a positive number, got {}", r.radius_factor);
    }
    if !(r.volume_radius_factor.is_finite() && r.volume_radius_factor > 0.0) {
        bail!("--volume-radius-factor must be a positive number, got {}", r.volume_radius_factor);
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
