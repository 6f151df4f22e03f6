//! Image file input and output for linear HDR radiance images.
//!
//! This crate owns the on-disk image formats of the renderer:
//!
//! - **EXR**: 32-bit float RGB, lossless; the canonical output format.
//! - **PFM**: portable float map, little-endian RGB on write; both byte
//!   orders and greyscale on read. Rows are stored bottom to top.
//! - **HDR**: Radiance RGBE (8-bit mantissas with a shared exponent).
//! - **PNG**: 8-bit sRGB for previews, with an exposure adjustment.
//!
//! The format is chosen from the file extension (case-insensitive) by
//! [`ImageFormat::from_path`]. All errors are [`ImageError`]s whose messages
//! name the file; malformed or truncated input gives an error, never a panic.
//!
//! Textures are read by [`read_texture_file`] in more formats (JPEG, TGA, BMP,
//! TIFF, GIF and 16-bit PNG besides the above), keeping the stored values apart
//! from their transfer function ([`TextureFile::linear`]). Scene files are
//! loaded by [`load_scene`] / [`load_scene_with`] ([`mitsuba`], [`pbrt`]).

mod curves;
mod cylinder;
mod error;
mod exr_file;
mod gz;
mod linear_image;
mod loop_subdivision;
pub mod nanovdb;
mod options;
mod pfm;
mod sdfgrid;
mod srgb;
mod texture_file;
mod via_image;
mod volfile;

use std::path::Path;

pub mod mesh;
pub mod mitsuba;
pub mod pbrt;
mod scene_error;
mod trace;

pub use crate::error::ImageError;
pub use crate::linear_image::{Image, MAX_PIXELS, downsample_box};
pub use crate::options::{LoadOptions, LoadedScene, RenderSettings};
pub use crate::scene_error::SceneError;
pub use crate::srgb::{linear_to_srgb8, srgb_eotf, srgb_oetf, srgb8_to_linear};
pub use crate::texture_file::{StoredValues, TEXTURE_EXTENSIONS, TextureEncoding, TextureFile, read_texture_file};
pub use crate::trace::load_scene_traced;

/// An image file format supported by [`write_image`] and [`read_image`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ImageFormat {
    /// OpenEXR (`.exr`), float32 RGB.
    Exr,
    /// Portable float map (`.pfm`).
    Pfm,
    /// Radiance RGBE (`.hdr`).
    Hdr,
    /// 8-bit sRGB PNG (`.png`).
    Png,
}

impl ImageFormat {
    /// Picks the format from the extension of `path`, ignoring case.
    ///
    /// Errors with [`ImageError::UnsupportedExtension`] or
    /// [`ImageError::MissingExtension`].
    pub fn from_path(path: &Path) -> Result<Self, ImageError> {
        let Some(extension) = path.extension() else {
            return Err(ImageError::MissingExtension { path: path.to_path_buf() });
        };
        let extension = extension.to_string_lossy();
        match extension.to_ascii_lowercase().as_str() {
            "exr" => Ok(Self::Exr),
            "pfm" => Ok(Self::Pfm),
            "hdr" => Ok(Self::Hdr),
            "png" => Ok(Self::Png),
            _ => Err(ImageError::UnsupportedExtension { path: path.to_path_buf(), extension: extension.into_owned() }),
        }
    }

    /// The canonical lower-case extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Exr => "exr",
            Self::Pfm => "pfm",
            Self::Hdr => "hdr",
            Self::Png => "png",
        }
    }
}

impl std::fmt::Display for ImageFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Exr => "EXR",
            Self::Pfm => "PFM",
            Self::Hdr => "HDR",
            Self::Png => "PNG",
        })
    }
}

/// Options for [`write_image`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WriteOptions {
    /// Exposure adjustment in stops, applied to PNG output only: values are
    /// multiplied by `2^exposure_stops` before sRGB encoding. The HDR formats
    /// always store the radiance unchanged.
    pub exposure_stops: f32,
}

/// Writes `image` to `path` in the format given by the path's extension.
///
/// - EXR and PFM store every `f32` bit for bit (including NaN and ±∞).
/// - HDR (RGBE) keeps about 8 bits of relative precision per pixel; NaN and
///   negative values become 0, and values beyond RGBE's range are clamped or
///   flushed to 0.
/// - PNG scales by `2^exposure_stops`, clamps to `[0, 1]` (NaN → 0) and
///   applies the sRGB transfer function with rounding to 8 bits.
///
/// Errors if the extension is unsupported, the image is empty or its pixel
/// buffer does not match `width * height`, or the file cannot be written.
/// The parent directory is not created. A failed write may leave a partial
/// file behind.
pub fn write_image(path: &Path, image: &Image, options: &WriteOptions) -> Result<(), ImageError> {
    let format = ImageFormat::from_path(path)?;
    image.check_shape().map_err(|message| ImageError::encode(path, format, message))?;
    match format {
        ImageFormat::Exr => exr_file::write(path, image),
        ImageFormat::Pfm => pfm::write(path, image),
        ImageFormat::Hdr => via_image::write_hdr(path, image),
        ImageFormat::Png => via_image::write_png(path, image, options),
    }
}

/// Reads the image at `path` in the format given by the path's extension,
/// returning linear RGB.
///
/// PNG input is decoded from sRGB to linear (any bit depth; alpha is
/// dropped). Greyscale PFM is replicated to RGB. EXR input takes the first
/// layer with `R`, `G`, `B` channels.
///
/// Errors (never panics) on unsupported extensions, unreadable files,
/// malformed or truncated contents, and images larger than [`MAX_PIXELS`].
pub fn read_image(path: &Path) -> Result<Image, ImageError> {
    trace::opened(path);
    match ImageFormat::from_path(path)? {
        ImageFormat::Exr => exr_file::read(path),
        ImageFormat::Pfm => pfm::read(path),
        format @ (ImageFormat::Hdr | ImageFormat::Png) => via_image::read(path, format),
    }
}

/// Loads a scene file, choosing the format by extension: `.xml` (Mitsuba 3) or `.pbrt`
/// (pbrt-v4, also gzip-compressed `.pbrt.gz`). `defines` override Mitsuba `<default>`
/// parameters; a `.pbrt` file with defines is an error. Strict: see [`load_scene_with`].
pub fn load_scene(path: &Path, defines: &[(String, String)]) -> Result<scene::desc::SceneDescription, SceneError> {
    load_scene_with(path, defines, &LoadOptions::default()).map(|loaded| loaded.description)
}

/// Loads a scene file as [`load_scene`] does, with `options`, and returns the file's
/// rendering settings too. Without [`LoadOptions::permissive`], parameters that would change
/// the image and are not supported are errors.
pub fn load_scene_with(
    path: &Path,
    defines: &[(String, String)],
    options: &LoadOptions,
) -> Result<LoadedScene, SceneError> {
    let name = path.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let extension = name.strip_suffix(".gz").unwrap_or(&name).rsplit_once('.').map(|(_, e)| e);
    match extension {
        Some("xml") => mitsuba::load_with(path, defines, options),
        Some("pbrt") => {
            if let Some((name, _)) = defines.first() {
                return Err(SceneError::in_file(path, format!("-D {name}=…: pbrt scenes have no parameters")));
            }
            pbrt::load_with(path, options)
        }
        _ => Err(SceneError::in_file(
            path,
            "unknown scene format (expected a .xml Mitsuba 3 or a .pbrt / .pbrt.gz pbrt-v4 file)",
        )),
    }
}
