//! Scratch directories for tests that are removed when the test is done.
//!
//! [`TempDir::new`] creates a fresh, empty directory `vcm-{prefix}-{pid}-{n}` under
//! [`std::env::temp_dir`]; dropping the guard removes it with everything in it. Set the
//! environment variable [`KEEP_ENV`] (`VCM_KEEP_TEST_DIRS=1 cargo test ...`) to keep the
//! directories instead, for instance to look at the files a failing test wrote: each kept
//! directory's path is printed to stderr when its guard is dropped.

use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The environment variable that, when set (to anything), keeps the directories of dropped
/// [`TempDir`] guards.
pub const KEEP_ENV: &str = "VCM_KEEP_TEST_DIRS";

/// Numbers the directories of this process, so that every [`TempDir`] is distinct.
static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A fresh, empty scratch directory under [`std::env::temp_dir`], removed (with its contents)
/// when the guard is dropped, unless [`KEEP_ENV`] is set.
///
/// Keep the guard alive for as long as the test uses paths into the directory: bind it with
/// `let dir = TempDir::new(..)` (not `let _ = ..`, which drops it at once), and return it
/// beside any path a helper hands back.
///
/// ```
/// let dir = testkit::TempDir::new("doc-example");
/// std::fs::write(dir.join("scene.xml"), "<scene/>").unwrap();
/// assert!(dir.join("scene.xml").is_file());
/// let path = dir.path().to_path_buf();
/// drop(dir);
/// assert!(std::env::var_os(testkit::temp_dir::KEEP_ENV).is_some() || !path.exists());
/// ```
#[derive(Debug)]
pub struct TempDir {
    path: PathBuf,
}

impl TempDir {
    /// Creates the directory `vcm-{prefix}-{pid}-{n}` under [`std::env::temp_dir`], where `n`
    /// counts the guards of this process; a stale directory of that name (left by an earlier
    /// process with the same id) is removed first.
    ///
    /// # Panics
    ///
    /// If the directory cannot be created.
    pub fn new(prefix: &str) -> TempDir {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("vcm-{prefix}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        if let Err(e) = std::fs::create_dir_all(&path) {
            panic!("cannot create the test directory {}: {e}", path.display());
        }
        TempDir { path }
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Deref for TempDir {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempDir {
    /// Removes the directory and its contents, ignoring errors; keeps it (and prints its path)
    /// if [`KEEP_ENV`] is set.
    fn drop(&mut self) {
        if std::env::var_os(KEEP_ENV).is_some() {
            eprintln!("{KEEP_ENV}: keeping {}", self.path.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keeping() -> bool {
        std::env::var_os(KEEP_ENV).is_some()
    }

    #[test]
    fn the_directory_lives_as_long_as_the_guard() {
        let dir = TempDir::new("testkit-lifetime");
        assert!(dir.path().is_dir());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "fresh directories are empty");
        std::fs::create_dir(dir.join("sub")).unwrap();
        std::fs::write(dir.join("sub/file.txt"), "contents").unwrap();
        let path = dir.path().to_path_buf();
        assert!(path.file_name().unwrap().to_str().unwrap().starts_with("vcm-testkit-lifetime-"));
        drop(dir);
        assert_eq!(path.exists(), keeping(), "{}", path.display());
    }

    #[test]
    fn two_guards_have_different_directories() {
        let (a, b) = (TempDir::new("testkit-distinct"), TempDir::new("testkit-distinct"));
        assert_ne!(a.path(), b.path());
        assert!(a.is_dir() && b.is_dir());
    }
}
