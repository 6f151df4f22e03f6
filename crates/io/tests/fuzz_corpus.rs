//! The fuzzing corpora and crash reproducers (`fuzz/corpus/<target>/`, `fuzz/artifacts/<target>/`)
//! as ordinary tests: every file must load into a sound result or give an error — no panic.
//! `docs/testing.md` says how the corpora were grown.

use std::path::{Path, PathBuf};

use scene::Scene;

fn files(target: &str) -> Vec<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    let mut files = Vec::new();
    for dir in ["corpus", "artifacts"] {
        if let Ok(entries) = std::fs::read_dir(root.join(dir).join(target)) {
            files.extend(entries.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.is_file()));
        }
    }
    files.sort();
    files
}

/// Runs `check` on every file of `target`'s corpus; there must be at least one.
fn each(target: &str, check: impl Fn(&Path, &[u8])) {
    let files = files(target);
    assert!(!files.is_empty(), "no corpus for {target}");
    for file in &files {
        let bytes = std::fs::read(file).unwrap();
        check(file, &bytes);
    }
}

#[test]
fn obj_corpus() {
    each("obj", |path, bytes| {
        if let Ok(mesh) = io::mesh::parse_obj(bytes, path) {
            assert!(mesh.validate().is_ok(), "{}", path.display());
        }
    });
}

#[test]
fn ply_corpus() {
    each("ply", |path, bytes| {
        if let Ok(mesh) = io::mesh::parse_ply(bytes, path) {
            assert!(mesh.validate().is_ok(), "{}", path.display());
        }
    });
}

#[test]
fn serialized_corpus() {
    each("serialized", |path, bytes| {
        let Some((index, bytes)) = bytes.split_first() else { return };
        if let Ok(mesh) = io::mesh::parse_serialized(bytes, u32::from(*index % 4), path) {
            assert!(mesh.validate().is_ok(), "{}", path.display());
        }
    });
}

/// Scene files are loaded from a copy with the loader's extension (corpus files are named by
/// their hash).
fn scene_corpus(
    target: &str,
    extension: &str,
    load: impl Fn(&Path) -> Result<scene::desc::SceneDescription, io::SceneError>,
) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("fuzz-corpus-{target}"));
    std::fs::create_dir_all(&dir).unwrap();
    each(target, |path, bytes| {
        let copy = dir.join(format!("scene.{extension}"));
        std::fs::write(&copy, bytes).unwrap();
        if let Ok(desc) = load(&copy) {
            let _ = Scene::from_description(&desc, Some((8, 8)));
        } else {
            // Errors must name the file.
            let message = load(&copy).unwrap_err().to_string();
            assert!(message.contains("scene."), "{}: {message}", path.display());
        }
    });
}

#[test]
fn mitsuba_corpus() {
    scene_corpus("mitsuba_xml", "xml", |p| io::mitsuba::load(p, &[]));
}

#[test]
fn pbrt_corpus() {
    scene_corpus("pbrt", "pbrt", io::pbrt::load);
}
