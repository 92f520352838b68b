//! The stages of the pipeline, in flow order. Each module holds the stage's fixed-point
//! model, its float reference, its work counts and its cost side by side.

pub mod accumulate;
pub mod dither;
pub mod dof;
pub mod gamma;
pub mod input;
pub mod logdomain;
pub mod raster;
pub mod setup;
pub mod visibility;

use crate::fixed::SignalStats;
use serde::Serialize;
use std::collections::BTreeMap;

/// Every stage name in flow order (the same names are used in `tests/`, `benches/`,
/// `hdl-models/`). A plan runs a subsequence: `logdomain` only for log coding, `dof` only
/// for a thin lens, `dither` only when configured (before or after `gamma`).
pub const STAGES: &[&str] = &[
    "input",
    "setup",
    "raster",
    "visibility",
    "logdomain",
    "accumulate",
    "dof",
    "gamma",
    "dither",
];

/// A hardware unit of one kind: `count` units of `width` bits (multipliers: `width` x `width_b`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Unit {
    /// What it does.
    pub role: String,
    /// How many.
    pub count: u32,
    /// Operand width in bits.
    pub width: u32,
    /// Second operand width (multipliers), else 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub width_b: u32,
}

fn is_zero(v: &u32) -> bool {
    *v == 0
}

impl Unit {
    /// An adder, comparator or accumulator register of `width` bits.
    pub fn adder(role: &str, count: u32, width: u32) -> Self {
        Self {
            role: role.into(),
            count,
            width,
            width_b: 0,
        }
    }
    /// A `width` x `width_b` multiplier.
    pub fn mul(role: &str, count: u32, width: u32, width_b: u32) -> Self {
        Self {
            role: role.into(),
            count,
            width,
            width_b,
        }
    }
}

/// Cost of a stage: storage and arithmetic, exact from the formats.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Cost {
    /// RAM bits (frame memory, z-buffer, sample buffer, line buffers).
    pub storage_bits: u64,
    /// ROM / LUT bits.
    pub lut_bits: u64,
    /// Adders, comparators, accumulators.
    pub adders: Vec<Unit>,
    /// Multipliers and dividers.
    pub multipliers: Vec<Unit>,
}

/// Stage-local comparison: the float stage fed the fixed stage's own input.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LocalError {
    /// Number of output values compared.
    pub values: u64,
    /// Values whose code equals the float value rounded to the nearest code.
    pub identical: u64,
    /// Largest |fixed - float| in output LSBs.
    pub max_abs_lsb: f64,
    /// Mean (fixed - float) in output LSBs (bias).
    pub mean_lsb: f64,
    /// Items that differ structurally (e.g. samples covered by one model only).
    pub mismatched_items: u64,
}

impl LocalError {
    /// Adds one compared value.
    #[inline]
    pub fn add(&mut self, fixed: f64, float: f64) {
        let d = fixed - float;
        self.values += 1;
        if float.round() == fixed {
            self.identical += 1;
        }
        self.max_abs_lsb = self.max_abs_lsb.max(d.abs());
        self.mean_lsb += d; // summed; divided in `finish`
    }
    /// Turns the running sum into a mean.
    pub fn finish(mut self) -> Self {
        if self.values > 0 {
            self.mean_lsb /= self.values as f64;
        }
        self
    }
}

/// What a stage reports: times, work, cost, signals, local error.
#[derive(Clone, Debug, Default, Serialize)]
pub struct StageReport {
    /// Stage name.
    pub name: String,
    /// Wall time of the fixed-point model, milliseconds.
    pub fixed_ms: f64,
    /// Wall time of the float reference, milliseconds.
    pub float_ms: f64,
    /// Work items for the cycle model (triangles, spans, samples, pixels, MACs, lookups).
    pub work: BTreeMap<String, u64>,
    /// Cost.
    pub cost: Cost,
    /// Instrumented signals.
    pub signals: Vec<SignalStats>,
    /// Stage-local error against the float stage on the same input.
    pub local: Option<LocalError>,
    /// Stage-specific notes (e.g. unreachable DAC codes).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub notes: BTreeMap<String, serde_json::Value>,
}

impl StageReport {
    /// Records work items (name, count) for the cycle model.
    pub fn record_work(&mut self, items: &[(&str, u64)]) {
        for &(k, v) in items {
            self.work.insert(k.to_string(), v);
        }
    }
}

/// The sample grid: `n x n` samples per pixel on a coordinate grid of `2^sub_bits` units per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// Samples per pixel along an axis.
    pub n: u32,
    /// Coordinate units per pixel are `2^sub_bits`.
    pub sub_bits: u32,
    /// Half the sample spacing in coordinate units: sample `c` is at `(2c + 1) * h`.
    pub h: i64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Grid {
    /// Builds the grid; `sub_bits >= log2(n) + 1` is validated by the hardware config.
    pub fn new(n: u32, sub_bits: u32, width: u32, height: u32) -> Self {
        let h = (1i64 << sub_bits) / (2 * n as i64);
        Self {
            n,
            sub_bits,
            h,
            width,
            height,
        }
    }
    /// Sample columns across the image.
    pub fn sw(&self) -> usize {
        (self.width * self.n) as usize
    }
    /// Sample rows down the image.
    pub fn sh(&self) -> usize {
        (self.height * self.n) as usize
    }
    /// Sample centre in pixels (float reference).
    #[inline]
    pub fn sample_pos(&self, c: i64) -> f64 {
        (c as f64 + 0.5) / self.n as f64
    }
}

/// A rectangle of pixels, half-open: `[x0, x1) x [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Region {
    /// Left.
    pub x0: u32,
    /// Top.
    pub y0: u32,
    /// Right (exclusive).
    pub x1: u32,
    /// Bottom (exclusive).
    pub y1: u32,
}

impl Region {
    /// Whether no pixel is inside.
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }
    /// Pixels inside.
    pub fn pixels(&self) -> u64 {
        if self.is_empty() {
            0
        } else {
            (self.x1 - self.x0) as u64 * (self.y1 - self.y0) as u64
        }
    }
}

/// Milliseconds since `t`.
pub fn ms_since(t: std::time::Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
