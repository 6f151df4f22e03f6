//! Triangle mesh readers: Wavefront OBJ, Stanford PLY and Mitsuba's `.serialized` format.
//!
//! Every reader returns the mesh in object space as [`scene::desc::MeshData`] (polygons
//! triangulated as fans, attributes de-indexed so that positions, normals and uvs share one
//! index) or a [`SceneError`] naming the file and, for text formats, the line and column. They
//! never panic on malformed input; the `parse_*` functions take the bytes directly for fuzzing.
//!
//! Common conventions of the three readers:
//!
//! - Lengths are in the file's units; nothing is transformed.
//! - Shading normals are normalised. A normal that cannot be normalised (zero length, NaN), and
//!   in an OBJ file a face corner without a normal in a mesh that has normals elsewhere, is
//!   replaced by the normalised area-weighted sum of the geometric normals of the triangles
//!   that use the vertex (`+z` if all of them are degenerate) — what Mitsuba computes for meshes
//!   without normals.
//! - A mesh without normals in the file has none in [`MeshData`]; the renderer then shades with
//!   the geometric normal (Mitsuba instead computes smooth vertex normals).
//! - Memory is bounded by the file's size: counts declared in a header are checked against the
//!   bytes that follow before anything is reserved.
//!
//! The hand-written parsers (rather than `tobj` / `ply-rs-bw`) exist so that every error can
//! point at a line and column, unknown OBJ statements are errors rather than silently dropped,
//! and allocations are bounded on hostile headers.

mod obj;
mod ply;
mod serialized;

use std::path::Path;

use math::Vec3;
use scene::desc::MeshData;

use crate::scene_error::SceneError;

/// Reads a Wavefront OBJ file (all objects and groups merged into one mesh). Texture
/// coordinates are flipped vertically (`v' = 1 − v`) as Mitsuba does by default; see
/// [`parse_obj`].
pub fn read_obj(path: &Path) -> Result<MeshData, SceneError> {
    parse_obj(&read_file(path)?, path)
}

/// Reads a PLY file (ASCII or binary, little or big endian; gzip-compressed files such as
/// `.ply.gz` are decompressed first); see [`parse_ply`].
pub fn read_ply(path: &Path) -> Result<MeshData, SceneError> {
    parse_ply(&read_file(path)?, path)
}

/// Reads mesh number `shape_index` (0-based) of a Mitsuba `.serialized` file; see
/// [`parse_serialized`].
pub fn read_serialized(path: &Path, shape_index: u32) -> Result<MeshData, SceneError> {
    parse_serialized(&read_file(path)?, shape_index, path)
}

/// Parses the contents of a Wavefront OBJ file; `path` only names the file in errors.
///
/// Reads `v` (3 to 7 numbers: x y z, then an ignored w or colour), `vt` (u, optional v and w;
/// a missing v counts as 0), `vn` and `f` (corners `v`, `v/vt`, `v//vn`, `v/vt/vn`, 1-based,
/// negative indices counting back from the last element defined so far; a face may only refer
/// to elements defined above it). Polygons with more than three corners become triangle fans
/// around their first corner. Each distinct `(v, vt, vn)` combination becomes one output
/// vertex. Texture coordinates are returned as `(u, 1 − v)`, Mitsuba's `flip_tex_coords`
/// default: OBJ puts `v = 0` at the bottom of the image, Mitsuba's lookups at the top. When
/// some corners have texture coordinates and others do not, the others get `(0, 0)`.
///
/// The other statements of the OBJ specification (`o`, `g`, `s`, `usemtl`, `mtllib`, `p`, `l`,
/// free-form geometry, …) are ignored; any other statement is an error. Comments start with
/// `#`; a line ending in `\` outside a comment continues on the next line.
pub fn parse_obj(bytes: &[u8], path: &Path) -> Result<MeshData, SceneError> {
    let mesh = obj::parse(bytes, path)?;
    finish(mesh, path)
}

