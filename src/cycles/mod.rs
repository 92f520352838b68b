//! Cycle model: a cycle-counting simulation of the stage graph on the real workload of
//! the scene, with bounded FIFOs and back-pressure (DESIGN.md §5), the plan of what is
//! modelled (stages and touched screen tiles), and the cost summary (DESIGN.md §6).
//!
//! # Model
//! The frame runs as two chains:
//! * **geometry** `input -> setup -> raster -> visibility`, one token per primitive in
//!   the order the pipeline processes them (surfaces in scene order, then light points);
//!   visibility writes the z-buffer (the chain's sink);
//! * **pixels** `accumulate -> gamma`, one token per touched tile (row-major); it starts
//!   when the geometry chain has drained (the filter reads resolved samples), and gamma
//!   writes the display buffer (the sink). Untouched tiles hold the background code and
//!   cost no cycles (a per-tile "background" flag, like a fast clear).
//!
//! A stage serves one token at a time for `max(1, ceil(items / lanes)) * ii` cycles, then
//! the token spends `latency` cycles in the stage's pipeline before it enters the FIFO to
//! the next stage (depth `fifo` tokens). When the FIFO is full the pipeline head cannot
//! leave and the whole stage freezes (stalled). The accumulate stage's frame memory is a
//! port of `frame_port_bits` per clock; each read-modify-write moves `2 x` the frame word,
//! so a tile takes at least `ceil(rmw * 2 * frame_bits / port_bits)` cycles.
//!
//! Items per token, from the real run: input = vertices (3, 2 or 1), setup = 1 primitive,
//! raster = sample positions the walker steps (emitted + walked outside the region),
//! visibility = depth tests, accumulate = MACs (window samples x pixels), gamma = pixels.
//! Approximation: the raster's items are charged per primitive (`ceil(items/lanes)`), not
//! per span, so the per-span rounding of a real span walker is not modelled.
//!
//! Evaluation order within a cycle is upstream first: a token leaving a stage's pipeline
//! at the start of cycle `t` can be taken by the next stage in the same cycle; a FIFO
//! slot freed in cycle `t` is seen upstream in cycle `t + 1`. A single token through the
//! whole graph therefore takes exactly `sum(service + latency)` cycles.

pub mod cost;
pub mod vcd;

use crate::config::CyclesCfg;
use crate::stage::Region;
use crate::stage::accumulate::{Kernel, PointFrags};
use crate::stage::visibility::{BACKGROUND, Samples};
use serde::Serialize;
use std::collections::VecDeque;
use std::time::Instant;

/// Stages with a cycle model, in flow order.
pub const CYCLE_STAGES: &[&str] = &[
    "input",
    "setup",
    "raster",
    "visibility",
    "accumulate",
    "dof",
    "gamma",
];
/// Index of the first stage of the pixel chain.
const PIXEL_CHAIN: usize = 4;
/// Index of the depth-of-field stage (the head of the post chain when a thin lens plans it).
const DOF: usize = 5;
/// Index of the gamma stage (the last stage).
const GAMMA: usize = 6;

/// The plan's touched-tile map: square tiles of `size` pixels over the screen.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tiles {
    /// Tile size in pixels.
    pub size: u32,
    /// Tile columns.
    pub cols: u32,
    /// Tile rows.
    pub rows: u32,
    /// Screen width, pixels.
    pub width: u32,
    /// Screen height, pixels.
    pub height: u32,
    /// Touched flags, row-major.
    pub touched: Vec<bool>,
}

impl Tiles {
    /// No tile touched.
    pub fn new(size: u32, width: u32, height: u32) -> Self {
        let (cols, rows) = (width.div_ceil(size), height.div_ceil(size));
        Self {
            size,
            cols,
            rows,
            width,
            height,
            touched: vec![false; cols as usize * rows as usize],
        }
    }

    /// Index of the tile holding pixel `(px, py)`.
    #[inline]
    pub fn index(&self, px: u32, py: u32) -> usize {
        (py / self.size * self.cols + px / self.size) as usize
    }

