//! The pbrt-v4 tokenizer: quoted strings, numbers, brackets and bare words, with `#` comments,
//! each token tagged with its 1-based line and column.

use std::path::Path;

use crate::scene_error::SceneError;

/// A position in a file (1-based line and column, columns counted in characters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pos {
    /// Line, from 1.
    pub line: u32,
    /// Column, from 1.
    pub column: u32,
}

/// What a token is.
#[derive(Clone, Debug, PartialEq)]
pub enum TokenKind {
    /// A quoted string, escapes resolved.
    Str(String),
    /// A number (integer or floating point).
    Num(f64),
    /// A bare word: a directive name, or `true` / `false`.
    Word(String),
    /// `[`
    Open,
    /// `]`
    Close,
}

/// A token and where it starts.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// The token.
    pub kind: TokenKind,
    /// Where it starts.
    pub pos: Pos,
}

/// Splits `text` (the contents of `file`, used in error messages) into tokens.
///
/// Numbers follow pbrt's syntax: an optional sign, digits with an optional `.` (a leading or
/// trailing `.` is allowed: `-.5`, `1.`), an optional exponent (`1e-3`). Strings are delimited
/// by `"` and may not span lines; `\"`, `\\`, `\n` and `\t` are escapes. `#` starts a comment
/// that runs to the end of the line.
pub fn tokenize(file: &Path, text: &str) -> Result<Vec<Token>, SceneError> {
    let chars: Vec<char> = text.chars().collect();
    let mut tokens = Vec::new();
    let (mut i, mut line, mut column) = (0usize, 1u32, 1u32);
    while i < chars.len() {
        let c = chars[i];
        let pos = Pos { line, column };
        if c == '\n' {
            i += 1;
            line += 1;
            column = 1;
        } else if c.is_whitespace() {
            i += 1;
            column += 1;
        } else if c == '#' {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '[' || c == ']' {
            tokens.push(Token { kind: if c == '[' { TokenKind::Open } else { TokenKind::Close }, pos });
            i += 1;
            column += 1;
        } else if c == '"' {
            let mut value = String::new();
            i += 1;
            column += 1;
            loop {
                let Some(&c) = chars.get(i) else {
                    return Err(SceneError::at(file, pos.line, pos.column, "unterminated string"));
                };
                i += 1;
                column += 1;
                match c {
                    '"' => break,
                    '\n' => {
                        return Err(SceneError::at(file, pos.line, pos.column, "string runs past the end of the line"));
                    }
                    '\\' => {
                        let escaped = chars.get(i).copied();
                        i += 1;
                        column += 1;
                        match escaped {
                            Some('"') => value.push('"'),
                            Some('\\') => value.push('\\'),
                            Some('n') => value.push('\n'),
                            Some('t') => value.push('\t'),
                            Some('\'') => value.push('\''),
                            other => {
                                return Err(SceneError::at(
                                    file,
                                    line,
                                    column.saturating_sub(2),
                                    format!(
                                        "unknown escape sequence \\{}",
                                        other.map(String::from).unwrap_or_default()
                                    ),
                                ));
                            }
                        }
                    }
                    c => value.push(c),
                }
            }
            tokens.push(Token { kind: TokenKind::Str(value), pos });
        } else if c.is_ascii_digit() || c == '-' || c == '+' || c == '.' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || matches!(chars[i], '.' | '-' | '+')) {
                // A sign belongs to the number only at its start or right after an exponent.
                if matches!(chars[i], '-' | '+') && i > start && !matches!(chars[i - 1], 'e' | 'E') {
                    break;
                }
                i += 1;
            }
            let word: String = chars[start..i].iter().collect();
            let value = parse_number(&word)
                .ok_or_else(|| SceneError::at(file, pos.line, pos.column, format!("bad number '{word}'")))?;
            column += (i - start) as u32;
            tokens.push(Token { kind: TokenKind::Num(value), pos });
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            column += (i - start) as u32;
            tokens.push(Token { kind: TokenKind::Word(chars[start..i].iter().collect()), pos });
        } else {
            return Err(SceneError::at(file, pos.line, pos.column, format!("unexpected character '{c}'")));
        }
    }
    Ok(tokens)
}

/// Parses a pbrt number; rejects `inf`, `nan`, hexadecimal and empty mantissas.
fn parse_number(word: &str) -> Option<f64> {
    let unsigned = word.strip_prefix(['-', '+']).unwrap_or(word);
    let mantissa = unsigned.split(['e', 'E']).next().unwrap_or("");
    let valid_chars = unsigned.chars().all(|c| c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '-' | '+'));
    if !valid_chars || !mantissa.chars().any(|c| c.is_ascii_digit()) {
        return None;
    }
    word.parse::<f64>().ok().filter(|v| v.is_finite())
}
