//! Cycle model: a cycle-counting simulation of the plan's stage chains on the real workload
//! of the scene, with bounded FIFOs and back-pressure (docs/reference.md §7a, docs/cycles.md).
//!
//! # Model
//! Every planned stage with a `[cycles.<stage>]` timing hands the model its tokens from the
//! real run ([`crate::stage::Tokens`]); the chains follow from the plan ([`workload`]):
//! * **geometry** `input -> setup -> raster -> visibility`, one token per primitive in the
//!   order the pipeline processes them (surfaces in scene order, then light points);
//!   visibility writes the sample buffer (the chain's sink);
//! * **pixels** `accumulate -> gamma`, one token per binned tile of the plan (row-major); it
//!   starts when the geometry chain has drained (the filter reads resolved samples), and
//!   gamma writes the display buffer. Tiles the plan did not bin hold the background code
//!   and cost no cycles (a per-tile "background" flag, like a fast clear);
//! * with a thin lens and `dof.schedule = "frame"`, accumulate writes the frame memory (a
//!   sink), `dof` runs on the finished frame (one token per depth layer) and `gamma` then
//!   reads it row by row;
//! * with `dof.schedule = "stream"` (the default), `dof` takes one token per screen row and
//!   reads accumulate's rows through line buffers ([`Lines`]): row `y` starts when rows up
//!   to `y + radius` are complete, accumulate stalls while the buffers are full, and gamma
//!   follows `dof` through its FIFO. The report carries both schedules' frame times
//!   ([`Schedules`]); the cost charges the line buffers.
//!
//! A stage serves one token at a time for `max(1, ceil(items / lanes)) * ii` cycles ([`sim`],
//! which jumps over the cycles in which nothing changes; [`stepwise`] is its one-clock-at-a-
//! time reference).
//! The accumulate stage's frame memory is a port of `frame_port_bits` per clock; each
//! read-modify-write moves `2 x` the frame word, so a tile takes at least
//! `ceil(rmw * 2 * frame_bits / port_bits)` cycles.
//!
//! Items per token, from the real run: input = vertices (3, 2 or 1), setup = 1 primitive,
//! raster = sample positions the walker steps (emitted + walked outside the region),
//! visibility = depth tests, accumulate = MACs (window samples x pixels), dof = output
//! samples of both 1-D passes (streamed: each layer's spread evenly over the rows of its
//! box), gamma = pixels. Approximation: the raster's items are
//! charged per primitive (`ceil(items/lanes)`), not per span, so the per-span rounding of a
//! real span walker is not modelled.

pub mod schedule;
pub mod sim;
pub mod stepwise;
pub mod vcd;
pub mod workload;

pub use schedule::{ScheduleTime, Schedules};
pub use sim::{SimResult, StageCycles, State, Trace, simulate};
pub use stepwise::simulate_stepwise;
pub use workload::{ChainStage, Lines, ScreenFacts, Workload};

use crate::cost::CostSummary;
use crate::stage::StageId;
use serde::Serialize;

/// The plan as the cycle model sees it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CyclePlan {
    /// Stages the run planned, in run order.
    pub stages: Vec<String>,
    /// Planned stages without a cycle model (not simulated).
    pub unmodelled: Vec<String>,
    /// Tile size, pixels.
    pub tile: u32,
    /// Binned tiles (simulated).
    pub tiles_touched: u64,
    /// Tiles of the screen.
    pub tiles_total: u64,
    /// Pixels simulated in the pixel chain.
    pub pixels_simulated: u64,
    /// Pixels of the screen.
    pub pixels_total: u64,
}

/// Frame rate against the display's real-time requirement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Throughput {
    /// Clock, MHz.
    pub clock_mhz: f64,
    /// Frame time, ms.
    pub frame_ms: f64,
    /// Frames per second.
    pub fps: f64,
    /// Screen pixels per second delivered (resolution x fps).
    pub pixel_rate: f64,
    /// Display refresh the scene asks for, Hz.
    pub refresh_hz: f64,
    /// Pixel rate the display needs (resolution x refresh).
    pub required_pixel_rate: f64,
    /// Whether a frame fits in a refresh period.
    pub real_time: bool,
}

impl Throughput {
    /// Frame rate of `cycles` at `clock_mhz` against the display.
    pub fn new(cycles: u64, clock_mhz: f64, screen_pixels: u64, refresh_hz: f64) -> Self {
        let frame_s = cycles as f64 / (clock_mhz * 1e6);
        let fps = if cycles == 0 {
            f64::INFINITY
        } else {
            1.0 / frame_s
        };
        Self {
            clock_mhz,
            frame_ms: frame_s * 1e3,
            fps,
            pixel_rate: screen_pixels as f64 * fps,
            refresh_hz,
            required_pixel_rate: screen_pixels as f64 * refresh_hz,
            real_time: fps >= refresh_hz,
        }
    }
}

