//! One render session for every front end (the `vcm` command line today; a Python module and
//! MPI ranks next): a [`Request`] in, an [`Outcome`] out. The session resolves and loads the
//! scene, validates the settings, runs the memory guard, saves and resumes checkpoints, renders
//! through [`render::driver`], writes the outputs and composes the summary line.
//!
//! Front ends only translate their arguments into a [`Request`] and present the result:
//! errors are values ([`anyhow::Error`], messages naming the setting as the command line spells
//! it), nothing here prints or exits; messages for the user arrive through [`Observer`], and the
//! progress bar is switched by [`Request::progress`].
//!
//! The steps of a session, shared by every front end: [`Prepared::new`] (request to loaded,
//! checked scene and settings), [`Progressive`] (one iteration at a time into the film and the
//! technique images), [`run_budget`] (stepping until the budget, checkpointing). [`render()`] runs
//! them to the end and writes the files; [`Live`] owns a prepared session and steps it when
//! asked (the Python module's `Session`).

mod budget;
pub mod builtin_files;
pub mod checkpoint;
pub mod fingerprint;
pub mod guard;
mod live;
pub mod merge;
pub mod outputs;
mod prepare;
mod request;
mod run;
pub mod slice;
pub mod source;
mod summary;

pub use budget::{Checkpointing, checkpoint_saver, run_budget};
pub use live::Live;
pub use prepare::{Prepared, resolve_russian_roulette};
pub use render::progressive::Progressive;
pub use request::{DEFAULT_SAMPLER, Request, radius_mode_from_name, radius_mode_name};
pub use run::{DEFAULT_ITERATIONS, Observer, Outcome, render, render_on};
pub use source::{LoadedScene, SceneSource, load_scene, scene_source};
pub use summary::Summary;

/// A message for the user from a session.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Notice {
    /// Something the user should look at (e.g. a scene-file attribute that was skipped).
    Warning(String),
    /// A decision the session took for the user (e.g. switching to the memory-efficient mode).
    Note(String),
    /// Progress information (e.g. what was loaded and how long it took); quiet front ends
    /// drop it.
    Progress(String),
}

impl std::fmt::Display for Notice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Notice::Warning(text) => write!(f, "warning: {text}"),
            Notice::Note(text) => write!(f, "note: {text}"),
            Notice::Progress(text) => f.write_str(text),
        }
    }
}