    /// Whether the tile of pixel `(px, py)` is touched.
    #[inline]
    pub fn is_touched(&self, px: u32, py: u32) -> bool {
        self.touched[self.index(px, py)]
    }

    /// Touched tiles.
    pub fn count(&self) -> usize {
        self.touched.iter().filter(|&&t| t).count()
    }

    /// Pixels of tile `t` (clipped to the screen).
    pub fn rect(&self, t: usize) -> Region {
        let (tx, ty) = (t as u32 % self.cols, t as u32 / self.cols);
        Region {
            x0: tx * self.size,
            y0: ty * self.size,
            x1: ((tx + 1) * self.size).min(self.width),
            y1: ((ty + 1) * self.size).min(self.height),
        }
    }

    /// Pixels in touched tiles that are inside `region`.
    pub fn touched_pixels(&self, region: &Region) -> u64 {
        (0..self.touched.len())
            .filter(|&t| self.touched[t])
            .map(|t| clip(&self.rect(t), region).pixels())
            .sum()
    }

    /// The tiles holding a pixel whose filter window (the kernel's `size x size` samples)
    /// contains a sample won by a primitive or a visible light-point sample; only pixels of
    /// `region` count. Every other pixel sees background samples only.
    pub fn touched_by(
        size: u32,
        region: &Region,
        k: &Kernel,
        s: &Samples,
        points: &[PointFrags<u32>],
        width: u32,
        height: u32,
    ) -> Self {
        let mut t = Self::new(size, width, height);
        if region.is_empty() {
            return t;
        }
        let sw = s.reg.width();
        let n = k.n as i64;
        let span = |c: i64, lo: u32, hi: u32| {
            let p0 = (c + k.off - k.size as i64 + 1).div_euclid(n).max(lo as i64);
            let p1 = (c + k.off).div_euclid(n).min(hi as i64 - 1);
            (p0 <= p1).then_some((p0 as u32, p1 as u32))
        };
        let mark = |idx: usize, t: &mut Tiles| {
            let c = s.reg.c0 + (idx % sw) as i64;
            let kk = s.reg.k0 + (idx / sw) as i64;
            if let (Some((x0, x1)), Some((y0, y1))) = (
                span(c, region.x0, region.x1),
                span(kk, region.y0, region.y1),
            ) {
                for ty in y0 / size..=y1 / size {
                    for tx in x0 / size..=x1 / size {
                        t.touched[(ty * t.cols + tx) as usize] = true;
                    }
                }
            }
        };
        let mut last_row = usize::MAX;
        let mut last_tiles = (u32::MAX, u32::MAX);
        for (idx, &p) in s.prim.iter().enumerate() {
            if p == BACKGROUND {
                continue;
            }
            // Skip samples whose tile span was just marked (same row, same tile columns).
            let row = idx / sw;
            let c = s.reg.c0 + (idx % sw) as i64;
            let key = span(c, region.x0, region.x1)
                .map_or((u32::MAX, u32::MAX), |(a, b)| (a / size, b / size));
            if row == last_row && key == last_tiles {
                continue;
            }
            last_row = row;
            last_tiles = key;
            mark(idx, &mut t);
        }
        for pt in points {
            for &idx in &pt.samples {
                mark(idx as usize, &mut t);
            }
        }
        t
    }
}

fn clip(a: &Region, b: &Region) -> Region {
    Region {
        x0: a.x0.max(b.x0),
        y0: a.y0.max(b.y0),
        x1: a.x1.min(b.x1),
        y1: a.y1.min(b.y1),
    }
}

/// Work of one primitive in the geometry chain, from the real run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct PrimWork {
    /// Vertices (3 triangle, 2 line, 1 point).
    pub vertices: u32,
    /// Sample positions the raster stepped (emitted + walked outside the region).
    pub stepped: u64,
    /// Depth tests.
    pub tests: u64,
}

