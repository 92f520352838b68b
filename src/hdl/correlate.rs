//! Correlation of the cycle model with the RTL: a stage's real token stream (the item count
//! of each token of the run's `Tokens`, as the cycle model takes them:
//! [`crate::cycles::workload`]) streamed through its handshake RTL under Verilator, the
//! RTL's cycles against the cycle model's busy cycles plus latency for that stage.
//!
//! One instance is run: the busiest lane's share of each token, `ceil(items / lanes)`
//! vectors (the model's `lanes` of the stage are instances x lanes per instance, and the
//! DoF row MAC's vector carries both passes' samples). The testbench (`+tokens`,
//! `hdl-models/tb/hs_tb.vh`) reads those counts from `tokens.hex`, streams that many vectors
//! at full rate (the bench's vectors taken cyclically, every output still checked) and counts
//! the cycles from the first input accepted to the last output taken, inclusive. The RTL
//! carries no token boundary: tokens follow each other back to back, where the model charges
//! each token `max(1, ceil(items / lanes)) * ii` cycles (and the frame-memory port's cycles
//! when they are more), so empty tokens and the port are where the two can differ.

use super::timing::{Timed, timing_run, work_dir};
use crate::cycles::Workload;
use crate::error::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

/// The documented bound of the correlation error, percent (docs/cycles.md).
pub const BOUND_PCT: f64 = 1.0;

/// One stage's correlation.
#[derive(Clone, Debug, PartialEq)]
pub struct Correlation {
    /// The stage and its module.
    pub timed: Timed,
    /// Tokens of the stage.
    pub tokens: usize,
    /// Items of all tokens.
    pub items: u64,
    /// Vectors the instance took (the sum of `ceil(items / lanes)` over tokens).
    pub vectors: u64,
    /// The RTL's cycles from the first input accepted to the last output taken.
    pub rtl_cycles: u64,
    /// The cycle model's busy cycles of the stage.
    pub model_busy: u64,
    /// The stage's latency in the model.
    pub latency: u32,
}

impl Correlation {
    /// The model's cycles for the stream: busy cycles plus latency.
    pub fn model_cycles(&self) -> u64 {
        self.model_busy + self.latency as u64
    }

    /// (RTL - model) / model, percent.
    pub fn error_pct(&self) -> f64 {
        let m = self.model_cycles().max(1) as f64;
        (self.rtl_cycles as f64 - m) / m * 100.0
    }

    /// Whether the error is within [`BOUND_PCT`].
    pub fn within_bound(&self) -> bool {
        self.error_pct().abs() <= BOUND_PCT
    }
}

/// The instance's vectors of each token of stage `i` of `w`: `ceil(items / lanes)`.
pub fn instance_counts(w: &Workload, i: usize) -> Vec<u64> {
    let s = &w.stages[i];
    s.items
        .iter()
        .map(|&n| n.div_ceil(s.timing.lanes.max(1) as u64))
        .collect()
}

/// Streams the tokens of stage `timed.timing` of `w` through its RTL (the bench `b`, written
/// with `tokens.hex` into a temporary folder) under Verilator; `None` when the plan has no
/// such stage.
pub fn correlate(
    timed: Timed,
    w: &Workload,
    b: &super::Bench,
    cache: &Path,
) -> Result<Option<Correlation>> {
    let Some(i) = w.stages.iter().position(|s| s.id == timed.timing) else {
        return Ok(None);
    };
    let counts = instance_counts(w, i);
    let mut text = String::with_capacity(counts.len() * 8);
    for c in &counts {
        let _ = writeln!(text, "{c:x}");
    }
    let dir = work_dir(timed.module);
    let run = (|| {
        b.write(&dir).map_err(|e| e.to_string())?;
        crate::output::write_file(dir.join("tokens.hex"), text).map_err(|e| e.to_string())?;
        timing_run(
            &format!("tb_{}", b.module),
            b.module,
            &dir,
            cache,
            &["+tokens"],
        )
    })();
    let _ = std::fs::remove_dir_all(&dir);
    let t = run.map_err(|m| Error::Io {
        path: format!("Verilator run of {} on the token stream", timed.module),
        source: std::io::Error::other(m),
    })?;
    let s = &w.stages[i];
    Ok(Some(Correlation {
        timed,
        tokens: s.items.len(),
        items: s.items.iter().sum(),
        vectors: t.items,
        rtl_cycles: t.last_out - t.first_in + 1,
        model_busy: w.services(i).0.iter().sum(),
        latency: s.timing.latency,
    }))
}
