//! Directives and their parameter lists, read from the token stream.
//!
//! Every directive has a fixed list of positional arguments (numbers, strings or a bare word)
//! and, for most, a parameter list of `"type name" value` or `"type name" [values]` entries.

use std::cell::Cell;
use std::path::{Path, PathBuf};

use crate::pbrt::tokenizer::{Pos, Token, TokenKind};
use crate::scene_error::SceneError;

/// One parameter value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// A number.
    Num(f64),
    /// A string.
    Str(String),
    /// A boolean (`true`/`false`, bare or quoted).
    Bool(bool),
}

/// A parameter: `"type name" values`.
#[derive(Debug)]
pub struct Param {
    /// Declared type (`float`, `rgb`, …; `point`/`normal`/`vector`/`color` are normalised to
    /// `point3`/`normal3`/`vector3`/`rgb`).
    pub ty: String,
    /// Name.
    pub name: String,
    /// Values.
    pub values: Vec<Value>,
    /// Where the declaration string starts.
    pub pos: Pos,
    used: Cell<bool>,
}

impl Param {
    /// The values as numbers (all values are numbers for the numeric types).
    pub fn numbers(&self) -> Vec<f64> {
        self.values.iter().filter_map(|v| if let Value::Num(x) = v { Some(*x) } else { None }).collect()
    }

    /// The values as strings.
    pub fn strings(&self) -> Vec<String> {
        self.values.iter().filter_map(|v| if let Value::Str(s) = v { Some(s.clone()) } else { None }).collect()
    }
}

/// The parameters of one directive, with the file and a description of the directive for
/// messages. Lookups mark parameters as used; [`ParamSet::unused`] lists the others.
#[derive(Debug)]
pub struct ParamSet {
    /// The file the directive is in.
    pub file: PathBuf,
    /// The directive and its type, e.g. `Shape "sphere"`, for messages.
    pub context: String,
    /// The parameters in file order.
    pub params: Vec<Param>,
}

/// A positional argument.
#[derive(Clone, Debug, PartialEq)]
pub enum Arg {
    /// A number.
    Num(f64),
    /// A quoted string.
    Str(String),
    /// A bare word (`ActiveTransform All`).
    Word(String),
}

/// A directive with its arguments and parameters.
#[derive(Debug)]
pub struct Directive {
    /// Directive name, e.g. `Shape`.
    pub name: String,
    /// Where the name starts.
    pub pos: Pos,
    /// Positional arguments.
    pub args: Vec<Arg>,
    /// Positions of the positional arguments.
    pub arg_pos: Vec<Pos>,
    /// Parameters.
    pub params: ParamSet,
}

impl Directive {
    /// The `i`-th positional argument as a string (the signature guarantees the kind).
    pub fn str_arg(&self, i: usize) -> &str {
        match &self.args[i] {
            Arg::Str(s) | Arg::Word(s) => s,
            Arg::Num(_) => "",
        }
    }

    /// All numeric positional arguments.
    pub fn num_args(&self) -> Vec<f64> {
        self.args.iter().filter_map(|a| if let Arg::Num(x) = a { Some(*x) } else { None }).collect()
    }
}

/// Positional arguments a directive takes.
#[derive(Clone, Copy)]
struct Signature {
    /// Leading numbers (accepted with or without brackets).
    numbers: usize,
    /// Quoted strings after the numbers.
    strings: usize,
    /// Optional extra quoted strings (MediumInterface takes one or two).
    optional_strings: usize,
    /// A bare word.
    word: bool,
    /// Whether a parameter list follows.
    params: bool,
}

const fn sig(numbers: usize, strings: usize, params: bool) -> Signature {
    Signature { numbers, strings, optional_strings: 0, word: false, params }
}

/// The signature of every pbrt-v4 directive, `None` for unknown names.
fn signature(name: &str) -> Option<Signature> {
    Some(match name {
        "WorldBegin" | "WorldEnd" | "AttributeBegin" | "AttributeEnd" | "TransformBegin" | "TransformEnd"
        | "ObjectEnd" | "ReverseOrientation" | "Identity" => sig(0, 0, false),
        "LookAt" => sig(9, 0, false),
        "Translate" | "Scale" => sig(3, 0, false),
        "Rotate" => sig(4, 0, false),
        "Transform" | "ConcatTransform" => sig(16, 0, false),
        "TransformTimes" => sig(2, 0, false),
        "CoordinateSystem" | "CoordSysTransform" | "NamedMaterial" | "Include" | "Import" | "ObjectBegin"
        | "ObjectInstance" | "ColorSpace" => sig(0, 1, false),
        "Camera" | "Film" | "Sampler" | "Integrator" | "PixelFilter" | "Accelerator" | "Shape" | "Material"
        | "MakeNamedMaterial" | "LightSource" | "AreaLightSource" | "MakeNamedMedium" | "Attribute" => sig(0, 1, true),
        "Texture" => sig(0, 3, true),
        "Option" => sig(0, 0, true),
        "MediumInterface" => Signature { numbers: 0, strings: 1, optional_strings: 1, word: false, params: false },
        "ActiveTransform" => Signature { numbers: 0, strings: 0, optional_strings: 0, word: true, params: false },
        _ => return None,
    })
}

