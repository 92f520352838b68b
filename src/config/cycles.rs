//! `[cycles]`: the clock, the tile size of the plan, the frame-memory port and the timing
//! (lanes, latency, initiation interval, FIFO depth) of every stage with a cycle model
//! (docs/cycles.md).

use super::set;
use crate::stage_id::StageId;
use serde::{Deserialize, Serialize};

/// `cycles.clock_mhz` (and `--clock-mhz`), MHz: 1 kHz to 10 GHz.
pub const CLOCK_MHZ: std::ops::RangeInclusive<f64> = 0.001..=10_000.0;
/// `cycles.tile`, pixels: a power of two in this range.
pub const TILE: std::ops::RangeInclusive<u32> = 4..=256;
/// `cycles.frame_port_bits`.
pub const FRAME_PORT_BITS: std::ops::RangeInclusive<u32> = 1..=4096;
/// The fields of a `[cycles.<stage>]` table and their ranges.
pub const TIMING_RANGES: [(&str, u32, u32); 4] = [
    ("lanes", 1, 1024),
    ("latency", 0, 1024),
    ("ii", 1, 64),
    ("fifo", 1, 65536),
];

/// Timing of one stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct StageTiming {
    /// Items per clock.
    pub lanes: u32,
    /// Cycles from a token's last item to its output.
    pub latency: u32,
    /// Initiation interval: clocks between two groups of `lanes` items.
    pub ii: u32,
    /// Depth of the FIFO to the next stage, in tokens (unused by a chain's last stage).
    pub fifo: u32,
}

impl StageTiming {
    const fn new(lanes: u32, latency: u32, ii: u32, fifo: u32) -> Self {
        Self {
            lanes,
            latency,
            ii,
            fifo,
        }
    }
    /// Cycles to serve `items`.
    #[inline]
    pub fn service(&self, items: u64) -> u64 {
        items.div_ceil(self.lanes as u64).max(1) * self.ii as u64
    }
}

/// The `[cycles]` section of the hardware file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CyclesCfg {
    /// Clock, MHz (`--clock-mhz` overrides).
    pub clock_mhz: f64,
    /// Tile size in pixels (square) of the plan's tile map.
    pub tile: u32,
    /// Frame-memory port width, bits per clock.
    pub frame_port_bits: u32,
    /// Input quantisation (items: vertices).
    pub input: StageTiming,
    /// Setup (items: primitives).
    pub setup: StageTiming,
    /// Raster (items: sample positions stepped).
    pub raster: StageTiming,
    /// Visibility (items: depth tests).
    pub visibility: StageTiming,
    /// Log coding: the encoder on the sample buffer's write port (items: codes, one per
    /// depth test and one per light point).
    pub logdomain: StageTiming,
    /// Accumulate (items: MACs).
    pub accumulate: StageTiming,
    /// Depth of field (items: output samples of the two 1-D passes).
    pub dof: StageTiming,
    /// Gamma (items: pixels).
    pub gamma: StageTiming,
    /// Dither (items: pixels; error diffusion runs each row's pixels one after another,
    /// `lanes` rows in flight).
    pub dither: StageTiming,
}

/// The stages with a `[cycles.<stage>]` timing table, in flow order.
pub const TIMED: [StageId; 9] = [
    StageId::Input,
    StageId::Setup,
    StageId::Raster,
    StageId::Visibility,
    StageId::Logdomain,
    StageId::Accumulate,
    StageId::Dof,
    StageId::Gamma,
    StageId::Dither,
];

impl CyclesCfg {
    /// Defaults of the presets: a 100 MHz design with a pipelined divider in setup (one
    /// primitive every 4 clocks), 4 samples per clock in raster and visibility, 16 MACs per
    /// clock in the filter, a tap-parallel depth-of-field row MAC per pass (two output
    /// samples per clock: one horizontal, one vertical, as `dof_row_mac`), one pixel per clock
    /// through the gamma LUT and the dither, a log encoder per depth-test lane (a threshold
    /// ROM searched in a 2-stage pipeline), and a frame-memory port of four frame words per
    /// clock.
    pub fn default_for(frame_int_bits: u32) -> Self {
        Self {
            clock_mhz: 100.0,
            tile: 16,
            frame_port_bits: 4 * frame_int_bits,
            input: StageTiming::new(1, 4, 1, 16),
            setup: StageTiming::new(1, 16, 4, 16),
            raster: StageTiming::new(4, 4, 1, 64),
            visibility: StageTiming::new(4, 3, 1, 64),
            logdomain: StageTiming::new(4, 2, 1, 64),
            accumulate: StageTiming::new(16, 6, 1, 4),
            dof: StageTiming::new(2, 8, 1, 4),
            gamma: StageTiming::new(1, 2, 1, 4),
            dither: StageTiming::new(1, 1, 1, 4),
        }
    }