/// Work of one touched tile in the pixel chain, from the real run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TileWork {
    /// Tile index (row-major over the screen's tiles).
    pub tile: u32,
    /// Pixels computed (touched tile inside the region).
    pub pixels: u64,
    /// Filter multiply-accumulates.
    pub macs: u64,
    /// Frame-memory read-modify-writes (fragments and light-point updates).
    pub rmw: u64,
}

/// The workload of a frame: per-primitive and per-tile token streams.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Workload {
    /// Geometry tokens in processing order.
    pub prims: Vec<PrimWork>,
    /// Pixel tokens (touched tiles) in row-major order.
    pub tiles: Vec<TileWork>,
    /// Frame-memory word, bits.
    pub frame_bits: u32,
    /// Tile size in pixels.
    pub tile_size: u32,
    /// Screen tiles.
    pub tiles_total: u64,
    /// Screen pixels.
    pub screen_pixels: u64,
    /// Screen width, pixels.
    pub screen_width: u32,
    /// Depth-of-field tokens (one per layer, in processing order; empty without a thin lens).
    pub dof: Vec<crate::stage::dof::LayerWork>,
}

impl Workload {
    /// Builds the tile tokens from the tile map, the region, the kernel and the per-tile
    /// read-modify-writes the accumulate stage counted.
    pub fn new(
        prims: Vec<PrimWork>,
        tiles: &Tiles,
        region: &Region,
        kernel_size: usize,
        tile_rmw: &[u64],
        frame_bits: u32,
        dof: &[crate::stage::dof::LayerWork],
    ) -> Self {
        let mut out = Vec::new();
        for (t, &on) in tiles.touched.iter().enumerate() {
            if !on {
                continue;
            }
            let px = clip(&tiles.rect(t), region).pixels();
            if px == 0 {
                continue;
            }
            out.push(TileWork {
                tile: t as u32,
                pixels: px,
                macs: px * (kernel_size * kernel_size) as u64,
                rmw: tile_rmw.get(t).copied().unwrap_or(0),
            });
        }
        Self {
            prims,
            tiles: out,
            frame_bits,
            tile_size: tiles.size,
            tiles_total: tiles.touched.len() as u64,
            screen_pixels: tiles.width as u64 * tiles.height as u64,
            screen_width: tiles.width,
            dof: dof.to_vec(),
        }
    }

    /// Whether the depth-of-field stage runs (it then owns the pixel stream into gamma).
    pub fn has_dof(&self) -> bool {
        !self.dof.is_empty()
    }

    /// Gamma tokens: the touched tiles' pixels, or with depth of field one token per screen
    /// row (the layers blur and composite over the whole screen).
    fn gamma_items(&self) -> Vec<u64> {
        if self.has_dof() {
            let w = self.screen_width.max(1) as u64;
            (0..self.screen_pixels.div_ceil(w))
                .map(|r| w.min(self.screen_pixels - r * w))
                .collect()
        } else {
            self.tiles.iter().map(|t| t.pixels).collect()
        }
    }

    /// Whether stage `i` (order of `CYCLE_STAGES`) has a FIFO to a next stage: not the
    /// sinks (visibility writes the sample buffer, depth of field the composited frame,
    /// gamma the display buffer; accumulate writes the frame memory when depth of field
    /// reads it whole).
    pub fn has_fifo(&self, i: usize) -> bool {
        !(i == PIXEL_CHAIN - 1 || i == DOF || i == GAMMA || (i == PIXEL_CHAIN && self.has_dof()))
    }

