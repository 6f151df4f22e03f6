//! The error type shared by every image reader and writer in this crate.

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::ImageFormat;

/// Everything that can go wrong while reading, writing or resampling an image.
///
/// Every variant that concerns a file names the file's path in its message, so
/// the message can be shown to a user as it is.
#[derive(Debug, Error)]
pub enum ImageError {
    /// The path's extension is not one of the supported formats.
    #[error(
        "unsupported image extension '.{extension}' in '{}' (expected .exr, .pfm, .hdr or .png)",
        .path.display()
    )]
    UnsupportedExtension {
        /// The offending path.
        path: PathBuf,
        /// The extension as written in the path, without the leading dot.
        extension: String,
    },

    /// The path has no extension, so the format cannot be chosen.
    #[error(
        "missing image extension in '{}' (expected .exr, .pfm, .hdr or .png)",
        .path.display()
    )]
    MissingExtension {
        /// The offending path.
        path: PathBuf,
    },

    /// The file could not be opened or read.
    #[error("cannot read '{}': {cause}", .path.display())]
    Read {
        /// The file being read.
        path: PathBuf,
        /// The underlying I/O error.
        cause: std::io::Error,
    },

    /// The file could not be created or written.
    #[error("cannot write '{}': {cause}", .path.display())]
    Write {
        /// The file being written.
        path: PathBuf,
        /// The underlying I/O error.
        cause: std::io::Error,
    },

    /// The file was read but its contents are not a valid image of the format.
    #[error("cannot decode {format} file '{}': {message}", .path.display())]
    Decode {
        /// The file being read.
        path: PathBuf,
        /// The format the file was read as.
        format: ImageFormat,
        /// What was wrong with the contents.
        message: String,
    },

    /// The image cannot be stored in the requested format (for example it
    /// is empty, or its pixel buffer does not match its dimensions).
    #[error("cannot encode {format} file '{}': {message}", .path.display())]
    Encode {
        /// The file being written.
        path: PathBuf,
        /// The format being written.
        format: ImageFormat,
        /// Why the image could not be encoded.
        message: String,
    },

    /// The path's extension is not one of the texture formats of
    /// [`read_texture_file`](crate::read_texture_file).
    #[error(
        "unsupported texture image extension '.{extension}' in '{}' (expected one of .{})",
        .path.display(), crate::TEXTURE_EXTENSIONS.join(", .")
    )]
    UnsupportedTexture {
        /// The offending path.
        path: PathBuf,
        /// The extension, lower case, without the dot.
        extension: String,
    },

    /// A texture file read through the `image` crate is malformed.
    #[error("cannot decode texture image '{}': {message}", .path.display())]
    TextureDecode {
        /// The file being read.
        path: PathBuf,
        /// What was wrong with the contents.
        message: String,
    },

    /// An in-memory image operation got an image or parameter it cannot
    /// handle (no file is involved).
    #[error("{operation}: {message}")]
    InvalidOperation {
        /// The operation that failed, e.g. `"downsample_box"`.
        operation: &'static str,
        /// What was wrong.
        message: String,
    },
}

impl ImageError {
    pub(crate) fn read(path: &Path, cause: std::io::Error) -> Self {
        Self::Read { path: path.to_path_buf(), cause }
    }

    pub(crate) fn write(path: &Path, cause: std::io::Error) -> Self {
        Self::Write { path: path.to_path_buf(), cause }
    }

    pub(crate) fn decode(path: &Path, format: ImageFormat, message: impl Into<String>) -> Self {
        Self::Decode { path: path.to_path_buf(), format, message: message.into() }
    }

    pub(crate) fn encode(path: &Path, format: ImageFormat, message: impl Into<String>) -> Self {
        Self::Encode { path: path.to_path_buf(), format, message: message.into() }
    }

    /// The path of the file involved, if any.
    pub fn path(&self) -> Option<&Path> {
        match self {
            Self::UnsupportedExtension { path, .. }
            | Self::MissingExtension { path }
            | Self::Read { path, .. }
            | Self::Write { path, .. }
            | Self::Decode { path, .. }
            | Self::Encode { path, .. }
            | Self::UnsupportedTexture { path, .. }
            | Self::TextureDecode { path, .. } => Some(path),
            Self::InvalidOperation { .. } => None,
        }
    }
}
