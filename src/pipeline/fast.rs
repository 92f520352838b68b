//! The fixed-only fast path (`render --no-reference`): the plan, the fixed model of every
//! planned stage (every channel's lane of a colour render), the cycle model on their tokens
//! and the cheap metrics (work, signals with their overflows, cost). No float reference
//! runs, so nothing is compared; the DAC codes are those of a full render, bit for bit
//! (tests/fast.rs), at the cost of the fixed model alone. The float reference stays the
//! default of `render` and `check`.

use super::cache::Cache;
use super::colour::{NAMES, fixed_codes, lane_totals};
use super::plan::{self, Plan, PlanReport};
use super::report::{SceneInfo, Timing, scene_info, totals};
use super::run::{self, Step};
use crate::config::HwConfig;
use crate::cycles::CycleReport;
use crate::error::Result;
use crate::scene::Scene;
use crate::stage::{Pool, RunOptions, StageReport};
use serde::Serialize;
use std::sync::Arc;

/// One channel of a fixed-only colour run (`colour.channels` of the JSON report).
#[derive(Clone, Debug, Serialize)]
pub struct FastChannel {
    /// `R`, `G` or `B`.
    pub name: &'static str,
    /// The channel's frame-memory word.
    pub frame: String,
    /// The channel's DAC width.
    pub dac_bits: u32,
    /// Overflows over the signals of the channel's lane.
    pub overflows: u64,
    /// Storage bits (RAM) of the channel's lane, its streamed depth of field's line buffers
    /// included.
    pub storage_bits: u64,
    /// LUT / ROM bits of the channel's lane.
    pub lut_bits: u64,
}

/// The report of a fixed-only run (`render --no-reference --json`): a render report
/// without the comparisons.
#[derive(Clone, Debug, Serialize)]
pub struct FastReport {
    /// Tool version.
    pub igemu_version: String,
    /// `"fixed only"`: no float reference ran.
    pub mode: &'static str,
    /// Scene.
    pub scene: SceneInfo,
    /// Hardware configuration.
    pub hardware: HwConfig,
    /// Plan.
    pub plan: PlanReport,
    /// Per stage, in run order (channel 0's lane for a colour render).
    pub stages: Vec<StageReport>,
    /// Overflows over all signals of every lane.
    pub overflows: u64,
    /// Total storage bits (RAM).
    pub storage_bits: u64,
    /// Total LUT / ROM bits.
    pub lut_bits: u64,
    /// Timing (`float_ms` and `local_ms` are 0).
    pub timing: Timing,
    /// Cycle model, throughput and cost summary.
    pub cycles: CycleReport,
    /// The channels of a colour run (empty: grey).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<FastChannel>,
}

/// Everything a fixed-only run produces.
pub struct Emulation {
    /// The report.
    pub report: FastReport,
    /// The plan it ran.
    pub plan: Plan,
    /// Every stage run, in order, with the fixed taps after it (channel 0's lane).
    pub steps: Vec<Step>,
    /// The steps after visibility of channels 1.. of a colour render (one list each).
    pub lanes: Vec<Vec<Step>>,
    /// Each channel's DAC codes (one plane for grey), row-major.
    pub channels: Vec<Vec<u16>>,
    /// Each channel's DAC width.
    pub bits: Vec<u32>,
}

/// Runs the fixed model of `scene` on `hw` (no float reference, no comparison): the DAC
/// codes, the cycle model and the cost. `opts` gives the memory limit, the band height and
/// whether the memories' images are built and pack-checked (`--rom-out` needs them); the
/// reference options are off. A one-shot run: see [`Emulator`] for a run of frames.
pub fn emulate(
    scene: &Scene,
    hw: &HwConfig,
    opts: RunOptions,
    cache: Option<&Cache>,
) -> Result<Emulation> {
    Emulator::new().emulate(scene, hw, opts, cache)
}

