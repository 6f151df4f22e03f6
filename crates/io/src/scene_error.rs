//! The error type of the scene-file loaders and mesh readers.

use std::fmt;
use std::path::{Path, PathBuf};

/// A problem with a scene or mesh file: the file, the position in it when known, and what was
/// wrong or expected. Displayed as `file:line:column: message` so that editors can jump to it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// The file the problem is in.
    pub file: PathBuf,
    /// 1-based line, when known.
    pub line: Option<u32>,
    /// 1-based column, when known.
    pub column: Option<u32>,
    /// What was wrong, naming the element or attribute.
    pub message: String,
}

impl SceneError {
    /// An error at a position in `file`.
    pub fn at(file: &Path, line: u32, column: u32, message: impl Into<String>) -> Self {
        Self { file: file.to_path_buf(), line: Some(line), column: Some(column), message: message.into() }
    }

    /// An error at a line of `file` (column unknown).
    pub fn at_line(file: &Path, line: u32, message: impl Into<String>) -> Self {
        Self { file: file.to_path_buf(), line: Some(line), column: None, message: message.into() }
    }

    /// An error concerning `file` as a whole.
    pub fn in_file(file: &Path, message: impl Into<String>) -> Self {
        Self { file: file.to_path_buf(), line: None, column: None, message: message.into() }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(column) = self.column {
                write!(f, ":{column}")?;
            }
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SceneError {}
