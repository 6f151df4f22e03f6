//! Which files a scene load read: [`load_scene_traced`] returns them with the scene, so a
//! caller can fingerprint everything the scene came from (the file, its includes, meshes,
//! textures, environment maps, spectrum files). The loaders call [`opened`] at each read; it
//! records only inside a traced load on the same thread (the loaders are single-threaded).

use std::cell::RefCell;
use std::path::{Path, PathBuf};

use crate::SceneError;

thread_local! {
    static OPENED: RefCell<Option<Vec<PathBuf>>> = const { RefCell::new(None) };
}

/// Records that `path` is read, when a traced load is running on this thread.
pub(crate) fn opened(path: &Path) {
    OPENED.with(|o| {
        if let Some(list) = o.borrow_mut().as_mut()
            && !list.iter().any(|p| p == path)
        {
            list.push(path.to_path_buf());
        }
    });
}

/// Ends the recording even when the load unwinds.
struct Recording;

impl Drop for Recording {
    fn drop(&mut self) {
        OPENED.with(|o| o.borrow_mut().take());
    }
}

/// [`crate::load_scene`], also returning every file the load read, in the order first read,
/// each once, spelled as the loader opened it (relative paths stay relative to the working
/// directory). The scene file itself comes first.
pub fn load_scene_traced(
    path: &Path,
    defines: &[(String, String)],
) -> Result<(scene::desc::SceneDescription, Vec<PathBuf>), SceneError> {
    let recording = Recording;
    OPENED.with(|o| *o.borrow_mut() = Some(Vec::new()));
    let scene = crate::load_scene(path, defines);
    let files = OPENED.with(|o| o.borrow_mut().take()).unwrap_or_default();
    drop(recording);
    Ok((scene?, files))
}
