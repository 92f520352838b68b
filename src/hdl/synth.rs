//! Yosys synthesis of the HDL models at the widths of a hardware config: generic `synth`
//! (gates, flip-flops; ROMs become logic), cell counts per type, cached by widths and ROM
//! contents.

use super::{Bench, model_file};
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Yosys cell counts of one module.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SynthCells {
    /// Verilog module.
    pub module: String,
    /// Total cells.
    pub cells: u64,
    /// Cells per type (`$_AND_`, `$_DFF_P_`, ...).
    pub by_type: BTreeMap<String, u64>,
    /// Whether the result came from the cache.
    pub cached: bool,
}

impl SynthCells {
    /// Flip-flops among the cells.
    pub fn flip_flops(&self) -> u64 {
        self.by_type
            .iter()
            .filter(|(k, _)| k.contains("DFF"))
            .map(|(_, v)| v)
            .sum()
    }
}

/// Parses yosys `stat` output.
pub fn parse_stat(module: &str, text: &str) -> Option<SynthCells> {
    let mut cells = None;
    let mut by_type = BTreeMap::new();
    for l in text.lines() {
        let t = l.trim();
        if let Some(r) = t.strip_prefix("Number of cells:") {
            cells = r.trim().parse().ok();
        } else if t.starts_with('$') && cells.is_some() {
            let mut it = t.split_whitespace();
            if let (Some(k), Some(Ok(v))) = (it.next(), it.next().map(str::parse)) {
                by_type.insert(k.to_string(), v);
            }
        }
    }
    Some(SynthCells {
        module: module.into(),
        cells: cells?,
        by_type,
        cached: false,
    })
}

/// Synthesises the bench's module at its parameters (ROM files from the bench) under
/// `cache` (one directory per input hash); reuses a cached result.
pub fn synth(b: &Bench, cache: &Path) -> Result<SynthCells> {
    let models = |name: &str| {
        model_file("rtl", name).map_err(|m| Error::Io {
            path: "HDL models".into(),
            source: std::io::Error::other(m),
        })
    };
    let (rtl, pipe) = (models(b.module)?, models(super::models::PIPE)?);
    let io = |p: &Path, e: std::io::Error| Error::Io {
        path: p.display().to_string(),
        source: e,
    };
    let mut src = std::fs::read(&rtl).map_err(|e| io(&rtl, e))?;
    src.extend(std::fs::read(&pipe).map_err(|e| io(&pipe, e))?);
    let params: String = b.params.iter().map(|(k, v)| format!("{k}={v};")).collect();
    let roms: String = b.roms.iter().map(|(n, r)| format!("{n}:{r:?};")).collect();
    let h = crate::fnv::fnv1a_parts(&[&src, params.as_bytes(), roms.as_bytes()]);
    let dir: PathBuf = cache.join(format!("{}-{h:016x}", b.module));
    let stat = dir.join("stat.txt");
    if let Some(mut c) = std::fs::read_to_string(&stat)
        .ok()
        .and_then(|t| parse_stat(b.module, &t))
    {
        c.cached = true;
        return Ok(c);
    }
    let mut rom_only = b.clone();
    rom_only.vectors.clear();
    rom_only.write(&dir)?;
    let sets: String = b
        .params
        .iter()
        .map(|(k, v)| format!(" -set {k} {v}"))
        .collect();
    let script = format!(
        "read_verilog -defer {} {}; chparam{sets} {m}; synth -flatten -top {m}; tee -q -o stat.txt stat",
        rtl.display(),
        pipe.display(),
        m = b.module
    );
    let out = Command::new("yosys")
        .arg("-q")
        .arg("-p")
        .arg(&script)
        .current_dir(&dir)
        .output()
        .map_err(|e| io(Path::new("yosys"), e))?;
    let t = std::fs::read_to_string(&stat).unwrap_or_default();
    parse_stat(b.module, &t).ok_or_else(|| Error::Io {
        path: stat.display().to_string(),
        source: std::io::Error::other(format!(
            "yosys gave no statistics: {}",
            String::from_utf8_lossy(&out.stderr)
        )),
    })
}
