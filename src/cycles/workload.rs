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
//!
//! With `dof.schedule = "stream"` (the default) a depth-of-field stage that can stream
//! ([`RowStream`]) takes one token per screen row instead, reads the rows the accumulate
//! stage writes through line buffers ([`Lines`]) and feeds the stages after it (gamma's rows)
//! through its FIFO.

use crate::config::{CyclesCfg, DofSchedule, StageTiming};
use crate::stage::{RowStream, StageId, TokenKind, Tokens};
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
    /// First screen row each token writes (empty: not rows of the frame).
    pub rows: Vec<u32>,
    /// The stage whose FIFO it reads (`None`: a chain head).
    pub feeder: Option<usize>,
    /// Depth of its output FIFO (`None`: a sink).
    pub fifo: Option<u32>,
    /// The line buffers it reads rows from (`None`: it reads a FIFO or a finished memory).
    pub lines: Option<Lines>,
}

/// The line buffers between the stage that writes the frame's rows (accumulate, one token
/// per binned tile) and a streamed reader (depth of field, one token per screen row): the
/// cross-kind dependency of the streamed schedule (docs/cycles.md).
///
/// Reader token `y` (row `y`) starts when rows `0 ..= min(y + radius, height - 1)` are
/// complete: the rows before the first row of the first writer token not yet out of the
/// writer's pipeline (every row once all are out; rows of tiles the plan did not bin hold
/// the background and are complete from the start). A writer token writes rows
/// `row .. min(row + tile, height)`; it starts only when they fit the buffers, i.e. end at
/// most `capacity` rows below the oldest row the reader still needs (`served - radius`,
/// `served` the reader tokens whose service is complete): else the writer stalls.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Lines {
    /// The writer stage.
    pub source: usize,
    /// First row each writer token writes.
    pub source_rows: Vec<u32>,
    /// Rows a writer token writes (the tile size).
    pub tile: u32,
    /// Rows of the frame (= reader tokens).
    pub height: u32,
    /// Largest blur radius of the plan, rows.
    pub radius: u32,
    /// Rows the line buffers hold: `min(height, 2 radius + 2 tile)`, the rows one output row
    /// reads, the tile row being written and the one being read.
    pub capacity: u32,
    /// Bits per pixel the reader reads.
    pub read_bits: u32,
    /// Bits of the line buffers: `capacity x width x read_bits`.
    pub bits: u64,
}

impl Lines {
    /// The rows the line buffers hold for `radius` and `tile` in a frame of `height` rows.
    pub fn capacity(height: u32, radius: u32, tile: u32) -> u32 {
        height.min(
            radius
                .saturating_mul(2)
                .saturating_add(tile.saturating_mul(2)),
        )
    }

    /// Rows complete when `out` writer tokens have left the writer's pipeline.
    pub fn complete(&self, out: usize) -> u32 {
        self.source_rows.get(out).copied().unwrap_or(self.height)
    }

    /// Whether reader token `row` can start with `complete` rows complete.
    pub fn readable(&self, row: usize, complete: u32) -> bool {
        let need = (row as u64 + self.radius as u64 + 1).min(self.height as u64);
        complete as u64 >= need
    }

    /// Whether writer token `k` fits the buffers when the reader has served `served` rows.
    pub fn fits(&self, k: usize, served: usize) -> bool {
        if self.capacity >= self.height {
            return true;
        }
        let end = (self.source_rows[k] as u64 + self.tile as u64).min(self.height as u64);
        let oldest = (served as u64).saturating_sub(self.radius as u64);
        end <= oldest + self.capacity as u64
    }
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
    /// The depth-of-field schedule simulated (`stream` only where a stage streams).
    pub schedule: DofSchedule,
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
    /// Chains the planned stages (run order, each with its tokens) under the timings `c`
    /// and the depth-of-field `schedule`.
    pub fn new(
        planned: &[(StageId, Option<&Tokens>)],
        c: &CyclesCfg,
        screen: ScreenFacts,
        schedule: DofSchedule,
    ) -> Self {
        let mut stages: Vec<ChainStage> = Vec::new();
        let mut unmodelled = Vec::new();
        let mut streamed = false;
        for &(id, tokens) in planned {
            let (Some(timing), Some(t)) = (c.timing(id), tokens) else {
                unmodelled.push(id);
                continue;
            };
            let lines = match (&t.stream, schedule) {
                (Some(s), DofSchedule::Stream) => lines(&stages, s, screen),
                _ => None,
            };
            let (kind, items) = match (&lines, &t.stream) {
                (Some(_), Some(s)) => (TokenKind::Row, s.items.clone()),
                _ => (t.kind, t.items.clone()),
            };
            streamed |= lines.is_some();
            let feeder = match stages.last_mut() {
                Some(prev) if prev.kind == kind && lines.is_none() => {
                    prev.fifo = Some(prev.timing.fifo);
                    Some(stages.len() - 1)
                }
                _ => None,
            };
            stages.push(ChainStage {
                id,
                item: t.item,
                kind,
                timing: *timing,
                items,
                port_bits: t.port_bits.clone(),
                rows: t.rows.clone(),
                feeder,
                fifo: None,
                lines,
            });
        }
        Self {
            schedule: if streamed {
                DofSchedule::Stream
            } else {
                DofSchedule::Frame
            },
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

    /// Bits of the streamed schedule's line buffers (0 in the frame schedule).
    pub fn line_buffer_bits(&self) -> u64 {
        self.stages
            .iter()
            .filter_map(|s| s.lines.as_ref())
            .map(|l| l.bits)
            .sum()
    }

    /// The streamed reader of the rows stage `i` writes, if any.
    pub fn reader(&self, i: usize) -> Option<usize> {
        self.stages
            .iter()
            .position(|s| s.lines.as_ref().is_some_and(|l| l.source == i))
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
            if let Some(l) = &s.lines {
                for v in [l.source as u32, l.tile, l.height, l.radius, l.capacity] {
                    h = h.u64(v as u64);
                }
                for &r in &l.source_rows {
                    h = h.u64(r as u64);
                }
            }
            h = h.u64(s.items.len() as u64);
            for &v in s.items.iter().chain(&s.port_bits) {
                h = h.u64(v);
            }
            h = h.u64(u64::MAX);
        }
        h.finish()
    }
}

/// The line buffers of a stage that streams `s` behind the last earlier stage whose tokens
/// are tiles of the frame with their rows (accumulate's; none when nothing was binned);
/// `None` when there is none (no frame is written before it) or the frame has no rows.
fn lines(stages: &[ChainStage], s: &RowStream, screen: ScreenFacts) -> Option<Lines> {
    let source = stages
        .iter()
        .rposition(|p| p.kind == TokenKind::Tile && p.rows.len() == p.items.len())?;
    let height = u32::try_from(s.items.len()).ok().filter(|&h| h > 0)?;
    let width = screen.screen_pixels / height as u64;
    let tile = screen.tile_size.max(1);
    let capacity = Lines::capacity(height, s.radius, tile);
    Some(Lines {
        source,
        source_rows: stages[source].rows.clone(),
        tile,
        height,
        radius: s.radius,
        capacity,
        read_bits: s.read_bits,
        bits: capacity as u64 * width * s.read_bits as u64,
    })
}
