//! Mitsuba 3 XML scene loader.

use std::path::Path;

use scene::desc::SceneDescription;

use crate::scene_error::SceneError;

/// Loads a Mitsuba 3 XML scene. `defines` are `name=value` pairs that override the file's
/// `<default>` parameters (the `-D` option of the command line).
pub fn load(path: &Path, defines: &[(String, String)]) -> Result<SceneDescription, SceneError> {
    let _ = defines;
    Err(SceneError::in_file(path, "Mitsuba scenes are not supported yet"))
}
