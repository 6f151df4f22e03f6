//! Stanford PLY reader; the accepted subset is documented at [`super::parse_ply`].

use std::fmt;
use std::path::Path;

use math::{Vec2, Vec3};
use scene::desc::{MeshAttribute, MeshData};
use spectrum::Rgb;

mod attributes;

use super::{plural, repair_normals};
use crate::scene_error::SceneError;

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    /// Size in bytes in the binary formats.
    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }

    /// The representable range of an integer type.
    fn range(self) -> (i64, i64) {
        match self {
            Self::I8 => (i8::MIN.into(), i8::MAX.into()),
            Self::U8 => (0, u8::MAX.into()),
            Self::I16 => (i16::MIN.into(), i16::MAX.into()),
            Self::U16 => (0, u16::MAX.into()),
            Self::I32 => (i32::MIN.into(), i32::MAX.into()),
            Self::U32 => (0, u32::MAX.into()),
            Self::F32 | Self::F64 => (i64::MIN, i64::MAX),
        }
    }
}

impl fmt::Display for Scalar {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::I8 => "char",
            Self::U8 => "uchar",
            Self::I16 => "short",
            Self::U16 => "ushort",
            Self::I32 => "int",
            Self::U32 => "uint",
            Self::F32 => "float",
            Self::F64 => "double",
        })
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    /// Header line of the `element` statement.
    line: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Binary { big_endian: bool },
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the first byte after the `end_header` line.
    body_start: usize,
    /// Number of header lines (the body starts on the next line).
    lines: u32,
}

fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, SceneError> {
    let mut pos = 0;
    let mut line_number = 0u32;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= bytes.len() {
            let message = if line_number == 0 {
                "the file is empty (expected `ply`)"
            } else {
                "the header has no `end_header` line"
            };
            return Err(SceneError::at_line(path, line_number.max(1), message));
        }
        line_number = line_number.saturating_add(1);
        let end = bytes[pos..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |i| pos + i);
        let raw = &bytes[pos..end];
        pos = (end + 1).min(bytes.len());
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let text = String::from_utf8_lossy(raw);
        let base = text.as_ptr() as usize;
        let words: Vec<(usize, &str)> =
            text.split_ascii_whitespace().map(|w| (w.as_ptr() as usize - base, w)).collect();
        let column = |i: usize| u32::try_from(words.get(i).map_or(text.len(), |w| w.0) + 1).unwrap_or(u32::MAX);
        let error = |i: usize, message: String| SceneError::at(path, line_number, column(i), message);
        let keyword = words.first().map_or("", |w| w.1);
        if line_number == 1 {
            if keyword != "ply" || words.len() != 1 {
                return Err(SceneError::at_line(path, 1, "not a PLY file (expected `ply` on the first line)"));
            }
            continue;
        }
        match keyword {
            "format" => {
                if format.is_some() {
                    return Err(error(0, "a second `format` line".into()));
                }
                let kind = match words.get(1).map(|w| w.1) {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::Binary { big_endian: false },
                    Some("binary_big_endian") => Format::Binary { big_endian: true },
                    _ => {
                        return Err(error(
                            1,
                            "expected `ascii`, `binary_little_endian` or `binary_big_endian` after `format`".into(),
                        ));
                    }
                };
                if words.get(2).map(|w| w.1) != Some("1.0") || words.len() != 3 {
                    return Err(error(2, "expected version `1.0` after the format".into()));
                }
                format = Some(kind);
            }
            "comment" | "obj_info" => {}
            "element" => {
                let [_, (_, name), (_, count)] = words[..] else {
                    return Err(error(words.len().min(3), "expected `element <name> <count>`".into()));
                };
                let count = count
                    .parse::<u64>()
                    .map_err(|_| error(2, format!("expected a non-negative element count, found `{count}`")))?;
                if elements.iter().any(|e| e.name == name) {
                    return Err(error(1, format!("a second `{name}` element")));
                }
                elements.push(Element { name: name.to_owned(), count, properties: Vec::new(), line: line_number });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(error(0, "`property` before any `element`".into()));
                };
                let scalar = |i: usize| {
                    let name = words.get(i).map_or("", |w| w.1);
                    Scalar::from_name(name).ok_or_else(|| error(i, format!("unknown property type `{name}`")))
                };
                let (kind, name_index) = if words.get(1).map(|w| w.1) == Some("list") {
                    let count = scalar(2)?;
                    if !count.is_integer() {
                        return Err(error(2, format!("a list count must have an integer type, not `{count}`")));
                    }
                    (Kind::List { count, item: scalar(3)? }, 4)
                } else {
                    (Kind::Scalar(scalar(1)?), 2)
                };
                let Some(&(_, name)) = words.get(name_index) else {
                    return Err(error(name_index, "expected the property name".into()));
                };
                if words.len() > name_index + 1 {
                    return Err(error(name_index + 1, "unexpected text after the property name".into()));
                }
                if element.properties.iter().any(|p| p.name == name) {
                    return Err(error(name_index, format!("a second property `{name}` in element `{}`", element.name)));
                }
                element.properties.push(Property { name: name.to_owned(), kind });
            }
            "end_header" => break,
            "" => return Err(error(0, "empty header line".into())),
            other => return Err(error(0, format!("unknown header statement `{other}`"))),
        }
    }
    let Some(format) = format else {
        return Err(SceneError::at_line(path, line_number, "the header has no `format` line"));
    };
    Ok(Header { format, elements, body_start: pos, lines: line_number })
}