/// Reads directives from the tokens of one file.
pub struct Parser<'a> {
    file: &'a Path,
    tokens: Vec<Token>,
    next: usize,
}

impl<'a> Parser<'a> {
    /// A parser over the tokens of `file`.
    pub fn new(file: &'a Path, tokens: Vec<Token>) -> Self {
        Self { file, tokens, next: 0 }
    }

    fn peek(&self) -> Option<&Token> {
        self.tokens.get(self.next)
    }

    fn error(&self, pos: Pos, message: impl Into<String>) -> SceneError {
        SceneError::at(self.file, pos.line, pos.column, message)
    }

    /// Where the file ends (for "expected … but the file ends" messages).
    fn end_pos(&self) -> Pos {
        self.tokens.last().map_or(Pos { line: 1, column: 1 }, |t| t.pos)
    }

    /// The next directive, or `None` at the end of the file.
    pub fn next_directive(&mut self) -> Result<Option<Directive>, SceneError> {
        let Some(token) = self.peek().cloned() else { return Ok(None) };
        self.next += 1;
        let TokenKind::Word(name) = token.kind else {
            return Err(self.error(token.pos, format!("expected a directive, found {}", describe(&token.kind))));
        };
        let Some(signature) = signature(&name) else {
            return Err(self.error(token.pos, format!("unknown directive '{name}'")));
        };
        let mut args = Vec::new();
        let mut arg_pos = Vec::new();
        if signature.numbers > 0 {
            let bracketed = matches!(self.peek(), Some(Token { kind: TokenKind::Open, .. }));
            if bracketed {
                self.next += 1;
            }
            for k in 0..signature.numbers {
                match self.peek().cloned() {
                    Some(Token { kind: TokenKind::Num(x), pos }) => {
                        self.next += 1;
                        args.push(Arg::Num(x));
                        arg_pos.push(pos);
                    }
                    other => {
                        let (pos, found) = other.map_or((self.end_pos(), "the end of the file".to_string()), |t| {
                            (t.pos, describe(&t.kind))
                        });
                        return Err(self.error(
                            pos,
                            format!("{name} expects {} numbers, found {found} after {k}", signature.numbers),
                        ));
                    }
                }
            }
            if bracketed {
                match self.peek().cloned() {
                    Some(Token { kind: TokenKind::Close, .. }) => self.next += 1,
                    other => {
                        let pos = other.map_or(self.end_pos(), |t| t.pos);
                        return Err(self.error(pos, format!("{name} expects ']' after {} numbers", signature.numbers)));
                    }
                }
            }
        }
        for k in 0..signature.strings + signature.optional_strings {
            match self.peek().cloned() {
                Some(Token { kind: TokenKind::Str(s), pos }) => {
                    // A string that is a parameter declaration ends the optional strings.
                    if k >= signature.strings && signature.params && s.contains(' ') {
                        break;
                    }
                    self.next += 1;
                    args.push(Arg::Str(s));
                    arg_pos.push(pos);
                }
                _ if k >= signature.strings => break,
                other => {
                    let (pos, found) = other
                        .map_or((self.end_pos(), "the end of the file".to_string()), |t| (t.pos, describe(&t.kind)));
                    return Err(self.error(pos, format!("{name} expects a quoted string, found {found}")));
                }
            }
        }
        if signature.word {
            match self.peek().cloned() {
                Some(Token { kind: TokenKind::Word(w), pos }) => {
                    self.next += 1;
                    args.push(Arg::Word(w));
                    arg_pos.push(pos);
                }
                other => {
                    let pos = other.map_or(self.end_pos(), |t| t.pos);
                    return Err(self.error(pos, format!("{name} expects StartTime, EndTime or All")));
                }
            }
        }
        let context = match args.first() {
            Some(Arg::Str(s)) => format!("{name} \"{s}\""),
            _ => name.clone(),
        };
        let mut params = ParamSet { file: self.file.to_path_buf(), context, params: Vec::new() };
        if signature.params {
            while let Some(Token { kind: TokenKind::Str(decl), pos }) = self.peek().cloned() {
                self.next += 1;
                let param = self.parameter(&name, &decl, pos)?;
                if params.params.iter().any(|p| p.name == param.name) {
                    return Err(self.error(pos, format!("parameter '{}' given twice", param.name)));
                }
                params.params.push(param);
            }
        }
        // Anything but the next directive here is a stray value.
        if let Some(t) = self.peek()
            && !matches!(&t.kind, TokenKind::Word(w) if w != "true" && w != "false")
        {
            let what = if signature.params { "a parameter declaration" } else { "the next directive" };
            return Err(self.error(t.pos, format!("{name}: unexpected {}, expected {what}", describe(&t.kind))));
        }
        Ok(Some(Directive { name, pos: token.pos, args, arg_pos, params }))
    }