/// The simulator's own speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SimSpeed {
    /// Wall time of the simulation, ms.
    pub wall_ms: f64,
    /// Simulated cycles per second of wall time.
    pub cycles_per_s: f64,
}

/// The cycle section of the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CycleReport {
    /// What was simulated.
    pub plan: CyclePlan,
    /// Cycles of a frame.
    pub total_cycles: u64,
    /// Stage with the most busy cycles.
    pub bottleneck: String,
    /// Analytic lower bound (largest stage work).
    pub lower_bound: u64,
    /// Analytic upper bound (sum of stage works + latencies).
    pub upper_bound: u64,
    /// Whether lower <= total <= upper.
    pub bounds_hold: bool,
    /// Cycles the accumulate stage was limited by the frame-memory port.
    pub frame_port_bound_cycles: u64,
    /// Frame rate.
    pub throughput: Throughput,
    /// Per stage.
    pub stages: Vec<StageCycles>,
    /// Simulator speed.
    pub sim: SimSpeed,
    /// Cost summary.
    pub cost: CostSummary,
    /// Both depth-of-field schedules' frame times (absent without a stage that streams,
    /// e.g. a pinhole scene).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub schedules: Option<Schedules>,
}

impl CycleReport {
    /// The summary lines of the text report and the HTML page: the frame (cycles,
    /// bottleneck, bounds, frame-port-bound cycles), the frame rate against the display and,
    /// with a streamed stage, both depth-of-field schedules.
    pub fn summary_lines(&self) -> Vec<String> {
        let t = &self.throughput;
        let mut v = vec![
            format!(
                "frame: {} cycles | bottleneck {} | bounds {} <= {} <= {} {} | frame-port-bound cycles {}",
                self.total_cycles,
                self.bottleneck,
                self.lower_bound,
                self.total_cycles,
                self.upper_bound,
                if self.bounds_hold { "hold" } else { "VIOLATED" },
                self.frame_port_bound_cycles
            ),
            format!(
                "at {} MHz: {:.3} ms/frame, {:.1} fps, {:.2} Mpixel/s | display needs {} Hz = {:.2} Mpixel/s: {}",
                t.clock_mhz,
                t.frame_ms,
                t.fps,
                t.pixel_rate / 1e6,
                t.refresh_hz,
                t.required_pixel_rate / 1e6,
                if t.real_time {
                    "real time"
                } else {
                    "NOT real time"
                }
            ),
        ];
        v.extend(self.schedules.as_ref().map(Schedules::line));
        v
    }
}

/// The report section of a simulation `r` of `w` (`wall`: its wall time, seconds) at
/// `clock_mhz` against a display of `refresh_hz`; `other`: the other depth-of-field
/// schedule's workload and simulation, for the comparison.
#[allow(clippy::too_many_arguments)]
pub fn report(
    w: &Workload,
    planned: &[StageId],
    clock_mhz: f64,
    refresh_hz: f64,
    cost: CostSummary,
    r: &SimResult,
    wall: f64,
    other: (&Workload, &SimResult),
) -> CycleReport {
    let (lo, hi) = r.bounds();
    CycleReport {
        plan: CyclePlan {
            stages: planned.iter().map(|s| s.name().to_string()).collect(),
            unmodelled: w.unmodelled.iter().map(|s| s.name().to_string()).collect(),
            tile: w.tile_size,
            tiles_touched: w.tiles_touched,
            tiles_total: w.tiles_total,
            pixels_simulated: w.pixels_simulated,
            pixels_total: w.screen_pixels,
        },
        total_cycles: r.total_cycles,
        bottleneck: r.bottleneck().to_string(),
        lower_bound: lo,
        upper_bound: hi,
        bounds_hold: lo <= r.total_cycles && r.total_cycles <= hi,
        frame_port_bound_cycles: r.frame_port_bound_cycles,
        throughput: Throughput::new(r.total_cycles, clock_mhz, w.screen_pixels, refresh_hz),
        stages: r.stages.clone(),
        sim: SimSpeed {
            wall_ms: wall * 1e3,
            cycles_per_s: if wall > 0.0 {
                r.total_cycles as f64 / wall
            } else {
                0.0
            },
        },
        cost,
        schedules: Schedules::new((w, r), other, clock_mhz),
    }
}
