//! Mitsuba's binary grid-volume format (`.vol`), shared by the `sdfgrid` shape and the grid
//! media.
//!
//! Layout (little-endian): the bytes `V O L`, the version byte `3`, an `i32` encoding (`1` =
//! 32-bit floats, the only one Mitsuba 3 reads), three `i32` sizes `x y z`, an `i32` channel
//! count, six `f32` bounds (min xyz, max xyz — unused: Mitsuba's volumes map the unit cube
//! through their `to_world` unless `use_grid_bbox` is set), then `x·y·z·channels` `f32` values
//! with `x` varying fastest, then `y`, then `z`, and the channels of one point together.

use std::path::Path;

/// Bytes before the values.
pub(crate) const HEADER_BYTES: usize = 48;

/// The header of a `.vol` file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct VolHeader {
    /// Points per axis (each ≥ 1 after [`VolHeader::parse`]; may be huge).
    pub dims: [i64; 3],
    /// Values per point.
    pub channels: i64,
    /// The bounds stored in the file: min xyz, max xyz.
    pub bounds: [f32; 6],
}

impl VolHeader {
    /// Parses the header of the bytes of a `.vol` file.
    pub(crate) fn parse(bytes: &[u8]) -> Result<Self, String> {
        if bytes.len() < 4 || &bytes[..3] != b"VOL" {
            return Err("not a grid volume file: it must start with the bytes 'VOL'".into());
        }
        if bytes[3] != 3 {
            return Err(format!("volume file version {}: only version 3 is supported", bytes[3]));
        }
        if bytes.len() < HEADER_BYTES {
            return Err(format!("truncated header: {} bytes, expected {HEADER_BYTES}", bytes.len()));
        }
        let word = |offset: usize| [bytes[offset], bytes[offset + 1], bytes[offset + 2], bytes[offset + 3]];
        let int = |offset: usize| i32::from_le_bytes(word(offset)) as i64;
        let encoding = int(4);
        if encoding != 1 {
            return Err(format!("encoding {encoding}: only encoding 1 (32-bit floats) is supported"));
        }
        let dims = [int(8), int(12), int(16)];
        let bounds = std::array::from_fn(|i| f32::from_le_bytes(word(24 + 4 * i)));
        Ok(Self { dims, channels: int(20), bounds })
    }

    /// The values that follow the header in `bytes` (bytes after them are ignored, as Mitsuba
    /// does). The sizes and channel count must be positive.
    pub(crate) fn values(&self, bytes: &[u8]) -> Result<Vec<f32>, String> {
        let [x, y, z] = self.dims;
        if x < 1 || y < 1 || z < 1 || self.channels < 1 {
            return Err(format!("grid size {x}×{y}×{z} with {} channels: all must be positive", self.channels));
        }
        let count = [x, y, z, self.channels]
            .iter()
            .try_fold(1usize, |c, &n| c.checked_mul(n as usize))
            .filter(|&c| c <= (usize::MAX - HEADER_BYTES) / 4)
            .ok_or_else(|| format!("grid size {x}×{y}×{z} is too large"))?;
        let expected = HEADER_BYTES + 4 * count;
        if bytes.len() < expected {
            return Err(format!(
                "truncated: {} bytes, expected {expected} for {x}×{y}×{z} points of {} channel(s)",
                bytes.len(),
                self.channels
            ));
        }
        Ok(bytes[HEADER_BYTES..expected]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }
}

/// The bytes of `path`, with the error naming the file.
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: cannot read the file: {e}", path.display()))
}

/// The bytes of a `.vol` file of `channels` values per point holding `values` (`x` fastest)
/// on a grid of `dims` points, with the unit cube as bounds. For tests.
#[cfg(test)]
pub(crate) fn encode_vol(dims: [usize; 3], channels: usize, values: &[f32]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(HEADER_BYTES + 4 * values.len());
    bytes.extend_from_slice(b"VOL\x03");
    for v in [1, dims[0] as i32, dims[1] as i32, dims[2] as i32, channels as i32] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes
}