    fn parameter(&mut self, directive: &str, decl: &str, pos: Pos) -> Result<Param, SceneError> {
        let words: Vec<&str> = decl.split_whitespace().collect();
        let [ty, name] = words[..] else {
            return Err(self
                .error(pos, format!("{directive}: expected a parameter declaration \"type name\", found \"{decl}\"")));
        };
        let ty = match ty {
            "point" => "point3",
            "normal" => "normal3",
            "vector" => "vector3",
            "color" => "rgb",
            t @ ("integer" | "float" | "point2" | "vector2" | "point3" | "vector3" | "normal3" | "bool" | "string"
            | "texture" | "rgb" | "spectrum" | "blackbody") => t,
            other => return Err(self.error(pos, format!("unknown parameter type '{other}' in \"{decl}\""))),
        };
        let mut values = Vec::new();
        let value_of = |kind: &TokenKind| -> Option<Value> {
            match kind {
                TokenKind::Num(x) => Some(Value::Num(*x)),
                TokenKind::Str(s) => Some(Value::Str(s.clone())),
                TokenKind::Word(w) if w == "true" => Some(Value::Bool(true)),
                TokenKind::Word(w) if w == "false" => Some(Value::Bool(false)),
                _ => None,
            }
        };
        match self.peek().cloned() {
            Some(Token { kind: TokenKind::Open, .. }) => {
                self.next += 1;
                loop {
                    match self.peek().cloned() {
                        Some(Token { kind: TokenKind::Close, .. }) => {
                            self.next += 1;
                            break;
                        }
                        Some(t) => match value_of(&t.kind) {
                            Some(v) => {
                                self.next += 1;
                                values.push((v, t.pos));
                            }
                            None => {
                                return Err(self.error(
                                    t.pos,
                                    format!("parameter \"{decl}\": unexpected {} in a value list", describe(&t.kind)),
                                ));
                            }
                        },
                        None => return Err(self.error(pos, format!("parameter \"{decl}\": missing ']'"))),
                    }
                }
            }
            Some(t) => match value_of(&t.kind) {
                Some(v) => {
                    self.next += 1;
                    values.push((v, t.pos));
                }
                None => return Err(self.error(t.pos, format!("parameter \"{decl}\" has no value"))),
            },
            None => return Err(self.error(pos, format!("parameter \"{decl}\" has no value"))),
        }
        // Check the value kinds against the declared type.
        for (value, vpos) in &values {
            let ok = match ty {
                "string" | "texture" => matches!(value, Value::Str(_)),
                "bool" => match value {
                    Value::Bool(_) => true,
                    Value::Str(s) => s == "true" || s == "false",
                    Value::Num(_) => false,
                },
                "spectrum" => matches!(value, Value::Num(_) | Value::Str(_)),
                _ => matches!(value, Value::Num(_)),
            };
            if !ok {
                return Err(
                    self.error(*vpos, format!("parameter \"{decl}\": value {} does not fit type '{ty}'", show(value)))
                );
            }
        }
        let values = values
            .into_iter()
            .map(|(v, _)| match v {
                Value::Str(s) if ty == "bool" => Value::Bool(s == "true"),
                v => v,
            })
            .collect();
        Ok(Param { ty: ty.to_string(), name: name.to_string(), values, pos, used: Cell::new(false) })
    }
}

fn show(value: &Value) -> String {
    match value {
        Value::Num(x) => format!("{x}"),
        Value::Str(s) => format!("\"{s}\""),
        Value::Bool(b) => format!("{b}"),
    }
}

