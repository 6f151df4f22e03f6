//! pbrt-v4 scene loader.

use std::path::Path;

use scene::desc::SceneDescription;

use crate::scene_error::SceneError;

/// Loads a pbrt-v4 scene.
pub fn load(path: &Path) -> Result<SceneDescription, SceneError> {
    Err(SceneError::in_file(path, "pbrt scenes are not supported yet"))
}