    /// Service cycles of every token at every stage (stage order of `CYCLE_STAGES`), and
    /// the cycles the accumulate stage spends limited by the frame port.
    pub fn services(&self, c: &CyclesCfg) -> (Vec<Vec<u64>>, u64) {
        let p = &self.prims;
        let mut port_bound = 0;
        let acc: Vec<u64> = self
            .tiles
            .iter()
            .map(|t| {
                let lanes = c.accumulate.service(t.macs);
                let port = (t.rmw * 2 * self.frame_bits as u64).div_ceil(c.frame_port_bits as u64);
                if port > lanes {
                    port_bound += port - lanes;
                }
                lanes.max(port)
            })
            .collect();
        (
            vec![
                p.iter()
                    .map(|w| c.input.service(w.vertices as u64))
                    .collect(),
                p.iter().map(|_| c.setup.service(1)).collect(),
                p.iter().map(|w| c.raster.service(w.stepped)).collect(),
                p.iter().map(|w| c.visibility.service(w.tests)).collect(),
                acc,
                self.dof
                    .iter()
                    .map(|l| c.dof.service(2 * l.pixels))
                    .collect(),
                self.gamma_items()
                    .into_iter()
                    .map(|px| c.gamma.service(px))
                    .collect(),
            ],
            port_bound,
        )
    }

    /// Work items per stage (what the `lanes` count).
    pub fn items(&self) -> [u64; 7] {
        let p = &self.prims;
        [
            p.iter().map(|w| w.vertices as u64).sum(),
            p.len() as u64,
            p.iter().map(|w| w.stepped).sum(),
            p.iter().map(|w| w.tests).sum(),
            self.tiles.iter().map(|t| t.macs).sum(),
            self.dof.iter().map(|l| 2 * l.pixels).sum(),
            self.gamma_items().iter().sum(),
        ]
    }
}

/// What a stage does in a cycle (the VCD `state` code).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum State {
    /// Every token served (its pipeline may still drain); nothing left to do.
    Idle = 0,
    /// Serving a token.
    Busy = 1,
    /// Frozen: its pipeline's head cannot enter the full FIFO.
    Stalled = 2,
    /// Tokens are still to come but none is available.
    Starved = 3,
}

/// Cycle counts of one stage.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageCycles {
    /// Stage name.
    pub name: String,
    /// What one item is.
    pub item: String,
    /// Timing used.
    pub lanes: u32,
    /// Latency used.
    pub latency: u32,
    /// Initiation interval used.
    pub ii: u32,
    /// FIFO depth to the next stage (0: the stage is a chain's sink).
    pub fifo: u32,
    /// Tokens served.
    pub tokens: u64,
    /// Items served.
    pub items: u64,
    /// Cycles serving (= the stage's work in cycles).
    pub busy: u64,
    /// Cycles frozen by back-pressure.
    pub stalled: u64,
    /// Cycles waiting for input while tokens were still to come.
    pub starved: u64,
    /// Cycles with nothing left to do.
    pub idle: u64,
    /// Largest occupancy of the FIFO to the next stage.
    pub fifo_max: u32,
}

/// Simulation result.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SimResult {
    /// Cycles of the frame.
    pub total_cycles: u64,
    /// Per stage, flow order.
    pub stages: Vec<StageCycles>,
    /// Cycles the accumulate stage was limited by the frame-memory port rather than its MAC lanes.
    pub frame_port_bound_cycles: u64,
}

impl SimResult {
    /// The stage with the most busy cycles (first on a tie).
    pub fn bottleneck(&self) -> &str {
        let mut best: Option<&StageCycles> = None;
        for s in &self.stages {
            if best.is_none_or(|b| s.busy > b.busy) {
                best = Some(s);
            }
        }
        best.map_or("-", |s| s.name.as_str())
    }
    /// Analytic bounds: (largest stage work, sum of works + latencies).
    pub fn bounds(&self) -> (u64, u64) {
        let lo = self.stages.iter().map(|s| s.busy).max().unwrap_or(0);
        let hi = self
            .stages
            .iter()
            .map(|s| s.busy + if s.tokens > 0 { s.latency as u64 } else { 0 })
            .sum();
        (lo, hi)
    }
}

