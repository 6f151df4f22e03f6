//! Fuzz target: the scene loader on arbitrary bytes (written to a file, since loaders resolve
//! includes and meshes relative to it) must give a description or an error, never panic; a
//! description must build into a scene or give an error.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("vcm-fuzz-pbrt-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("scene.pbrt");
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(desc) = io::pbrt::load(&path) {
        let _ = scene::Scene::from_description(&desc, Some((8, 8)));
    }
});
