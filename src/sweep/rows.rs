//! The rows file of a sweep: row ids by content, reading a file back (`--resume`), the
//! ordered rewrite, and whole-file writes through a temporary file and a rename.
//!
//! The row id is 16 hex digits of
//! `FNV-1a("igemu sweep row", version, scene key, hardware key)` ([`row_id`]):
//! * the **scene key** is FNV-1a of the scene as parsed, serialised to JSON
//!   ([`scene_key`]): an edit that changes the scene changes the id, while comments and
//!   formatting do not (the file's bytes are not hashed); the scene's name is part of it;
//! * the **hardware key** is FNV-1a of the validated [`HwConfig`] serialised to JSON
//!   without its `name` ([`hardware_key`]): two grids spelling the same hardware
//!   differently (`preset = ["linear12"]` or not, the order of the axes) give the same key,
//!   and a preset whose defaults change in a new version gives a new one;
//!   with `--dof-truth` the lens-sample count is mixed into it ([`with_truth`]), so rows
//!   with and without the truth, or with another count, are not mixed by `--resume`;
//! * the **version** is the tool's (`CARGO_PKG_VERSION`): rows of another version are
//!   recomputed.

use super::Row;
use super::grid::Config;
use crate::config::HwConfig;
use crate::error::{Error, Result};
use crate::fnv::{Fnv, fnv1a};
use crate::scene::Scene;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The tool version that is part of every row id.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// JSON text of a serialisable value; a value serde cannot express (none today) falls back
/// to its `Debug` text, which still covers every field.
fn json_of<T: serde::Serialize + std::fmt::Debug>(v: &T) -> String {
    serde_json::to_string(v).unwrap_or_else(|_| format!("{v:?}"))
}

/// The content key of a scene: FNV-1a of the scene as parsed, as JSON.
pub fn scene_key(scene: &Scene) -> u64 {
    fnv1a(json_of(scene).as_bytes())
}

/// The content key of a hardware configuration: FNV-1a of its JSON without `name`.
pub fn hardware_key(hw: &HwConfig) -> u64 {
    let text = match serde_json::to_value(hw) {
        Ok(mut v) => {
            if let Some(o) = v.as_object_mut() {
                o.remove("name");
            }
            v.to_string()
        }
        Err(_) => {
            let mut anonymous = hw.clone();
            anonymous.name.clear();
            format!("{anonymous:?}")
        }
    };
    fnv1a(text.as_bytes())
}

/// A [`hardware_key`] with the depth-of-field truth's lens-sample count mixed in (`None`:
/// unchanged).
pub fn with_truth(hardware_key: u64, lens_samples: Option<u32>) -> u64 {
    match lens_samples {
        None => hardware_key,
        Some(n) => Fnv::new()
            .u64(hardware_key)
            .str("dof truth")
            .u64(u64::from(n))
            .finish(),
    }
}

/// The row id from a [`scene_key`] and a [`hardware_key`] (16 hex digits).
pub fn row_id_from_keys(scene_key: u64, hardware_key: u64) -> String {
    let h = Fnv::new()
        .str("igemu sweep row")
        .str(VERSION)
        .u64(scene_key)
        .u64(hardware_key)
        .finish();
    format!("{h:016x}")
}

/// The stable id of the row of `hw` on `scene` (see the module docs).
pub fn row_id(scene: &Scene, hw: &HwConfig) -> String {
    row_id_from_keys(scene_key(scene), hardware_key(hw))
}

/// The row id of every job of a sweep of `configs` on `scenes`, in job order ([`super::jobs`]),
/// with the truth's lens-sample count mixed in when `dof_truth` is given ([`with_truth`]).
pub fn job_ids(configs: &[Config], scenes: &[Scene], dof_truth: Option<u32>) -> Vec<String> {
    let scene_keys: Vec<u64> = scenes.iter().map(scene_key).collect();
    let hw_keys: Vec<u64> = configs
        .iter()
        .map(|c| with_truth(hardware_key(&c.hw), dof_truth))
        .collect();
    super::jobs(configs.len(), scenes.len())
        .iter()
        .map(|j| row_id_from_keys(scene_keys[j.scene], hw_keys[j.config]))
        .collect()
}