    /// The timing of a stage (every stage has one; `Option` for the callers that also
    /// handle a stage without tokens).
    pub fn timing(&self, id: StageId) -> Option<&StageTiming> {
        Some(match id {
            StageId::Input => &self.input,
            StageId::Setup => &self.setup,
            StageId::Raster => &self.raster,
            StageId::Visibility => &self.visibility,
            StageId::Accumulate => &self.accumulate,
            StageId::Dof => &self.dof,
            StageId::Gamma => &self.gamma,
            StageId::Logdomain => &self.logdomain,
            StageId::Dither => &self.dither,
        })
    }

    /// Mutable timing of a stage.
    pub fn timing_mut(&mut self, id: StageId) -> Option<&mut StageTiming> {
        Some(match id {
            StageId::Input => &mut self.input,
            StageId::Setup => &mut self.setup,
            StageId::Raster => &mut self.raster,
            StageId::Visibility => &mut self.visibility,
            StageId::Accumulate => &mut self.accumulate,
            StageId::Dof => &mut self.dof,
            StageId::Gamma => &mut self.gamma,
            StageId::Logdomain => &mut self.logdomain,
            StageId::Dither => &mut self.dither,
        })
    }

    /// Checks the ranges; returns the failing field and a message.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let err = |f: &str, m: String| Err((format!("cycles.{f}"), m));
        if let Err(m) = check_clock(self.clock_mhz) {
            return err("clock_mhz", m);
        }
        if !(self.tile.is_power_of_two() && TILE.contains(&self.tile)) {
            return err(
                "tile",
                format!(
                    "must be a power of two in {}..={} pixels, got {}",
                    TILE.start(),
                    TILE.end(),
                    self.tile
                ),
            );
        }
        if !FRAME_PORT_BITS.contains(&self.frame_port_bits) {
            return err(
                "frame_port_bits",
                format!(
                    "must be in {}..={}, got {}",
                    FRAME_PORT_BITS.start(),
                    FRAME_PORT_BITS.end(),
                    self.frame_port_bits
                ),
            );
        }
        for id in TIMED {
            let t = self.timing(id).expect("every timed stage has a timing");
            let values = [t.lanes, t.latency, t.ii, t.fifo];
            for ((field, lo, hi), v) in TIMING_RANGES.into_iter().zip(values) {
                if !(lo..=hi).contains(&v) {
                    return err(
                        &format!("{id}.{field}"),
                        format!("must be in {lo}..={hi}, got {v}"),
                    );
                }
            }
        }
        Ok(())
    }
}

/// Checks a clock frequency (`cycles.clock_mhz`, `--clock-mhz`).
pub fn check_clock(mhz: f64) -> Result<(), String> {
    if mhz.is_finite() && CLOCK_MHZ.contains(&mhz) {
        Ok(())
    } else {
        Err(format!(
            "must be in [{}, {}] MHz (1 kHz to 10 GHz), got {}",
            CLOCK_MHZ.start(),
            CLOCK_MHZ.end(),
            crate::files::num(mhz)
        ))
    }
}

/// `[cycles]` as written in the hardware file (every field optional).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCycles {
    clock_mhz: Option<f64>,
    tile: Option<u32>,
    frame_port_bits: Option<u32>,
    input: Option<RawTiming>,
    setup: Option<RawTiming>,
    raster: Option<RawTiming>,
    visibility: Option<RawTiming>,
    logdomain: Option<RawTiming>,
    accumulate: Option<RawTiming>,
    dof: Option<RawTiming>,
    gamma: Option<RawTiming>,
    dither: Option<RawTiming>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTiming {
    lanes: Option<u32>,
    latency: Option<u32>,
    ii: Option<u32>,
    fifo: Option<u32>,
}

impl RawCycles {
    /// Overrides the given fields of `c`.
    pub(super) fn apply(self, c: &mut CyclesCfg) {
        set(&mut c.clock_mhz, self.clock_mhz);
        set(&mut c.tile, self.tile);
        set(&mut c.frame_port_bits, self.frame_port_bits);
        for (id, raw) in [
            (StageId::Input, self.input),
            (StageId::Setup, self.setup),
            (StageId::Raster, self.raster),
            (StageId::Visibility, self.visibility),
            (StageId::Logdomain, self.logdomain),
            (StageId::Accumulate, self.accumulate),
            (StageId::Dof, self.dof),
            (StageId::Gamma, self.gamma),
            (StageId::Dither, self.dither),
        ] {
            if let (Some(r), Some(t)) = (raw, c.timing_mut(id)) {
                set(&mut t.lanes, r.lanes);
                set(&mut t.latency, r.latency);
                set(&mut t.ii, r.ii);
                set(&mut t.fifo, r.fifo);
            }
        }
    }
}
