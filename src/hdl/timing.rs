//! RTL-measured timing: each HDL model's latency and initiation interval measured by a
//! cycle-accurate Verilator run of its vector testbench through the valid/ready handshake
//! (`hdl-models/tb/hs_tb.vh`), and its comparison with the `[cycles.<stage>]` timing of a
//! hardware config.
//!
//! One module instance is one lane of the cycle model (the DoF row MAC two: one output
//! sample per pass per clock), so what is measured is the per-instance latency and ii; the
//! model's `lanes` is the number of instances. Two runs per module: at full rate (every
//! vector offered at once, the output always taken) and with the testbench's injected stalls
//! (`+stall`: `in_valid` withheld and `out_ready` held low in about one cycle of four each).
//! * latency: cycles from the first input accepted to the first `out_valid` (full rate);
//! * ii at full rate: cycles between the first and the last input accepted per input after
//!   the first;
//! * ii under stalls: the same, less the cycles in which the testbench withheld an input or
//!   held back a valid output (a design that loses no cycle of its own gives the full-rate ii).

use super::bench::{Bench, Verdict};
use super::verilator::Sim;
use crate::config::{CyclesCfg, StageTiming};
use crate::stage_id::StageId;
use std::path::Path;

/// A module timed against a `[cycles.<stage>]` table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timed {
    /// The stage whose `[cycles.<stage>]` timing the module implements.
    pub timing: StageId,
    /// The stage whose vectors drive it (the edge stepper's come from setup's edges).
    pub vectors: StageId,
    /// Verilog module.
    pub module: &'static str,
    /// Lanes of the cycle model one instance is.
    pub lanes: u32,
}

/// The six HDL models in flow order: the edge stepper is the raster's edge walk (its
/// vectors are setup's edges), the DoF row MAC serves both passes (two lanes).
pub const TIMED: [Timed; 6] = [
    Timed::new(StageId::Raster, StageId::Setup, "edge_stepper", 1),
    Timed::new(StageId::Logdomain, StageId::Logdomain, "log_adder", 1),
    Timed::new(StageId::Accumulate, StageId::Accumulate, "acc_mac", 1),
    Timed::new(StageId::Dof, StageId::Dof, "dof_row_mac", 2),
    Timed::new(StageId::Gamma, StageId::Gamma, "gamma_lut", 1),
    Timed::new(StageId::Dither, StageId::Dither, "dither_ordered", 1),
];

impl Timed {
    const fn new(timing: StageId, vectors: StageId, module: &'static str, lanes: u32) -> Self {
        Self {
            timing,
            vectors,
            module,
            lanes,
        }
    }

    /// The timed module of a `[cycles.<stage>]` stage, if it has one.
    pub fn of(stage: StageId) -> Option<Timed> {
        TIMED.into_iter().find(|t| t.timing == stage)
    }
}

/// The counts of a testbench's `TIMING` line (cycles from 0 after reset).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TimingLine {
    /// Inputs streamed.
    pub items: u64,
    /// Cycle of the first input accepted.
    pub first_in: u64,
    /// Cycle of the first `out_valid`.
    pub first_out: u64,
    /// Cycle of the last input accepted.
    pub last_in: u64,
    /// Cycle of the last output taken.
    pub last_out: u64,
    /// Cycles between the first and last acceptance the testbench stalled.
    pub stalls: u64,
}

/// Parses the single `TIMING` line of a testbench's output.
pub fn parse_timing(out: &str) -> Option<TimingLine> {
    let mut lines = out.lines().filter_map(|l| l.trim().strip_prefix("TIMING "));
    let l = lines.next()?;
    if lines.next().is_some() {
        return None;
    }
    let mut t = TimingLine::default();
    for kv in l.split_whitespace() {
        let (k, v) = kv.split_once('=')?;
        let v: u64 = v.parse().ok()?;
        *match k {
            "items" => &mut t.items,
            "first_in" => &mut t.first_in,
            "first_out" => &mut t.first_out,
            "last_in" => &mut t.last_in,
            "last_out" => &mut t.last_out,
            "stalls" => &mut t.stalls,
            _ => return None,
        } = v;
    }
    (t.items >= 2 && t.last_in >= t.first_in + t.stalls && t.first_out >= t.first_in).then_some(t)
}