struct Sim {
    service: Vec<u64>,
    next: usize,
    remaining: u64,
    pipe: VecDeque<u32>,
    latency: u32,
    /// FIFO to the next stage: occupancy and depth (`None` for a sink).
    occ: u32,
    depth: Option<u32>,
}

impl Sim {
    fn done(&self) -> bool {
        self.next == self.service.len() && self.remaining == 0 && self.pipe.is_empty()
    }
}

/// Receives every cycle: the cycle, each stage's state and each stage's FIFO occupancy.
pub type Trace<'a> = dyn FnMut(u64, &[State], &[u32]) + 'a;

/// Runs the cycle-counting simulation; `trace` receives every cycle's stage states and
/// FIFO occupancies (for the VCD writer).
pub fn simulate(w: &Workload, c: &CyclesCfg, mut trace: Option<&mut Trace>) -> SimResult {
    let (services, port_bound) = w.services(c);
    let items = w.items();
    let mut sims: Vec<Sim> = CYCLE_STAGES
        .iter()
        .zip(services)
        .enumerate()
        .map(|(i, (name, service))| {
            let t = c
                .timing(crate::stage_id::StageId::parse(name).expect("a stage"))
                .expect("timing");
            let sink = !w.has_fifo(i);
            Sim {
                service,
                next: 0,
                remaining: 0,
                pipe: VecDeque::new(),
                latency: t.latency,
                occ: 0,
                depth: (!sink).then_some(t.fifo),
            }
        })
        .collect();
    let ns = sims.len();
    // Where each stage takes its tokens from: the previous stage's FIFO, or (chain heads)
    // nowhere. Without depth of field, gamma reads the accumulate stage's FIFO (tile
    // tokens); with it, depth of field and then gamma each start on the finished frame.
    let feeder: Vec<Option<usize>> = (0..ns)
        .map(|i| match i {
            0 | PIXEL_CHAIN | DOF => None,
            GAMMA if w.has_dof() => None,
            GAMMA => Some(PIXEL_CHAIN),
            _ => Some(i - 1),
        })
        .collect();
    let mut counts = vec![[0u64; 4]; ns];
    let mut fifo_max = vec![0u32; ns];
    let mut states = vec![State::Idle; ns];
    let mut occ = vec![0u32; ns];
    let mut t = 0u64;
    loop {
        for i in 0..ns {
            // Leave the pipeline into the FIFO (or the sink).
            let s = &sims[i];
            if s.pipe.front() == Some(&0) {
                match s.depth {
                    Some(d) if s.occ >= d => {
                        states[i] = State::Stalled;
                        continue;
                    }
                    Some(_) => {
                        sims[i].occ += 1;
                        sims[i].pipe.pop_front();
                    }
                    None => {
                        sims[i].pipe.pop_front();
                    }
                }
            }
            for r in sims[i].pipe.iter_mut() {
                *r = r.saturating_sub(1);
            }
            let available = match (i, feeder[i]) {
                (_, Some(f)) => sims[f].occ > 0,
                (0, None) => true,
                // The pixel chain starts when the geometry chain has drained (the filter
                // reads resolved samples), depth of field when the frame memory is complete,
                // gamma after depth of field when the last layer is composited.
                (_, None) => sims[..i].iter().all(Sim::done),
            };
            let s = &mut sims[i];
            let state = if s.remaining > 0 {
                s.remaining -= 1;
                State::Busy
            } else if s.next < s.service.len() {
                if available {
                    s.remaining = s.service[s.next] - 1;
                    s.next += 1;
                    if let Some(f) = feeder[i] {
                        sims[f].occ -= 1;
                    }
                    State::Busy
                } else {
                    State::Starved
                }
            } else {
                State::Idle
            };
            let s = &mut sims[i];
            if state == State::Busy && s.remaining == 0 {
                s.pipe.push_back(s.latency);
            }
            states[i] = state;
        }
        if sims.iter().all(Sim::done) {
            break;
        }
        for i in 0..ns {
            counts[i][states[i] as usize] += 1;
            occ[i] = sims[i].occ;
            fifo_max[i] = fifo_max[i].max(occ[i]);
        }
        if let Some(f) = trace.as_mut() {
            f(t, &states, &occ);
        }
        t += 1;
    }
    let item_names = [
        "vertices",
        "primitives",
        "samples stepped",
        "depth tests",
        "MACs",
        "pass outputs",
        "pixels",
    ];
    let stages = CYCLE_STAGES
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let tm = c
                .timing(crate::stage_id::StageId::parse(name).expect("a stage"))
                .expect("timing");
            StageCycles {
                name: name.to_string(),
                item: item_names[i].into(),
                lanes: tm.lanes,
                latency: tm.latency,
                ii: tm.ii,
                fifo: sims[i].depth.unwrap_or(0),
                tokens: sims[i].service.len() as u64,
                items: items[i],
                busy: counts[i][State::Busy as usize],
                stalled: counts[i][State::Stalled as usize],
                starved: counts[i][State::Starved as usize],
                idle: counts[i][State::Idle as usize],
                fifo_max: fifo_max[i],
            }
        })
        .collect();
    SimResult {
        total_cycles: t,
        stages,
        frame_port_bound_cycles: port_bound,
    }
}