/// The fixed-only path over a run of frames (a sequence, a benchmark, the rows of a
/// sweep): the planes of the taps live across frames in a [`Pool`], so a frame whose
/// emulation is given back with [`Emulator::recycle`] leaves its buffers to the next, and
/// from the second frame of the same screen on a run allocates no frame-sized buffer
/// (tests/frame_pool.rs counts them). The codes are those of [`emulate`], bit for bit.
#[derive(Debug, Default)]
pub struct Emulator {
    pool: Pool,
}

impl Emulator {
    /// An emulator with an empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// The buffers it keeps.
    pub fn pool(&self) -> &Pool {
        &self.pool
    }

    /// [`emulate`] with the planes taken from the pool.
    pub fn emulate(
        &self,
        scene: &Scene,
        hw: &HwConfig,
        opts: RunOptions,
        cache: Option<&Cache>,
    ) -> Result<Emulation> {
        // On the pool, as a render (see `super::render_with`).
        rayon::scope(|_| emulate_on_pool(scene, hw, opts, cache, &self.pool))
    }

    /// Gives the planes of a finished frame back to the pool (the codes, and every tap no
    /// one else holds: a cache that kept a stage's outcome keeps its planes).
    pub fn recycle(&self, e: Emulation) {
        for c in e.channels {
            self.pool.give(c);
        }
        let taps: Vec<_> = e
            .steps
            .into_iter()
            .chain(e.lanes.into_iter().flatten())
            .filter_map(|s| Arc::try_unwrap(s.outcome).ok())
            .map(|o| o.taps)
            .collect();
        self.pool.recycle(taps);
        if let Ok(host) = Arc::try_unwrap(e.plan.host) {
            self.pool.give(host.prims);
        }
    }
}

fn emulate_on_pool(
    scene: &Scene,
    hw: &HwConfig,
    opts: RunOptions,
    cache: Option<&Cache>,
    pool: &Pool,
) -> Result<Emulation> {
    let opts = RunOptions {
        max_memory: opts.max_memory,
        band_rows: opts.band_rows,
        pack_check: opts.pack_check,
        ..RunOptions::FIXED_ONLY
    };
    let plan = plan::build_in(scene, hw, pool)?;
    super::check_memory(scene, &plan, opts)?;
    let (steps, lanes) = run::run_lanes(scene, hw, &plan, opts, cache, None, pool)?;
    let hw0 = hw.channel(0);
    let t = totals(scene, hw, &plan, (&steps, &lanes), cache);
    // Channel 0's lane (a grey run's steps are all its own).
    let split = lanes.first().map_or(0, |l| steps.len() - l.len());
    let lane = |c: usize| -> &[Step] {
        if c == 0 {
            &steps[split..]
        } else {
            &lanes[c - 1]
        }
    };
    let n = plan.layout.channels;
    let codes: Vec<Vec<u16>> = (0..n).map(|c| fixed_codes(lane(c), pool)).collect();
    let bits: Vec<u32> = (0..n).map(|c| hw.channel(c).gamma.dac_bits).collect();
    let channels = if n > 1 {
        (0..n)
            .map(|c| {
                let h = hw.channel(c);
                let stages = lane(c).iter().map(|s| &s.outcome.report);
                let (overflows, storage_bits, lut_bits) = lane_totals(stages);
                // The lane's streamed depth of field has its own line buffers.
                let storage_bits = storage_bits + t.lane_line_bits[c];
                FastChannel {
                    name: NAMES[c],
                    frame: h.accumulate.frame.format.to_string(),
                    dac_bits: h.gamma.dac_bits,
                    overflows,
                    storage_bits,
                    lut_bits,
                }
            })
            .collect()
    } else {
        Vec::new()
    };
    let report = FastReport {
        igemu_version: env!("CARGO_PKG_VERSION").into(),
        mode: "fixed only",
        scene: scene_info(scene, &plan),
        hardware: hw.clone(),
        plan: plan.report(scene, &hw0, opts),
        stages: t.stages,
        overflows: t.overflows,
        storage_bits: t.storage_bits,
        lut_bits: t.lut_bits,
        timing: t.timing,
        cycles: t.cycles,
        channels,
    };
    Ok(Emulation {
        report,
        plan,
        steps,
        lanes,
        channels: codes,
        bits,
    })
}
