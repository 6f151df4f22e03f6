//! Where Mitsuba looks for the files a scene names (meshes, textures, `<include>`s).
//!
//! Mitsuba 3 keeps one list of directories per load: the scene file's directory, with every
//! `<path value="…"/>` *prepended* as it is read (a relative value is taken relative to the
//! file that declares it). So the most recently declared `<path>` is searched first and the
//! scene file's directory last. `<include>`s are resolved while the file is read and see the
//! `<path>`s declared before them; meshes and textures are resolved after the whole file has
//! been read and see all of them. We search the same list, then — our extension, which
//! Mitsuba does not have — the directory of the file that contains the reference (for
//! includes in a sub-directory that name their neighbours). The current working directory is
//! never searched, so a scene loads the same from anywhere.

use std::path::{Path, PathBuf};

/// The directories searched for relative file names, in search order.
#[derive(Clone, Debug, Default)]
pub(crate) struct SearchPath {
    /// `<path>` directories, most recently declared first.
    declared: Vec<PathBuf>,
    /// The main scene file's directory.
    main_dir: PathBuf,
    /// `<path>`s whose directory does not exist: `(location, directory)`, mentioned when a
    /// file is not found.
    missing: Vec<(String, PathBuf)>,
}

impl SearchPath {
    /// A search path with only the scene file's directory.
    pub fn new(main_file: &Path) -> Self {
        Self {
            declared: Vec::new(),
            main_dir: main_file.parent().map(Path::to_path_buf).unwrap_or_default(),
            missing: Vec::new(),
        }
    }

    /// Adds a `<path>` directory (searched before every directory added earlier).
    pub fn declare(&mut self, dir: PathBuf) {
        self.declared.insert(0, dir);
    }

    /// Records a `<path>` (declared at `location`) whose directory does not exist. Mitsuba
    /// stops there; we go on (a scene copied without its shared directory may not need it)
    /// and name it if a file is then not found.
    pub fn declare_missing(&mut self, location: String, dir: PathBuf) {
        self.missing.push((location, dir));
    }

    /// The candidates for `filename` named in `referencing_file`, in search order, without
    /// duplicates; an absolute `filename` is its only candidate.
    pub fn candidates(&self, filename: &str, referencing_file: &Path) -> Vec<PathBuf> {
        let name = Path::new(filename);
        if name.is_absolute() {
            return vec![name.to_path_buf()];
        }
        let here = referencing_file.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut out: Vec<PathBuf> = Vec::new();
        for dir in self.declared.iter().chain([&self.main_dir, &here]) {
            let candidate = dir.join(name);
            if !out.contains(&candidate) {
                out.push(candidate);
            }
        }
        out
    }

    /// The first existing file among the candidates, or an error message listing every path
    /// searched.
    pub fn find(&self, filename: &str, referencing_file: &Path) -> Result<PathBuf, String> {
        let candidates = self.candidates(filename, referencing_file);
        candidates.iter().find(|p| p.is_file()).cloned().ok_or_else(|| {
            let looked: Vec<String> = candidates.iter().map(|p| format!("'{}'", p.display())).collect();
            let mut message = format!("file '{filename}' not found (searched {})", looked.join(", "));
            for (location, dir) in &self.missing {
                message.push_str(&format!("; the <path> at {location}, '{}', does not exist", dir.display()));
            }
            message
        })
    }
}
