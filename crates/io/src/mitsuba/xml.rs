//! Reading Mitsuba XML files into an owned element tree: `<include>` expanded in place,
//! `<default>` parameters collected and `$name` substituted in every attribute, `<path>`
//! directories added to the [`SearchPath`]. Every element remembers its file, line and column.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::search::SearchPath;
use crate::scene_error::SceneError;

/// Where an element starts.
#[derive(Clone, Debug)]
pub(crate) struct Pos {
    /// The file the element is in.
    pub file: Arc<PathBuf>,
    /// 1-based line.
    pub line: u32,
    /// 1-based column.
    pub column: u32,
}

impl Pos {
    /// An error at this position.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.file, self.line, self.column, message)
    }

    /// `file:line:column` for warnings.
    pub fn location(&self) -> String {
        format!("{}:{}:{}", self.file.display(), self.line, self.column)
    }
}

/// An element after parameter substitution.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    /// Tag name.
    pub tag: String,
    /// Attributes in document order, values substituted.
    pub attrs: Vec<(String, String)>,
    /// Child elements (comments and whitespace dropped; includes expanded).
    pub children: Vec<Node>,
    /// Where the element starts.
    pub pos: Pos,
}

impl Node {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    /// The value of attribute `name`, or an error naming the element.
    pub fn required_attr(&self, name: &str) -> Result<&str, SceneError> {
        self.attr(name).ok_or_else(|| self.pos.error(format!("<{}> is missing the attribute '{name}'", self.tag)))
    }
}

/// The parsed scene: the root's children and the search path its `<path>`s declare.
pub(crate) struct ParsedScene {
    /// Top-level elements in document order (includes spliced in).
    pub elements: Vec<Node>,
    /// Where files named in the elements are looked for.
    pub search: SearchPath,
}

/// Reads `path` and everything it includes.
pub(crate) fn parse_scene(
    path: &Path,
    defines: &[(String, String)],
    warnings: &mut Vec<String>,
) -> Result<ParsedScene, SceneError> {
    let mut reader = Reader {
        params: defines.iter().cloned().collect(),
        stack: Vec::new(),
        search: SearchPath::new(path),
        warnings,
    };
    let elements = reader.read_file(path, None)?;
    Ok(ParsedScene { elements, search: reader.search })
}

struct Reader<'w> {
    /// Parameters: `-D` defines first, then `<default>`s (first definition wins).
    params: HashMap<String, String>,
    /// Canonical paths of the files being read (include cycle detection).
    stack: Vec<PathBuf>,
    /// The scene file's directory and the `<path>`s read so far.
    search: SearchPath,
    warnings: &'w mut Vec<String>,
}