fn describe(kind: &TokenKind) -> String {
    match kind {
        TokenKind::Str(s) => format!("string \"{s}\""),
        TokenKind::Num(x) => format!("number {x}"),
        TokenKind::Word(w) => format!("'{w}'"),
        TokenKind::Open => "'['".into(),
        TokenKind::Close => "']'".into(),
    }
}

impl ParamSet {
    /// An error at `pos` in this directive's file.
    pub fn error(&self, pos: Pos, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.file, pos.line, pos.column, format!("{}: {}", self.context, message.into()))
    }

    /// The parameter called `name`, marked as used.
    pub fn find(&self, name: &str) -> Option<&Param> {
        let p = self.params.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// The parameter called `name`, which must have one of `types`.
    pub fn typed(&self, name: &str, types: &[&str]) -> Result<Option<&Param>, SceneError> {
        let Some(p) = self.find(name) else { return Ok(None) };
        if !types.contains(&p.ty.as_str()) {
            return Err(
                self.error(p.pos, format!("parameter '{name}' has type '{}', expected {}", p.ty, types.join(" or ")))
            );
        }
        Ok(Some(p))
    }

    /// Numbers of a parameter of one of `types`, checking the count is a multiple of `group`.
    pub fn numbers(&self, name: &str, types: &[&str], group: usize) -> Result<Option<(Vec<f64>, Pos)>, SceneError> {
        let Some(p) = self.typed(name, types)? else { return Ok(None) };
        let values = p.numbers();
        if values.is_empty() || values.len() % group != 0 {
            return Err(self
                .error(p.pos, format!("parameter '{name}' needs a multiple of {group} values, got {}", values.len())));
        }
        Ok(Some((values, p.pos)))
    }

    /// A single `float`.
    pub fn float(&self, name: &str, default: f32) -> Result<f32, SceneError> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }

    /// A single `float`, if given.
    pub fn float_opt(&self, name: &str) -> Result<Option<f32>, SceneError> {
        let Some((values, pos)) = self.numbers(name, &["float"], 1)? else { return Ok(None) };
        if values.len() != 1 {
            return Err(self.error(pos, format!("parameter '{name}' needs one value, got {}", values.len())));
        }
        Ok(Some(values[0] as f32))
    }

    /// A single `integer`.
    pub fn int(&self, name: &str, default: i64) -> Result<i64, SceneError> {
        let Some(values) = self.ints(name)? else { return Ok(default) };
        let p = self.find(name).map(|p| p.pos).unwrap_or(Pos { line: 0, column: 0 });
        if values.len() != 1 {
            return Err(self.error(p, format!("parameter '{name}' needs one value, got {}", values.len())));
        }
        Ok(values[0])
    }

    /// An `integer` array.
    pub fn ints(&self, name: &str) -> Result<Option<Vec<i64>>, SceneError> {
        let Some((values, pos)) = self.numbers(name, &["integer"], 1)? else { return Ok(None) };
        values
            .iter()
            .map(|&v| {
                if v.fract() == 0.0 && v.abs() < 9.0e15 {
                    Ok(v as i64)
                } else {
                    Err(self.error(pos, format!("parameter '{name}': {v} is not an integer")))
                }
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }

    /// A single `bool`.
    pub fn bool(&self, name: &str, default: bool) -> Result<bool, SceneError> {
        let Some(p) = self.typed(name, &["bool"])? else { return Ok(default) };
        match p.values[..] {
            [Value::Bool(b)] => Ok(b),
            _ => Err(self.error(p.pos, format!("parameter '{name}' needs one value, got {}", p.values.len()))),
        }
    }

    /// A single `string`.
    pub fn string(&self, name: &str) -> Result<Option<(String, Pos)>, SceneError> {
        let Some(p) = self.typed(name, &["string"])? else { return Ok(None) };
        match &p.values[..] {
            [Value::Str(s)] => Ok(Some((s.clone(), p.pos))),
            _ => Err(self.error(p.pos, format!("parameter '{name}' needs one string, got {}", p.values.len()))),
        }
    }

    /// Warnings for the parameters nobody asked for.
    pub fn unused(&self) -> Vec<String> {
        self.params
            .iter()
            .filter(|p| !p.used.get())
            .map(|p| {
                format!(
                    "{}:{}:{}: {}: parameter \"{} {}\" is not supported and was ignored",
                    self.file.display(),
                    p.pos.line,
                    p.pos.column,
                    self.context,
                    p.ty,
                    p.name
                )
            })
            .collect()
    }
}
