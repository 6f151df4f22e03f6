//! Wavefront OBJ reader; the accepted syntax is documented at [`super::parse_obj`].

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

use math::{Vec2, Vec3};
use scene::desc::MeshData;

use super::repair_normals;
use crate::scene_error::SceneError;

/// Statements of the OBJ specification (and the common `maplib`/`usemap`) that do not
/// describe polygonal geometry: accepted and ignored.
const IGNORED: &[&str] = &[
    "vp",
    "cstype",
    "deg",
    "bmat",
    "step",
    "p",
    "l",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "g",
    "s",
    "mg",
    "o",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "usemtl",
    "mtllib",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "maplib",
    "usemap",
    "call",
    "csh",
];

/// Marks an absent texture coordinate or normal in a corner key.
const NONE: u32 = u32::MAX;

/// Where a problem is: line, and the byte offset of the token in the line when known.
struct At {
    line: u32,
    /// Columns are only reported for lines that were not joined with `\`.
    columns_valid: bool,
}

impl At {
    fn error(&self, path: &Path, offset: Option<usize>, message: impl Into<String>) -> SceneError {
        match offset {
            Some(offset) if self.columns_valid => {
                SceneError::at(path, self.line, u32::try_from(offset + 1).unwrap_or(u32::MAX), message)
            }
            _ => SceneError::at_line(path, self.line, message),
        }
    }
}

/// The mesh under construction.
#[derive(Default)]
struct Builder {
    /// `v`, `vt` (already flipped) and `vn` statements in file order.
    file_positions: Vec<Vec3>,
    file_uvs: Vec<Vec2>,
    file_normals: Vec<Vec3>,
    /// Output vertex of each distinct `(v, vt, vn)` corner.
    corners: HashMap<[u32; 3], u32>,
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    normal_missing: Vec<bool>,
    any_uv: bool,
    any_normal: bool,
    triangles: Vec<[u32; 3]>,
    /// Output vertices of the face being read (reused).
    face: Vec<u32>,
}

/// Splits off the first physical line (without `\n` and a trailing `\r`).
fn split_line(bytes: &[u8]) -> (&[u8], &[u8]) {
    let (line, rest) = match bytes.iter().position(|&b| b == b'\n') {
        Some(i) => (&bytes[..i], &bytes[i + 1..]),
        None => (bytes, &bytes[bytes.len()..]),
    };
    (line.strip_suffix(b"\r").unwrap_or(line), rest)
}

/// Whether the line (ignoring trailing blanks) ends with the continuation mark `\` outside a
/// comment (so that a comment ending in a backslash cannot swallow the next statement).
fn continues(line: &[u8]) -> bool {
    line.trim_ascii_end().ends_with(b"\\") && !line.contains(&b'#')
}

/// The whitespace-separated tokens of `line` with their byte offsets.
fn tokens(line: &str) -> impl Iterator<Item = (usize, &str)> {
    let base = line.as_ptr() as usize;
    line.split_ascii_whitespace().map(move |t| (t.as_ptr() as usize - base, t))
}

pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<MeshData, SceneError> {
    let mut builder = Builder::default();
    let mut rest = bytes;
    let mut line_number = 0u32;
    while !rest.is_empty() {
        line_number = line_number.saturating_add(1);
        let at_line = line_number;
        let (first, after) = split_line(rest);
        rest = after;
        let mut text = Cow::Borrowed(first);
        let mut joined = false;
        while continues(&text) && !rest.is_empty() {
            let mut owned = text.into_owned();
            owned.truncate(owned.trim_ascii_end().len() - 1);
            owned.push(b' ');
            let (next, after) = split_line(rest);
            rest = after;
            line_number = line_number.saturating_add(1);
            owned.extend_from_slice(next);
            text = Cow::Owned(owned);
            joined = true;
        }
        let at = At { line: at_line, columns_valid: !joined };
        builder.statement(&text, &at, path)?;
    }
    builder.finish(path, line_number)
}

