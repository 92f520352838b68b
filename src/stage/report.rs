//! What a stage reports: its work, cost (memories and arithmetic units, exact from the
//! formats), instrumented signals, stage-local error and notes, plus the tokens it hands the
//! cycle model and the images of its memories for the pack check.

use crate::fixed::SignalStats;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Stage-specific facts for the report (e.g. unreachable DAC codes), by name.
pub type Notes = BTreeMap<String, serde_json::Value>;

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

/// RAM (written by the datapath) or ROM (built from a formula).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MemKind {
    /// Read-write memory: frame memory, sample buffer, line buffers.
    Ram,
    /// Read-only memory: LUTs, coefficient and weight tables.
    Rom,
}

/// One memory of a stage, sized from the formats.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Memory {
    /// Name (the pack check and `--rom-out` use it).
    pub name: String,
    /// RAM or ROM.
    pub kind: MemKind,
    /// Words.
    pub depth: u64,
    /// Bits per word.
    pub width: u32,
}

impl Memory {
    /// A RAM of `depth` words of `width` bits.
    pub fn ram(name: &str, depth: u64, width: u32) -> Self {
        Self {
            name: name.into(),
            kind: MemKind::Ram,
            depth,
            width,
        }
    }
    /// A ROM of `depth` words of `width` bits.
    pub fn rom(name: &str, depth: u64, width: u32) -> Self {
        Self {
            name: name.into(),
            kind: MemKind::Rom,
            depth,
            width,
        }
    }
    /// Bits.
    pub fn bits(&self) -> u64 {
        self.depth * self.width as u64
    }
}

/// Cost of a stage: its memories and arithmetic, exact from the formats.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Cost {
    /// RAM bits (sum of the RAMs).
    pub storage_bits: u64,
    /// ROM / LUT bits (sum of the ROMs).
    pub lut_bits: u64,
    /// The memories one by one.
    pub memories: Vec<Memory>,
    /// Adders, comparators, accumulators.
    pub adders: Vec<Unit>,
    /// Multipliers and dividers.
    pub multipliers: Vec<Unit>,
}

impl Cost {
    /// A cost from its memories and units (the bit totals are their sums).
    pub fn new(memories: Vec<Memory>, adders: Vec<Unit>, multipliers: Vec<Unit>) -> Self {
        let sum = |k: MemKind| {
            memories
                .iter()
                .filter(|m| m.kind == k)
                .map(Memory::bits)
                .sum()
        };
        Self {
            storage_bits: sum(MemKind::Ram),
            lut_bits: sum(MemKind::Rom),
            memories,
            adders,
            multipliers,
        }
    }
    /// Adds another cost's memories and units.
    pub fn merge(self, other: Cost) -> Self {
        let mut m = self.memories;
        m.extend(other.memories);
        let mut a = self.adders;
        a.extend(other.adders);
        let mut x = self.multipliers;
        x.extend(other.multipliers);
        Cost::new(m, a, x)
    }
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
    /// Adds another part's values (before [`LocalError::finish`]).
    pub fn merge(&mut self, o: &Self) {
        self.values += o.values;
        self.identical += o.identical;
        self.max_abs_lsb = self.max_abs_lsb.max(o.max_abs_lsb);
        self.mean_lsb += o.mean_lsb;
        self.mismatched_items += o.mismatched_items;
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
    /// Wall time of the stage-local comparison, milliseconds.
    pub local_ms: f64,
    /// Work items (triangles, spans, samples, pixels, MACs, lookups).
    pub work: BTreeMap<String, u64>,
    /// Cost.
    pub cost: Cost,
    /// Instrumented signals.
    pub signals: Vec<SignalStats>,
    /// Stage-local error against the float stage on the same input.
    pub local: Option<LocalError>,
    /// Stage-specific notes (e.g. unreachable DAC codes).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub notes: Notes,
}

/// What the fixed model tells the report besides its output taps.
#[derive(Clone, Debug, Default)]
pub struct Facts {
    /// Work items, by name.
    pub work: Vec<(&'static str, u64)>,
    /// Instrumented signals.
    pub signals: Vec<SignalStats>,
    /// Notes.
    pub notes: Notes,
}

impl Facts {
    /// Adds a note.
    pub fn note(&mut self, key: &str, v: impl Serialize) {
        self.notes
            .insert(key.into(), serde_json::to_value(v).unwrap_or_default());
    }
}

/// What one token of a stage is: the cycle model links consecutive stages with the same
/// kind by a FIFO; a change of kind means the upstream stage writes a memory (a sink) and
/// the downstream one starts when everything before it has finished.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TokenKind {
    /// One primitive (geometry chain).
    Primitive,
    /// One binned tile of the plan (pixel chain).
    Tile,
    /// One depth-of-field layer.
    Layer,
    /// One screen row.
    Row,
}

/// The tokens a stage hands the cycle model, from the real run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Tokens {
    /// What a token is.
    pub kind: TokenKind,
    /// What one item is (the unit `lanes` count).
    pub item: &'static str,
    /// Items per token, in processing order.
    pub items: Vec<u64>,
    /// Bits each token moves over the frame-memory port (empty: none).
    pub port_bits: Vec<u64>,
    /// First screen row each token writes (empty: the tokens are not rows of the frame);
    /// the accumulate stage's tiles, which the streamed depth of field waits for.
    pub rows: Vec<u32>,
    /// The same work as screen rows, for a stage that can stream behind accumulate
    /// (`dof.schedule = "stream"`; `None`: it runs on the finished frame only).
    pub stream: Option<RowStream>,
}