/// Why reading a value failed.
enum Fail {
    /// The data ended.
    End,
    /// The value could not be parsed (ASCII) — the message says what was expected.
    Syntax(String),
}

/// Where the values of the body come from.
trait Source {
    /// The next value, converted to `f64` (exact for every PLY integer type).
    fn value(&mut self, scalar: Scalar) -> Result<f64, Fail>;
    /// An error at the last value read.
    fn error(&self, message: String) -> SceneError;
    /// An error at the end of the data.
    fn end_error(&self, message: String) -> SceneError;
    /// The fewest bytes one value can take (for checks of the declared counts).
    fn min_bytes(&self, scalar: Scalar) -> u64;
    /// Bytes left.
    fn remaining(&self) -> u64;
}

struct Ascii<'a> {
    path: &'a Path,
    data: &'a [u8],
    pos: usize,
    line: u32,
    line_start: usize,
    token_line: u32,
    token_column: u32,
}

impl<'a> Ascii<'a> {
    fn next_token(&mut self) -> Option<&'a [u8]> {
        while let Some(&b) = self.data.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
            if b == b'\n' {
                self.line = self.line.saturating_add(1);
                self.line_start = self.pos;
            }
        }
        if self.pos >= self.data.len() {
            return None;
        }
        let start = self.pos;
        while self.data.get(self.pos).is_some_and(|b| !b.is_ascii_whitespace()) {
            self.pos += 1;
        }
        self.token_line = self.line;
        self.token_column = u32::try_from(start - self.line_start + 1).unwrap_or(u32::MAX);
        Some(&self.data[start..self.pos])
    }
}

impl Source for Ascii<'_> {
    fn value(&mut self, scalar: Scalar) -> Result<f64, Fail> {
        let token = self.next_token().ok_or(Fail::End)?;
        let text = String::from_utf8_lossy(token);
        if scalar.is_integer() {
            let value: i64 =
                text.parse().map_err(|_| Fail::Syntax(format!("expected an integer ({scalar}), found `{text}`")))?;
            let (min, max) = scalar.range();
            if value < min || value > max {
                return Err(Fail::Syntax(format!("{value} does not fit in the declared type {scalar}")));
            }
            Ok(value as f64)
        } else {
            text.parse().map_err(|_| Fail::Syntax(format!("expected a number ({scalar}), found `{text}`")))
        }
    }

    fn error(&self, message: String) -> SceneError {
        SceneError::at(self.path, self.token_line, self.token_column, message)
    }

    fn end_error(&self, message: String) -> SceneError {
        SceneError::at_line(self.path, self.line, message)
    }

    fn min_bytes(&self, _: Scalar) -> u64 {
        // A digit and a separator.
        2
    }

    fn remaining(&self) -> u64 {
        // One more: the last value needs no separator.
        (self.data.len() - self.pos) as u64 + 1
    }
}