impl Builder {
    /// Handles one logical line.
    fn statement(&mut self, line: &[u8], at: &At, path: &Path) -> Result<(), SceneError> {
        let line = match line.iter().position(|&b| b == b'#') {
            Some(comment) => &line[..comment],
            None => line,
        };
        let Some(keyword) = line.split(|b| b.is_ascii_whitespace()).find(|t| !t.is_empty()) else {
            return Ok(());
        };
        let keyword_offset = keyword.as_ptr() as usize - line.as_ptr() as usize;
        if !matches!(keyword, b"v" | b"vt" | b"vn" | b"f") {
            if std::str::from_utf8(keyword).is_ok_and(|k| IGNORED.contains(&k)) {
                return Ok(());
            }
            return Err(at.error(
                path,
                Some(keyword_offset),
                format!("unknown OBJ statement `{}`", String::from_utf8_lossy(keyword)),
            ));
        }
        let text = std::str::from_utf8(line).map_err(|e| {
            at.error(path, Some(e.valid_up_to()), "the line is not valid UTF-8 (expected numbers and indices)")
        })?;
        let mut tokens = tokens(text);
        let (_, keyword) = tokens.next().unwrap_or((0, ""));
        let arguments: Vec<(usize, &str)> = tokens.collect();
        let end_offset = text.trim_ascii_end().len();
        match keyword {
            "v" => {
                let values = numbers(&arguments, 3, 7, "`v` (x y z, optionally w or r g b)", end_offset, at, path)?;
                self.file_positions.push(Vec3::new(values[0], values[1], values[2]));
            }
            "vt" => {
                let values = numbers(&arguments, 1, 3, "`vt` (u, optionally v and w)", end_offset, at, path)?;
                let v = values.get(1).copied().unwrap_or(0.0);
                // Mitsuba's `flip_tex_coords` default: OBJ's v runs bottom to top.
                self.file_uvs.push(Vec2::new(values[0], 1.0 - v));
            }
            "vn" => {
                let values = numbers(&arguments, 3, 3, "`vn` (x y z)", end_offset, at, path)?;
                self.file_normals.push(Vec3::new(values[0], values[1], values[2]));
            }
            _ => self.face(&arguments, keyword_offset, at, path)?,
        }
        Ok(())
    }

    /// Handles the corners of an `f` statement.
    fn face(
        &mut self,
        corners: &[(usize, &str)],
        keyword_offset: usize,
        at: &At,
        path: &Path,
    ) -> Result<(), SceneError> {
        self.face.clear();
        for &(offset, corner) in corners {
            let error = |message: String| at.error(path, Some(offset), message);
            let mut parts = corner.split('/');
            let v = parts.next().unwrap_or("");
            let vt = parts.next();
            let vn = parts.next();
            if parts.next().is_some() || v.is_empty() || vn == Some("") || (vt == Some("") && vn.is_none()) {
                return Err(error(format!("`{corner}` is not a face corner (expected v, v/vt, v//vn or v/vt/vn)")));
            }
            let p = resolve(v, self.file_positions.len(), "vertex").map_err(&error)?;
            let t = match vt {
                Some(t) if !t.is_empty() => resolve(t, self.file_uvs.len(), "texture coordinate").map_err(&error)?,
                _ => NONE,
            };
            let n = match vn {
                Some(n) => resolve(n, self.file_normals.len(), "normal").map_err(&error)?,
                None => NONE,
            };
            let id = self.vertex([p, t, n]).ok_or_else(|| error("more than 2³² − 1 distinct vertices".into()))?;
            self.face.push(id);
        }
        if corners.len() < 3 {
            return Err(at.error(
                path,
                Some(keyword_offset),
                format!("a face needs at least 3 vertices, this one has {}", corners.len()),
            ));
        }
        for i in 1..self.face.len() - 1 {
            self.triangles.push([self.face[0], self.face[i], self.face[i + 1]]);
        }
        Ok(())
    }

