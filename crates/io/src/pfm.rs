//! Portable float map (PFM) reading and writing.
//!
//! Layout: an ASCII header `PF` (RGB) or `Pf` (greyscale), the width and
//! height, and a scale whose sign gives the byte order (negative:
//! little-endian, positive: big-endian), each separated by whitespace and
//! the scale followed by exactly one whitespace byte; then binary `f32`
//! samples, rows stored **bottom to top**, left to right, channels
//! interleaved. The magnitude of the scale is ignored when reading.

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::Path;

use crate::{Image, ImageError, ImageFormat, MAX_PIXELS};

/// Longest header token (width, height or scale) accepted, in bytes.
const MAX_TOKEN_LEN: usize = 64;

/// Writes `image` as a little-endian RGB PFM (`PF`, scale `-1.0`).
/// The image's shape must already have been checked.
pub(crate) fn write(path: &Path, image: &Image) -> Result<(), ImageError> {
    let file = File::create(path).map_err(|e| ImageError::write(path, e))?;
    let mut out = BufWriter::new(file);
    let io = |out: &mut BufWriter<File>| -> std::io::Result<()> {
        write!(out, "PF\n{} {}\n-1.0\n", image.width, image.height)?;
        let mut row_bytes = Vec::with_capacity(image.width * 12);
        for row in image.pixels.chunks_exact(image.width).rev() {
            row_bytes.clear();
            for sample in row.iter().flatten() {
                row_bytes.extend_from_slice(&sample.to_le_bytes());
            }
            out.write_all(&row_bytes)?;
        }
        out.flush()
    };
    io(&mut out).map_err(|e| ImageError::write(path, e))
}

/// Reads an RGB (`PF`) or greyscale (`Pf`, replicated to RGB) PFM of either
/// byte order.
pub(crate) fn read(path: &Path) -> Result<Image, ImageError> {
    let malformed = |message: String| ImageError::decode(path, ImageFormat::Pfm, message);
    let file = File::open(path).map_err(|e| ImageError::read(path, e))?;
    let file_len = file.metadata().map_err(|e| ImageError::read(path, e))?.len();
    let mut reader = HeaderReader { inner: BufReader::new(file), consumed: 0 };

    let magic = reader.read_magic().map_err(|e| ImageError::read(path, e))?;
    let channels = match &magic[..] {
        b"PF" => 3,
        b"Pf" => 1,
        other => {
            return Err(malformed(format!(
                "malformed header: expected magic 'PF' (RGB) or 'Pf' (greyscale), found '{}'",
                other.escape_ascii()
            )));
        }
    };
    let after_magic = reader.read_byte().map_err(|e| ImageError::read(path, e))?;
    if !after_magic.is_some_and(|b| b.is_ascii_whitespace()) {
        return Err(malformed("malformed header: expected whitespace after the magic 'PF'/'Pf'".to_string()));
    }

    let mut token = |what: &str| -> Result<String, ImageError> {
        match reader.read_token().map_err(|e| ImageError::read(path, e))? {
            Token::Text(t) => Ok(t),
            Token::Eof => Err(malformed(format!("malformed header: file ends before the {what}"))),
            Token::TooLong(prefix) => Err(malformed(format!(
                "malformed header: expected the {what}, found an overlong token starting '{}'",
                prefix.escape_ascii()
            ))),
        }
    };
    let parse_dim = |text: &str, what: &str| -> Result<usize, ImageError> {
        match text.parse::<usize>() {
            Ok(n) if n > 0 => Ok(n),
            _ => Err(malformed(format!(
                "malformed header: expected a positive integer {what}, found '{}'",
                text.escape_default()
            ))),
        }
    };
    let width_text = token("width")?;
    let width = parse_dim(&width_text, "width")?;
    let height_text = token("height")?;
    let height = parse_dim(&height_text, "height")?;
    let scale_text = token("scale")?;
    let little_endian = match scale_text.parse::<f32>() {
        Ok(s) if s.is_finite() && s != 0.0 => s < 0.0,
        _ => {
            return Err(malformed(format!(
                "malformed header: expected a finite non-zero scale \
                 (negative for little-endian, positive for big-endian), found '{}'",
                scale_text.escape_default()
            )));
        }
    };
    // `read_token` consumed the single whitespace byte that ends the header.

    let kind = if channels == 3 { "RGB" } else { "greyscale" };
    let pixel_count = width
        .checked_mul(height)
        .filter(|&n| n <= MAX_PIXELS)
        .ok_or_else(|| malformed(format!("dimensions {width}x{height} exceed the limit of {MAX_PIXELS} pixels")))?;
    let expected = pixel_count * channels * 4;
    let available = file_len.saturating_sub(reader.consumed);
    if available < expected as u64 {
        return Err(malformed(format!(
            "truncated pixel data: expected {expected} bytes for {width}x{height} {kind} \
             pixels, found {available}"
        )));
    }
    if available > expected as u64 {
        return Err(malformed(format!(
            "{} unexpected bytes after the {expected} bytes of {width}x{height} {kind} pixel data",
            available - expected as u64
        )));
    }

    let mut data = vec![0u8; expected];
    reader.inner.read_exact(&mut data).map_err(|e| ImageError::read(path, e))?;

    let decode = |bytes: &[u8]| {
        let b = [bytes[0], bytes[1], bytes[2], bytes[3]];
        if little_endian { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) }
    };
    let mut image = Image::new(width, height);
    let row_len = width * channels * 4;
    for (file_row, bytes) in data.chunks_exact(row_len).enumerate() {
        let y = height - 1 - file_row;
        let row = &mut image.pixels[y * width..(y + 1) * width];
        for (pixel, sample_bytes) in row.iter_mut().zip(bytes.chunks_exact(channels * 4)) {
            *pixel = if channels == 3 {
                [decode(&sample_bytes[0..4]), decode(&sample_bytes[4..8]), decode(&sample_bytes[8..12])]
            } else {
                [decode(sample_bytes); 3]
            };
        }
    }
    Ok(image)
}

