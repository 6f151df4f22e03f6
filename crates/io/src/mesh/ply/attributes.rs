//! PLY properties beyond positions, normals, uvs and face indices, grouped into named mesh
//! attributes as Mitsuba 3 groups them (see [`super::super::parse_ply`]).

use super::{Element, Kind, Scalar};

/// A mesh attribute found in the header: its name and the indices of its properties (1 or 3)
/// in the element.
#[derive(Debug)]
pub(super) struct Group {
    /// `vertex_<name>` or `face_<name>`.
    pub name: String,
    /// Property indices, one per component.
    pub properties: Vec<usize>,
}

/// Consecutive properties `<prefix>_<s>` being grouped.
struct Run {
    prefix: String,
    /// Row of [`SUFFIXES`].
    row: usize,
    properties: Vec<usize>,
    /// A suffix was out of sequence.
    broken: bool,
}

/// Suffix categories: a multi-component attribute's properties are `<prefix>_<s>` with the
/// suffixes `s` of one row, in order.
const SUFFIXES: [[char; 4]; 4] =
    [['x', 'y', 'z', 'w'], ['r', 'g', 'b', 'a'], ['0', '1', '2', '3'], ['1', '2', '3', '4']];

/// The attributes of `element`, whose properties marked in `taken` are already used: `r g b`
/// (or `red green blue`, an alpha channel dropped) becomes `<kind>color`; consecutive scalar
/// properties `<prefix>_<s>` with the suffixes of one row of [`SUFFIXES`] become
/// `<kind><prefix>` (`<kind><prefix>_color` for the `r g b a` row) when there are 1 or 3 of
/// them. Other properties (lists, names without a one-character suffix, groups of 2 or 4) are
/// not attributes. `kind` is `vertex_` or `face_`.
pub(super) fn groups(element: &Element, taken: &[bool], kind: &str) -> Vec<Group> {
    let free = |i: usize| !taken[i] && matches!(element.properties[i].kind, Kind::Scalar(_));
    let find = |name: &str| element.properties.iter().position(|p| p.name == name).filter(|&i| free(i));
    let mut used: Vec<bool> = taken.to_vec();
    let mut groups: Vec<Group> = Vec::new();
    for (names, alpha) in [(["r", "g", "b"], "a"), (["red", "green", "blue"], "alpha")] {
        if let [Some(r), Some(g), Some(b)] = names.map(find) {
            groups.push(Group { name: format!("{kind}color"), properties: vec![r, g, b] });
            for i in [r, g, b].into_iter().chain(find(alpha)) {
                used[i] = true;
            }
            break;
        }
    }
    let mut run: Option<Run> = None;
    let flush = |run: &mut Option<Run>, groups: &mut Vec<Group>| {
        if let Some(Run { prefix, row, properties, broken: false }) = run.take()
            && (properties.len() == 1 || properties.len() == 3)
        {
            let name = format!("{kind}{prefix}{}", if row == 1 { "_color" } else { "" });
            if !groups.iter().any(|g| g.name == name) {
                groups.push(Group { name, properties });
            }
        }
    };
    for (i, property) in element.properties.iter().enumerate() {
        if used[i] || !free(i) {
            flush(&mut run, &mut groups);
            continue;
        }
        let split = property.name.rsplit_once('_').and_then(|(prefix, suffix)| {
            let mut chars = suffix.chars();
            match (chars.next(), chars.next()) {
                (Some(c), None) if !prefix.is_empty() => Some((prefix, c)),
                _ => None,
            }
        });
        let Some((prefix, suffix)) = split else {
            flush(&mut run, &mut groups);
            continue;
        };
        if let Some(r) = &mut run
            && r.prefix == prefix
        {
            // Out of sequence: the whole run is not an attribute.
            r.broken |= SUFFIXES[r.row].get(r.properties.len()) != Some(&suffix);
            r.properties.push(i);
            continue;
        }
        flush(&mut run, &mut groups);
        if let Some(row) = SUFFIXES.iter().position(|row| row[0] == suffix) {
            run = Some(Run { prefix: prefix.to_owned(), row, properties: vec![i], broken: false });
        }
    }
    flush(&mut run, &mut groups);
    groups
}

/// An attribute value as Mitsuba reads it: floats as they are; integers normalised by their
/// type's largest value and sRGB-decoded (uchar `255` is 1, `128` is 0.216).
pub(super) fn value(x: f64, scalar: Scalar) -> f32 {
    if !scalar.is_integer() {
        return x as f32;
    }
    let normalised = x / scalar.range().1 as f64;
    (crate::srgb_eotf(normalised.abs()) * normalised.signum()) as f32
}
