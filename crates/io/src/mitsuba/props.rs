//! The properties of one plugin element (`<bsdf type=…>`, `<shape type=…>`, …): typed values
//! parsed from the child elements, nested objects, and typed getters that report the wrong
//! type, bad numbers and missing required values with the element's position. Properties
//! nobody asked for become warnings.

use std::cell::Cell;

use std::sync::Arc;

use scene::desc::EmissionSpectrum;
use spectrum::tabulated::Tabulated;

use super::colour::{SpectrumUse, blackbody_to_rgb, constant_spectrum_to_rgb, spectrum_to_rgb};
use super::transform::Mat4;
use super::xml::{Node, Pos};
use crate::scene_error::SceneError;

/// Tags of nested plugin objects.
pub(crate) const OBJECT_TAGS: [&str; 12] = [
    "bsdf",
    "texture",
    "emitter",
    "shape",
    "sensor",
    "film",
    "rfilter",
    "sampler",
    "integrator",
    "medium",
    "phase",
    "volume",
];

/// A parsed property value.
#[derive(Clone, Debug)]
pub(crate) enum Value {
    Integer(i64),
    Float(f64),
    Boolean(bool),
    Str(String),
    Rgb([f64; 3]),
    /// A constant `<spectrum value="v">`.
    SpectrumConstant(f64),
    /// Wavelength (nm) / value pairs, strictly increasing wavelengths.
    SpectrumTable(Vec<(f64, f64)>),
    /// Planck's law (W·m⁻²·sr⁻¹·nm⁻¹) at `kelvin` times `scale`: `<spectrum type="blackbody">`
    /// (Mitsuba 3) or `<blackbody temperature=… scale=…/>` (the older short form).
    Blackbody {
        /// Temperature (K, > 0).
        kelvin: f64,
        /// Factor (≥ 0).
        scale: f64,
    },
    /// `<point>` or `<vector>`.
    Vector([f64; 3]),
    Transform(Mat4),
}

impl Value {
    fn type_name(&self) -> &'static str {
        match self {
            Value::Integer(_) => "integer",
            Value::Float(_) => "float",
            Value::Boolean(_) => "boolean",
            Value::Str(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::SpectrumConstant(_) | Value::SpectrumTable(_) | Value::Blackbody { .. } => "spectrum",
            Value::Vector(_) => "point/vector",
            Value::Transform(_) => "transform",
        }
    }
}

/// A named property.
pub(crate) struct Prop {
    pub name: String,
    pub value: Value,
    pub pos: Pos,
    used: Cell<bool>,
}

/// A nested object (`<bsdf>`, `<texture>`, `<emitter>`, …) or an object reference
/// (`<ref id=…>`), with its optional `name`.
pub(crate) struct Object<'a> {
    pub name: Option<String>,
    pub node: &'a Node,
    used: Cell<bool>,
}

impl Object<'_> {
    /// Marks the object as handled.
    pub fn take(&self) {
        self.used.set(true);
    }

    /// Whether the object has been handled.
    pub fn is_taken(&self) -> bool {
        self.used.get()
    }
}

/// A plugin element with its properties.
pub(crate) struct Plugin<'a> {
    /// Element tag (`bsdf`, `shape`, …).
    pub class: String,
    /// The `type` attribute.
    pub ty: String,
    /// The element.
    pub node: &'a Node,
    props: Vec<Prop>,
    /// Nested objects and references, in document order.
    pub objects: Vec<Object<'a>>,
}

