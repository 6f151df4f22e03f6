//! Where a scene comes from (a built-in Cornell box or a scene file with its parameters), and
//! loading it with the defaults its source implies.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use scene::Scene;
use scene::cornell;

use crate::fingerprint::Fingerprint;

/// Where a scene comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    /// A built-in Cornell box, by its bit mask (see `vcm scenes`).
    Builtin(u32),
    /// A scene file with its `-D NAME=VALUE` parameters, as given.
    File(PathBuf, Vec<String>),
}

/// Resolves a scene name as the command line gives it: a built-in id or name, a built-in scene
/// file ([`crate::builtin_files`], written to [`crate::builtin_files::cache_folder`] and then a
/// file source), or a scene file (a name with an extension or a `/`). `defines` are
/// `NAME=VALUE` strings; they apply to scene files only.
pub fn scene_source(name: &str, defines: &[String]) -> Result<SceneSource> {
    if let Some(file) = crate::builtin_files::find(name) {
        let path = file.materialise(&crate::builtin_files::cache_folder())?;
        return Ok(SceneSource::File(path, defines.to_vec()));
    }
    if let Some(s) = cornell::builtin_scenes().find(|s| s.name == name || s.id.to_string() == name) {
        if let Some(define) = defines.first() {
            bail!("-D {define}: parameters apply to scene files, not to the built-in scene '{name}'");
        }
        return Ok(SceneSource::Builtin(s.mask));
    }
    let valid: Vec<String> = cornell::builtin_scenes()
        .map(|s| format!("{} ({})", s.id, s.name))
        .chain(crate::builtin_files::BUILTIN_FILES.iter().map(|f| f.name.to_string()))
        .collect();
    if Path::new(name).extension().is_some() || name.contains('/') {
        if !Path::new(name).exists() {
            bail!("scene file '{name}' does not exist (built-in scenes: {})", valid.join(", "));
        }
        return Ok(SceneSource::File(PathBuf::from(name), defines.to_vec()));
    }
    bail!("unknown scene '{name}'; valid scenes: {}", valid.join(", "))
}

/// A loaded scene with the defaults its source implies and what it was built from.
pub struct LoadedScene {
    /// The scene, ready to render.
    pub scene: Scene,
    /// Path length from the file's integrator (`None`: a built-in scene).
    pub file_max_length: Option<u32>,
    /// Samples per pixel the file asks for (its sampler), if any.
    pub file_samples: Option<u64>,
    /// The first bounce of Mitsuba 3's Russian roulette the file asks for
    /// ([`io::RenderSettings::rr_depth`]: every Mitsuba file has one, default 5; `None` for
    /// pbrt files and built-in scenes).
    pub file_rr_depth: Option<u32>,
    /// What the scene was built from (checkpoints record it).
    pub fingerprint: Fingerprint,
    /// Loader warnings (skipped optional attributes) for the user.
    pub warnings: Vec<String>,
    /// One line on what was loaded and how long it took (scene files only), for progress
    /// output.
    pub loaded: Option<String>,
}

/// Path length used when a scene file asks for unlimited paths (Russian roulette ends them
/// long before).
pub const UNLIMITED_PATH_LENGTH: u32 = 100;

/// Loads or builds the scene; `resolution` (pixels) overrides the file's film, built-in scenes
/// default to 512×512. `permissive` turns unsupported parameters that would change the image
/// from errors into warnings.
pub fn load_scene(source: &SceneSource, resolution: Option<(u32, u32)>, permissive: bool) -> Result<LoadedScene> {
    match source {
        SceneSource::Builtin(mask) => {
            let (width, height) = resolution.unwrap_or((512, 512));
            let scene = cornell::build(*mask, width, height)
                .with_context(|| format!("invalid scene mask {mask}: expected 0-{}", cornell::MAX_MASK))?;
            Ok(LoadedScene {
                scene,
                file_max_length: None,
                file_samples: None,
                file_rr_depth: None,
                fingerprint: Fingerprint::builtin(*mask, (width, height)),
                warnings: Vec::new(),
                loaded: None,
            })
        }
        SceneSource::File(path, defines) => {
            let pairs = parse_defines(defines)?;
            let start = Instant::now();
            let options = io::LoadOptions { permissive };
            let (loaded, files) = io::load_scene_traced(path, &pairs, &options).map_err(|e| {
                let message = e.to_string().replace("a permissive load would continue", "--permissive would continue");
                anyhow::anyhow!(message)
            })?;
            let file_samples = loaded.settings.samples_per_pixel.map(u64::from);
            let file_rr_depth = loaded.settings.rr_depth;
            let desc = loaded.description;
            let (scene, report) =
                Scene::from_description(&desc, resolution).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            let loaded = format!(
                "loaded {} in {:.2} s: {} triangles, {} analytic shapes, {} lights{}",
                path.display(),
                start.elapsed().as_secs_f64(),
                report.triangles,
                report.analytic_shapes,
                report.lights,
                if report.degenerate_triangles > 0 {
                    format!(", {} degenerate triangles dropped", report.degenerate_triangles)
                } else {
                    String::new()
                }
            );
            Ok(LoadedScene {
                scene,
                file_max_length: Some(desc.max_path_length.unwrap_or(UNLIMITED_PATH_LENGTH)),
                file_samples,
                file_rr_depth,
                fingerprint: Fingerprint::of_files(&files, defines)?,
                warnings: desc.warnings.clone(),
                loaded: Some(loaded),
            })
        }
    }
}

/// Splits `NAME=VALUE` parameters.
fn parse_defines(defines: &[String]) -> Result<Vec<(String, String)>> {
    defines
        .iter()
        .map(|d| match d.split_once('=') {
            Some((name, value)) if !name.is_empty() => Ok((name.to_string(), value.to_string())),
            _ => bail!("-D '{d}': expected NAME=VALUE"),
        })
        .collect()
}
