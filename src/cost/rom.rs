//! `igemu render --rom-out DIR`: the memory images of a render as `$readmemh` hex files,
//! with a manifest of their widths and depths.
//!
//! One file per memory, `<stage>.<name>.hex`, one word per line, `ceil(width / 4)` hex
//! digits, word 0 first; a word of several fields holds field 0 in its least significant
//! bits (the packing of [`super::pack`]). ROMs are always written; a RAM image larger than
//! [`MAX_RAM_WORDS`] words (the sample buffer of a large region) is listed in the manifest
//! but not written. Every file is written atomically ([`crate::output::write_file`]); the
//! manifest last.

use crate::error::{Error, Result};
use crate::stage::{Cost, MemImage, MemKind, StageId};
use serde::Serialize;
use std::path::Path;

/// Largest RAM image written, in words.
pub const MAX_RAM_WORDS: usize = 1 << 20;

/// One memory in the manifest.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RomEntry {
    /// The stage that holds it.
    pub stage: StageId,
    /// Memory name.
    pub name: String,
    /// RAM or ROM.
    pub kind: MemKind,
    /// Bits per word.
    pub width: u32,
    /// Words of the memory (the cost model's depth).
    pub depth: u64,
    /// Field widths of a word (field 0 in the low bits).
    pub fields: Vec<u32>,
    /// Words in the image (the modelled region for a screen-sized RAM).
    pub words: u64,
    /// The hex file, relative to the manifest (`None`: not written).
    pub file: Option<String>,
}

/// The manifest (`manifest.json`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Manifest {
    /// Every memory image of the render.
    pub memories: Vec<RomEntry>,
}

fn file_name(stage: StageId, name: &str) -> String {
    let slug: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect::<String>()
        .split('_')
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join("_");
    format!("{stage}.{slug}.hex")
}

/// The hex text of an image.
pub fn hex(im: &MemImage) -> String {
    let width: u32 = im.fields.iter().sum();
    let digits = width.div_ceil(4).max(1) as usize;
    let mut s = String::with_capacity(im.words * (digits + 1));
    for w in 0..im.words {
        let mut word = 0u128;
        let mut at = 0;
        for (k, &f) in im.fields.iter().enumerate() {
            word |= ((im.get)(w, k) as u128) << at;
            at += f;
        }
        s.push_str(&format!("{word:0digits$x}\n"));
    }
    s
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.display().to_string(),
        source,
    }
}

/// The names of the files [`write`] writes into its folder: the hex files, then
/// `manifest.json`.
pub fn files(stages: &[(StageId, &Cost, &[MemImage])]) -> Vec<String> {
    let mut out: Vec<String> = stages
        .iter()
        .flat_map(|&(stage, cost, images)| {
            images
                .iter()
                .filter(|im| written(cost, im))
                .map(move |im| file_name(stage, &im.name))
        })
        .collect();
    out.push(MANIFEST.into());
    out
}

/// The manifest's file name.
pub const MANIFEST: &str = "manifest.json";

/// Whether an image is written: every ROM, a RAM of at most [`MAX_RAM_WORDS`] words.
fn written(cost: &Cost, im: &MemImage) -> bool {
    let kind = cost
        .memories
        .iter()
        .find(|x| x.name == im.name)
        .map_or(MemKind::Rom, |x| x.kind);
    kind == MemKind::Rom || im.words <= MAX_RAM_WORDS
}

/// Writes the images of every stage (`(stage, its cost, its images)`) into `dir` (created
/// if needed; an empty path or a file is refused, see [`crate::output::unwritable_folder`])
/// and `dir/manifest.json`; returns the manifest.
pub fn write(dir: &Path, stages: &[(StageId, &Cost, &[MemImage])]) -> Result<Manifest> {
    if let Some(why) = crate::output::unwritable_folder(dir) {
        return Err(io(dir)(std::io::Error::other(why)));
    }
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let mut m = Manifest::default();
    for &(stage, cost, images) in stages {
        for im in images {
            let mem = cost.memories.iter().find(|x| x.name == im.name);
            let kind = mem.map_or(MemKind::Rom, |x| x.kind);
            let file = written(cost, im).then(|| file_name(stage, &im.name));
            if let Some(f) = &file {
                crate::output::write_file(dir.join(f), hex(im))?;
            }
            m.memories.push(RomEntry {
                stage,
                name: im.name.clone(),
                kind,
                width: im.fields.iter().sum(),
                depth: mem.map_or(im.words as u64, |x| x.depth),
                fields: im.fields.clone(),
                words: im.words as u64,
                file,
            });
        }
    }
    let json = serde_json::to_string_pretty(&m).unwrap_or_default();
    crate::output::write_file(dir.join(MANIFEST), json)?;
    Ok(m)
}