impl<'a> Plugin<'a> {
    /// Parses the properties of `node`.
    pub fn new(node: &'a Node) -> Result<Plugin<'a>, SceneError> {
        let ty = node.required_attr("type")?.to_string();
        if node.tag == "texture" && ty == "volume" {
            return Err(node.pos.error("<texture type=\"volume\"> (a texture read from volume data) is not supported"));
        }
        let mut plugin = Plugin { class: node.tag.clone(), ty, node, props: Vec::new(), objects: Vec::new() };
        for child in &node.children {
            let name = child.attr("name").map(str::to_string);
            if OBJECT_TAGS.contains(&child.tag.as_str()) || child.tag == "ref" {
                if child.tag == "ref" {
                    child.required_attr("id")?;
                }
                if let Some(n) = &name {
                    plugin.check_duplicate(n, &child.pos)?;
                }
                plugin.objects.push(Object { name, node: child, used: Cell::new(false) });
                continue;
            }
            let value = parse_value(child)?;
            let name = child.required_attr("name")?.to_string();
            plugin.check_duplicate(&name, &child.pos)?;
            plugin.props.push(Prop { name, value, pos: child.pos.clone(), used: Cell::new(false) });
        }
        Ok(plugin)
    }

    fn check_duplicate(&self, name: &str, pos: &Pos) -> Result<(), SceneError> {
        let earlier = self
            .props
            .iter()
            .find(|p| p.name == name)
            .map(|p| &p.pos)
            .or_else(|| self.objects.iter().find(|o| o.name.as_deref() == Some(name)).map(|o| &o.node.pos));
        match earlier {
            Some(first) => {
                Err(pos.error(format!("property '{name}' is specified twice (first at {})", first.location())))
            }
            None => Ok(()),
        }
    }

    /// What this plugin is called in messages: `bsdf 'diffuse'`.
    pub fn what(&self) -> String {
        format!("{} '{}'", self.class, self.ty)
    }

    /// An error at the plugin element.
    pub fn error(&self, message: impl std::fmt::Display) -> SceneError {
        self.node.pos.error(format!("{}: {message}", self.what()))
    }

    /// Whether a property or named object `name` exists.
    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name) || self.objects.iter().any(|o| o.name.as_deref() == Some(name))
    }

    /// The property `name`, marked as used.
    pub fn prop(&self, name: &str) -> Option<&Prop> {
        let p = self.props.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// The named nested object or reference `name`, marked as used.
    pub fn named_object(&self, name: &str) -> Option<&Object<'a>> {
        let o = self.objects.iter().find(|o| o.name.as_deref() == Some(name))?;
        o.take();
        Some(o)
    }

    fn wrong_type(&self, prop: &Prop, expected: &str) -> SceneError {
        prop.pos.error(format!(
            "{}: property '{}' has the wrong type (expected {expected}, got {})",
            self.what(),
            prop.name,
            prop.value.type_name()
        ))
    }

    /// A float property (integers are accepted).
    pub fn float(&self, name: &str) -> Result<Option<f64>, SceneError> {
        if let Some(o) = self.named_object(name) {
            return Err(o
                .node
                .pos
                .error(format!("{}: property '{name}' must be a number, not a texture", self.what())));
        }
        match self.prop(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Float(v) => Ok(Some(v)),
                Value::Integer(v) => Ok(Some(v as f64)),
                _ => Err(self.wrong_type(p, "float")),
            },
        }
    }

    /// A float property with a default.
    pub fn float_or(&self, name: &str, default: f64) -> Result<f64, SceneError> {
        Ok(self.float(name)?.unwrap_or(default))
    }

    /// A required float property.
    pub fn float_required(&self, name: &str) -> Result<f64, SceneError> {
        self.float(name)?.ok_or_else(|| self.error(format!("missing required float property '{name}'")))
    }

    /// An integer property.
    pub fn integer(&self, name: &str) -> Result<Option<i64>, SceneError> {
        match self.prop(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Integer(v) => Ok(Some(v)),
                _ => Err(self.wrong_type(p, "integer")),
            },
        }
    }

    /// A boolean property with a default.
    pub fn boolean_or(&self, name: &str, default: bool) -> Result<bool, SceneError> {
        match self.prop(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Boolean(v) => Ok(v),
                _ => Err(self.wrong_type(p, "boolean")),
            },
        }
    }

    /// A string property.
    pub fn string(&self, name: &str) -> Result<Option<&str>, SceneError> {
        match self.prop(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::Str(v) => Ok(Some(v.as_str())),
                _ => Err(self.wrong_type(p, "string")),
            },
        }
    }

    /// A required string property.
    pub fn string_required(&self, name: &str) -> Result<&str, SceneError> {
        self.string(name)?.ok_or_else(|| self.error(format!("missing required string property '{name}'")))
    }

    /// A point or vector property.
    pub fn vector(&self, name: &str) -> Result<Option<[f64; 3]>, SceneError> {
        match self.prop(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Vector(v) => Ok(Some(v)),
                _ => Err(self.wrong_type(p, "point or vector")),
            },
        }
    }

    /// A transform property.
    pub fn transform(&self, name: &str) -> Result<Option<Mat4>, SceneError> {
        match self.prop(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Transform(m) => Ok(Some(m)),
                _ => Err(self.wrong_type(p, "transform")),
            },
        }
    }

    /// A colour property (`rgb`, `spectrum`, or a number for a grey) as linear RGB. Tabulated
    /// spectra are converted as `usage` says; clamping adds a warning.
    pub fn color(
        &self,
        name: &str,
        usage: SpectrumUse,
        warnings: &mut Vec<String>,
    ) -> Result<Option<[f64; 3]>, SceneError> {
        if let Some(o) = self.named_object(name) {
            return Err(o
                .node
                .pos
                .error(format!("{}: property '{name}' must be a colour, not a texture", self.what())));
        }
        let Some(p) = self.prop(name) else { return Ok(None) };
        let rgb = match &p.value {
            Value::Float(v) => [*v; 3],
            Value::Integer(v) => [*v as f64; 3],
            Value::Rgb(v) => *v,
            Value::SpectrumConstant(v) => constant_spectrum_to_rgb(*v, usage),
            Value::SpectrumTable(table) => {
                let (rgb, clamped) = spectrum_to_rgb(table, usage);
                if clamped {
                    warnings.push(format!(
                        "{}: {}: spectrum '{name}' is outside the sRGB gamut; clamped to {:?}",
                        p.pos.location(),
                        self.what(),
                        rgb
                    ));
                }
                rgb
            }
            Value::Blackbody { kelvin, scale } => {
                if usage != SpectrumUse::Emission {
                    return Err(p.pos.error(format!(
                        "{}: property '{name}': a blackbody spectrum can only be emitted",
                        self.what()
                    )));
                }
                blackbody_to_rgb(*kelvin, *scale)
            }
            _ => return Err(self.wrong_type(p, "rgb, spectrum or float")),
        };
        if rgb.iter().any(|v| !v.is_finite()) {
            return Err(p.pos.error(format!("{}: property '{name}' is not finite", self.what())));
        }
        Ok(Some(rgb))
    }

    /// The spectrum of an emitted colour property `name` (read after [`Plugin::color`]), when
    /// the file gives one: a tabulated spectrum, a constant `<spectrum value="c"/>` (emitting
    /// `c` at every wavelength of 360–830 nm, as Mitsuba's spectral variants do) or a
    /// blackbody. `rgb` and plain numbers have none (spectral rendering upsamples them).
    pub fn emission_spectrum(&self, name: &str) -> Result<Option<EmissionSpectrum>, SceneError> {
        let Some(p) = self.prop(name) else { return Ok(None) };
        let table = |pairs: &[(f64, f64)]| -> Result<EmissionSpectrum, SceneError> {
            let points: Vec<(f32, f32)> = pairs.iter().map(|&(l, v)| (l as f32, v as f32)).collect();
            let t =
                Tabulated::new(&points).map_err(|e| p.pos.error(format!("{}: property '{name}': {e}", self.what())))?;
            Ok(EmissionSpectrum::Tabulated(Arc::new(t)))
        };
        let spectrum = match &p.value {
            Value::SpectrumTable(pairs) => table(pairs)?,
            Value::SpectrumConstant(c) => table(&[(360.0, *c), (830.0, *c)])?,
            Value::Blackbody { kelvin, scale } => {
                EmissionSpectrum::Blackbody { kelvin: *kelvin as f32, scale: *scale as f32 }
            }
            _ => return Ok(None),
        };
        spectrum.validate().map_err(|e| p.pos.error(format!("{}: property '{name}': {e}", self.what())))?;
        Ok(Some(spectrum))
    }

    /// Marks properties that do not influence the rendered image as used, so that they
    /// raise no warning.
    pub fn ignore(&self, names: &[&str]) {
        for p in &self.props {
            if names.contains(&p.name.as_str()) {
                p.used.set(true);
            }
        }
    }

    /// Adds a warning for every property and nested object nobody used.
    pub fn finish(&self, warnings: &mut Vec<String>) {
        for p in self.props.iter().filter(|p| !p.used.get()) {
            warnings.push(format!("{}: {}: unsupported property '{}' ignored", p.pos.location(), self.what(), p.name));
        }
        for o in self.objects.iter().filter(|o| !o.used.get()) {
            let name = o.name.as_deref().map(|n| format!(" '{n}'")).unwrap_or_default();
            warnings.push(format!("{}: {}: nested <{}>{name} ignored", o.node.pos.location(), self.what(), o.node.tag));
        }
    }
}