/// An initiation interval as measured: `cycles` over `inputs` (inputs after the first).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Interval {
    /// Cycles between the first and last acceptance (less the injected stalls).
    pub cycles: u64,
    /// Inputs accepted after the first.
    pub inputs: u64,
}

impl Interval {
    /// Cycles per input.
    pub fn value(&self) -> f64 {
        self.cycles as f64 / self.inputs.max(1) as f64
    }

    /// Whether it is exactly `ii` cycles per input.
    pub fn is(&self, ii: u32) -> bool {
        self.cycles == self.inputs * ii as u64
    }
}

/// A module's measured timing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Measured {
    /// The module.
    pub timed: Timed,
    /// Latency, cycles (full rate).
    pub latency: u64,
    /// ii at full rate.
    pub ii_full: Interval,
    /// ii under the injected stalls (net of them).
    pub ii_stall: Interval,
    /// Cycles the testbench stalled in the stalled run.
    pub stalls: u64,
    /// Vectors streamed in each run.
    pub items: u64,
}

/// Runs `tb` under Verilator in `dir` with `plusargs`; the `TIMING` line of a passing run.
pub fn timing_run(
    tb: &str,
    module: &str,
    dir: &Path,
    cache: &Path,
    plusargs: &[&str],
) -> std::result::Result<TimingLine, String> {
    let r = Sim::Verilator.run_args(tb, module, dir, cache, plusargs)?;
    let mode = if plusargs.is_empty() {
        "full rate".to_string()
    } else {
        plusargs.join(" ")
    };
    if let Verdict::Failed(m) = r.verdict {
        return Err(format!("{module} ({mode}): TESTBENCH FAILED: {m}"));
    }
    parse_timing(&r.stdout)
        .ok_or_else(|| format!("{module} ({mode}): no valid TIMING line in: {}", r.stdout))
}

/// Measures the module of bench `b` (written into `dir`) at full rate and under stalls;
/// Verilator builds are cached under `cache`.
pub fn measure(
    timed: Timed,
    b: &Bench,
    dir: &Path,
    cache: &Path,
) -> std::result::Result<Measured, String> {
    b.write(dir).map_err(|e| e.to_string())?;
    let tb = format!("tb_{}", b.module);
    let full = timing_run(&tb, b.module, dir, cache, &[])?;
    let stall = timing_run(&tb, b.module, dir, cache, &["+stall"])?;
    let ii = |t: &TimingLine| Interval {
        cycles: t.last_in - t.first_in - t.stalls,
        inputs: t.items - 1,
    };
    Ok(Measured {
        timed,
        latency: full.first_out - full.first_in,
        ii_full: ii(&full),
        ii_stall: ii(&stall),
        stalls: stall.stalls,
        items: full.items,
    })
}

/// Where the RTL and a `[cycles.<stage>]` table disagree: the field and both values.
#[derive(Clone, Debug, PartialEq)]
pub struct Mismatch {
    /// The stage.
    pub stage: StageId,
    /// The field (`latency`, `ii`, `ii under stalls`, `lanes`).
    pub field: &'static str,
    /// What the RTL does.
    pub rtl: String,
    /// What the table says.
    pub model: String,
}

impl std::fmt::Display for Mismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "stage {}: {}: the RTL ({}) measures {}, [cycles.{}] says {}",
            self.stage,
            self.field,
            self.timed_module(),
            self.rtl,
            self.stage,
            self.model
        )
    }
}

impl Mismatch {
    fn timed_module(&self) -> &'static str {
        Timed::of(self.stage).map_or("?", |t| t.module)
    }
}

