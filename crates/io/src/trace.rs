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

/// [`crate::load_scene_with`], also returning every file the load read, in the order first read,
/// each once, spelled as the loader opened it (relative paths stay relative to the working
/// directory). The scene file itself comes first.
pub fn load_scene_traced(
    path: &Path,
    defines: &[(String, String)],
    options: &crate::LoadOptions,
) -> Result<(crate::LoadedScene, Vec<PathBuf>), SceneError> {
    let recording = Recording;
    OPENED.with(|o| *o.borrow_mut() = Some(Vec::new()));
    let scene = crate::load_scene_with(path, defines, options);
    let files = OPENED.with(|o| o.borrow_mut().take()).unwrap_or_default();
    drop(recording);
    Ok((scene?, files))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Image, WriteOptions, write_image};
    use testkit::TempDir;

    fn scratch(name: &str) -> TempDir {
        TempDir::new(&format!("trace-test-{name}"))
    }

    fn write_pixel_image(path: &Path) {
        let image = Image { width: 1, height: 1, pixels: vec![[0.5, 0.5, 0.5]] };
        write_image(path, &image, &WriteOptions::default()).unwrap();
    }

    #[test]
    fn a_mitsuba_load_lists_every_file_it_read_once() {
        let dir = scratch("mitsuba");
        let main = dir.join("main.xml");
        std::fs::write(
            &main,
            r#"<scene version="3.0.0">
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
  <include filename="parts.xml"/>
  <shape type="obj"><string name="filename" value="quad.obj"/><ref id="textured"/></shape>
  <shape type="obj"><string name="filename" value="quad.obj"/><ref id="textured"/></shape>
  <emitter type="envmap"><string name="filename" value="env.exr"/></emitter>
</scene>"#,
        )
        .unwrap();
        std::fs::write(
            dir.join("parts.xml"),
            r#"<scene version="3.0.0"><bsdf type="diffuse" id="textured"><texture type="bitmap" name="reflectance">
  <string name="filename" value="tex.png"/></texture></bsdf></scene>"#,
        )
        .unwrap();
        std::fs::write(dir.join("quad.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n").unwrap();
        write_pixel_image(&dir.join("tex.png"));
        write_pixel_image(&dir.join("env.exr"));
        let (_, files) = load_scene_traced(&main, &[], &Default::default()).unwrap();
        let names: Vec<String> =
            files.iter().map(|f| f.strip_prefix(&dir).unwrap_or(f).display().to_string()).collect();
        assert_eq!(names, ["main.xml", "parts.xml", "tex.png", "quad.obj", "env.exr"]);
        // Outside a traced load nothing is recorded.
        crate::load_scene(&main, &[]).unwrap();
        assert!(OPENED.with(|o| o.borrow().is_none()));
    }

    #[test]
    fn a_pbrt_load_lists_its_includes_and_images() {
        let dir = scratch("pbrt");
        let main = dir.join("main.pbrt");
        std::fs::write(
            &main,
            "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\nInclude \"part.pbrt\"\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("part.pbrt"),
            "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"tex.pfm\"\n\
             Material \"diffuse\" \"texture reflectance\" \"t\"\n\
             Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"integer indices\" [0 1 2]\n",
        )
        .unwrap();
        write_pixel_image(&dir.join("tex.pfm"));
        let (_, files) = load_scene_traced(&main, &[], &Default::default()).unwrap();
        assert_eq!(files, [main.clone(), dir.join("part.pbrt"), dir.join("tex.pfm")]);
        // A failed load still ends the recording.
        assert!(load_scene_traced(&dir.join("absent.pbrt"), &[], &Default::default()).is_err());
        assert!(OPENED.with(|o| o.borrow().is_none()));
    }
}
