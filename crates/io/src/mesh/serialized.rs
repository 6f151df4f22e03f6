//! Mitsuba `.serialized` reader; the format is described at [`super::parse_serialized`].

use std::io::Read;
use std::path::Path;

use flate2::read::ZlibDecoder;
use math::{Vec2, Vec3};
use scene::desc::MeshData;

use super::{plural, repair_normals};
use crate::scene_error::SceneError;

/// File format identifier at the start of every mesh.
const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_UVS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const FACE_NORMALS: u32 = 0x0010;
const SINGLE_PRECISION: u32 = 0x1000;
const DOUBLE_PRECISION: u32 = 0x2000;

/// Deflate expands at most about 1032:1; counts promising more data than that are lies.
const MAX_DEFLATE_RATIO: u64 = 1032;
/// Longest mesh name accepted (bytes).
const MAX_NAME: usize = 1 << 16;

fn u16_at(bytes: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(bytes.get(at..at.checked_add(2)?)?.try_into().ok()?))
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(bytes.get(at..at.checked_add(4)?)?.try_into().ok()?))
}

fn u64_at(bytes: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(bytes.get(at..at.checked_add(8)?)?.try_into().ok()?))
}

/// Checks the uncompressed header at `offset`, returning the version.
fn check_header(bytes: &[u8], offset: usize, index: u32, path: &Path) -> Result<u16, SceneError> {
    let (Some(magic), Some(version)) = (u16_at(bytes, offset), u16_at(bytes, offset.saturating_add(2))) else {
        return Err(SceneError::in_file(path, format!("the file ends inside the header of mesh {index}")));
    };
    if magic != MAGIC {
        return Err(SceneError::in_file(
            path,
            format!(
                "mesh {index} (at byte {offset}) starts with {magic:#06x}, not the serialized-mesh identifier 0x041c"
            ),
        ));
    }
    if version != 3 && version != 4 {
        return Err(SceneError::in_file(
            path,
            format!("unsupported serialized-mesh version {version} (expected 3 or 4)"),
        ));
    }
    Ok(version)
}

/// The byte offset of mesh `index` from the dictionary at the end of the file.
fn mesh_offset(bytes: &[u8], index: u32, version: u16, path: &Path) -> Result<usize, SceneError> {
    let len = bytes.len();
    let count = len.checked_sub(4).and_then(|at| u32_at(bytes, at)).unwrap_or(0);
    let entry = if version == 3 { 4 } else { 8 };
    let table = (count as usize).saturating_mul(entry);
    if len < 8 || table > len - 8 {
        return Err(SceneError::in_file(
            path,
            format!("the mesh dictionary at the end of the file is missing or damaged (it claims {count} meshes)"),
        ));
    }
    if index >= count {
        return Err(SceneError::in_file(
            path,
            format!("shape_index {index} is out of range: the file holds {}", plural(count.into(), "mesh", "meshes")),
        ));
    }
    let at = len - 4 - entry * (count - index) as usize;
    let offset = if version == 3 { u32_at(bytes, at).map(u64::from) } else { u64_at(bytes, at) };
    offset.and_then(|o| usize::try_from(o).ok()).filter(|&o| o < len - table - 4).ok_or_else(|| {
        SceneError::in_file(path, format!("the dictionary gives mesh {index} an offset beyond the file"))
    })
}