/// The disagreements of a measurement with the stage's timing `t` (empty: they agree). The
/// model's lanes must be a whole number of instances.
pub fn compare(m: &Measured, t: &StageTiming) -> Vec<Mismatch> {
    let stage = m.timed.timing;
    let mut out = Vec::new();
    let mut put = |field, rtl: String, model: String| {
        out.push(Mismatch {
            stage,
            field,
            rtl,
            model,
        })
    };
    if m.latency != t.latency as u64 {
        put("latency", m.latency.to_string(), t.latency.to_string());
    }
    for (field, ii) in [("ii", &m.ii_full), ("ii under stalls", &m.ii_stall)] {
        if !ii.is(t.ii) {
            put(field, format!("{:.3}", ii.value()), t.ii.to_string());
        }
    }
    if !t.lanes.is_multiple_of(m.timed.lanes) {
        put(
            "lanes",
            format!("{} per instance", m.timed.lanes),
            format!("{} (not a whole number of instances)", t.lanes),
        );
    }
    out
}

/// The timings of `c` with the measured latency and ii of the stages in `measured`
/// (`igemu cycles --timing-from-rtl`); lanes and FIFO depths stay.
pub fn with_measured(c: &CyclesCfg, measured: &[Measured]) -> CyclesCfg {
    let mut out = c.clone();
    for m in measured {
        if let Some(t) = out.timing_mut(m.timed.timing) {
            t.latency = m.latency.min(u32::MAX as u64) as u32;
            t.ii = m.ii_full.value().round().max(1.0) as u32;
        }
    }
    out
}

/// The preset whose log adder times `logdomain` when the chosen hardware has none (the
/// module's timing does not depend on its widths).
pub const LOG_PRESET: &str = "log8-logadd";

/// The bench that times `timed` on `scene` and `hw`, and a note when it comes from another
/// configuration: where `hw` has no such module (no log adder on linear hardware, no linear
/// MAC on log-add hardware) the bench is built on [`LOG_PRESET`] for the log adder, on the
/// first preset for the others.
pub fn bench_for(
    timed: Timed,
    scene: &crate::scene::Scene,
    hw: &crate::config::HwConfig,
) -> crate::error::Result<(Bench, Option<String>)> {
    match super::vectors(timed.vectors, scene, hw) {
        Ok(b) => Ok((b, None)),
        Err(e) => {
            let name = if timed.timing == StageId::Logdomain {
                LOG_PRESET
            } else {
                crate::config::PRESETS[0]
            };
            let other = crate::config::HwConfig::preset(name).ok_or(e)?;
            let b = super::vectors(timed.vectors, scene, &other)?;
            Ok((
                b,
                Some(format!(
                    "bench from preset {name}: hardware `{}` has no {}",
                    hw.name, timed.module
                )),
            ))
        }
    }
}

/// A fresh work folder under the system's temporary folder for one run of `module`.
pub fn work_dir(module: &str) -> std::path::PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static SEQ: AtomicU64 = AtomicU64::new(0);
    std::env::temp_dir().join(format!(
        "igemu-timing-{}-{}-{module}",
        std::process::id(),
        SEQ.fetch_add(1, Ordering::Relaxed)
    ))
}

/// Measures the module of `timed` on `scene` and `hw` in a temporary folder (removed after);
/// the measurement and the bench's note ([`bench_for`]).
pub fn measure_stage(
    timed: Timed,
    scene: &crate::scene::Scene,
    hw: &crate::config::HwConfig,
    cache: &Path,
) -> crate::error::Result<(Measured, Option<String>)> {
    let (b, note) = bench_for(timed, scene, hw)?;
    let dir = work_dir(timed.module);
    let m = measure(timed, &b, &dir, cache);
    let _ = std::fs::remove_dir_all(&dir);
    let m = m.map_err(|m| crate::error::Error::Io {
        path: format!("Verilator run of {}", timed.module),
        source: std::io::Error::other(m),
    })?;
    Ok((m, note))
}
