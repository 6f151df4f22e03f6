//! Reading an `sdfgrid`'s distances from a `.vol` file (the format: [`crate::volfile`]). The
//! grid's object space is the unit cube; the file's bounds are ignored.

use std::path::Path;

use super::grid::SdfGrid;
use crate::volfile::{VolHeader, read_bytes};

/// Reads a single-channel `.vol` file as an SDF grid. Errors name the file and what was
/// expected.
pub(crate) fn read_vol(path: &Path) -> Result<SdfGrid, String> {
    let bytes = read_bytes(path)?;
    parse_vol(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Parses the bytes of a single-channel `.vol` file with at least 2 points per axis.
pub(crate) fn parse_vol(bytes: &[u8]) -> Result<SdfGrid, String> {
    let header = VolHeader::parse(bytes)?;
    let mut dims = [0usize; 3];
    for (axis, dim) in dims.iter_mut().enumerate() {
        let size = header.dims[axis];
        *dim = usize::try_from(size).ok().filter(|&s| s >= 2).ok_or_else(|| {
            format!(
                "grid size {size} along {}: an SDF grid needs at least 2 points per axis",
                "xyz".as_bytes()[axis] as char
            )
        })?;
    }
    if header.channels != 1 {
        return Err(format!("{} channels: an SDF grid has exactly 1", header.channels));
    }
    SdfGrid::new(dims, header.values(bytes)?)
}

/// The bytes of a single-channel `.vol` file (see [`crate::volfile::encode_vol`]). For tests.
#[cfg(test)]
pub(crate) fn encode_vol(dims: [usize; 3], values: &[f32]) -> Vec<u8> {
    crate::volfile::encode_vol(dims, 1, values)
}