pub(crate) fn io(path: &str) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_string(),
        source,
    }
}

/// Reads the complete rows of an output file (none if it does not exist). A line that does
/// not parse as a row, or a last line without its newline (a killed run's partial line, even
/// if it parses), is skipped; returns the rows and the number of lines skipped.
pub fn read_rows(path: &str) -> Result<(Vec<Row>, usize)> {
    let text = match std::fs::read(path) {
        Ok(b) => String::from_utf8_lossy(&b).into_owned(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((Vec::new(), 0)),
        Err(e) => return Err(io(path)(e)),
    };
    let (rows, skipped) = parse_rows(&text);
    Ok((rows.into_iter().map(|(_, r)| r).collect(), skipped.len()))
}

/// The complete rows of a rows file's text with their 1-based line numbers, and the numbers
/// of the lines skipped as [`read_rows`] skips them (blank lines are neither).
pub fn parse_rows(text: &str) -> (Vec<(usize, Row)>, Vec<usize>) {
    let lines: Vec<&str> = text.split('\n').collect();
    let last = lines.len() - 1;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<Row>(line) {
            Ok(r) if i < last => rows.push((i + 1, r)),
            _ => skipped.push(i + 1),
        }
    }
    (rows, skipped)
}

/// A temporary path in the folder of `path` (so the rename that replaces `path` stays on
/// one file system), ending with `path`'s file name (so a writer that picks the format by
/// the extension sees the same one). Unique within the process.
pub(crate) fn temp_path(path: &str) -> String {
    static COUNT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let p = Path::new(path);
    let dir = p.parent().unwrap_or(Path::new(""));
    let name = p
        .file_name()
        .map_or_else(|| "out".to_string(), |s| s.to_string_lossy().into_owned());
    let tmp: PathBuf = dir.join(format!(".igemu-tmp-{}-{n}-{name}", std::process::id()));
    tmp.to_string_lossy().into_owned()
}

/// Writes `path` as a whole: `write` fills a temporary file in the same folder
/// ([`temp_path`]), which is synced and renamed onto `path`. On any error the temporary
/// file is removed and `path` is left as it was.
pub(crate) fn write_via_temp(path: &str, write: impl FnOnce(&str) -> Result<()>) -> Result<()> {
    let tmp = temp_path(path);
    let result = write(&tmp)
        .and_then(|()| {
            std::fs::OpenOptions::new()
                .write(true)
                .open(&tmp)
                .and_then(|f| f.sync_all())
                .map_err(io(&tmp))
        })
        .and_then(|()| std::fs::rename(&tmp, path).map_err(io(path)));
    if result.is_err() {
        // The temporary may not exist (the writer failed before creating it).
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Writes rows (sorted by index, the first row of each index) to `path` through a temporary
/// file in the same folder and a rename.
pub fn rewrite_sorted(path: &str, rows: &[Row]) -> Result<()> {
    let mut by_index: BTreeMap<usize, &Row> = BTreeMap::new();
    for r in rows {
        by_index.entry(r.index).or_insert(r);
    }
    write_via_temp(path, |tmp| {
        let mut f = std::io::BufWriter::new(std::fs::File::create(tmp).map_err(io(tmp))?);
        for r in by_index.values() {
            writeln!(f, "{}", json_of(r)).map_err(io(tmp))?;
        }
        f.flush().map_err(io(tmp))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_temporary_is_in_the_same_folder_and_keeps_the_name() {
        for path in ["out.jsonl", "a/b/pareto.png", "/tmp/x.svg"] {
            let t = temp_path(path);
            assert_eq!(Path::new(&t).parent(), Path::new(path).parent(), "{t}");
            assert!(t.ends_with(Path::new(path).file_name().unwrap().to_str().unwrap()));
            assert_ne!(t, path);
        }
        assert_ne!(temp_path("o.jsonl"), temp_path("o.jsonl"));
    }
}