/// Parses one property element.
fn parse_value(node: &Node) -> Result<Value, SceneError> {
    let name = node.attr("name").unwrap_or("?");
    let value_attr = || node.required_attr("value");
    let numbers = |text: &str| parse_numbers(text, node, name);
    Ok(match node.tag.as_str() {
        "integer" => {
            let text = value_attr()?;
            Value::Integer(
                text.trim().parse::<i64>().map_err(|_| {
                    node.pos.error(format!("integer '{name}': bad number '{text}' (expected an integer)"))
                })?,
            )
        }
        "float" => {
            let text = value_attr()?;
            Value::Float(parse_number(text, node, name)?)
        }
        "boolean" => {
            let text = value_attr()?;
            match text.trim().to_ascii_lowercase().as_str() {
                "true" => Value::Boolean(true),
                "false" => Value::Boolean(false),
                _ => {
                    return Err(node
                        .pos
                        .error(format!("boolean '{name}': bad value '{text}' (expected true or false)")));
                }
            }
        }
        "string" => Value::Str(value_attr()?.to_string()),
        "rgb" | "color" => {
            let v = numbers(value_attr()?)?;
            match v.as_slice() {
                [g] => Value::Rgb([*g; 3]),
                [r, g, b] => Value::Rgb([*r, *g, *b]),
                _ => {
                    return Err(node.pos.error(format!(
                        "rgb '{name}': expected one or three values, got {} in '{}'",
                        v.len(),
                        value_attr()?
                    )));
                }
            }
        }
        "spectrum" => parse_spectrum(node, name)?,
        "blackbody" => {
            let text = node.required_attr("temperature")?;
            let kelvin = text.trim().strip_suffix(['K', 'k']).unwrap_or(text);
            let kelvin = parse_number(kelvin, node, name)?;
            let scale = match node.attr("scale") {
                Some(v) => parse_number(v, node, name)?,
                None => 1.0,
            };
            blackbody(node, name, kelvin, scale)?
        }
        "point" | "vector" => parse_vector(node, name, 0.0)?,
        "transform" => Value::Transform(parse_transform(node)?),
        other => return Err(node.pos.error(format!("unknown element <{other}>"))),
    })
}

