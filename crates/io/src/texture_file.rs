//! Image files read as textures: every common format, with the stored values kept apart from
//! their transfer function so that each scene format can apply its own rule.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use image::{ColorType, ImageReader, Limits};

use crate::srgb::srgb_eotf;
use crate::{Image, ImageError, MAX_PIXELS};

/// The extensions [`read_texture_file`] accepts (lower case).
pub const TEXTURE_EXTENSIONS: &[&str] =
    &["exr", "pfm", "hdr", "png", "jpg", "jpeg", "tga", "bmp", "tif", "tiff", "gif"];

/// How the values of a texture file are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoredValues {
    /// Integer codes of `bits` bits (8 or 16), divided by `2^bits − 1` into [0, 1]. Usually
    /// sRGB-encoded (JPEG, PNG, TGA, BMP, GIF, integer TIFF).
    Integer {
        /// Bits per channel.
        bits: u8,
    },
    /// Floating-point values, linear (EXR, PFM, HDR, float TIFF).
    Float,
}

/// A texture file's pixels as stored (integer codes scaled to [0, 1], not yet decoded).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureFile {
    /// The stored values (greyscale replicated to RGB, alpha dropped).
    pub image: Image,
    /// How they are stored.
    pub stored: StoredValues,
}

/// A transfer function from stored integer values in [0, 1] to linear values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TextureEncoding {
    /// The sRGB curve ([`srgb_eotf`]).
    Srgb,
    /// The identity (Mitsuba's `raw`, pbrt's `"linear"`).
    Linear,
    /// `linear = stored^gamma` (pbrt's `"gamma g"`).
    Gamma(f32),
}

impl TextureEncoding {
    /// The linear value of the stored value `v`.
    pub fn to_linear(self, v: f32) -> f32 {
        match self {
            TextureEncoding::Srgb => srgb_eotf(f64::from(v)) as f32,
            TextureEncoding::Linear => v,
            TextureEncoding::Gamma(g) => v.max(0.0).powf(g),
        }
    }
}

impl TextureFile {
    /// Linear RGB: integer formats decoded with `encoding`, float formats unchanged (they are
    /// linear whatever the scene says, as in Mitsuba and pbrt).
    pub fn linear(&self, encoding: TextureEncoding) -> Image {
        let mut image = self.image.clone();
        if matches!(self.stored, StoredValues::Integer { .. }) && encoding != TextureEncoding::Linear {
            for p in &mut image.pixels {
                *p = p.map(|v| encoding.to_linear(v));
            }
        }
        image
    }
}

/// Reads a texture image: EXR, PFM and HDR through this crate's readers; PNG (8 and 16 bit),
/// JPEG, TGA, BMP, TIFF and GIF through the `image` crate (the first frame of an animated
/// GIF). The format is chosen by the extension (case-insensitive, see
/// [`TEXTURE_EXTENSIONS`]).
///
/// Errors (never panics) on unknown extensions, unreadable or malformed files and images
/// larger than [`MAX_PIXELS`].
pub fn read_texture_file(path: &Path) -> Result<TextureFile, ImageError> {
    let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let float = |image| Ok(TextureFile { image, stored: StoredValues::Float });
    match extension.as_str() {
        "exr" | "pfm" | "hdr" => float(crate::read_image(path)?),
        e if TEXTURE_EXTENSIONS.contains(&e) => read_with_image_crate(path),
        _ => Err(ImageError::UnsupportedTexture { path: path.to_path_buf(), extension }),
    }
}

fn read_with_image_crate(path: &Path) -> Result<TextureFile, ImageError> {
    let fail = |message: String| ImageError::TextureDecode { path: path.to_path_buf(), message };
    crate::trace::opened(path);
    let file = File::open(path).map_err(|e| ImageError::Read { path: path.to_path_buf(), cause: e })?;
    let mut reader = ImageReader::new(BufReader::new(file))
        .with_guessed_format()
        .map_err(|e| ImageError::Read { path: path.to_path_buf(), cause: e })?;
    if reader.format().is_none() {
        reader.set_format(image::ImageFormat::from_path(path).map_err(|e| fail(e.to_string()))?);
    }
    let mut limits = Limits::default();
    limits.max_alloc = Some(MAX_PIXELS as u64 * 16);
    reader.limits(limits);
    let decoded = reader.decode().map_err(|e| match e {
        image::ImageError::IoError(cause) => ImageError::Read { path: path.to_path_buf(), cause },
        other => fail(other.to_string()),
    })?;
    let (width, height) = (decoded.width() as usize, decoded.height() as usize);
    if width == 0 || height == 0 {
        return Err(fail(format!("image is empty ({width}x{height})")));
    }
    if width.checked_mul(height).is_none_or(|n| n > MAX_PIXELS) {
        return Err(fail(format!("dimensions {width}x{height} exceed the limit of {MAX_PIXELS} pixels")));
    }
    let stored = match decoded.color() {
        ColorType::Rgb32F | ColorType::Rgba32F => StoredValues::Float,
        ColorType::L16 | ColorType::La16 | ColorType::Rgb16 | ColorType::Rgba16 => StoredValues::Integer { bits: 16 },
        _ => StoredValues::Integer { bits: 8 },
    };
    let pixels = decoded.into_rgb32f().pixels().map(|p| p.0).collect();
    Ok(TextureFile { image: Image { width, height, pixels }, stored })
}