/// The plan as the cycle model sees it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CyclePlan {
    /// Stages the run planned, in flow order.
    pub stages: Vec<String>,
    /// Planned stages without a cycle model (not simulated).
    pub unmodelled: Vec<String>,
    /// Tile size, pixels.
    pub tile: u32,
    /// Touched tiles (simulated).
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
    pub cost: cost::CostSummary,
}

/// Simulates `w` and builds the report section.
pub fn report(
    w: &Workload,
    c: &CyclesCfg,
    planned: &[String],
    refresh_hz: f64,
    cost: cost::CostSummary,
    trace: Option<&mut Trace>,
) -> CycleReport {
    let t = Instant::now();
    let r = simulate(w, c, trace);
    let wall = t.elapsed().as_secs_f64();
    report_simulated(w, c, planned, refresh_hz, cost, &r, wall)
}

/// [`report`] of a simulation already run (`wall`: its wall time, seconds); sweeps reuse one
/// simulation for every configuration that shares the workload and the timings.
pub fn report_simulated(
    w: &Workload,
    c: &CyclesCfg,
    planned: &[String],
    refresh_hz: f64,
    cost: cost::CostSummary,
    r: &SimResult,
    wall: f64,
) -> CycleReport {
    let (lo, hi) = r.bounds();
    CycleReport {
        plan: CyclePlan {
            stages: planned.to_vec(),
            unmodelled: planned
                .iter()
                .filter(|s| {
                    crate::stage_id::StageId::parse(s)
                        .and_then(|i| c.timing(i))
                        .is_none()
                })
                .cloned()
                .collect(),
            tile: w.tile_size,
            tiles_touched: w.tiles.len() as u64,
            tiles_total: w.tiles_total,
            pixels_simulated: w.tiles.iter().map(|t| t.pixels).sum(),
            pixels_total: w.screen_pixels,
        },
        total_cycles: r.total_cycles,
        bottleneck: r.bottleneck().to_string(),
        lower_bound: lo,
        upper_bound: hi,
        bounds_hold: lo <= r.total_cycles && r.total_cycles <= hi,
        frame_port_bound_cycles: r.frame_port_bound_cycles,
        throughput: Throughput::new(r.total_cycles, c.clock_mhz, w.screen_pixels, refresh_hz),
        // A cycle stage the run did not plan (dof for a pinhole camera) has no row.
        stages: r
            .stages
            .iter()
            .filter(|s| s.tokens > 0 || planned.contains(&s.name))
            .cloned()
            .collect(),
        sim: SimSpeed {
            wall_ms: wall * 1e3,
            cycles_per_s: if wall > 0.0 {
                r.total_cycles as f64 / wall
            } else {
                0.0
            },
        },
        cost,
    }
}
