//! [`Source`]: where a parsed value (a scene, a hardware config) was read from, kept with it
//! so that a check made later, across fields or across files (the screen against the
//! coordinate format), names each field with its file and line as the parser's own
//! messages do.

use super::TomlFile;
use crate::error::FileError;
use std::sync::Arc;

/// Where a value's fields come from: a file (its name and text, to locate a field's line)
/// and the base of the fields the file does not give (a preset's name). Not part of the
/// value: every `Source` compares equal (a config read from a file equals the same config
/// built in code), and the values skip it when serialised.
#[derive(Clone, Default)]
pub struct Source {
    file: Option<Arc<TomlFile>>,
    base: Option<String>,
}

impl Source {
    /// Fields read from `file`; those it does not give come from the preset `base`, if any.
    pub fn file(file: &TomlFile, base: Option<&str>) -> Source {
        Source {
            file: Some(Arc::new(TomlFile::from_text(&file.name, &file.text))),
            base: base.map(str::to_string),
        }
    }

    /// Every field from the preset `name` (no file).
    pub fn preset(name: &str) -> Source {
        Source {
            file: None,
            base: Some(name.to_string()),
        }
    }

    /// The same file with another base (the configurations of one grid file share it).
    pub fn with_base(&self, base: Option<&str>) -> Source {
        Source {
            file: self.file.clone(),
            base: base.map(str::to_string),
        }
    }

    /// The preset the fields not in the file come from.
    pub fn base(&self) -> Option<&str> {
        self.base.as_deref()
    }

    /// The file's name, if the value was read from one.
    pub fn file_name(&self) -> Option<&str> {
        self.file.as_deref().map(|f| f.name.as_str())
    }

    /// Line and column of a field (dotted path) the file gives itself.
    pub fn locate(&self, field: &str) -> Option<(usize, usize)> {
        self.file.as_deref()?.locate_field(field)
    }

    /// Where a field's value comes from, for a message: `hw.toml:4` when the file gives it,
    /// else `preset linear12` (its base), else `hw.toml` or `default`.
    pub fn origin(&self, field: &str, default: &str) -> String {
        match (self.file_name(), self.locate(field), self.base()) {
            (Some(f), Some((l, _)), _) => format!("{f}:{l}"),
            (_, _, Some(b)) => format!("preset {b}"),
            (f, _, None) => f.unwrap_or(default).to_string(),
        }
    }

    /// An error at `field`: the file and line when the file gives the field, else the file
    /// (or `default`, the value's name) without a line.
    pub fn error(&self, default: &str, field: &str, msg: impl Into<String>) -> FileError {
        let (line, col) = self.locate(field).unzip();
        FileError {
            file: self.file_name().unwrap_or(default).to_string(),
            line,
            col,
            field: field.to_string(),
            msg: msg.into(),
        }
    }
}

impl PartialEq for Source {
    fn eq(&self, _: &Source) -> bool {
        true
    }
}

impl std::fmt::Debug for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Source({:?}, base {:?})", self.file_name(), self.base)
    }
}
