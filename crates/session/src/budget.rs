//! Stepping a [`Progressive`] render until its budget, with the session's checkpoints: the
//! render crate's loop ([`render::progressive::run_budget`]) with checkpoints that record the
//! session's settings ([`Recorded`]).

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use anyhow::Result;
use render::RenderSettings;
use render::driver::SaveFilm;
use render::progressive::Progressive;

use crate::checkpoint::{self, Recorded};

/// Where and how often to checkpoint: the file, the wall-clock time between checkpoints, and
/// what the checkpoint records.
pub type Checkpointing<'a> = (&'a Path, Duration, &'a Recorded);

/// Steps `progressive` until `settings.budget` is reached or `stop` is set
/// ([`render::progressive::run_budget`]), checkpointing every interval and once at the end.
/// Returns whether the stop flag ended the render.
pub fn run_budget(
    progressive: &mut Progressive,
    settings: &RenderSettings,
    stop: Option<&AtomicBool>,
    checkpoint: Option<Checkpointing>,
) -> Result<bool> {
    let checkpoint = checkpoint.map(checkpoint_saver);
    render::progressive::run_budget(progressive, settings, stop, checkpoint).map_err(anyhow::Error::msg)
}

/// The render crate's form of a session checkpoint: the interval and a callback that saves the
/// film with what the session records.
pub fn checkpoint_saver<'a>((path, every, recorded): Checkpointing<'a>) -> (Duration, SaveFilm<'a>) {
    let save = move |film: &scene::Film| checkpoint::save(path, recorded, film).map_err(|e| format!("{e:#}"));
    (every, Box::new(save) as SaveFilm)
}