pub(super) fn parse(bytes: &[u8], shape_index: u32, path: &Path) -> Result<MeshData, SceneError> {
    let version = check_header(bytes, 0, 0, path)?;
    let offset = if shape_index == 0 { 0 } else { mesh_offset(bytes, shape_index, version, path)? };
    let version = check_header(bytes, offset, shape_index, path)?;
    let compressed = &bytes[offset + 4..];
    let mut stream = ZlibDecoder::new(compressed);
    let fail = |what: &str, e: std::io::Error| {
        let message = if e.kind() == std::io::ErrorKind::UnexpectedEof {
            format!("mesh {shape_index}: the compressed data ends inside the {what}")
        } else {
            format!("mesh {shape_index}: corrupt compressed data in the {what} ({e})")
        };
        SceneError::in_file(path, message)
    };

    let mut word = [0u8; 4];
    stream.read_exact(&mut word).map_err(|e| fail("flags", e))?;
    let flags = u32::from_le_bytes(word);
    if version == 4 {
        // A NUL-terminated name, not needed here.
        let mut length = 0;
        loop {
            let mut byte = [0u8; 1];
            stream.read_exact(&mut byte).map_err(|e| fail("mesh name", e))?;
            if byte[0] == 0 {
                break;
            }
            length += 1;
            if length > MAX_NAME {
                return Err(SceneError::in_file(
                    path,
                    format!("mesh {shape_index}: the name is longer than {MAX_NAME} bytes"),
                ));
            }
        }
    }
    let mut counts = [0u8; 16];
    stream.read_exact(&mut counts).map_err(|e| fail("vertex and triangle counts", e))?;
    let vertex_count = u64_at(&counts, 0).unwrap_or(0);
    let triangle_count = u64_at(&counts, 8).unwrap_or(0);

    if flags & SINGLE_PRECISION != 0 && flags & DOUBLE_PRECISION != 0 {
        return Err(SceneError::in_file(
            path,
            format!("mesh {shape_index}: flags {flags:#x} ask for both single and double precision"),
        ));
    }
    let double = flags & DOUBLE_PRECISION != 0;
    let float_size: u64 = if double { 8 } else { 4 };
    if vertex_count > u64::from(u32::MAX) {
        return Err(SceneError::in_file(
            path,
            format!("mesh {shape_index}: {vertex_count} vertices are more than 2³² − 1"),
        ));
    }
    if triangle_count == 0 {
        return Err(SceneError::in_file(path, format!("mesh {shape_index} has no triangles")));
    }
    let has_normals = flags & HAS_NORMALS != 0;
    let has_uvs = flags & HAS_UVS != 0;
    let floats_per_vertex =
        3 + if has_normals { 3 } else { 0 } + if has_uvs { 2 } else { 0 } + if flags & HAS_COLORS != 0 { 3 } else { 0 };
    let needed =
        vertex_count.saturating_mul(floats_per_vertex * float_size).saturating_add(triangle_count.saturating_mul(12));
    let possible = (compressed.len() as u64).saturating_mul(MAX_DEFLATE_RATIO);
    if needed > possible {
        return Err(SceneError::in_file(
            path,
            format!(
                "mesh {shape_index} claims {vertex_count} vertices and {triangle_count} triangles ({needed} bytes), \
                 more than the {} compressed bytes can hold",
                compressed.len()
            ),
        ));
    }
    // Reserve what the data can plausibly hold; a lying header makes the read fail instead.
    let mut data = Vec::with_capacity(needed.min((compressed.len() as u64).saturating_mul(16)) as usize);
    (&mut stream).take(needed).read_to_end(&mut data).map_err(|e| fail("mesh data", e))?;
    if (data.len() as u64) < needed {
        return Err(SceneError::in_file(
            path,
            format!(
                "mesh {shape_index}: the compressed data ends after {} of the {needed} bytes that \
                 {vertex_count} vertices and {triangle_count} triangles need",
                data.len()
            ),
        ));
    }
    // Reading past the end verifies the zlib checksum and shows whether the counts were too small.
    let mut extra = [0u8; 1];
    match stream.read(&mut extra) {
        Ok(0) => {}
        Ok(_) => {
            return Err(SceneError::in_file(
                path,
                format!(
                    "mesh {shape_index}: the compressed data is longer than its counts say ({vertex_count} vertices, {triangle_count} triangles)"
                ),
            ));
        }
        Err(e) => return Err(fail("end of the mesh data", e)),
    }

    // `needed` fits in memory, so the counts fit in `usize`.
    let n = vertex_count as usize;
    let mut reader = Floats { data: &data, pos: 0, double };
    let positions: Vec<Vec3> = (0..n).map(|_| reader.vec3()).collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(SceneError::in_file(path, format!("mesh {shape_index}: vertex {i} has a non-finite position")));
    }
    let mut normals: Vec<Vec3> = if has_normals { (0..n).map(|_| reader.vec3()).collect() } else { Vec::new() };
    let uvs: Vec<Vec2> =
        if has_uvs { (0..n).map(|_| Vec2::new(reader.next(), reader.next())).collect() } else { Vec::new() };
    if let Some(i) = uvs.iter().position(|uv| !uv.is_finite()) {
        return Err(SceneError::in_file(
            path,
            format!("mesh {shape_index}: vertex {i} has a non-finite texture coordinate"),
        ));
    }
    if flags & HAS_COLORS != 0 {
        reader.pos += n * 3 * float_size as usize;
    }
    let indices = &data[reader.pos..];
    let mut triangles = Vec::with_capacity(triangle_count as usize);
    for (t, chunk) in indices.chunks_exact(12).enumerate() {
        let triangle = [0, 4, 8].map(|k| u32_at(chunk, k).unwrap_or(u32::MAX));
        if let Some(&bad) = triangle.iter().find(|&&i| u64::from(i) >= vertex_count) {
            return Err(SceneError::in_file(
                path,
                format!(
                    "mesh {shape_index}: triangle {t} refers to vertex {bad} but the mesh has {vertex_count} vertices"
                ),
            ));
        }
        triangles.push(triangle);
    }
    if flags & FACE_NORMALS != 0 {
        normals.clear();
    } else if has_normals {
        repair_normals(&positions, &triangles, &mut normals, None);
    }
    Ok(MeshData { positions, normals, uvs, triangles, attributes: Vec::new() })
}

/// Little-endian floats of either precision from a buffer known to be long enough.
struct Floats<'a> {
    data: &'a [u8],
    pos: usize,
    double: bool,
}

impl Floats<'_> {
    fn next(&mut self) -> f32 {
        if self.double {
            let value = u64_at(self.data, self.pos).map_or(f64::NAN, f64::from_bits);
            self.pos += 8;
            value as f32
        } else {
            let value = u32_at(self.data, self.pos).map_or(f32::NAN, f32::from_bits);
            self.pos += 4;
            value
        }
    }

    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}
