//! TOML input files: parsing with serde and locating fields for error messages.
//!
//! `serde` with `deny_unknown_fields` rejects unknown keys and wrong types with a span;
//! semantic validation afterwards names a dotted field path, and [`TomlFile::locate`]
//! turns that path back into a line and column of the user's text.

use crate::error::FileError;
use serde::de::DeserializeOwned;
use toml::de::{DeTable, DeValue};

/// The text of one TOML file plus its name, kept for error messages.
pub struct TomlFile {
    /// File name as given by the user.
    pub name: String,
    /// Full text.
    pub text: String,
}

/// One step of a field path: a table key or an array index.
#[derive(Debug, Clone, PartialEq)]
pub enum Seg {
    /// `key`
    Key(String),
    /// `[i]`
    Index(usize),
}

/// Parses a dotted path like `object[2].radius` into segments.
pub fn parse_path(path: &str) -> Vec<Seg> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let mut rest = part;
        if let Some(b) = rest.find('[') {
            if b > 0 {
                out.push(Seg::Key(rest[..b].to_string()));
            }
            rest = &rest[b..];
            while let Some(stripped) = rest.strip_prefix('[') {
                let end = stripped.find(']').unwrap_or(stripped.len());
                if let Ok(i) = stripped[..end].parse() {
                    out.push(Seg::Index(i));
                }
                rest = stripped.get(end + 1..).unwrap_or("");
            }
        } else if !rest.is_empty() {
            out.push(Seg::Key(rest.to_string()));
        }
    }
    out
}

impl TomlFile {
    /// Reads a file from disk.
    pub fn read(path: &str) -> Result<Self, FileError> {
        let text = std::fs::read_to_string(path).map_err(|e| FileError {
            file: path.to_string(),
            line: None,
            col: None,
            field: String::new(),
            msg: format!("cannot read the file: {e}"),
        })?;
        Ok(Self {
            name: path.to_string(),
            text,
        })
    }

    /// Wraps an in-memory text (an embedded default, a test).
    pub fn from_text(name: &str, text: &str) -> Self {
        Self {
            name: name.to_string(),
            text: text.to_string(),
        }
    }

    /// Deserialises the whole file. Syntax errors, unknown fields and wrong types
    /// come back with line and column.
    pub fn parse<T: DeserializeOwned>(&self) -> Result<T, FileError> {
        toml::from_str(&self.text).map_err(|e| {
            let (line, col) = match e.span() {
                Some(s) => {
                    let (l, c) = self.line_col(s.start);
                    (Some(l), Some(c))
                }
                None => (None, None),
            };
            // The toml message is multi-line with a source excerpt; keep its first line.
            let msg = e
                .message()
                .lines()
                .next()
                .unwrap_or("invalid TOML")
                .to_string();
            FileError {
                file: self.name.clone(),
                line,
                col,
                field: String::new(),
                msg,
            }
        })
    }

    /// 1-based line and column of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let before = &self.text[..offset.min(self.text.len())];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        (line, col)
    }

    /// Line and column of a field given as a dotted path, if it is present in the text.
    /// Falls back to the nearest enclosing table that is present.
    pub fn locate(&self, path: &str) -> Option<(usize, usize)> {
        let doc = DeTable::parse(&self.text).ok()?;
        let segs = parse_path(path);
        let mut best: Option<usize> = None;
        let mut table: &DeTable<'_> = doc.get_ref();
        let mut value: Option<&DeValue<'_>> = None;
        for seg in &segs {
            match seg {
                Seg::Key(k) => {
                    let t = match value {
                        None => table,
                        Some(DeValue::Table(t)) => t,
                        _ => break,
                    };
                    let Some((key, v)) = t.get_key_value(k.as_str()) else {
                        break;
                    };
                    best = Some(key.span().start);
                    table = t;
                    value = Some(v.get_ref());
                }
                Seg::Index(i) => {
                    let Some(DeValue::Array(a)) = value else {
                        break;
                    };
                    let Some(v) = a.get(*i) else { break };
                    best = Some(v.span().start);
                    value = Some(v.get_ref());
                }
            }
        }
        best.map(|o| self.line_col(o))
    }

    /// Builds a located error for a field path.
    pub fn error(&self, field: &str, msg: impl Into<String>) -> FileError {
        let (line, col) = match self.locate(field) {
            Some((l, c)) => (Some(l), Some(c)),
            None => (None, None),
        };
        FileError {
            file: self.name.clone(),
            line,
            col,
            field: field.to_string(),
            msg: msg.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locates_nested_fields_and_array_items() {
        let f = TomlFile::from_text(
            "t.toml",
            "[camera]\nnear = 1.0\n\n[[object]]\nkind = \"sphere\"\n\n[[object]]\nkind = \"torus\"\nradius = -1\n",
        );
        assert_eq!(f.locate("camera.near"), Some((2, 1)));
        assert_eq!(f.locate("object[1].radius"), Some((9, 1)));
        // A missing field falls back to its table.
        assert_eq!(f.locate("object[1].missing"), f.locate("object[1]"));
        assert!(f.locate("object[1]").is_some());
        assert!(f.locate("nothing").is_none());
    }

    #[test]
    fn syntax_errors_have_a_line() {
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct T {
            a: u32,
        }
        let f = TomlFile::from_text("t.toml", "a = 1\nb = 2\n");
        let e = f.parse::<T>().unwrap_err();
        assert_eq!(e.line, Some(2));
        assert!(e.msg.contains("unknown field"), "{}", e.msg);
    }
}