struct Binary<'a> {
    path: &'a Path,
    data: &'a [u8],
    /// File offset of `data[0]`.
    base: usize,
    pos: usize,
    last: usize,
    big_endian: bool,
}

impl Binary<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], Fail> {
        let bytes = self.data.get(self.pos..self.pos + N).ok_or(Fail::End)?;
        self.last = self.pos;
        self.pos += N;
        let mut array = [0; N];
        array.copy_from_slice(bytes);
        if self.big_endian {
            array.reverse();
        }
        Ok(array)
    }
}

impl Source for Binary<'_> {
    fn value(&mut self, scalar: Scalar) -> Result<f64, Fail> {
        // `take` returns the bytes in little-endian order.
        Ok(match scalar {
            Scalar::I8 => i8::from_le_bytes(self.take()?).into(),
            Scalar::U8 => u8::from_le_bytes(self.take()?).into(),
            Scalar::I16 => i16::from_le_bytes(self.take()?).into(),
            Scalar::U16 => u16::from_le_bytes(self.take()?).into(),
            Scalar::I32 => i32::from_le_bytes(self.take()?).into(),
            Scalar::U32 => u32::from_le_bytes(self.take()?).into(),
            Scalar::F32 => f32::from_le_bytes(self.take()?).into(),
            Scalar::F64 => f64::from_le_bytes(self.take()?),
        })
    }

    fn error(&self, message: String) -> SceneError {
        SceneError::in_file(self.path, format!("{message} (at byte {})", self.base + self.last))
    }

    fn end_error(&self, message: String) -> SceneError {
        SceneError::in_file(self.path, message)
    }

    fn min_bytes(&self, scalar: Scalar) -> u64 {
        scalar.size() as u64
    }

    fn remaining(&self) -> u64 {
        (self.data.len() - self.pos) as u64
    }
}

/// What a vertex property is used for.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    Position(usize),
    Normal(usize),
    Uv(usize),
    /// Component `.1` of mesh attribute `.0`.
    Attribute(usize, usize),
    Skip,
}

/// What a face property is used for.
#[derive(Clone, Copy, PartialEq, Eq)]
enum FaceRole {
    Indices,
    /// Component `.1` of mesh attribute `.0`.
    Attribute(usize, usize),
    Skip,
}

/// Sets the roles of the properties of attribute groups `groups`, numbering them from `first`,
/// and adds the (empty) attributes to `mesh`.
fn assign_groups<R: Copy>(
    groups: &[attributes::Group],
    roles: &mut [R],
    role: impl Fn(usize, usize) -> R,
    mesh: &mut MeshData,
) {
    for group in groups {
        let slot = mesh.attributes.len();
        for (channel, &i) in group.properties.iter().enumerate() {
            roles[i] = role(slot, channel);
        }
        mesh.attributes.push(MeshAttribute {
            name: group.name.clone(),
            components: group.properties.len() as u8,
            values: Vec::new(),
        });
    }
}