/// A whitespace-separated header token.
enum Token {
    Text(String),
    Eof,
    TooLong(Vec<u8>),
}

/// Reads the ASCII header byte by byte, counting how much was consumed.
struct HeaderReader {
    inner: BufReader<File>,
    consumed: u64,
}

impl HeaderReader {
    fn read_byte(&mut self) -> std::io::Result<Option<u8>> {
        let buf = self.inner.fill_buf()?;
        let Some(&byte) = buf.first() else {
            return Ok(None);
        };
        self.inner.consume(1);
        self.consumed += 1;
        Ok(Some(byte))
    }

    /// Up to two bytes of magic (fewer if the file is shorter).
    fn read_magic(&mut self) -> std::io::Result<Vec<u8>> {
        let mut magic = Vec::with_capacity(2);
        while magic.len() < 2 {
            match self.read_byte()? {
                Some(b) => magic.push(b),
                None => break,
            }
        }
        Ok(magic)
    }

    /// Skips leading whitespace, then reads non-whitespace bytes up to and
    /// including the single whitespace byte that terminates the token.
    fn read_token(&mut self) -> std::io::Result<Token> {
        let mut text = Vec::new();
        loop {
            match self.read_byte()? {
                None => break,
                Some(b) if b.is_ascii_whitespace() => {
                    if text.is_empty() {
                        continue;
                    }
                    break;
                }
                Some(b) => {
                    text.push(b);
                    if text.len() > MAX_TOKEN_LEN {
                        return Ok(Token::TooLong(text));
                    }
                }
            }
        }
        if text.is_empty() {
            return Ok(Token::Eof);
        }
        // Non-UTF-8 bytes make the number unparsable; the caller reports it.
        Ok(Token::Text(String::from_utf8_lossy(&text).into_owned()))
    }
}
