//! Sweep grids: a TOML file naming hardware fields by dotted paths with lists of values.
//!
//! ```toml
//! preset = ["linear12", "linear11"]      # optional: base presets
//! accumulate.frame = ["UQ11.0", "UQ12.0"]
//! gamma.dac_bits = [8, 9]
//! ```
//!
//! The grid expands to the cartesian product of its lists. Fields are taken in sorted
//! path order (`preset` sorts with the others) and the last field varies fastest, so the
//! order is deterministic. Every configuration is built as a hardware TOML text and parsed
//! by [`HwConfig::from_toml`], so a grid accepts exactly the fields and ranges a hardware
//! file accepts, and a bad value is reported before any render starts.

use crate::config::HwConfig;
use crate::error::FileError;
use crate::files::{Seg, TomlFile};
use std::collections::BTreeMap;

/// The shards of a sweep's job list ([`crate::shard`], shared with the sequences).
pub use crate::shard::Shard;

/// One point of the grid: field path -> value, plus the validated hardware.
#[derive(Clone, Debug)]
pub struct Config {
    /// Position in the expanded grid (0-based).
    pub index: usize,
    /// Field path -> value (TOML value).
    pub fields: BTreeMap<String, toml::Value>,
    /// The canonical text `path=value;...` (sorted paths): names the configuration in
    /// messages (the row id hashes the validated hardware, see [`super::rows`]).
    pub canonical: String,
    /// The hardware it describes.
    pub hw: HwConfig,
}

/// A parsed grid.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Field path -> list of values, sorted by path.
    pub axes: Vec<(String, Vec<toml::Value>)>,
}

/// Refuses a key that no hardware field has (a newline, a space, `=` or a quote in it: the
/// configuration's text would not say what the grid says), at its line; `keys` are the keys
/// down to it, the last one checked.
fn check_key(file: &TomlFile, keys: &[String]) -> Result<(), FileError> {
    let ok = |c: char| c.is_ascii_alphanumeric() || "_-.".contains(c);
    let key = keys.last().map_or("", String::as_str);
    if !key.is_empty() && key.chars().all(ok) {
        return Ok(());
    }
    let segs: Vec<Seg> = keys.iter().cloned().map(Seg::Key).collect();
    let (line, col) = file.locate_segs(&segs).unzip();
    let shown: Vec<String> = keys.iter().map(|k| k.escape_debug().to_string()).collect();
    Err(FileError {
        file: file.name.clone(),
        line,
        col,
        field: shown.join("."),
        msg: format!(
            "the key \"{}\" is not a hardware field name: a grid key is a dotted field path of letters, digits, `_` and `-` (e.g. `gamma.dac_bits = [8, 9]`)",
            shown.last().map_or("", String::as_str)
        ),
    })
}

fn flatten(
    file: &TomlFile,
    prefix: &[String],
    t: &toml::Table,
    out: &mut Vec<(String, Vec<toml::Value>)>,
) -> Result<(), FileError> {
    for (k, v) in t {
        let keys = [prefix, std::slice::from_ref(k)].concat();
        check_key(file, &keys)?;
        let path = keys.join(".");
        match v {
            toml::Value::Table(sub) => flatten(file, &keys, sub, out)?,
            toml::Value::Array(a) if a.is_empty() => {
                return Err(file.error(
                    &path,
                    "the list of values is empty; give at least one value",
                ));
            }
            toml::Value::Array(a) => out.push((path, a.clone())),
            other => {
                return Err(file.error(
                    &path,
                    format!(
                        "must be a list of values (e.g. `{path} = [{other}]`), got a single {}",
                        other.type_str()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Largest number of configurations a grid may expand to.
pub const MAX_CONFIGS: usize = 100_000;

impl Grid {
    /// Parses a grid file (syntax, lists; not yet the values).
    pub fn parse(file: &TomlFile) -> Result<Grid, FileError> {
        let t: toml::Table = file.parse()?;
        let mut axes = Vec::new();
        flatten(file, &[], &t, &mut axes)?;
        if axes.is_empty() {
            return Err(file.error(
                "",
                "the grid names no field; give e.g. `gamma.dac_bits = [8, 9]`",
            ));
        }
        let mut n: usize = 1;
        for (p, v) in &axes {
            n = n.saturating_mul(v.len());
            if n > MAX_CONFIGS {
                return Err(file.error(
                    p,
                    format!("the grid expands to more than {MAX_CONFIGS} configurations"),
                ));
            }
        }
        Ok(Grid { axes })
    }

    /// Number of configurations.
    pub fn len(&self) -> usize {
        self.axes.iter().map(|(_, v)| v.len()).product()
    }

    /// Whether the grid is empty (never, after [`Grid::parse`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Expands and validates every configuration, in order. The first bad one is an error
    /// naming the grid file, the field and the value.
    pub fn expand(&self, file: &TomlFile) -> Result<Vec<Config>, FileError> {
        let total = self.len();
        let mut out = Vec::with_capacity(total);
        // A configuration's fields are the grid's keys: later checks locate them there.
        let source = crate::files::Source::file(file, None);
        for index in 0..total {
            let mut rest = index;
            let mut picks = vec![0usize; self.axes.len()];
            for (k, (_, vals)) in self.axes.iter().enumerate().rev() {
                picks[k] = rest % vals.len();
                rest /= vals.len();
            }
            let mut fields = BTreeMap::new();
            let mut text = String::new();
            let mut canonical = String::new();
            for (k, (path, vals)) in self.axes.iter().enumerate() {
                let v = &vals[picks[k]];
                fields.insert(path.clone(), v.clone());
                text.push_str(&format!("{path} = {v}\n"));
                if !canonical.is_empty() {
                    canonical.push(';');
                }
                canonical.push_str(&format!("{path}={v}"));
            }
            let hw_file = TomlFile::from_text(&canonical, &text);
            let mut hw = HwConfig::from_toml(&hw_file).map_err(|e| {
                // Point at the grid field: the one the hardware error names, else the one
                // on the line it points at (the text has one line per axis, in order), else
                // one whose name the message mentions.
                let field = if !e.field.is_empty() {
                    e.field.clone()
                } else if let Some((p, _)) = e.line.and_then(|l| self.axes.get(l.wrapping_sub(1))) {
                    p.clone()
                } else {
                    self.axes
                        .iter()
                        .map(|(p, _)| p.as_str())
                        .find(|p| e.msg.contains(p.rsplit('.').next().unwrap_or(p)))
                        .unwrap_or("")
                        .to_string()
                };
                let (line, col) = file
                    .locate(&field)
                    .map_or((None, None), |(l, c)| (Some(l), Some(c)));
                FileError {
                    file: file.name.clone(),
                    line,
                    col,
                    field,
                    msg: format!("configuration {index} ({canonical}): {}", e.msg),
                }
            })?;
            hw.name = canonical.clone();
            hw.source = source.with_base(hw.source.base());
            out.push(Config {
                index,
                fields,
                canonical,
                hw,
            });
        }
        Ok(out)
    }
}