/// Texture coordinate property names, in order of preference.
const UV_NAMES: [(&str, &str); 4] = [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")];

pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<MeshData, SceneError> {
    let header = parse_header(bytes, path)?;
    let body = &bytes[header.body_start..];
    match header.format {
        Format::Ascii => {
            let mut source = Ascii {
                path,
                data: body,
                pos: 0,
                line: header.lines.saturating_add(1),
                line_start: 0,
                token_line: 0,
                token_column: 0,
            };
            let mesh = read_body(&mut source, &header, path)?;
            if source.next_token().is_some() {
                return Err(source.error("unexpected data after the last element declared in the header".into()));
            }
            Ok(mesh)
        }
        Format::Binary { big_endian } => {
            let mut source = Binary { path, data: body, base: header.body_start, pos: 0, last: 0, big_endian };
            read_body(&mut source, &header, path)
        }
    }
}

fn read_body<S: Source>(source: &mut S, header: &Header, path: &Path) -> Result<MeshData, SceneError> {
    // Every instance of an element with properties takes at least `min` bytes: refuse counts
    // the data cannot hold before reserving anything.
    let mut needed = 0u64;
    for element in &header.elements {
        let min: u64 = element
            .properties
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => source.min_bytes(s),
                Kind::List { count, .. } => source.min_bytes(count),
            })
            .sum();
        needed = needed.saturating_add(element.count.saturating_mul(min));
        if needed > source.remaining() {
            return Err(SceneError::at_line(
                path,
                element.line,
                format!(
                    "the header declares {} but only {} of data follow the header",
                    plural(
                        element.count,
                        &format!("`{}` element", element.name),
                        &format!("`{}` elements", element.name)
                    ),
                    plural(source.remaining(), "byte", "bytes"),
                ),
            ));
        }
    }
    let vertex = header.elements.iter().position(|e| e.name == "vertex");
    let Some(vertex) = vertex else {
        return Err(SceneError::in_file(path, "the header declares no `vertex` element"));
    };
    let vertex_count = header.elements[vertex].count;
    if vertex_count > u64::from(u32::MAX) {
        return Err(SceneError::at_line(path, header.elements[vertex].line, "more than 2³² − 1 vertices"));
    }
    let Some(face) = header.elements.iter().position(|e| e.name == "face") else {
        return Err(SceneError::in_file(path, "the header declares no `face` element"));
    };
    if header.elements[face].count == 0 {
        return Err(SceneError::at_line(path, header.elements[face].line, "the file has no faces"));
    }
    let mut mesh = MeshData::default();
    let mut roles = vertex_roles(&header.elements[vertex], path)?;
    let has_normals = roles.contains(&Role::Normal(0));
    let has_uvs = roles.contains(&Role::Uv(0));
    let taken: Vec<bool> = roles.iter().map(|r| *r != Role::Skip).collect();
    let groups = attributes::groups(&header.elements[vertex], &taken, "vertex_");
    assign_groups(&groups, &mut roles, Role::Attribute, &mut mesh);
    let mut face_roles = face_roles(&header.elements[face], path)?;
    let taken: Vec<bool> = face_roles.iter().map(|r| *r != FaceRole::Skip).collect();
    let groups = attributes::groups(&header.elements[face], &taken, "face_");
    assign_groups(&groups, &mut face_roles, FaceRole::Attribute, &mut mesh);

    for element in &header.elements {
        if element.properties.is_empty() {
            continue;
        }
        if element.name == "vertex" {
            read_vertices(source, element, &roles, has_normals, has_uvs, &mut mesh)?;
        } else if element.name == "face" {
            read_faces(source, element, &face_roles, vertex_count, &mut mesh)?;
        } else {
            for i in 0..element.count {
                for property in &element.properties {
                    skip_property(source, property.kind, element, i)?;
                }
            }
        }
    }
    if has_normals {
        repair_normals(&mesh.positions, &mesh.triangles, &mut mesh.normals, None);
    }
    Ok(mesh)
}

/// Maps the vertex element's properties to their use.
fn vertex_roles(element: &Element, path: &Path) -> Result<Vec<Role>, SceneError> {
    let find = |name: &str| element.properties.iter().position(|p| p.name == name);
    let mut roles = vec![Role::Skip; element.properties.len()];
    let mut assign = |index: usize, role: Role| -> Result<(), SceneError> {
        let property = &element.properties[index];
        if let Kind::List { .. } = property.kind {
            return Err(SceneError::at_line(
                path,
                element.line,
                format!("vertex property `{}` must be a scalar, not a list", property.name),
            ));
        }
        roles[index] = role;
        Ok(())
    };
    for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
        let index = find(name).ok_or_else(|| {
            SceneError::at_line(path, element.line, format!("the vertex element has no `{name}` property"))
        })?;
        assign(index, Role::Position(axis))?;
    }
    let normal = ["nx", "ny", "nz"].map(find);
    match normal {
        [Some(x), Some(y), Some(z)] => {
            assign(x, Role::Normal(0))?;
            assign(y, Role::Normal(1))?;
            assign(z, Role::Normal(2))?;
        }
        [None, None, None] => {}
        _ => {
            return Err(SceneError::at_line(
                path,
                element.line,
                "the vertex element has some of `nx`, `ny`, `nz` but not all three",
            ));
        }
    }
    if let Some((u, v)) = UV_NAMES.iter().find_map(|(u, v)| Some((find(u)?, find(v)?))) {
        assign(u, Role::Uv(0))?;
        assign(v, Role::Uv(1))?;
    }
    Ok(roles)
}