/// One number, with an error naming the property.
pub(crate) fn parse_number(text: &str, node: &Node, name: &str) -> Result<f64, SceneError> {
    let t = text.trim();
    t.parse::<f64>().map_err(|_| node.pos.error(format!("<{}> '{name}': bad number '{t}'", node.tag)))
}

/// Numbers separated by commas and/or whitespace.
pub(crate) fn parse_numbers(text: &str, node: &Node, name: &str) -> Result<Vec<f64>, SceneError> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| parse_number(s, node, name))
        .collect()
}

/// `x`, `y`, `z` attributes (default `default`) or a `value` of three numbers.
fn parse_xyz(node: &Node, name: &str, default: f64) -> Result<[f64; 3], SceneError> {
    if let Some(v) = node.attr("value") {
        let n = parse_numbers(v, node, name)?;
        return match n.as_slice() {
            [x, y, z] => Ok([*x, *y, *z]),
            _ => Err(node.pos.error(format!("<{}> '{name}': expected three values, got '{v}'", node.tag))),
        };
    }
    let mut out = [default; 3];
    for (i, axis) in ["x", "y", "z"].iter().enumerate() {
        if let Some(v) = node.attr(axis) {
            out[i] = parse_number(v, node, name)?;
        }
    }
    Ok(out)
}

