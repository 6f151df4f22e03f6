//! Stepping a [`Progressive`] render until its budget is spent or a stop flag is set, with
//! periodic checkpoints and the progress bar: the command line's loop (the driver's
//! [`render::driver::render_with`] loop, over the session's stepping API).

use std::io::IsTerminal;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use render::RenderSettings;
use render::driver::Budget;

use crate::checkpoint::{self, Recorded};
use crate::progressive::Progressive;

/// Where and how often to checkpoint: the file, the wall-clock time between checkpoints, and
/// what the checkpoint records.
pub type Checkpointing<'a> = (&'a Path, Duration, &'a Recorded);

/// Steps `progressive` until `settings.budget` is reached (`Iterations` counts a resumed
/// film's iterations; `Time` this call's time, at least one iteration) or `stop` is set
/// (checked before each iteration). Checkpoints every interval and once at the end. Returns
/// whether the stop flag ended the render.
pub fn run_budget(
    progressive: &mut Progressive,
    settings: &RenderSettings,
    stop: Option<&AtomicBool>,
    checkpoint: Option<Checkpointing>,
) -> Result<bool> {
    let progress = progress_bar(settings);
    let start = Instant::now();
    let mut last_checkpoint = Instant::now();
    let first_iteration = progressive.iterations();
    let mut interrupted = false;
    loop {
        let iteration = progressive.iterations();
        match settings.budget {
            Budget::Iterations(n) if iteration >= n => break,
            Budget::Time(limit) if iteration > first_iteration && start.elapsed() >= limit => break,
            _ => {}
        }
        if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            interrupted = true;
            break;
        }
        progressive.step()?;
        if let Some((path, every, recorded)) = checkpoint
            && last_checkpoint.elapsed() >= every
        {
            checkpoint::save(path, recorded, progressive.film())?;
            last_checkpoint = Instant::now();
        }
        if let Some(bar) = &progress {
            match settings.budget {
                Budget::Iterations(_) => bar.set_position(iteration + 1),
                Budget::Time(_) => {
                    bar.set_position(start.elapsed().as_millis() as u64);
                    bar.set_message(format!("{} it", iteration + 1));
                }
            }
        }
    }
    if let Some(bar) = progress {
        bar.finish_and_clear();
    }
    if let Some((path, _, recorded)) = checkpoint {
        checkpoint::save(path, recorded, progressive.film())?;
    }
    Ok(interrupted)
}

/// A progress bar on stderr when asked for and stderr is a terminal.
fn progress_bar(settings: &RenderSettings) -> Option<ProgressBar> {
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
