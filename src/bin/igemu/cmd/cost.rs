//! `igemu cost`: hardware cost per stage, the analytic model, and with `--synth` the yosys
//! cell counts of the HDL models at the configured widths.

use crate::args::{HdlDirs, SceneArgs};
use crate::out::outln;
use clap::Args;
use igemu::cost::LINE_BUFFERS;
use igemu::error::Error;
use igemu::hdl;
use igemu::hdl::synth::SynthCells;
use igemu::pipeline;
use igemu::stage::RunOptions;
use igemu::stage_id::StageId;
use std::process::ExitCode;

#[derive(Args)]
pub struct CostArgs {
    #[command(flatten)]
    pub s: SceneArgs,
    /// Synthesise each HDL model with yosys at the configured widths (cached in CACHE/hdl-synth, see --cache-dir).
    #[arg(long)]
    pub synth: bool,
    #[command(flatten)]
    pub dirs: HdlDirs,
    /// Print the table as JSON on stdout (docs/formats.md).
    #[arg(long)]
    pub json: bool,
}

/// Runs `igemu cost`; returns the exit code.
pub fn run(a: CostArgs) -> Result<ExitCode, Error> {
    let scene = a.s.scene()?;
    let hw = a.s.hw()?;
    let r = pipeline::render(&scene, &hw, a.s.opts(RunOptions::FAST))?;
    let cache = a.dirs.apply()?.join("hdl-synth");
    let rows: Vec<Row> = r
        .report
        .stages
        .iter()
        .map(|st| {
            let c = &st.cost;
            let model = StageId::parse(&st.name).and_then(|id| Some((id, hdl::module_of(id)?)));
            let synth = match model {
                Some((id, _)) if a.synth => Some(
                    hdl::vectors(id, &scene, &hw)
                        .and_then(|b| hdl::synth::synth(&b, &cache))
                        .map_err(|e| e.to_string()),
                ),
                _ => None,
            };
            Row {
                stage: st.name.clone(),
                storage_bits: c.storage_bits,
                lut_bits: c.lut_bits,
                adders: c.adders.iter().map(|u| u.count).sum(),
                multipliers: c.multipliers.iter().map(|u| u.count).sum(),
                module: model.map(|m| m.1),
                synth,
            }
        })
        .collect();
    if a.json {
        let stages: Vec<serde_json::Value> = rows.iter().map(Row::json).collect();
        let v = serde_json::json!({
            "hardware": hw.name,
            "scene": scene.name,
            "synth": a.synth,
            "stages": stages,
            "line_buffers": line_buffers(&r.report.cycles),
        });
        outln!(
            "{}",
            serde_json::to_string_pretty(&v).expect("serialisable")
        );
        return Ok(ExitCode::SUCCESS);
    }
    outln!(
        "cost | hardware `{}` | scene `{}`{}",
        hw.name,
        scene.name,
        if a.synth {
            " | yosys synth (generic gates)"
        } else {
            ""
        }
    );
    outln!(
        "{:<11} {:>12} {:>10} {:>7} {:>6}  HDL model: yosys cells (flip-flops)",
        "stage",
        "storage_bits",
        "lut_bits",
        "adders",
        "mults"
    );
    for row in &rows {
        let synth = match (row.module, &row.synth) {
            (Some(m), Some(Ok(s))) => format!(
                "{m}: {} cells ({} FF){}",
                s.cells,
                s.flip_flops(),
                if s.cached { ", cached" } else { "" }
            ),
            (Some(m), Some(Err(e))) => format!("{m}: synthesis failed: {e}"),
            (Some(m), None) => format!("{m} (use --synth)"),
            (None, _) => "-".into(),
        };
        outln!(
            "{:<11} {:>12} {:>10} {:>7} {:>6}  {synth}",
            row.stage,
            row.storage_bits,
            row.lut_bits,
            row.adders,
            row.multipliers
        );
    }
    if let Some(lb) = &r.report.cycles.schedules {
        let s = &lb.stream;
        outln!(
            "{LINE_BUFFERS}: {} bits ({} rows; dof.schedule = \"{}\"{})",
            s.line_buffer_bits,
            s.line_buffer_rows,
            lb.chosen.name(),
            if r.report.cycles.cost.line_buffer_bits > 0 {
                ""
            } else {
                ", not charged"
            }
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The streamed depth-of-field schedule's line buffers as JSON: null without a stage that
/// streams, else `{schedule, bits, rows, charged}` (`charged`: the chosen schedule is
/// "stream", so the cycle report's cost includes them).
fn line_buffers(c: &igemu::cycles::CycleReport) -> serde_json::Value {
    match &c.schedules {
        None => serde_json::Value::Null,
        Some(b) => serde_json::json!({
            "schedule": b.chosen.name(),
            "bits": b.stream.line_buffer_bits,
            "rows": b.stream.line_buffer_rows,
            "charged": c.cost.line_buffer_bits > 0,
        }),
    }
}

/// One stage's row of the cost table.
struct Row {
    stage: String,
    storage_bits: u64,
    lut_bits: u64,
    adders: u32,
    multipliers: u32,
    /// The stage's HDL module, if it has one.
    module: Option<&'static str>,
    /// With `--synth`: the yosys cell counts or why there are none.
    synth: Option<Result<SynthCells, String>>,
}

impl Row {
    /// The row as JSON: `synth` is null without `--synth` or without a model, else
    /// `{cells, flip_flops, cached, by_type}` or `{error}`.
    fn json(&self) -> serde_json::Value {
        let synth = match &self.synth {
            None => serde_json::Value::Null,
            Some(Ok(s)) => serde_json::json!({
                "cells": s.cells,
                "flip_flops": s.flip_flops(),
                "cached": s.cached,
                "by_type": s.by_type,
            }),
            Some(Err(e)) => serde_json::json!({ "error": e }),
        };
        serde_json::json!({
            "stage": self.stage,
            "storage_bits": self.storage_bits,
            "lut_bits": self.lut_bits,
            "adders": self.adders,
            "multipliers": self.multipliers,
            "hdl_module": self.module,
            "synth": synth,
        })
    }
}
