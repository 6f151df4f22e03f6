//! The layout of Mitsuba 3's render test suite: which scene files it holds and where their
//! references are. Nothing here loads a scene or an image.
//!
//! A suite directory holds one folder per group; a test scene is an XML file directly inside a
//! group folder, named `<name>_<integrator>.xml` (e.g. `test_arealight_path.xml`); its
//! references are `refs/<name>_ref_rgb.exr` (the image) and `refs/<name>_ref_rgb_var.exr` (the
//! variance of one sample, not of the mean) in the same group folder. Files in sub-folders
//! (fragments, includes) are not test scenes.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// One test scene of the suite.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Case {
    /// The group folder's name, e.g. `bsdf_spheres`.
    pub group: String,
    /// The scene's name without the integrator suffix, e.g. `test_arealight`.
    pub name: String,
    /// Mitsuba's integrator the references were rendered with (the file name's suffix).
    pub integrator: String,
    /// The scene file.
    pub scene: PathBuf,
    /// The reference image.
    pub reference: PathBuf,
    /// The reference's per-sample variance image.
    pub reference_variance: PathBuf,
}

impl Case {
    /// `group/name`, as the table shows it.
    pub fn label(&self) -> String {
        format!("{}/{}", self.group, self.name)
    }

    /// Whether both reference files exist.
    pub fn has_references(&self) -> bool {
        self.reference.is_file() && self.reference_variance.is_file()
    }
}

/// Lists the suite's test scenes in `dir`, sorted by group and file name. Errors when `dir`
/// cannot be read or holds no test scene.
pub fn discover(dir: &Path) -> Result<Vec<Case>> {
    let mut cases = Vec::new();
    for group_dir in sorted_entries(dir)? {
        if !group_dir.is_dir() {
            continue;
        }
        let group = file_name(&group_dir);
        for file in sorted_entries(&group_dir)? {
            if !(file.is_file() && file.extension().is_some_and(|e| e == "xml")) {
                continue;
            }
            let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let (name, integrator) = match stem.rsplit_once('_') {
                Some((name, integrator)) => (name.to_string(), integrator.to_string()),
                None => (stem.clone(), String::new()),
            };
            let refs = group_dir.join("refs");
            cases.push(Case {
                reference: refs.join(format!("{name}_ref_rgb.exr")),
                reference_variance: refs.join(format!("{name}_ref_rgb_var.exr")),
                group: group.clone(),
                name,
                integrator,
                scene: file,
            });
        }
    }
    anyhow::ensure!(
        !cases.is_empty(),
        "no test scene in '{}': expected <group>/<name>_<integrator>.xml (Mitsuba 3's tests/scenes folder)",
        dir.display()
    );
    Ok(cases)
}

fn sorted_entries(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir).with_context(|| format!("cannot read the directory '{}'", dir.display()))?;
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    Ok(paths)
}

fn file_name(path: &Path) -> String {
    path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_scenes_and_their_references() {
        let dir = testkit::TempDir::new("suite-discover");
        std::fs::create_dir_all(dir.join("b_group/refs")).unwrap();
        std::fs::create_dir_all(dir.join("b_group/fragments")).unwrap();
        std::fs::create_dir_all(dir.join("participating_media")).unwrap();
        for file in ["b_group/test_one_path.xml", "b_group/fragments/part.xml", "participating_media/fog_volpath.xml"] {
            std::fs::write(dir.join(file), "<scene/>").unwrap();
        }
        std::fs::write(dir.join("b_group/refs/test_one_ref_rgb.exr"), "").unwrap();
        let cases = discover(&dir).unwrap();
        assert_eq!(cases.len(), 2, "{cases:?}");
        assert_eq!((cases[0].label().as_str(), cases[0].integrator.as_str()), ("b_group/test_one", "path"));
        assert!(!cases[0].has_references());
        assert_eq!(cases[0].reference_variance, dir.join("b_group/refs/test_one_ref_rgb_var.exr"));
        assert_eq!(cases[1].label(), "participating_media/fog");
        assert!(discover(&dir.join("b_group/refs")).is_err());
    }
}
