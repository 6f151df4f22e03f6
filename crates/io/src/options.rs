//! What a caller chooses about loading a scene, and what a scene file says about rendering
//! besides the scene itself.

use scene::desc::SceneDescription;

/// Options of [`load_scene_with`](crate::load_scene_with) and the per-format loaders.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// When a file asks for something that would change the image and that we cannot render
    /// (e.g. Mitsuba's `hide_emitters`, a spot light's `texture`, pbrt's EWA texture
    /// filtering), load the scene anyway and report it in
    /// [`SceneDescription::warnings`] instead of failing. Default `false`: such files are
    /// errors naming file, line, column and the parameter.
    pub permissive: bool,
}

/// Rendering settings a scene file gives besides the scene (`None`/`false` when absent).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderSettings {
    /// Samples per pixel asked for by the file: Mitsuba's `<sampler>` `sample_count` (in the
    /// `<sensor>` or at the top level), pbrt's `Sampler` `pixelsamples`.
    pub samples_per_pixel: Option<u32>,
    /// Mitsuba's integrator `hide_emitters`: emitters seen directly by the camera are black.
    /// Not supported by the renderer: `true` only reaches the caller from a permissive load.
    pub hide_emitters: bool,
    /// Mitsuba's integrator `rr_depth` (`path`, `volpath`, `volpathmis` and the other path
    /// integrators, also inside `aov`/`moment`): the first bounce (a scattering vertex; the first
    /// surface hit is bounce 1) at which Mitsuba 3's Russian roulette may end a path, with
    /// survival probability `min(max throughput component, 0.95)`. A Mitsuba file always has
    /// one: Mitsuba's default 5 when its integrator does not say or it has none. `None` for
    /// pbrt files (pbrt-v4's roulette is another rule).
    pub rr_depth: Option<u32>,
}

/// A loaded scene and the file's rendering settings.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene.
    pub description: SceneDescription,
    /// Settings the file gives for rendering it.
    pub settings: RenderSettings,
}

/// Reports something the renderer cannot reproduce: an error, or with
/// [`LoadOptions::permissive`] a warning (the error's text and what is done instead).
pub(crate) fn unsupported(
    permissive: bool,
    warnings: &mut Vec<String>,
    error: crate::SceneError,
    instead: &str,
) -> Result<(), crate::SceneError> {
    if permissive {
        warnings.push(format!("{error}; {instead} (permissive load)"));
        Ok(())
    } else {
        let message = format!("{} (it changes the image; a permissive load would continue: {instead})", error.message);
        Err(crate::SceneError { message, ..error })
    }
}