/// A depth-of-field stage's work as a stream of screen rows (docs/cycles.md, "Streamed
/// depth of field").
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct RowStream {
    /// Items per screen row, top to bottom (their sum is the tokens' items).
    pub items: Vec<u64>,
    /// Largest blur radius of the plan, rows: output row `y` reads input rows
    /// `y - radius ..= y + radius`.
    pub radius: u32,
    /// Bits per pixel the stage reads from its input (the line buffers' word).
    pub read_bits: u32,
}

/// The contents of one memory of a stage, for the pack check and `--rom-out`: `fields`
/// widths per word (their sum is the word width), `words` words, `get(word, field)`.
#[derive(Clone)]
pub struct MemImage {
    /// The memory's name (as in the stage's [`Cost`]).
    pub name: String,
    /// Field widths of one word, bits.
    pub fields: Vec<u32>,
    /// Words.
    pub words: usize,
    /// Whether the image covers only the plan's region of a screen-sized memory (its
    /// depth is then at most the cost's).
    pub region_only: bool,
    /// Field `f` of word `w`.
    pub get: Arc<dyn Fn(usize, usize) -> u64 + Send + Sync>,
}

impl std::fmt::Debug for MemImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MemImage")
            .field("name", &self.name)
            .field("fields", &self.fields)
            .field("words", &self.words)
            .finish()
    }
}

impl MemImage {
    /// A one-field image of a table (a ROM): entry `w` of `table`, `width` bits.
    pub fn table<T>(name: &str, width: u32, table: Arc<Vec<T>>) -> Self
    where
        T: Copy + Into<u64> + Send + Sync + 'static,
    {
        Self {
            name: name.into(),
            fields: vec![width],
            words: table.len(),
            region_only: false,
            get: Arc::new(move |w, _| table[w].into()),
        }
    }
}

/// Luminance-domain comparison.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct WeberCompare {
    /// The visibility threshold delta from the scene.
    pub delta: f64,
    /// Largest Weber fraction.
    pub max: f64,
    /// Mean Weber fraction.
    pub mean: f64,
    /// Pixels whose error exceeds delta (visible).
    pub over_delta: u64,
    /// `over_delta / count`.
    pub over_delta_fraction: f64,
}

/// Weber statistics of (luminance, reference luminance) pairs against the threshold `delta`.
pub fn weber_of(pairs: impl Iterator<Item = (f64, f64)>, delta: f64) -> WeberCompare {
    let mut w = WeberCompare {
        delta,
        ..Default::default()
    };
    let (mut sum, mut n) = (0.0, 0u64);
    for (ba, bb) in pairs {
        let f = (ba - bb).abs() / bb;
        sum += f;
        n += 1;
        w.max = w.max.max(f);
        if f > delta {
            w.over_delta += 1;
        }
    }
    if n > 0 {
        w.mean = sum / n as f64;
        w.over_delta_fraction = w.over_delta as f64 / n as f64;
    }
    w
}

/// Milliseconds since `t`.
pub fn ms_since(t: std::time::Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