/// Parses the contents of a PLY file; `path` only names the file in errors.
///
/// Formats `ascii 1.0`, `binary_little_endian 1.0` and `binary_big_endian 1.0`. The `vertex`
/// element must have scalar properties `x`, `y`, `z`; `nx`, `ny`, `nz` give normals and the
/// first complete pair of `u`/`v`, `s`/`t`, `texture_u`/`texture_v`, `texture_s`/`texture_t`
/// gives texture coordinates (unflipped, as Mitsuba reads PLY). The `face` element must have a
/// list property `vertex_indices` (or `vertex_index`) with integer counts and indices; faces
/// become triangle fans. Any scalar type is accepted for any property; other properties and
/// elements are skipped. In ASCII files, data after the last element is an error.
///
/// Other scalar properties of `vertex` and `face` become [`scene::desc::MeshAttribute`]s as
/// Mitsuba 3 groups them: `r g b` or `red green blue` (an alpha channel is dropped) is
/// `vertex_color` / `face_color`; consecutive properties `<p>_x <p>_y <p>_z`, `<p>_0 <p>_1 <p>_2`,
/// `<p>_1 <p>_2 <p>_3` (three components) or just the first of a row (one component) are
/// `vertex_<p>` / `face_<p>`, and `<p>_r <p>_g <p>_b` is `vertex_<p>_color`; groups of two or four
/// and out-of-order suffixes are skipped. Integer values are divided by their type's largest
/// value and sRGB-decoded (Mitsuba reads integer PLY fields so); floats are kept. Face values
/// are repeated for every triangle of the face's fan. A non-finite value is an error.
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<MeshData, SceneError> {
    let mesh = ply::parse(bytes, path)?;
    finish(mesh, path)
}

/// Parses mesh number `shape_index` (0-based) of the contents of a Mitsuba `.serialized` file;
/// `path` only names the file in errors.
///
/// The file starts each mesh with the little-endian `u16` identifier `0x041C` and a `u16`
/// version (3 or 4), followed by a zlib stream holding a `u32` flags word (`0x1` normals, `0x2`
/// texture coordinates, `0x8` colours, `0x10` face normals, `0x1000` single, `0x2000` double
/// precision), the name (version 4: NUL-terminated UTF-8), `u64` vertex and triangle counts,
/// the positions, normals, uvs and colours, and `u32` triangle indices. The file ends with the
/// byte offsets of the meshes (`u32` in version 3, `u64` in version 4) and a `u32` mesh count.
/// Colours are skipped; with the face-normal flag the normals are dropped. The zlib checksum
/// is verified and a stream longer than its counts say is an error.
pub fn parse_serialized(bytes: &[u8], shape_index: u32, path: &Path) -> Result<MeshData, SceneError> {
    let mesh = serialized::parse(bytes, shape_index, path)?;
    finish(mesh, path)
}

/// Reads a whole file, naming it in the error.
/// The file's bytes, gunzipped when it is gzip-compressed (e.g. `.ply.gz`).
fn read_file(path: &Path) -> Result<Vec<u8>, SceneError> {
    crate::trace::opened(path);
    crate::gz::read_maybe_gzip(path).map_err(|e| SceneError::in_file(path, e))
}

/// The reader's common last step: [`MeshData::validate`], with the file named in the error.
fn finish(mesh: MeshData, path: &Path) -> Result<MeshData, SceneError> {
    mesh.validate().map_err(|message| SceneError::in_file(path, message))?;
    Ok(mesh)
}

/// Normalises `normals` (one per position) in place. Entries that cannot be normalised (zero,
/// non-finite) and entries with `missing[i]` set are replaced by the normalised area-weighted
/// sum of the geometric normals `(p1 − p0) × (p2 − p0)` of the triangles using the vertex, or
/// `+z` when that sum is zero. `triangles` must be valid indices into `positions`.
fn repair_normals(positions: &[Vec3], triangles: &[[u32; 3]], normals: &mut [Vec3], missing: Option<&[bool]>) {
    let mut needs_repair = vec![false; normals.len()];
    let mut any = false;
    for (i, n) in normals.iter_mut().enumerate() {
        let length = n.length();
        let absent = missing.is_some_and(|m| m[i]);
        if absent || !(length.is_finite() && length > 1e-30) {
            needs_repair[i] = true;
            any = true;
        } else {
            *n /= length;
        }
    }
    if !any {
        return;
    }
    let mut sums = vec![Vec3::ZERO; normals.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        if !(needs_repair[a] || needs_repair[b] || needs_repair[c]) {
            continue;
        }
        // Twice the area times the unit normal: the area weighting comes for free.
        let face = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        if !face.is_finite() {
            continue;
        }
        for v in [a, b, c] {
            sums[v] += face;
        }
    }
    for (i, n) in normals.iter_mut().enumerate() {
        if needs_repair[i] {
            *n = sums[i].try_normalize().unwrap_or(Vec3::Z);
        }
    }
}

/// `"1 thing"` or `"n things"`, for messages.
fn plural(count: u64, singular: &str, plural: &str) -> String {
    if count == 1 { format!("1 {singular}") } else { format!("{count} {plural}") }
}