/// For the face element: which property is the vertex index list (the others are skipped).
fn face_roles(element: &Element, path: &Path) -> Result<Vec<FaceRole>, SceneError> {
    let index = element
        .properties
        .iter()
        .position(|p| p.name == "vertex_indices")
        .or_else(|| element.properties.iter().position(|p| p.name == "vertex_index"))
        .ok_or_else(|| SceneError::at_line(path, element.line, "the face element has no `vertex_indices` list"))?;
    match element.properties[index].kind {
        Kind::List { item, .. } if item.is_integer() => {}
        Kind::List { item, .. } => {
            return Err(SceneError::at_line(
                path,
                element.line,
                format!("vertex indices must have an integer type, not `{item}`"),
            ));
        }
        Kind::Scalar(_) => {
            return Err(SceneError::at_line(
                path,
                element.line,
                format!("face property `{}` must be a list", element.properties[index].name),
            ));
        }
    }
    Ok((0..element.properties.len()).map(|i| if i == index { FaceRole::Indices } else { FaceRole::Skip }).collect())
}

/// Reads one value of instance `i` of `element`, turning failures into errors.
fn value<S: Source>(source: &mut S, scalar: Scalar, element: &Element, i: u64) -> Result<f64, SceneError> {
    source.value(scalar).map_err(|fail| match fail {
        Fail::End => source.end_error(format!(
            "the file ends inside {} {} of the {} the header declares",
            element.name,
            i,
            match element.name.as_str() {
                "vertex" => plural(element.count, "vertex", "vertices"),
                "face" => plural(element.count, "face", "faces"),
                name => plural(element.count, &format!("`{name}` element"), &format!("`{name}` elements")),
            },
        )),
        Fail::Syntax(message) => source.error(format!("{message} in {} {i}", element.name)),
    })
}

/// Reads a list count: a non-negative integer.
fn list_count<S: Source>(source: &mut S, scalar: Scalar, element: &Element, i: u64) -> Result<u64, SceneError> {
    let count = value(source, scalar, element, i)?;
    if count < 0.0 {
        return Err(source.error(format!("negative list length {count} in {} {i}", element.name)));
    }
    Ok(count as u64)
}

fn skip_property<S: Source>(source: &mut S, kind: Kind, element: &Element, i: u64) -> Result<(), SceneError> {
    match kind {
        Kind::Scalar(s) => {
            value(source, s, element, i)?;
        }
        Kind::List { count, item } => {
            let n = list_count(source, count, element, i)?;
            // Every value takes at least one byte, so this loop ends with the data.
            for _ in 0..n {
                value(source, item, element, i)?;
            }
        }
    }
    Ok(())
}

