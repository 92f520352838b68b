//! TOML input files: parsing with serde and locating fields for error messages.
//!
//! `serde` with `deny_unknown_fields` rejects unknown keys and wrong types with a span;
//! semantic validation afterwards names a dotted field path, and [`TomlFile::locate`]
//! turns that path back into a line and column of the user's text. A check across fields
//! (or across a scene and a hardware config) runs after parsing: the value keeps its
//! [`Source`], which locates each field it names the same way.

mod cache;
mod messages;
mod source;

pub use cache::{CACHE_ENV, cache_dir};
pub use messages::{generic_path, nearest, num};
pub use source::Source;

use crate::error::FileError;
use messages::{describe, line_paths};
use serde::de::DeserializeOwned;
use toml::de::{DeTable, DeValue};

/// What a field expects, by dotted path (`object[2].radius` -> `a finite number in [1e-9,
/// 1e9]`): the type and the allowed range, for messages. `None`: no hint.
pub type Hint<'a> = &'a dyn Fn(&str) -> Option<String>;

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

    /// Deserialises the whole file. Syntax errors, unknown fields and wrong types come back
    /// with line, column and the dotted path of the field (no hint of the expected value:
    /// see [`TomlFile::parse_with`]).
    pub fn parse<T: DeserializeOwned>(&self) -> Result<T, FileError> {
        self.parse_with(&|_| None)
    }

    /// Deserialises the whole file; every error names the dotted field path
    /// (`object[2].tessellation`), what was found and what is expected. `hint` gives, for a
    /// field path, what the field expects (type and allowed range: `an integer in
    /// 3..=1024`); without one the message names the serde type (`an integer`).
    pub fn parse_with<T: DeserializeOwned>(&self, hint: Hint<'_>) -> Result<T, FileError> {
        let de = toml::Deserializer::parse(&self.text).map_err(|e| self.syntax_error(&e, hint))?;
        serde_path_to_error::deserialize(de).map_err(|e| self.type_error(e, hint))
    }

    /// A TOML syntax error (including a duplicate key or table): the field is the key or
    /// table header of the line the error is on.
    fn syntax_error(&self, e: &toml::de::Error, hint: Hint<'_>) -> FileError {
        let offset = e.span().map_or(self.text.len(), |s| s.start);
        let (line, col) = self.line_col(offset);
        let lines = line_paths(&self.text);
        let here = lines.get(line - 1).cloned().unwrap_or_default();
        let field = here.path.clone();
        let first = e.message().lines().next().unwrap_or("invalid TOML").trim();
        let array = lines[..line - 1]
            .iter()
            .position(|l| l.header && l.path != field && generic_path(&l.path) == field);
        let msg = if let (true, Some(k)) = (here.header, array) {
            format!(
                "[{field}] is an array of tables (first [[{field}]] at line {}); write [[{field}]] for each entry",
                k + 1
            )
        } else if first.starts_with("duplicate key") {
            let earlier = lines[..line - 1]
                .iter()
                .position(|l| l.defines && l.path == field)
                .map(|k| format!(" (first at line {})", k + 1))
                .unwrap_or_default();
            if here.header {
                format!(
                    "duplicate table: [{field}] is given twice{earlier}; write its fields under one header"
                )
            } else {
                format!("duplicate key: given twice{earlier}; keep one of them")
            }
        } else {
            let expects = hint(&field)
                .map(|h| format!("; `{field}` expects {h}"))
                .unwrap_or_default();
            format!("invalid TOML: {first}{expects}")
        };
        FileError {
            file: self.name.clone(),
            line: Some(line),
            col: Some(col),
            field,
            msg,
        }
    }

    /// A serde error (wrong type or value, unknown or missing field) at a field path.
    fn type_error(
        &self,
        e: serde_path_to_error::Error<toml::de::Error>,
        hint: Hint<'_>,
    ) -> FileError {
        let path = e.path().to_string();
        let path = if path == "." { String::new() } else { path };
        let inner = e.into_inner();
        let span = inner.span();
        let found = span
            .as_ref()
            .and_then(|s| self.text.get(s.clone()))
            .unwrap_or("");
        let raw = inner.message().lines().next().unwrap_or("invalid value");
        let (field, msg, relocate) = describe(&path, raw, found, hint);
        let span = if relocate { None } else { span };
        let (line, col) = match span {
            Some(s) => {
                let (l, c) = self.line_col(s.start);
                (Some(l), Some(c))
            }
            None => match self.locate(&field) {
                Some((l, c)) => (Some(l), Some(c)),
                None => (Some(1), Some(1)),
            },
        };
        FileError {
            file: self.name.clone(),
            line,
            col,
            field,
            msg,
        }
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
        self.find(path).map(|(at, _)| self.line_col(at))
    }

    /// Line and column of a field given as a dotted path, only if the text gives the field
    /// itself (no fallback to its table): where a value comes from.
    pub fn locate_field(&self, path: &str) -> Option<(usize, usize)> {
        match self.find(path) {
            Some((at, true)) => Some(self.line_col(at)),
            _ => None,
        }
    }

    /// The byte offset of the deepest segment of `path` present in the text, and whether
    /// that is the whole path.
    fn find(&self, path: &str) -> Option<(usize, bool)> {
        self.find_segs(&parse_path(path))
    }

    /// Line and column of a field given by its segments (a key may hold a `.` or a newline
    /// that a dotted path cannot), falling back to the nearest enclosing table present.
    pub fn locate_segs(&self, segs: &[Seg]) -> Option<(usize, usize)> {
        self.find_segs(segs).map(|(at, _)| self.line_col(at))
    }

    fn find_segs(&self, segs: &[Seg]) -> Option<(usize, bool)> {
        let doc = DeTable::parse(&self.text).ok()?;
        let mut best: Option<usize> = None;
        let mut found = 0;
        let mut table: &DeTable<'_> = doc.get_ref();
        let mut value: Option<&DeValue<'_>> = None;
        for seg in segs {
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
                    found += 1;
                    table = t;
                    value = Some(v.get_ref());
                }
                Seg::Index(i) => {
                    let Some(DeValue::Array(a)) = value else {
                        break;
                    };
                    let Some(v) = a.get(*i) else { break };
                    best = Some(v.span().start);
                    found += 1;
                    value = Some(v.get_ref());
                }
            }
        }
        best.map(|o| (o, found == segs.len()))
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
    use super::messages::line_paths;
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
        // Only the field itself, for where a value comes from.
        assert_eq!(f.locate_field("object[1].radius"), Some((9, 1)));
        assert_eq!(f.locate_field("object[1].missing"), None);
        assert_eq!(f.locate_field("camera.far"), None);
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

    #[test]
    fn line_paths_follow_headers_keys_and_continuations() {
        let text = "name = 1\n[[object]] # first\nkind = 2\n[[object]]\nvertices = [\n  [1, 2, 3],\n  [4, 5\n\n[object.material]\n'a b'.c = 1\n[ camera . lens ]\n";
        let paths: Vec<String> = line_paths(text).into_iter().map(|l| l.path).collect();
        assert_eq!(
            paths[..11],
            [
                "name",
                "object[0]",
                "object[0].kind",
                "object[1]",
                "object[1].vertices",
                "object[1].vertices",
                "object[1].vertices",
                "object[1].vertices",
                "object[1].material",
                "object[1].material.a b.c",
                "camera.lens",
            ]
        );
        assert_eq!(generic_path("object[2].vertices[1][0]"), "object.vertices");
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(0.035), "0.035");
        assert_eq!(num(f64::NAN), "NaN");
    }

    #[test]
    fn type_errors_name_the_field_and_the_hint() {
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct T {
            a: Vec<A>,
        }
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct A {
            n: u32,
        }
        let f = TomlFile::from_text("t.toml", "[[a]]\nn = 1\n[[a]]\nn = \"2\"\n");
        let hint = |p: &str| (generic_path(p) == "a.n").then(|| "an integer in 1..=9".to_string());
        let e = f.parse_with::<T>(&hint).unwrap_err();
        assert_eq!(
            (e.field.as_str(), e.line, e.col),
            ("a[1].n", Some(4), Some(5))
        );
        assert!(
            e.msg.contains("an integer in 1..=9, got the string \"2\""),
            "{e}"
        );
        // Without a hint the serde type is named.
        let e = f.parse::<T>().unwrap_err();
        assert!(e.msg.contains("must be an integer >= 0"), "{e}");
    }
}
