//! A render session that owns its scene and advances when asked: the Python module's
//! `Session`. It is a [`Prepared`] session (the owner) with its [`Progressive`] render (which
//! borrows the owner's scene), stepped by [`Live::step`] through the same code as
//! [`crate::render`].

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Result;
use scene::Film;

use crate::checkpoint;
use crate::prepare::Prepared;
use render::progressive::Progressive;

self_cell::self_cell!(
    /// The prepared session and its render.
    struct Cell {
        owner: Prepared,
        #[not_covariant]
        dependent: Progressive,
    }
);

/// A render session that owns its scene (see the module documentation).
pub struct Live {
    cell: Cell,
}

impl Live {
    /// Starts the render of a prepared session (no iteration is rendered yet); a resumed
    /// checkpoint's film is continued.
    pub fn start(mut prepared: Prepared) -> Result<Self> {
        let resumed = prepared.resumed.take();
        let cell = Cell::try_new(prepared, |p| {
            Progressive::new(&p.scene, &p.settings, resumed, p.record_families, p.layout).map_err(anyhow::Error::msg)
        })?;
        Ok(Self { cell })
    }

    /// Renders up to `iterations` more iterations, side by side when the render has lanes
    /// ([`Progressive::step_batch`]), checking `stop` before each batch; returns the number
    /// rendered (fewer only when `stop` was set).
    pub fn step(&mut self, iterations: u64, stop: Option<&AtomicBool>) -> Result<u64> {
        self.cell.with_dependent_mut(|_, progressive| {
            let mut done = 0;
            while done < iterations {
                if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
                    return Ok(done);
                }
                done += progressive.step_batch(iterations - done).map_err(anyhow::Error::msg)?;
            }
            Ok(iterations)
        })
    }

    /// The prepared session: the scene, the settings and the request as resolved.
    pub fn prepared(&self) -> &Prepared {
        self.cell.borrow_owner()
    }

    /// Reads the render (film, technique images) through `read`.
    pub fn with_render<R>(&self, read: impl FnOnce(&Progressive) -> R) -> R {
        self.cell.with_dependent(|_, progressive| read(progressive))
    }

    /// The accumulated film, copied.
    pub fn film(&self) -> Film {
        self.with_render(|p| p.film().clone())
    }

    /// Writes a checkpoint of the render to `path`; [`crate::Request::resume`] continues it.
    pub fn checkpoint(&self, path: &Path) -> Result<()> {
        self.with_render(|p| checkpoint::save(path, &self.prepared().recorded, p.film()))
    }
}