fn read_vertices<S: Source>(
    source: &mut S,
    element: &Element,
    roles: &[Role],
    has_normals: bool,
    has_uvs: bool,
    mesh: &mut MeshData,
) -> Result<(), SceneError> {
    // The count was checked against the data size.
    let count = element.count as usize;
    mesh.positions.reserve_exact(count);
    if has_normals {
        mesh.normals.reserve_exact(count);
    }
    if has_uvs {
        mesh.uvs.reserve_exact(count);
    }
    let mut attribute = vec![[0.0f32; 3]; mesh.attributes.len()];
    for a in &mut mesh.attributes {
        a.values.reserve_exact(count);
    }
    for i in 0..element.count {
        let mut position = [0.0f32; 3];
        let mut normal = [0.0f32; 3];
        let mut uv = [0.0f32; 2];
        for (property, &role) in element.properties.iter().zip(roles) {
            let scalar = match (property.kind, role) {
                (Kind::Scalar(s), _) => s,
                (kind, _) => {
                    skip_property(source, kind, element, i)?;
                    continue;
                }
            };
            let raw = value(source, scalar, element, i)?;
            let x = raw as f32;
            match role {
                Role::Attribute(slot, channel) => {
                    attribute[slot][channel] = attribute_value(source, raw, scalar, element, i, property)?;
                }
                Role::Position(axis) => {
                    if !x.is_finite() {
                        return Err(source.error(format!("vertex {i} has a non-finite position")));
                    }
                    position[axis] = x;
                }
                Role::Normal(axis) => normal[axis] = x,
                Role::Uv(axis) => {
                    if !x.is_finite() {
                        return Err(source.error(format!("vertex {i} has a non-finite texture coordinate")));
                    }
                    uv[axis] = x;
                }
                Role::Skip => {}
            }
        }
        mesh.positions.push(Vec3::from_array(position));
        if has_normals {
            mesh.normals.push(Vec3::from_array(normal));
        }
        if has_uvs {
            mesh.uvs.push(Vec2::from_array(uv));
        }
        push_attributes(mesh, &attribute);
    }
    Ok(())
}

/// Appends one value to each vertex attribute of `mesh` (a one-component value in all
/// channels).
fn push_attributes(mesh: &mut MeshData, values: &[[f32; 3]]) {
    for (a, v) in mesh.attributes.iter_mut().zip(values).filter(|(a, _)| !a.per_face()) {
        a.values.push(if a.components == 1 { Rgb::splat(v[0]) } else { Rgb::from_array(*v) });
    }
}

/// An attribute's value ([`attributes::value`]); non-finite values are errors.
fn attribute_value<S: Source>(
    source: &S,
    raw: f64,
    scalar: Scalar,
    element: &Element,
    i: u64,
    property: &Property,
) -> Result<f32, SceneError> {
    let x = attributes::value(raw, scalar);
    if !x.is_finite() {
        return Err(source.error(format!("{} {i} has a non-finite `{}`", element.name, property.name)));
    }
    Ok(x)
}

fn read_faces<S: Source>(
    source: &mut S,
    element: &Element,
    roles: &[FaceRole],
    vertex_count: u64,
    mesh: &mut MeshData,
) -> Result<(), SceneError> {
    // The count was checked against the data size; a fan has at least one triangle.
    mesh.triangles.reserve(element.count as usize);
    let mut face = Vec::new();
    let mut attribute = vec![[0.0f32; 3]; mesh.attributes.len()];
    let first_face_attribute = mesh.attributes.iter().position(MeshAttribute::per_face).unwrap_or(usize::MAX);
    for i in 0..element.count {
        face.clear();
        for (property, &role) in element.properties.iter().zip(roles) {
            if let (FaceRole::Attribute(slot, channel), Kind::Scalar(scalar)) = (role, property.kind) {
                let raw = value(source, scalar, element, i)?;
                attribute[slot][channel] = attribute_value(source, raw, scalar, element, i, property)?;
                continue;
            }
            let (Kind::List { count, item }, FaceRole::Indices) = (property.kind, role) else {
                skip_property(source, property.kind, element, i)?;
                continue;
            };
            let n = list_count(source, count, element, i)?;
            if n < 3 {
                return Err(source.error(format!("face {i} has {n} vertices (at least 3 are needed)")));
            }
            for _ in 0..n {
                let index = value(source, item, element, i)?;
                if index < 0.0 || index >= vertex_count as f64 {
                    return Err(source.error(format!(
                        "face {i} refers to vertex {index} but the header declares {}",
                        plural(vertex_count, "vertex", "vertices")
                    )));
                }
                face.push(index as u32);
            }
        }
        // One triangle per fan corner, each with the face's attribute values.
        for k in 1..face.len() - 1 {
            mesh.triangles.push([face[0], face[k], face[k + 1]]);
            for (a, v) in mesh.attributes.iter_mut().zip(&attribute).skip(first_face_attribute) {
                a.values.push(if a.components == 1 { Rgb::splat(v[0]) } else { Rgb::from_array(*v) });
            }
        }
    }
    Ok(())
}
