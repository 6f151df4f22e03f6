//! Reading files that may be gzip-compressed (`.pbrt.gz`, `.ply.gz`).

use std::io::Read;
use std::path::Path;

use flate2::read::GzDecoder;

/// Largest decompressed size accepted (4 GiB): a guard against decompression bombs.
pub(crate) const MAX_DECOMPRESSED_BYTES: u64 = 1 << 32;

/// The bytes of `path`, decompressed when the file starts with the gzip magic number
/// (`1f 8b`), whatever its name. Errors are messages for the caller to place.
pub(crate) fn read_maybe_gzip(path: &Path) -> Result<Vec<u8>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read the file: {e}"))?;
    if !bytes.starts_with(&[0x1f, 0x8b]) {
        return Ok(bytes);
    }
    let mut out = Vec::new();
    GzDecoder::new(bytes.as_slice())
        .take(MAX_DECOMPRESSED_BYTES + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("cannot decompress the gzip file: {e}"))?;
    if out.len() as u64 > MAX_DECOMPRESSED_BYTES {
        return Err(format!("decompresses to more than {MAX_DECOMPRESSED_BYTES} bytes"));
    }
    Ok(out)
}
