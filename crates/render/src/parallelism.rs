//! How a render's threads share the work: the pixels of one iteration, or whole iterations side
//! by side ([`Parallelism`]; the loop that runs them is [`crate::progressive`]).

use crate::driver::{Algorithm, RenderSettings};

/// How a render's threads share the work. Every iteration is a function of the seed and its
/// index alone, and the film adds the iterations in index order, so the image does not depend
/// on this choice (bit for bit); speed and peak memory do.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Parallelism {
    /// [`Parallelism::Iterations`] for the VCM engine's algorithms on images of at least
    /// [`Parallelism::AUTO_MIN_PIXELS`] pixels outside the memory-efficient mode,
    /// [`Parallelism::Pixels`] otherwise (docs/performance.md, "Iterations side by side").
    #[default]
    Auto,
    /// All threads work on one iteration at a time, splitting its pixels and light sub-paths.
    Pixels,
    /// One iteration per thread, as many iterations at a time as there are threads
    /// ([`crate::progressive`]): no thread waits at the phase boundaries inside an iteration,
    /// at the cost of one set of the integrator's buffers per thread.
    Iterations,
}

impl Parallelism {
    /// Images with fewer pixels than this render one iteration at a time under
    /// [`Parallelism::Auto`]: their iterations are short, and a batch's thread hand-over
    /// would weigh more than the phase boundaries it saves.
    pub const AUTO_MIN_PIXELS: usize = 256 * 256;

    /// Every choice with its command-line name.
    pub const ALL: [(Parallelism, &'static str); 3] =
        [(Parallelism::Auto, "auto"), (Parallelism::Pixels, "pixels"), (Parallelism::Iterations, "iterations")];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(p, _)| *p == self).map_or("?", |(_, n)| n)
    }

    /// Parses a command-line name.
    pub fn from_name(name: &str) -> Option<Parallelism> {
        Self::ALL.iter().find(|(_, n)| *n == name).map(|(p, _)| *p)
    }
}

impl RenderSettings {
    /// Iterations rendered at a time ([`Parallelism`]) on `threads` worker threads (the
    /// resolved count, [`worker_threads`]) for an image of `pixels` pixels: 1 (all threads on
    /// one iteration) or `threads` (one iteration per thread).
    pub fn lanes(&self, threads: usize, pixels: usize) -> usize {
        let threads = threads.max(1);
        match self.parallelism {
            Parallelism::Pixels => 1,
            Parallelism::Iterations => threads,
            // The path tracer already keeps its threads busy (one phase per iteration), and
            // a second set of its buffers cost it time on matpreview (docs/performance.md).
            Parallelism::Auto
                if matches!(self.algorithm, Algorithm::Vcm(_))
                    && !self.memory_efficient
                    && pixels >= Parallelism::AUTO_MIN_PIXELS =>
            {
                threads
            }
            Parallelism::Auto => 1,
        }
    }
}

/// The worker threads a render with `threads` (0: all cores) gets: rayon's rule, the
/// `RAYON_NUM_THREADS` environment variable when set to a positive number, else the processors
/// available to the process.
pub fn worker_threads(threads: usize) -> usize {
    if threads > 0 {
        return threads;
    }
    let from_env = std::env::var("RAYON_NUM_THREADS").ok().and_then(|v| v.parse::<usize>().ok());
    from_env.filter(|&n| n > 0).unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}