fn parse_vector(node: &Node, name: &str, default: f64) -> Result<Value, SceneError> {
    Ok(Value::Vector(parse_xyz(node, name, default)?))
}

/// A checked blackbody value.
fn blackbody(node: &Node, name: &str, kelvin: f64, scale: f64) -> Result<Value, SceneError> {
    if !(kelvin.is_finite() && kelvin > 0.0) {
        return Err(node.pos.error(format!("blackbody '{name}': the temperature must be positive, got {kelvin} K")));
    }
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(node.pos.error(format!("blackbody '{name}': the scale must be non-negative, got {scale}")));
    }
    Ok(Value::Blackbody { kelvin, scale })
}

/// `<spectrum type="blackbody">` with `<float name="temperature">` (required) and
/// `<float name="scale">` (our addition, default 1) inside.
fn parse_typed_spectrum(node: &Node, name: &str, ty: &str) -> Result<Value, SceneError> {
    if ty != "blackbody" {
        return Err(node.pos.error(format!("spectrum '{name}': unsupported spectrum type '{ty}' (blackbody is)")));
    }
    let (mut kelvin, mut scale) = (None, 1.0);
    for child in &node.children {
        let field = child.required_attr("name")?;
        let value = match parse_value(child)? {
            Value::Float(v) => v,
            Value::Integer(v) => v as f64,
            _ => return Err(child.pos.error(format!("blackbody '{name}': '{field}' must be a float"))),
        };
        match field {
            "temperature" => kelvin = Some(value),
            "scale" => scale = value,
            other => {
                return Err(child.pos.error(format!(
                    "blackbody '{name}': unknown parameter '{other}' (temperature and scale are known)"
                )));
            }
        }
    }
    let kelvin = kelvin.ok_or_else(|| node.pos.error(format!("blackbody '{name}': missing float 'temperature'")))?;
    blackbody(node, name, kelvin, scale)
}

fn parse_spectrum(node: &Node, name: &str) -> Result<Value, SceneError> {
    if let Some(ty) = node.attr("type") {
        return parse_typed_spectrum(node, name, ty);
    }
    let pairs: Vec<(f64, f64)> = if let Some(filename) = node.attr("filename") {
        let dir = node.pos.file.parent().map(|d| d.join(filename)).unwrap_or_else(|| filename.into());
        crate::trace::opened(&dir);
        let text = std::fs::read_to_string(&dir)
            .map_err(|e| node.pos.error(format!("spectrum '{name}': cannot read '{}': {e}", dir.display())))?;
        let mut pairs = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let n: Vec<f64> =
                line.split_whitespace().map(|s| s.parse::<f64>()).collect::<Result<_, _>>().map_err(|_| {
                    SceneError::at_line(&dir, i as u32 + 1, format!("bad spectrum line '{line}' (expected 'nm value')"))
                })?;
            match n.as_slice() {
                [w, v] => pairs.push((*w, *v)),
                _ => {
                    return Err(SceneError::at_line(
                        &dir,
                        i as u32 + 1,
                        format!("bad spectrum line '{line}' (expected 'nm value')"),
                    ));
                }
            }
        }
        pairs
    } else if let (Some(w), Some(v)) = (node.attr("wavelengths"), node.attr("values")) {
        let w = parse_numbers(w, node, name)?;
        let v = parse_numbers(v, node, name)?;
        if w.len() != v.len() {
            return Err(node.pos.error(format!("spectrum '{name}': {} wavelengths but {} values", w.len(), v.len())));
        }
        w.into_iter().zip(v).collect()
    } else {
        let text = node.required_attr("value")?;
        if !text.contains(':') {
            let v = parse_numbers(text, node, name)?;
            return match v.as_slice() {
                [c] => Ok(Value::SpectrumConstant(*c)),
                _ => Err(node
                    .pos
                    .error(format!("spectrum '{name}': expected one value or 'wavelength:value' pairs, got '{text}'"))),
            };
        }
        let mut pairs = Vec::new();
        for token in text.split(',').flat_map(str::split_whitespace) {
            let Some((w, v)) = token.split_once(':') else {
                return Err(node
                    .pos
                    .error(format!("spectrum '{name}': bad entry '{token}' (expected wavelength:value)")));
            };
            pairs.push((parse_number(w, node, name)?, parse_number(v, node, name)?));
        }
        pairs
    };
    if pairs.len() < 2 {
        return Err(node.pos.error(format!("spectrum '{name}': needs at least two wavelength:value pairs")));
    }
    if pairs.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err(node.pos.error(format!("spectrum '{name}': wavelengths must increase strictly")));
    }
    if pairs.iter().any(|(w, v)| !w.is_finite() || !v.is_finite()) {
        return Err(node.pos.error(format!("spectrum '{name}': non-finite entry")));
    }
    Ok(Value::SpectrumTable(pairs))
}