impl Reader<'_> {
    /// Reads one file and returns its root's children. `included_from` is the `<include>`
    /// element's position for included files.
    fn read_file(&mut self, path: &Path, included_from: Option<&Pos>) -> Result<Vec<Node>, SceneError> {
        crate::trace::opened(path);
        let text = std::fs::read_to_string(path).map_err(|e| match included_from {
            Some(pos) => pos.error(format!("cannot read included file '{}': {e}", path.display())),
            None => SceneError::in_file(path, format!("cannot read scene file: {e}")),
        })?;
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        if self.stack.contains(&canonical) {
            let chain: Vec<String> = self.stack.iter().map(|p| p.display().to_string()).collect();
            let message = format!("include cycle: '{}' is already being read ({})", path.display(), chain.join(" → "));
            return Err(match included_from {
                Some(pos) => pos.error(message),
                None => SceneError::in_file(path, message),
            });
        }
        let options = roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
        let doc = roxmltree::Document::parse_with_options(&text, options).map_err(|e| {
            let p = e.pos();
            SceneError::at(path, p.row, p.col, format!("malformed XML: {e}"))
        })?;
        let file = Arc::new(path.to_path_buf());
        let root = doc.root_element();
        let root_pos = position(&doc, &file, root);
        if root.tag_name().name() != "scene" {
            return Err(root_pos.error(format!("expected a <scene> root element, found <{}>", root.tag_name().name())));
        }
        match root.attribute("version") {
            None => self.warnings.push(format!("{}: <scene> has no version attribute", root_pos.location())),
            Some(v) => {
                let major = v.split('.').next().and_then(|m| m.trim().parse::<u32>().ok());
                match major {
                    Some(m) if m >= 2 => {}
                    Some(_) => return Err(root_pos.error(old_format(&format!("scene version {v}")))),
                    None => return Err(root_pos.error(format!("bad scene version '{v}'"))),
                }
            }
        }
        self.stack.push(canonical);
        let result = self.children(&doc, &file, root);
        self.stack.pop();
        result
    }

    fn children(
        &mut self,
        doc: &roxmltree::Document,
        file: &Arc<PathBuf>,
        parent: roxmltree::Node,
    ) -> Result<Vec<Node>, SceneError> {
        let mut out = Vec::new();
        for child in parent.children() {
            if child.is_text() {
                let text = child.text().unwrap_or("");
                if !text.trim().is_empty() {
                    let pos = position(doc, file, child);
                    return Err(pos.error(format!("unexpected text '{}'", text.trim())));
                }
                continue;
            }
            if !child.is_element() {
                continue;
            }
            let pos = position(doc, file, child);
            let tag = child.tag_name().name().to_string();
            let mut attrs = Vec::new();
            for a in child.attributes() {
                attrs.push((a.name().to_string(), self.substitute(a.value(), &pos, a.name())?));
            }
            let node = Node { tag, attrs, children: Vec::new(), pos };
            match node.tag.as_str() {
                "default" => {
                    let name = node.required_attr("name")?.to_string();
                    let value = node.required_attr("value")?.to_string();
                    if name.is_empty() {
                        return Err(node.pos.error("<default> with an empty name"));
                    }
                    self.params.entry(name).or_insert(value);
                }
                "include" => {
                    let filename = node.required_attr("filename")?;
                    let resolved =
                        self.search.find(filename, file).map_err(|e| node.pos.error(format!("<include>: {e}")))?;
                    let included = self.read_file(&resolved, Some(&node.pos))?;
                    out.extend(included);
                }
                "path" => {
                    if parent.parent().is_some_and(|p| p.is_element()) {
                        return Err(node.pos.error("<path> must be a child of the <scene> root"));
                    }
                    let value = node.required_attr("value")?;
                    let declared = Path::new(value);
                    let dir = match file.parent() {
                        Some(here) if !declared.is_absolute() => here.join(declared),
                        _ => declared.to_path_buf(),
                    };
                    if dir.is_dir() {
                        self.search.declare(dir);
                    } else {
                        self.warnings.push(format!(
                            "{}: <path value=\"{value}\">: directory '{}' not found (relative to the file that \
                             declares it); ignored",
                            node.pos.location(),
                            dir.display()
                        ));
                        self.search.declare_missing(node.pos.location(), dir);
                    }
                }
                _ => {
                    let children = self.children(doc, file, child)?;
                    out.push(Node { children, ..node });
                }
            }
        }
        Ok(out)
    }

    /// Replaces every `$name` (name = letters, digits, `_`) by the parameter's value.
    fn substitute(&self, value: &str, pos: &Pos, attribute: &str) -> Result<String, SceneError> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut out = String::with_capacity(value.len());
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let end = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let name = &after[..end];
            if name.is_empty() {
                return Err(pos.error(format!("attribute '{attribute}': '$' not followed by a parameter name")));
            }
            let Some(v) = self.params.get(name) else {
                return Err(pos.error(format!(
                    "attribute '{attribute}': undefined parameter '${name}' (add <default name=\"{name}\" …/> or -D {name}=…)"
                )));
            };
            out.push_str(v);
            rest = &after[end..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

fn position(doc: &roxmltree::Document, file: &Arc<PathBuf>, node: roxmltree::Node) -> Pos {
    let p = doc.text_pos_at(node.range().start);
    Pos { file: file.clone(), line: p.row, column: p.col }
}

/// The message for a file in the format of Mitsuba 0.x (before Mitsuba 2), named by `what`.
pub(crate) fn old_format(what: &str) -> String {
    format!(
        "{what}: this is a Mitsuba 0.x scene file (before Mitsuba 2), an old format that is not supported; \
         convert it to the Mitsuba 3 format (version 3.x: snake_case property names, hdrfilm, …)"
    )
}
