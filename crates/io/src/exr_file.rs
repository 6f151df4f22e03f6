//! OpenEXR reading and writing through the `exr` crate.
//!
//! Files are written as a single layer of 32-bit float `R`, `G`, `B` channels, RLE-compressed
//! scanlines (lossless, so values round-trip bit for bit). ZIP, the other common choice, saves
//! little on rendered floats, whose low mantissa bits are noise, at a large cost in time: on a
//! 512² render of scene 1 (`pt`, 1 iteration) the file was 2.60 MB with ZIP, 2.88 MB with RLE
//! and 3.15 MB uncompressed, and writing it with ZIP took 606 M more instructions than with RLE
//! (callgrind, whole process); on a 64-iteration `vcm` render at 256², 733, 755 and 791 kB
//! (measured 2026-11-28).
//!
//! Reading accepts any sample type (f16, f32, u32), takes the first layer that has `R`, `G` and
//! `B` channels at its largest resolution level, and ignores alpha.

use std::fs::File;
use std::io::{BufReader, BufWriter, Seek, SeekFrom, Write};
use std::path::Path;

use exr::prelude::{Compression, Encoding, ReadChannels, ReadLayers, SpecificChannels, Vec2, WritableImage};

use crate::{Image, ImageError, ImageFormat, MAX_PIXELS};

/// Turns an `exr` error into ours: I/O failures keep their `io::Error`,
/// everything else is a content problem.
fn convert(path: &Path, error: exr::error::Error, writing: bool) -> ImageError {
    match error {
        exr::error::Error::Io(cause) if writing => ImageError::write(path, cause),
        exr::error::Error::Io(cause) => ImageError::read(path, cause),
        other if writing => ImageError::encode(path, ImageFormat::Exr, other.to_string()),
        other => ImageError::decode(path, ImageFormat::Exr, other.to_string()),
    }
}

/// Writes `image` as float32 RGB. The image's shape must already have been
/// checked.
pub(crate) fn write(path: &Path, image: &Image) -> Result<(), ImageError> {
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b] = image.pixels[y * image.width + x];
        (r, g, b)
    });
    let exr_image = exr::image::Image::from_encoded_channels(
        (image.width, image.height),
        Encoding { compression: Compression::RLE, ..Encoding::SMALL_LOSSLESS },
        channels,
    );
    let file = File::create(path).map_err(|e| ImageError::write(path, e))?;
    let mut out = BufWriter::new(file);
    exr_image.write().to_buffered(&mut out).map_err(|e| convert(path, e, true))?;
    out.flush().map_err(|e| ImageError::write(path, e))
}

/// Reads the first RGB layer as linear float RGB.
pub(crate) fn read(path: &Path) -> Result<Image, ImageError> {
    let file = File::open(path).map_err(|e| ImageError::read(path, e))?;
    let mut input = BufReader::new(file);

    // Check the declared sizes before the decoder allocates anything.
    let meta = exr::meta::MetaData::read_from_buffered(&mut input, false).map_err(|e| convert(path, e, false))?;
    for header in meta.headers.iter() {
        let Vec2(w, h) = header.layer_size;
        if w.checked_mul(h).is_none_or(|n| n > MAX_PIXELS) {
            return Err(ImageError::decode(
                path,
                ImageFormat::Exr,
                format!("layer size {w}x{h} exceeds the limit of {MAX_PIXELS} pixels"),
            ));
        }
    }
    input.seek(SeekFrom::Start(0)).map_err(|e| ImageError::read(path, e))?;

    let decoded = exr::image::read::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size: Vec2<usize>, _| Image::new(size.width(), size.height()),
            |image: &mut Image, position: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
                let index = position.y() * image.width + position.x();
                image.pixels[index] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(input)
        .map_err(|e| convert(path, e, false))?;
    let image = decoded.layer_data.channel_data.pixels;
    if image.width == 0 || image.height == 0 {
        return Err(ImageError::decode(
            path,
            ImageFormat::Exr,
            format!("image is empty ({}x{})", image.width, image.height),
        ));
    }
    Ok(image)
}
