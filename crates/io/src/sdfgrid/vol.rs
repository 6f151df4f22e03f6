//! Mitsuba's binary grid-volume format (`.vol`), as far as an `sdfgrid` needs it.
//!
//! Layout (little-endian): the bytes `V O L`, the version byte `3`, an `i32` encoding (`1` =
//! 32-bit floats, the only one Mitsuba 3 reads), three `i32` sizes `x y z`, an `i32` channel
//! count, six `f32` bounds (min xyz, max xyz — ignored by `sdfgrid`, whose object space is the
//! unit cube), then `x·y·z·channels` `f32` values with `x` varying fastest, then `y`, then `z`,
//! and the channels of one point together.

use std::path::Path;

use super::grid::SdfGrid;

/// Bytes before the values.
pub(crate) const HEADER_BYTES: usize = 48;

/// Reads a single-channel `.vol` file as an SDF grid. Errors name the file and what was
/// expected.
pub(crate) fn read_vol(path: &Path) -> Result<SdfGrid, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read the file: {e}", path.display()))?;
    parse_vol(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Parses the bytes of a single-channel `.vol` file (see the module documentation).
pub(crate) fn parse_vol(bytes: &[u8]) -> Result<SdfGrid, String> {
    if bytes.len() < 4 || &bytes[..3] != b"VOL" {
        return Err("not a grid volume file: it must start with the bytes 'VOL'".into());
    }
    if bytes[3] != 3 {
        return Err(format!("volume file version {}: only version 3 is supported", bytes[3]));
    }
    if bytes.len() < HEADER_BYTES {
        return Err(format!("truncated header: {} bytes, expected {HEADER_BYTES}", bytes.len()));
    }
    let int =
        |offset: usize| i32::from_le_bytes([bytes[offset], bytes[offset + 1], bytes[offset + 2], bytes[offset + 3]]);
    let encoding = int(4);
    if encoding != 1 {
        return Err(format!("encoding {encoding}: only encoding 1 (32-bit floats) is supported"));
    }
    let mut dims = [0usize; 3];
    for (axis, dim) in dims.iter_mut().enumerate() {
        let size = int(8 + 4 * axis);
        *dim = usize::try_from(size).ok().filter(|&s| s >= 2).ok_or_else(|| {
            format!(
                "grid size {size} along {}: an SDF grid needs at least 2 points per axis",
                "xyz".as_bytes()[axis] as char
            )
        })?;
    }
    let channels = int(20);
    if channels != 1 {
        return Err(format!("{channels} channels: an SDF grid has exactly 1"));
    }
    let count = dims[0]
        .checked_mul(dims[1])
        .and_then(|c| c.checked_mul(dims[2]))
        .filter(|&c| c <= (usize::MAX - HEADER_BYTES) / 4)
        .ok_or_else(|| format!("grid size {}×{}×{} is too large", dims[0], dims[1], dims[2]))?;
    let expected = HEADER_BYTES + 4 * count;
    // Bytes after the values are ignored, as Mitsuba does.
    if bytes.len() < expected {
        return Err(format!(
            "truncated: {} bytes, expected {expected} for {}×{}×{} values",
            bytes.len(),
            dims[0],
            dims[1],
            dims[2]
        ));
    }
    let values =
        bytes[HEADER_BYTES..expected].chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    SdfGrid::new(dims, values)
}

/// The bytes of a single-channel `.vol` file holding `values` (`x` fastest) on a grid of
/// `dims` points, with the unit cube as bounds. For tests.
#[cfg(test)]
pub(crate) fn encode_vol(dims: [usize; 3], values: &[f32]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(HEADER_BYTES + 4 * values.len());
    bytes.extend_from_slice(b"VOL\x03");
    for v in [1, dims[0] as i32, dims[1] as i32, dims[2] as i32, 1] {
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
