//! Radiance HDR (RGBE) and 8-bit sRGB PNG, encoded and decoded by the
//! `image` crate.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::Path;

use image::codecs::hdr::HdrEncoder;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder, ImageReader, Limits, Rgb};

use crate::srgb::{linear_to_srgb8, srgb_eotf};
use crate::{Image, ImageError, ImageFormat, MAX_PIXELS, WriteOptions};

/// Largest component written to an HDR file: RGBE's exponent byte cannot
/// hold 2^127 or more.
const RGBE_MAX: f32 = 1.0e38;
/// Pixels whose largest component is below this are written as zero: RGBE's
/// exponent byte cannot hold such small exponents.
const RGBE_MIN: f32 = 1.0e-37;

fn image_crate_format(format: ImageFormat) -> image::ImageFormat {
    match format {
        ImageFormat::Hdr => image::ImageFormat::Hdr,
        _ => image::ImageFormat::Png,
    }
}

/// Turns an `image` crate error into ours: I/O failures keep their
/// `io::Error`, everything else is a content problem.
fn convert(path: &Path, format: ImageFormat, error: image::ImageError, writing: bool) -> ImageError {
    match error {
        image::ImageError::IoError(cause) if writing => ImageError::write(path, cause),
        image::ImageError::IoError(cause) => ImageError::read(path, cause),
        other if writing => ImageError::encode(path, format, other.to_string()),
        other => ImageError::decode(path, format, other.to_string()),
    }
}

/// Makes a value representable in RGBE: NaN and negatives become 0, huge
/// values (including +∞) are clamped.
fn rgbe_sanitize(pixel: [f32; 3]) -> Rgb<f32> {
    let clean = pixel.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, RGBE_MAX) });
    if clean.iter().all(|&v| v < RGBE_MIN) { Rgb([0.0; 3]) } else { Rgb(clean) }
}

/// Writes `image` as Radiance RGBE. The image's shape must already have been
/// checked.
pub(crate) fn write_hdr(path: &Path, image: &Image) -> Result<(), ImageError> {
    let pixels: Vec<Rgb<f32>> = image.pixels.iter().map(|&p| rgbe_sanitize(p)).collect();
    let file = File::create(path).map_err(|e| ImageError::write(path, e))?;
    let mut out = BufWriter::new(file);
    HdrEncoder::new(&mut out)
        .encode(&pixels, image.width, image.height)
        .map_err(|e| convert(path, ImageFormat::Hdr, e, true))?;
    out.flush().map_err(|e| ImageError::write(path, e))
}

/// Writes `image` as 8-bit sRGB PNG after scaling by `2^exposure_stops`.
/// The image's shape must already have been checked.
pub(crate) fn write_png(path: &Path, image: &Image, options: &WriteOptions) -> Result<(), ImageError> {
    let too_large =
        || ImageError::encode(path, ImageFormat::Png, format!("{}x{} is too large for PNG", image.width, image.height));
    let width = u32::try_from(image.width).map_err(|_| too_large())?;
    let height = u32::try_from(image.height).map_err(|_| too_large())?;
    let scale = 2f64.powf(f64::from(options.exposure_stops));
    let bytes: Vec<u8> = image.pixels.iter().flatten().map(|&v| linear_to_srgb8(f64::from(v) * scale)).collect();
    let file = File::create(path).map_err(|e| ImageError::write(path, e))?;
    let mut out = BufWriter::new(file);
    PngEncoder::new(&mut out)
        .write_image(&bytes, width, height, ExtendedColorType::Rgb8)
        .map_err(|e| convert(path, ImageFormat::Png, e, true))?;
    out.flush().map_err(|e| ImageError::write(path, e))
}

/// Reads an HDR file (linear) or a PNG file (any bit depth and colour type;
/// sRGB decoded to linear, alpha dropped).
pub(crate) fn read(path: &Path, format: ImageFormat) -> Result<Image, ImageError> {
    let file = File::open(path).map_err(|e| ImageError::read(path, e))?;
    let mut reader = ImageReader::with_format(BufReader::new(file), image_crate_format(format));
    let mut limits = Limits::default();
    // Room for the decoder's buffer plus the float conversion of the largest
    // image we accept.
    limits.max_alloc = Some(MAX_PIXELS as u64 * 16);
    reader.limits(limits);
    let decoded = reader.decode().map_err(|e| convert(path, format, e, false))?;
    let (width, height) = (decoded.width() as usize, decoded.height() as usize);
    if width == 0 || height == 0 {
        return Err(ImageError::decode(path, format, format!("image is empty ({width}x{height})")));
    }
    if width.checked_mul(height).is_none_or(|n| n > MAX_PIXELS) {
        return Err(ImageError::decode(
            path,
            format,
            format!("dimensions {width}x{height} exceed the limit of {MAX_PIXELS} pixels"),
        ));
    }
    let float = decoded.into_rgb32f();
    let linearize = |v: f32| match format {
        ImageFormat::Png => srgb_eotf(f64::from(v)) as f32,
        _ => v,
    };
    let pixels = float.pixels().map(|p| p.0.map(linearize)).collect();
    Ok(Image { width, height, pixels })
}
