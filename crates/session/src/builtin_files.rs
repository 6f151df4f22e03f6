//! Built-in scenes that are scene files: shipped inside the binary (the repository's
//! `scenes/` files), written to a cache folder when asked for, and then loaded like any file,
//! so the loader, `-D` parameters, checkpoints and warnings work as for a file on disk.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// A scene file built into the binary.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinFile {
    /// The name `--scene` takes.
    pub name: &'static str,
    /// The file name it is written under (its extension picks the loader).
    pub file_name: &'static str,
    /// One line for `vcm scenes`.
    pub description: &'static str,
    /// The file's text.
    pub text: &'static str,
}

/// The built-in scene files.
pub const BUILTIN_FILES: &[BuiltinFile] = &[BuiltinFile {
    name: "cornell-fog",
    file_name: "cornell-fog.xml",
    description: "fog-filled Cornell box, spot light focused by a glass sphere (volumetric caustic); scenes/cornell-fog.xml",
    text: include_str!("../../../scenes/cornell-fog.xml"),
}];

/// The built-in scene file called `name`, if any.
pub fn find(name: &str) -> Option<&'static BuiltinFile> {
    BUILTIN_FILES.iter().find(|f| f.name == name)
}

impl BuiltinFile {
    /// Writes the file into `folder` (created if needed) unless an identical copy is there, and
    /// returns its path. The write goes to a temporary name first and is renamed into place,
    /// so processes writing it at once (MPI ranks) never read a partial file.
    pub fn materialise(&self, folder: &Path) -> Result<PathBuf> {
        let path = folder.join(self.file_name);
        if std::fs::read_to_string(&path).is_ok_and(|text| text == self.text) {
            return Ok(path);
        }
        std::fs::create_dir_all(folder)
            .with_context(|| format!("cannot create {} for the built-in scene '{}'", folder.display(), self.name))?;
        let temporary = folder.join(format!(".{}.{}", self.file_name, std::process::id()));
        std::fs::write(&temporary, self.text)
            .and_then(|()| std::fs::rename(&temporary, &path))
            .with_context(|| format!("cannot write the built-in scene '{}' to {}", self.name, path.display()))?;
        Ok(path)
    }
}

/// The folder built-in scene files are written to: `vcm-builtin-scenes` in the system's
/// temporary folder.
pub fn cache_folder() -> PathBuf {
    std::env::temp_dir().join("vcm-builtin-scenes")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_fog_box_is_the_repository_file() {
        let on_disk =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-fog.xml"))
                .unwrap();
        assert_eq!(find("cornell-fog").unwrap().text, on_disk);
        assert!(find("cornell-smoke").is_none());
    }

    #[test]
    fn materialising_writes_the_text_once_and_rewrites_a_changed_copy() {
        // A folder that does not exist yet: materialising creates it.
        let dir = testkit::TempDir::new("builtin-test");
        let folder = dir.join("scenes");
        let file = find("cornell-fog").unwrap();
        let path = file.materialise(&folder).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), file.text);
        std::fs::write(&path, "edited").unwrap();
        assert_eq!(file.materialise(&folder).unwrap(), path);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), file.text);
    }
}