/// A `<transform>`: its operations composed in document order (a later operation is applied
/// after the earlier ones: `M = op_n ⋯ op_1`).
pub(crate) fn parse_transform(node: &Node) -> Result<Mat4, SceneError> {
    let mut m = Mat4::IDENTITY;
    for op in &node.children {
        let name = op.tag.as_str();
        let step = match name {
            "translate" => Mat4::translate(parse_xyz(op, name, 0.0)?),
            "scale" => {
                if let Some(v) = op.attr("value") {
                    let n = parse_numbers(v, op, name)?;
                    match n.as_slice() {
                        [s] => Mat4::scale([*s; 3]),
                        [x, y, z] => Mat4::scale([*x, *y, *z]),
                        _ => return Err(op.pos.error(format!("<scale>: expected one or three values, got '{v}'"))),
                    }
                } else {
                    Mat4::scale(parse_xyz(op, name, 1.0)?)
                }
            }
            "rotate" => {
                let angle = parse_number(op.required_attr("angle")?, op, name)?;
                let axis = parse_xyz(op, name, 0.0)?;
                Mat4::rotate(axis, angle)
                    .ok_or_else(|| op.pos.error("<rotate>: the rotation axis is zero (give x, y, z or value)"))?
            }
            "matrix" => {
                let text = op.required_attr("value")?;
                let n = parse_numbers(text, op, name)?;
                match n.len() {
                    16 => Mat4 { m: [0, 1, 2, 3].map(|r| [0, 1, 2, 3].map(|c| n[4 * r + c])) },
                    9 => {
                        let mut r = Mat4::IDENTITY;
                        for i in 0..3 {
                            for j in 0..3 {
                                r.m[i][j] = n[3 * i + j];
                            }
                        }
                        r
                    }
                    k => return Err(op.pos.error(format!("<matrix>: expected 16 (or 9) values, got {k}"))),
                }
            }
            "lookat" => {
                let read = |attr: &str| -> Result<[f64; 3], SceneError> {
                    let text = op.required_attr(attr)?;
                    let n = parse_numbers(text, op, attr)?;
                    match n.as_slice() {
                        [x, y, z] => Ok([*x, *y, *z]),
                        _ => Err(op.pos.error(format!("<lookat> '{attr}': expected three values, got '{text}'"))),
                    }
                };
                let origin = read("origin")?;
                let target = read("target")?;
                let up = match op.attr("up") {
                    Some(_) => read("up")?,
                    None => [0.0, 1.0, 0.0],
                };
                Mat4::look_at(origin, target, up).ok_or_else(|| {
                    op.pos.error("<lookat>: origin equals target, or 'up' is parallel to the viewing direction")
                })?
            }
            other => return Err(op.pos.error(format!("unknown transform operation <{other}>"))),
        };
        m = step.mul(&m);
    }
    if !m.is_affine() {
        return Err(node.pos.error("transform is not a finite affine transform"));
    }
    Ok(m)
}
