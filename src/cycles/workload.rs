//! The cycle model's workload: the chains of the plan with each stage's tokens from the
//! real run.
//!
//! The chains are derived from the plan, not wired by hand: the planned stages that have a
//! timing (`[cycles.<stage>]`) and tokens are taken in run order; two consecutive ones are
//! linked by a FIFO (the upstream stage's `fifo` depth) when their tokens are of the same
//! kind, e.g. `input -> setup -> raster -> visibility` (one token per primitive) or
//! `accumulate -> gamma` (one per binned tile). Where the kind changes the upstream stage
//! writes a memory (it is a sink: visibility the sample buffer, accumulate the frame memory
//! before depth of field) and the downstream stage starts when every stage before it has
//! finished (the filter reads resolved samples; depth of field reads the finished frame).

use crate::config::{CyclesCfg, StageTiming};
use crate::stage::{StageId, TokenKind, Tokens};
use serde::Serialize;

/// One stage of a chain.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ChainStage {
    /// The stage.
    pub id: StageId,
    /// What one item is.
    pub item: &'static str,
    /// What one token is.
    pub kind: TokenKind,
    /// Its timing.
    pub timing: StageTiming,
    /// Items per token.
    pub items: Vec<u64>,
    /// Frame-memory port bits per token (empty: none).
    pub port_bits: Vec<u64>,
    /// The stage whose FIFO it reads (`None`: a chain head).
    pub feeder: Option<usize>,
    /// Depth of its output FIFO (`None`: a sink).
    pub fifo: Option<u32>,
}

/// The workload of a frame: the chained stages and the screen facts of the plan.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Workload {
    /// Stages with a cycle model, in run order.
    pub stages: Vec<ChainStage>,
    /// Planned stages without a cycle model.
    pub unmodelled: Vec<StageId>,
    /// Frame-memory port width, bits per clock.
    pub frame_port_bits: u32,
    /// Tile size, pixels.
    pub tile_size: u32,
    /// Binned tiles.
    pub tiles_touched: u64,
    /// Tiles of the screen.
    pub tiles_total: u64,
    /// Pixels of binned tiles inside the region (the pixel chain's pixels).
    pub pixels_simulated: u64,
    /// Screen pixels.
    pub screen_pixels: u64,
}

/// Screen facts of the plan the cycle report shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ScreenFacts {
    /// Tile size, pixels.
    pub tile_size: u32,
    /// Binned tiles.
    pub tiles_touched: u64,
    /// Tiles of the screen.
    pub tiles_total: u64,
    /// Pixels of binned tiles inside the region.
    pub pixels_simulated: u64,
    /// Screen pixels.
    pub screen_pixels: u64,
}

impl Workload {
    /// Chains the planned stages (run order, each with its tokens) under the timings `c`.
    pub fn new(planned: &[(StageId, Option<&Tokens>)], c: &CyclesCfg, screen: ScreenFacts) -> Self {
        let mut stages: Vec<ChainStage> = Vec::new();
        let mut unmodelled = Vec::new();
        for &(id, tokens) in planned {
            let (Some(timing), Some(t)) = (c.timing(id), tokens) else {
                unmodelled.push(id);
                continue;
            };
            let feeder = match stages.last_mut() {
                Some(prev) if prev.kind == t.kind => {
                    prev.fifo = Some(prev.timing.fifo);
                    Some(stages.len() - 1)
                }
                _ => None,
            };
            stages.push(ChainStage {
                id,
                item: t.item,
                kind: t.kind,
                timing: *timing,
                items: t.items.clone(),
                port_bits: t.port_bits.clone(),
                feeder,
                fifo: None,
            });
        }
        Self {
            stages,
            unmodelled,
            frame_port_bits: c.frame_port_bits,
            tile_size: screen.tile_size,
            tiles_touched: screen.tiles_touched,
            tiles_total: screen.tiles_total,
            pixels_simulated: screen.pixels_simulated,
            screen_pixels: screen.screen_pixels,
        }
    }

    /// Whether stage `i` has a FIFO to a next stage.
    pub fn has_fifo(&self, i: usize) -> bool {
        self.stages[i].fifo.is_some()
    }

    /// Service cycles of every token of stage `i`: `ceil(items / lanes) * ii`, or the
    /// frame-memory port's `ceil(port_bits / frame_port_bits)` when that is longer. Also
    /// returns the cycles the port added over the lanes.
    pub fn services(&self, i: usize) -> (Vec<u64>, u64) {
        let s = &self.stages[i];
        let mut port_bound = 0;
        let v = s
            .items
            .iter()
            .enumerate()
            .map(|(k, &n)| {
                let lanes = s.timing.service(n);
                let port = s
                    .port_bits
                    .get(k)
                    .map_or(0, |&b| b.div_ceil(self.frame_port_bits as u64));
                if port > lanes {
                    port_bound += port - lanes;
                }
                lanes.max(port)
            })
            .collect();
        (v, port_bound)
    }

    /// A stable hash of the workload (stages, tokens, timings, port): the key of its
    /// simulation.
    pub fn key(&self) -> u64 {
        let mut h = crate::fnv::Fnv::new().u64(self.frame_port_bits as u64);
        for s in &self.stages {
            h = h.str(s.id.name());
            for v in [s.timing.lanes, s.timing.latency, s.timing.ii, s.timing.fifo] {
                h = h.u64(v as u64);
            }
            h = h.u64(s.feeder.map_or(u64::MAX, |f| f as u64));
            h = h.u64(s.fifo.map_or(u64::MAX, |f| f as u64));
            h = h.u64(s.items.len() as u64);
            for &v in s.items.iter().chain(&s.port_bits) {
                h = h.u64(v);
            }
            h = h.u64(u64::MAX);
        }
        h.finish()
    }
}
