//! The one-line summary that ends every render.

use std::fmt;

use render::path_tracer::RussianRoulette;

/// What a render did, for the summary line ([`fmt::Display`] gives the line `vcm render`
/// prints).
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// Algorithm name as the command line spells it.
    pub algorithm: &'static str,
    /// Spectral mode.
    pub spectral: bool,
    /// The path tracer's Russian roulette (`None` for the other algorithms, which always use
    /// the albedo rule); the line names it as `--rr-depth` spells it.
    pub russian_roulette: Option<RussianRoulette>,
    /// Image size in pixels.
    pub resolution: (u32, u32),
    /// Iterations in the film (a resumed checkpoint's included).
    pub iterations: u64,
    /// Iterations the resumed checkpoint already had.
    pub resumed_after: Option<u64>,
    /// Wall-clock seconds of this session's iterations.
    pub seconds: f64,
    /// Worker threads used (per rank when distributed).
    pub threads: usize,
    /// Ranks of a distributed render (`None`: one process).
    pub ranks: Option<usize>,
    /// Light vertices stored in the last iteration and bytes per vertex (VCM engine only).
    pub light_vertices: Option<(usize, usize)>,
    /// Non-finite samples discarded, in the whole film.
    pub rejected: u64,
    /// This session's discarded samples per technique family that had any (name, count).
    pub rejected_by_family: Vec<(&'static str, u64)>,
    /// Stopped early (interrupt).
    pub interrupted: bool,
    /// The files written, as the summary names them.
    pub written: Vec<String>,
    /// The slice of the render this session rendered (`--slice`).
    pub slice: Option<crate::slice::Slice>,
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let here = self.iterations - self.resumed_after.unwrap_or(0);
        let vertices = match self.light_vertices {
            Some((count, bytes)) => format!(", {count} light vertices x {bytes} B"),
            None => String::new(),
        };
        let resumed = match self.resumed_after {
            Some(n) => format!(" (resumed after {n})"),
            None => String::new(),
        };
        let ranks = match self.ranks {
            Some(1) => " x 1 rank".to_string(),
            Some(n) => format!(" x {n} ranks"),
            None => String::new(),
        };
        let slice = match &self.slice {
            Some(slice) => {
                let range = slice.range();
                format!(" of slice {} ({}..{} of {})", slice.name(), range.start, range.end, slice.iterations)
            }
            None => String::new(),
        };
        let options: Vec<String> = self
            .spectral
            .then(|| "spectral".to_string())
            .into_iter()
            .chain(self.russian_roulette.map(|rr| format!("rr-depth {}", rr.name())))
            .collect();
        let options = if options.is_empty() { String::new() } else { format!(" ({})", options.join(", ")) };
        let rejected = if self.rejected_by_family.is_empty() {
            String::new()
        } else {
            let parts: Vec<String> = self.rejected_by_family.iter().map(|(f, c)| format!("{f} {c}")).collect();
            format!(" ({})", parts.join(", "))
        };
        write!(
            f,
            "{}{} with {}{options} at {}x{}: {} iterations{slice}{resumed} in {:.2} s ({:.1} ms/iteration, {} threads{ranks}{vertices}), {} rejected samples{rejected} -> {}",
            if self.interrupted { "interrupted: " } else { "" },
            self.scene,
            self.algorithm,
            self.resolution.0,
            self.resolution.1,
            self.iterations,
            self.seconds,
            1e3 * self.seconds / here.max(1) as f64,
            self.threads,
            self.rejected,
            self.written.join(", ")
        )
    }
}
