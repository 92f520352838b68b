//! TOML input files: parsing with serde and locating fields for error messages.
//!
//! `serde` with `deny_unknown_fields` rejects unknown keys and wrong types with a span;
//! semantic validation afterwards names a dotted field path, and [`TomlFile::locate`]
//! turns that path back into a line and column of the user's text.

use crate::error::FileError;
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
        let msg = if first.starts_with("duplicate key") {
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

/// A number as messages print it: `1e9`, `1e-9`, `0.035`, `NaN` (never 300 digits).
pub fn num(x: f64) -> String {
    let a = x.abs();
    if x.is_finite() && a != 0.0 && !(1e-4..1e6).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A field path without its array indices (`object[2].center[1]` -> `object.center`): the
/// key of a schema's hints.
pub fn generic_path(path: &str) -> String {
    let mut out = String::with_capacity(path.len());
    let mut depth = 0;
    for ch in path.chars() {
        match ch {
            '[' => depth += 1,
            ']' => depth -= 1,
            _ if depth == 0 => out.push(ch),
            _ => {}
        }
    }
    out
}

/// `parent.name` (or `name` at the top).
fn join(parent: &str, name: &str) -> String {
    if parent.is_empty() {
        name.to_string()
    } else {
        format!("{parent}.{name}")
    }
}

/// The text between the first pair of backquotes of `s`.
fn quoted(s: &str) -> Option<&str> {
    let a = s.find('`')? + 1;
    let b = s[a..].find('`')? + a;
    Some(&s[a..b])
}

/// A serde list of names (`` `a` or `b` ``, `` one of `a`, `b`, `c` ``) as `` `a`, `b` ``.
fn names(list: &str) -> String {
    let list = list.trim().trim_start_matches("one of ");
    list.replace(" or ", ", ")
}

/// The field path and the message of a serde error `raw` at `path`; `found` is the text of
/// the value the error points at. The flag: the error is about an enclosing table, locate
/// it by its path rather than by the error's span.
fn describe(path: &str, raw: &str, found: &str, hint: Hint<'_>) -> (String, String, bool) {
    // A table written as an array of tables (`[[image]]`): serde reads a struct from a
    // sequence positionally, so the error lands on an element of it; name the table.
    let mut prefix = String::new();
    for seg in path.split('.') {
        let key = seg.split('[').next().unwrap_or(seg);
        prefix = join(&prefix, key);
        if seg.contains('[')
            && let Some(h) = hint(&prefix).filter(|h| h.starts_with("a table"))
        {
            let name = prefix.clone();
            return (
                prefix,
                format!("must be {h}, got an array of tables [[{name}]]; write [{name}] once"),
                true,
            );
        }
        if let Some(b) = seg.find('[') {
            prefix.push_str(&seg[b..]);
        }
    }
    if let Some(rest) = raw.strip_prefix("missing field ") {
        let name = quoted(rest).unwrap_or(rest);
        let field = join(path, name);
        let req = hint(&field)
            .map(|h| format!(" (required: {h})"))
            .unwrap_or_default();
        return (field, format!("missing field `{name}`{req}"), false);
    }
    if let Some(rest) = raw.strip_prefix("unknown field ") {
        let name = quoted(rest).unwrap_or(rest);
        let allowed = match rest.split_once(", expected ") {
            Some((_, l)) => format!("; allowed: {}", names(l)),
            None => "; this table has no fields".into(),
        };
        return (
            path.to_string(),
            format!("unknown field `{name}`{allowed} (check the spelling)"),
            false,
        );
    }
    if let Some(rest) = raw.strip_prefix("unknown variant ") {
        let name = quoted(rest).unwrap_or(rest);
        let allowed = rest
            .split_once(", expected ")
            .map(|(_, l)| format!("; allowed: {}", names(l)))
            .unwrap_or_default();
        return (
            path.to_string(),
            format!("unknown value \"{name}\"{allowed}"),
            false,
        );
    }
    let field = path.to_string();
    let expected = |e: &str| hint(&field).unwrap_or_else(|| expected_type(e));
    let (got, want) = if let Some(rest) = raw
        .strip_prefix("invalid type: ")
        .or_else(|| raw.strip_prefix("invalid value: "))
    {
        match rest.rsplit_once(", expected ") {
            Some((f, e)) => (found_value(f, found), e.to_string()),
            None => (rest.to_string(), String::new()),
        }
    } else if let Some(rest) = raw.strip_prefix("invalid length ") {
        match rest.split_once(", expected ") {
            Some((n, e)) => (format!("an array of {n} values"), e.to_string()),
            None => (rest.to_string(), String::new()),
        }
    } else {
        // A custom message (a format string that does not parse, a number out of f64).
        let h = hint(&field)
            .map(|h| format!(" (expected {h})"))
            .unwrap_or_default();
        return (field, format!("{raw}{h}"), false);
    };
    let mut msg = format!("must be {}, got {got}", expected(&want));
    let numeric = |e: &str| {
        e.starts_with('i') || e.starts_with('u') || e.starts_with('f') || e.contains("number")
    };
    let unquoted = found.trim().trim_matches(['"', '\'']);
    if got.starts_with("the string") && numeric(&want) && unquoted.parse::<f64>().is_ok() {
        msg.push_str("; write the number without quotes");
    } else if got.starts_with("a table [") && want == "a sequence" {
        msg.push_str(&format!(
            "; write [[{}]], once per entry",
            generic_path(&field)
        ));
    } else if want == "a boolean" && !msg.contains("true or false") {
        msg.push_str("; write true or false");
    }
    (field, msg, false)
}

/// serde's description of a found value (`string "64"`, ``integer `3` ``, `map`) in words;
/// `text` is the value as written.
fn found_value(f: &str, text: &str) -> String {
    let t = text.trim();
    let inner = quoted(f).map(|v| v.trim_end_matches(" as i128").to_string());
    if let Some(s) = f.strip_prefix("string ") {
        format!("the string {s}")
    } else if f.starts_with("integer") || f.starts_with("floating point") {
        format!("the number {}", inner.unwrap_or_else(|| t.to_string()))
    } else if f.starts_with("boolean") {
        inner.unwrap_or_else(|| t.to_string())
    } else if f == "map" {
        if t.starts_with("[[") {
            format!("an array of tables {}", t.lines().next().unwrap_or(t))
        } else if t.starts_with('[') {
            format!("a table {}", t.lines().next().unwrap_or(t))
        } else if t.starts_with('{') {
            "an inline table".into()
        } else if t.starts_with(|c: char| c.is_ascii_digit()) {
            format!("the date-time {t}")
        } else {
            "a table".into()
        }
    } else if f == "sequence" {
        if t.starts_with("[[") {
            format!("an array of tables {}", t.lines().next().unwrap_or(t))
        } else {
            "an array".into()
        }
    } else {
        f.to_string()
    }
}

/// serde's name of an expected type (`i64`, `struct RawImage`, `a sequence`) in words.
fn expected_type(e: &str) -> String {
    match e {
        "i8" | "i16" | "i32" | "i64" | "i128" | "isize" => "an integer".into(),
        "u8" | "u16" | "u32" | "u64" | "u128" | "usize" => "an integer >= 0".into(),
        "f32" | "f64" => "a number".into(),
        "a boolean" => "true or false".into(),
        "a sequence" => "an array".into(),
        _ if e.starts_with("struct ") => "a table".into(),
        _ if e.starts_with("an array of length ") => {
            format!("an array of {} values", &e["an array of length ".len()..])
        }
        _ => e.to_string(),
    }
}

/// What one line of a TOML text is, for locating syntax errors.
#[derive(Clone, Debug, Default)]
struct LinePath {
    /// Dotted path of the key or table the line belongs to.
    path: String,
    /// The line is a table header (`[a]`, `[[a]]`).
    header: bool,
    /// The line defines its path (a header, or `key = ...`), rather than continuing one.
    defines: bool,
}

/// The dotted path of each line of a TOML text, found by reading headers and keys as text
/// (the text may not parse): `[[object]]` headers are counted to give `object[k]`; a line
/// that continues a multi-line value, a comment and a blank line belong to the last key.
fn line_paths(text: &str) -> Vec<LinePath> {
    let key_of = |k: &str| -> String {
        k.split('.')
            .map(|p| p.trim().trim_matches(['"', '\'']))
            .collect::<Vec<_>>()
            .join(".")
    };
    let is_key = |k: &str| {
        !k.trim().is_empty()
            && k.chars()
                .all(|c| c.is_alphanumeric() || "_-.\"' ".contains(c))
    };
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    let mut table = String::new();
    let mut last = LinePath::default();
    let mut out = Vec::new();
    for line in text.split('\n') {
        let t = line.trim();
        let (body, array) = match t.strip_prefix("[[") {
            Some(b) => (Some(b), true),
            None => (t.strip_prefix('['), false),
        };
        let head = body.map(|b| b.split(']').next().unwrap_or(b));
        let rest_ok = body.is_some_and(|b| {
            let after = b.split_once(']').map_or("", |(_, a)| a);
            let after = after.trim_start_matches(']').trim();
            after.is_empty() || after.starts_with('#')
        });
        if let Some(h) = head.filter(|h| is_key(h) && rest_ok) {
            let name = key_of(h);
            // Resolve every prefix that names an array of tables to its last element.
            let mut path = String::new();
            let parts: Vec<&str> = name.split('.').collect();
            for (k, part) in parts.iter().enumerate() {
                path = join(&path, part);
                let generic = generic_path(&path);
                let last_part = k + 1 == parts.len();
                if last_part && array {
                    let n = counts.entry(generic).or_insert(0);
                    *n += 1;
                    path = format!("{path}[{}]", *n - 1);
                } else if let Some(n) = counts.get(&generic) {
                    path = format!("{path}[{}]", n - 1);
                }
            }
            table = path.clone();
            last = LinePath {
                path,
                header: true,
                defines: true,
            };
            out.push(last.clone());
            continue;
        }
        let key = t.split_once('=').map(|(k, _)| k).filter(|k| is_key(k));
        let key = key.or_else(|| {
            // `key value` without `=`: the first word, if it reads as a key.
            let w = t.split_whitespace().next().unwrap_or("");
            (!t.starts_with('#') && is_key(w) && !w.starts_with(|c: char| c.is_ascii_digit()))
                .then_some(w)
        });
        match key {
            Some(k) => {
                last = LinePath {
                    path: join(&table, &key_of(k)),
                    header: false,
                    defines: true,
                };
                out.push(last.clone());
            }
            None => out.push(LinePath {
                defines: false,
                ..last.clone()
            }),
        }
    }
    out
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