    /// The output vertex of a corner (indices into the file's lists, [`NONE`] when absent),
    /// created on first use. `None` when the output would exceed the `u32` index range.
    fn vertex(&mut self, key: [u32; 3]) -> Option<u32> {
        if let Some(&id) = self.corners.get(&key) {
            return Some(id);
        }
        let id = u32::try_from(self.positions.len()).ok().filter(|&id| id != u32::MAX)?;
        let [p, t, n] = key.map(|i| i as usize);
        self.positions.push(self.file_positions[p]);
        if key[1] == NONE {
            self.uvs.push(Vec2::ZERO);
        } else {
            self.uvs.push(self.file_uvs[t]);
            self.any_uv = true;
        }
        if key[2] == NONE {
            self.normals.push(Vec3::ZERO);
            self.normal_missing.push(true);
        } else {
            self.normals.push(self.file_normals[n]);
            self.normal_missing.push(false);
            self.any_normal = true;
        }
        self.corners.insert(key, id);
        Some(id)
    }

    fn finish(mut self, path: &Path, last_line: u32) -> Result<MeshData, SceneError> {
        if self.triangles.is_empty() {
            let what = if self.file_positions.is_empty() { "no vertices and no faces" } else { "no faces" };
            return Err(SceneError::at_line(
                path,
                last_line.max(1),
                format!("the file has {what} (expected `f` statements)"),
            ));
        }
        if !self.any_uv {
            self.uvs.clear();
        }
        if self.any_normal {
            repair_normals(&self.positions, &self.triangles, &mut self.normals, Some(&self.normal_missing));
        } else {
            self.normals.clear();
        }
        Ok(MeshData {
            positions: self.positions,
            normals: self.normals,
            uvs: self.uvs,
            triangles: self.triangles,
            attributes: Vec::new(),
        })
    }
}

/// Parses between `min` and `max` finite numbers of a `v`, `vt` or `vn` statement.
fn numbers(
    arguments: &[(usize, &str)],
    min: usize,
    max: usize,
    what: &str,
    end_offset: usize,
    at: &At,
    path: &Path,
) -> Result<[f32; 7], SceneError> {
    if arguments.len() < min || arguments.len() > max {
        let expected = if min == max { format!("{min}") } else { format!("{min} to {max}") };
        let offset = arguments.get(max).map_or(end_offset, |a| a.0);
        return Err(at.error(
            path,
            Some(offset),
            format!("{what} takes {expected} numbers, found {}", arguments.len()),
        ));
    }
    let mut values = [0.0; 7];
    for (value, &(offset, token)) in values.iter_mut().zip(arguments) {
        *value = match token.parse::<f32>() {
            Ok(x) if x.is_finite() => x,
            Ok(_) => return Err(at.error(path, Some(offset), format!("`{token}` is not a finite number"))),
            Err(_) => return Err(at.error(path, Some(offset), format!("expected a number, found `{token}`"))),
        };
    }
    Ok(values)
}

/// Resolves a 1-based or negative (relative) OBJ index against the `count` elements defined so
/// far, returning the 0-based index.
fn resolve(token: &str, count: usize, what: &str) -> Result<u32, String> {
    let index: i64 = token.parse().map_err(|_| format!("expected a {what} index, found `{token}`"))?;
    let count_i64 = i64::try_from(count).unwrap_or(i64::MAX);
    let defined = match count {
        0 => format!("no {what} is defined above"),
        1 => format!("only 1 {what} is defined above"),
        _ => format!(
            "only {count} {} are defined above",
            if what == "vertex" { "vertices".into() } else { format!("{what}s") }
        ),
    };
    let resolved = if index > 0 {
        if index > count_i64 {
            return Err(format!("face refers to {what} {index} but {defined}"));
        }
        index - 1
    } else if index < 0 {
        if index < -count_i64 {
            return Err(format!("face refers to {what} {index} (counting back from the last) but {defined}"));
        }
        count_i64 + index
    } else {
        return Err(format!("{what} index 0 is invalid (OBJ indices start at 1)"));
    };
    // `count` elements fit in memory, so the index fits in `u32` unless the file is > 4 GiB
    // of `v` lines; refuse that instead of wrapping.
    u32::try_from(resolved).ok().filter(|&i| i != NONE).ok_or_else(|| format!("{what} index {index} is too large"))
}
