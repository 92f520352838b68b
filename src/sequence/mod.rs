//! Sequences: every frame of an animated scene (`[sequence]`, [`Scene::frame`]) through the
//! fixed pipeline and, unless asked not to, its float reference; per frame the error
//! figures, the cycle count and the frame time at the clock against the sequence's period;
//! over the sequence the worst frame, the frames that miss the period, percentiles and the
//! temporal metrics ([`temporal`]). docs/sequence.md.
//!
//! Reuse: the frames share one stage cache ([`Cache::with_tile_rows`]). A grey sequence
//! runs raster, visibility and accumulate band by band of one tile row
//! ([`pipeline::bands`]), and a tile row whose primitives (after quantisation), tiles and
//! filter-window rows are the same as in an earlier frame keeps that frame's results
//! ([`pipeline::tile_rows`]): only the tile rows something moved in are emulated again.
//! The stages after accumulate (depth of field, gamma, dither) run on the whole frame, and
//! again whenever any tile row changed (their stage key is the frame's); a frame in which
//! nothing moved reuses every stage. The codes and reports are those of a full emulation
//! (the cache returns the identical results; `tests/sequence_tiles.rs`).

pub mod merge;
pub mod shard;
pub mod temporal;

use crate::colour::ColourDisplay;
use crate::compare::DisplayModel;
use crate::config::HwConfig;
use crate::error::Result;
use crate::pipeline::{self, Cache, fast};
use crate::scene::{GuardBand, Primitive, Scene, Sequence, front_end};
use crate::stage::{RunOptions, StageId, taps::PixelTapF};
use serde::{Deserialize, Serialize};
use std::ops::Range;
use std::time::Instant;
use temporal::{MARGIN, SMALL, THIN, Temporal, TemporalReport, TemporalState, Window};

/// What to run.
#[derive(Clone, Debug)]
pub struct SequenceOptions {
    /// Frames to run (within the scene's `0..frames`).
    pub frames: Range<u32>,
    /// Run the float reference beside the fixed model (error figures, excess flicker).
    pub reference: bool,
    /// Share a stage cache between the frames.
    pub reuse: bool,
}

/// One frame.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrameRecord {
    /// Frame number.
    pub frame: u32,
    /// Cycles of the frame.
    pub cycles: u64,
    /// Frame time at the clock, ms.
    pub frame_ms: f64,
    /// Frames per second at the clock.
    pub fps: f64,
    /// Stage with the most busy cycles.
    pub bottleneck: String,
    /// Whether the frame takes longer than the sequence's period.
    pub misses_period: bool,
    /// Fraction of DAC codes identical to the reference (with a reference; of all three
    /// channels' codes for colour, as are the next two figures).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub identical_fraction: Option<f64>,
    /// Largest |fixed - reference| DAC code.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_abs_diff: Option<u32>,
    /// Largest luminance difference in Weber units.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weber_max: Option<f64>,
    /// A colour frame: mean CIEDE2000 of the fixed against the reference image.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta_e_mean: Option<f64>,
    /// A colour frame: largest CIEDE2000.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta_e_max: Option<f64>,
    /// Stages whose outcome came from an earlier frame.
    pub reused_stages: u64,
    /// Stages run for this frame.
    pub emulated_stages: u64,
    /// Tile rows whose raster, visibility and accumulate results came from an earlier frame.
    pub tile_rows_reused: u64,
    /// Tile rows emulated for this frame.
    pub tile_rows_emulated: u64,
    /// Wall time of the frame's emulation, ms.
    pub wall_ms: f64,
}

/// The sequence's throughput against its period.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    /// Frames run.
    pub frames: u32,
    /// The sequence's rate, Hz.
    pub rate_hz: f64,
    /// Clock, MHz.
    pub clock_mhz: f64,
    /// Cycles in one period at the clock.
    pub period_cycles: f64,
    /// Most cycles of a frame.
    pub worst_cycles: u64,
    /// The frame with the most cycles (the first of equals).
    pub worst_frame: u32,
    /// Worst frame's time at the clock, ms.
    pub worst_frame_ms: f64,
    /// Frames that miss the period.
    pub missed: u32,
    /// `missed / frames`.
    pub missed_fraction: f64,
    /// Mean cycles.
    pub mean_cycles: f64,
    /// Median, 95th and 99th percentile of the cycles (nearest rank).
    pub p50_cycles: u64,
    /// 95th percentile.
    pub p95_cycles: u64,
    /// 99th percentile.
    pub p99_cycles: u64,
}

/// Reuse between frames.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReuseReport {
    /// Whether frames shared a stage cache.
    pub enabled: bool,
    /// Whether the camera moves (then no stage output repeats).
    pub camera_moves: bool,
    /// Frames after the first that ran no stage (every stage reused).
    pub frames_fully_reused: u32,
    /// Stage runs over the sequence.
    pub stages_emulated: u64,
    /// Stage outcomes reused over the sequence.
    pub stages_reused: u64,
    /// Why tile rows are not reused (`None`: they are).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tile_rows_off: Option<String>,
    /// Tile rows of one frame (pixel rows of `tile_size`).
    pub tile_rows: u32,
    /// Tile size, pixels.
    pub tile_size: u32,
    /// Tile rows emulated over the frames after the first.
    pub tile_rows_emulated: u64,
    /// Tile rows reused over the frames after the first.
    pub tile_rows_reused: u64,
    /// Wall time of the first frame (every tile row emulated) over the median wall time of
    /// the frames after it (measured in this run; 0 with one frame).
    pub first_over_later_wall: f64,
    /// Emulation wall time over all frames, s.
    pub wall_s: f64,
    /// Frames per second of emulation (frames / wall time).
    pub frames_per_s: f64,
}

/// The report of `igemu sequence`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SequenceReport {
    /// Tool version.
    pub igemu_version: String,
    /// Scene name.
    pub scene: String,
    /// Hardware name.
    pub hardware: String,
    /// The accumulate filter.
    pub filter: String,
    /// Screen.
    pub width: u32,
    /// Screen.
    pub height: u32,
    /// First frame run.
    pub first: u32,
    /// Frames of the whole sequence.
    pub sequence_frames: u32,
    /// Whether a float reference ran.
    pub reference: bool,
    /// Per frame.
    pub frames: Vec<FrameRecord>,
    /// Over the frames.
    pub summary: Summary,
    /// Temporal metrics.
    pub temporal: TemporalReport,
    /// Reuse between frames.
    pub reuse: ReuseReport,
}

/// A frame's images, handed to the caller as they are made (an APNG writer).
pub struct FrameImages<'a> {
    /// Frame number.
    pub frame: u32,
    /// Fixed DAC codes, row-major: one plane for a grey sequence, R, G, B for colour.
    pub fixed: &'a [&'a [u16]],
    /// Reference DAC codes, the same planes.
    pub reference: Option<&'a [&'a [u16]]>,
    /// Each plane's DAC width.
    pub bits: &'a [u32],
}

/// The screen box of object `o` in `scene` (a still frame), grown by [`MARGIN`] and cut to
/// the screen; `None` when it draws nothing on the screen or is neither small nor thin (its
/// box's short side above [`SMALL`] or its long side above [`THIN`]).
fn small_window(scene: &Scene, o: usize) -> Option<Window> {
    let mut one = scene.clone();
    one.objects = vec![scene.objects[o].clone()];
    let (w, h) = (scene.image.width, scene.image.height);
    let host = front_end(&one, &GuardBand::around(w, h, 0.0));
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    let mut grow = |x: f64, y: f64, r: f64| {
        x0 = x0.min(x - r);
        y0 = y0.min(y - r);
        x1 = x1.max(x + r);
        y1 = y1.max(y + r);
    };
    for p in &host.prims {
        match p {
            Primitive::Triangle(v) => v.iter().for_each(|v| grow(v.x, v.y, 0.0)),
            Primitive::Line { a, b, width } => {
                grow(a.x, a.y, width / 2.0);
                grow(b.x, b.y, width / 2.0);
            }
            Primitive::Point { v, size } => grow(v.x, v.y, size / 2.0),
        }
    }
    let (bw, bh) = (x1 - x0, y1 - y0);
    if host.prims.is_empty() || bw.min(bh) > SMALL || bw.max(bh) > THIN {
        return None;
    }
    let cut = |v: f64, m: i64, hi: u32| (v.floor() as i64 + m).clamp(0, i64::from(hi)) as u32;
    let win = Window {
        x0: cut(x0, -MARGIN, w),
        y0: cut(y0, -MARGIN, h),
        x1: cut(x1.ceil(), MARGIN, w),
        y1: cut(y1.ceil(), MARGIN, h),
    };
    (win.x1 > win.x0 + 2 && win.y1 > win.y0 + 2).then_some(win)
}

/// A frame's error figures against its reference.
#[derive(Clone, Copy)]
struct Errors {
    identical: f64,
    max_abs_diff: u32,
    weber_max: f64,
    /// Mean and largest CIEDE2000 (colour).
    delta_e: Option<(f64, f64)>,
}

/// The error figures of a render's report: channel 0's (grey), or over the three channels
/// with the CIEDE2000 (colour).
fn errors_of(r: &crate::pipeline::Report) -> Errors {
    let c = &r.end_to_end;
    let grey = Errors {
        identical: c.codes.identical_fraction,
        max_abs_diff: c.codes.max_abs_diff,
        weber_max: c.weber.max,
        delta_e: None,
    };
    let Some(col) = &r.colour else {
        return grey;
    };
    let n = col.channels.len().max(1) as f64;
    col.channels.iter().fold(
        Errors {
            identical: 0.0,
            delta_e: Some((col.delta_e.mean, col.delta_e.max)),
            ..grey
        },
        |e, k| Errors {
            identical: e.identical + k.end_to_end.codes.identical_fraction / n,
            max_abs_diff: e.max_abs_diff.max(k.end_to_end.codes.max_abs_diff),
            weber_max: e.weber_max.max(k.end_to_end.weber.max),
            ..e
        },
    )
}

/// The first frame's wall time over the median of the later frames' (0 with one frame).
fn first_over_later(records: &[FrameRecord]) -> f64 {
    let mut later: Vec<f64> = records.iter().skip(1).map(|r| r.wall_ms).collect();
    if later.is_empty() {
        return 0.0;
    }
    later.sort_by(f64::total_cmp);
    records[0].wall_ms / later[later.len() / 2].max(1e-9)
}

fn percentile(sorted: &[u64], p: f64) -> u64 {
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// The display model of the temporal figures' DAC codes (the grey channel, or R: the
/// temporal dither's figures are channel R's).
pub(crate) fn temporal_model(scene: &Scene, hw: &HwConfig) -> DisplayModel {
    let bits = if scene.image.colour {
        hw.channel(0).gamma.dac_bits
    } else {
        hw.gamma.dac_bits
    };
    DisplayModel::new(&scene.display, bits)
}

/// Runs frames `o.frames` of `scene`'s sequence on `hw`, handing each frame's images to
/// `on_frame` as they are made.
pub fn run(
    scene: &Scene,
    hw: &HwConfig,
    o: &SequenceOptions,
    on_frame: &mut dyn FnMut(&FrameImages) -> Result<()>,
) -> Result<SequenceReport> {
    run_with_state(scene, hw, o, false, on_frame).map(|(r, _)| r)
}

/// `scene`'s sequence, when `frames` can run on it: refused without a `[sequence]` and when
/// `frames` is empty or reaches past the sequence (naming the scene file and
/// `sequence.frames`).
pub fn check_frames<'a>(scene: &'a Scene, frames: &Range<u32>) -> Result<&'a Sequence> {
    let Some(seq) = &scene.sequence else {
        return Err(scene
            .error(
                "sequence",
                "the scene has no [sequence] table: add one with `frames = N` and keys (docs/sequence.md), or run `igemu sequence flypast`",
            )
            .into());
    };
    if frames.start >= frames.end || frames.end > seq.frames {
        let msg = format!(
            "--frames {}..{} is not a non-empty range within the sequence's frames 0..{}",
            frames.start, frames.end, seq.frames
        );
        return Err(scene.error("sequence.frames", msg).into());
    }
    Ok(seq)
}

/// [`run`], also returning the state the temporal figures are computed from (a shard's
/// part); with `lead_in` and a reference, frame `o.frames.start - 1` is emulated first,
/// unreported, so that the first frame's pair is compared as in a run that includes it.
pub(crate) fn run_with_state(
    scene: &Scene,
    hw: &HwConfig,
    o: &SequenceOptions,
    lead_in: bool,
    on_frame: &mut dyn FnMut(&FrameImages) -> Result<()>,
) -> Result<(SequenceReport, TemporalState)> {
    let seq = check_frames(scene, &o.frames)?;
    // The small moving objects (small in every frame run) and their windows, from one pass
    // over the frames' scenes; each frame's scene is made again when it runs, so the
    // sequence never holds more than one.
    let moving = seq.moving_objects();
    let mut windows: Vec<Vec<Option<Window>>> = Vec::with_capacity(o.frames.len());
    let mut camera_moves = false;
    let mut camera0 = None;
    for f in o.frames.clone() {
        let fs = scene.frame(f)?;
        windows.push(moving.iter().map(|&k| small_window(&fs, k)).collect());
        let c0 = camera0.get_or_insert_with(|| fs.camera.clone());
        camera_moves |= fs.camera != *c0;
    }
    let small: Vec<usize> = (0..moving.len())
        .filter(|&j| windows.iter().all(|w| w[j].is_some()))
        .collect();
    let kinds = small
        .iter()
        .map(|&j| {
            let k = moving[j];
            let v = serde_json::to_value(&scene.objects[k]).unwrap_or_default();
            (k, v["kind"].as_str().unwrap_or("object").to_string())
        })
        .collect();
    let temporal_dither = o.reference && hw.dither.temporal;
    let width = scene.image.width;
    let mut temporal = if scene.image.colour {
        let bits = [0, 1, 2].map(|c| hw.channel(c).gamma.dac_bits);
        let display = ColourDisplay::new(&scene.display, bits);
        Temporal::colour(&display, scene.display.b_max, width, kinds, temporal_dither)
    } else {
        Temporal::new(&temporal_model(scene, hw), width, kinds, temporal_dither)
    };
    let cache = o.reuse.then(Cache::with_tile_rows);
    let tile = hw.cycles.tile;
    // Bands of one tile row (a plan that runs in one band, e.g. a log-add frame, ignores it).
    let band_rows = o.reuse.then_some(tile);
    let opts = |base: RunOptions| RunOptions { band_rows, ..base };
    let emulator = fast::Emulator::new();
    if lead_in && o.reference && o.frames.start > 0 {
        let (fixed, reference) = shard::lead_in(scene, hw, o.frames.start - 1, cache.as_ref())?;
        let [fixed, reference] =
            [&fixed, &reference].map(|p| p.iter().map(Vec::as_slice).collect::<Vec<_>>());
        temporal.prime(&fixed, Some(&reference));
    }
    let period_ms = 1e3 / seq.rate_hz;
    let mut records = Vec::with_capacity(windows.len());
    let t_all = Instant::now();
    for (f, win) in o.frames.clone().zip(&windows) {
        let fs = scene.frame(f)?;
        let win: Vec<Window> = small.iter().filter_map(|&j| win[j]).collect();
        let (h0, m0) = cache.as_ref().map_or((0, 0), Cache::stats);
        let (rh0, rm0) = cache.as_ref().map_or((0, 0), Cache::tile_row_stats);
        let t = Instant::now();
        // The frame's codes are handed on borrowed: the fixed-only path's planes go back to
        // the emulator's pool afterwards.
        let mut consume = |fixed: &[&[u16]],
                           reference: Option<&[&[u16]]>,
                           bits: &[u32],
                           ideal: Option<&[f64]>| {
            temporal.add(f, fixed, reference, &win, ideal);
            on_frame(&FrameImages {
                frame: f,
                fixed,
                reference,
                bits,
            })
        };
        let (cycles, errors) = if o.reference {
            let r = pipeline::render_with(&fs, hw, opts(RunOptions::FAST), cache.as_ref())?;
            let ideal = match r.taps(StageId::Gamma).map(|t| t.float.pixels()) {
                Some(PixelTapF::Values(v)) if temporal_dither => Some(v.as_slice()),
                _ => None,
            };
            let errors = errors_of(&r.report);
            match &r.colour {
                Some(c) => {
                    let planes = |reference: bool| {
                        c.channels
                            .iter()
                            .map(|k| {
                                if reference {
                                    &k.dac_ref[..]
                                } else {
                                    &k.dac[..]
                                }
                            })
                            .collect::<Vec<_>>()
                    };
                    let bits: Vec<u32> = c.channels.iter().map(|k| k.bits).collect();
                    consume(&planes(false), Some(&planes(true)), &bits, ideal)?;
                }
                None => consume(&[&r.dac], Some(&[&r.dac_ref]), &[r.dac_bits], ideal)?,
            }
            (r.report.cycles.clone(), Some(errors))
        } else {
            let e = emulator.emulate(&fs, hw, opts(RunOptions::FIXED_ONLY), cache.as_ref())?;
            let planes: Vec<&[u16]> = e.channels.iter().map(Vec::as_slice).collect();
            let done = consume(&planes, None, &e.bits, None);
            let cycles = e.report.cycles.clone();
            emulator.recycle(e);
            done?;
            (cycles, None)
        };
        let wall_ms = t.elapsed().as_secs_f64() * 1e3;
        let (h1, m1) = cache.as_ref().map_or((0, 0), Cache::stats);
        let (rh1, rm1) = cache.as_ref().map_or((0, 0), Cache::tile_row_stats);
        let stages = cycles.plan.stages.len() as u64;
        let (reused, emulated) = if cache.is_some() {
            (h1 - h0, m1 - m0)
        } else {
            (0, stages)
        };
        let th = &cycles.throughput;
        records.push(FrameRecord {
            frame: f,
            cycles: cycles.total_cycles,
            frame_ms: th.frame_ms,
            fps: th.fps,
            bottleneck: cycles.bottleneck.clone(),
            misses_period: th.frame_ms > period_ms,
            identical_fraction: errors.map(|e| e.identical),
            max_abs_diff: errors.map(|e| e.max_abs_diff),
            weber_max: errors.map(|e| e.weber_max),
            delta_e_mean: errors.and_then(|e| e.delta_e.map(|d| d.0)),
            delta_e_max: errors.and_then(|e| e.delta_e.map(|d| d.1)),
            reused_stages: reused,
            emulated_stages: emulated,
            tile_rows_reused: rh1 - rh0,
            tile_rows_emulated: rm1 - rm0,
            wall_ms,
        });
    }
    let wall_s = t_all.elapsed().as_secs_f64();
    let tile_rows_off = if !o.reuse {
        Some("reuse is off (--no-reuse)".to_string())
    } else if cache.as_ref().map_or((0, 0), Cache::tile_row_stats) == (0, 0) {
        Some("the plan runs in one band (a log-coded frame, or no accumulate stage): only whole stages are reused".to_string())
    } else {
        None
    };
    let (temporal, state) = temporal.finish_with_state();
    let report = SequenceReport {
        igemu_version: env!("CARGO_PKG_VERSION").to_string(),
        scene: scene.name.clone(),
        hardware: hw.name.clone(),
        filter: hw.accumulate.filter.name().to_string(),
        width: scene.image.width,
        height: scene.image.height,
        first: o.frames.start,
        sequence_frames: seq.frames,
        reference: o.reference,
        summary: summarize(&records, seq.rate_hz, hw.cycles.clock_mhz),
        reuse: reuse_report(
            (o.reuse, camera_moves),
            (tile_rows_off, scene.image.height.div_ceil(tile), tile),
            &records,
            wall_s,
        ),
        frames: records,
        temporal,
    };
    Ok((report, state))
}

/// The summary of `records` (at least one) at `rate_hz` and `clock_mhz`.
pub(crate) fn summarize(records: &[FrameRecord], rate_hz: f64, clock_mhz: f64) -> Summary {
    let n = records.len() as u32;
    let mut sorted: Vec<u64> = records.iter().map(|r| r.cycles).collect();
    sorted.sort_unstable();
    let worst = records
        .iter()
        .fold(&records[0], |w, r| if r.cycles > w.cycles { r } else { w });
    let missed = records.iter().filter(|r| r.misses_period).count() as u32;
    Summary {
        frames: n,
        rate_hz,
        clock_mhz,
        period_cycles: clock_mhz * 1e6 / rate_hz,
        worst_cycles: worst.cycles,
        worst_frame: worst.frame,
        worst_frame_ms: worst.frame_ms,
        missed,
        missed_fraction: missed as f64 / n as f64,
        mean_cycles: sorted.iter().sum::<u64>() as f64 / n as f64,
        p50_cycles: percentile(&sorted, 50.0),
        p95_cycles: percentile(&sorted, 95.0),
        p99_cycles: percentile(&sorted, 99.0),
    }
}

/// The reuse of `records`, emulated in `wall_s` seconds: `(enabled, camera_moves)`, and
/// `(why tile rows are not reused, tile rows per frame, tile size)`.
pub(crate) fn reuse_report(
    (enabled, camera_moves): (bool, bool),
    (tile_rows_off, tile_rows, tile_size): (Option<String>, u32, u32),
    records: &[FrameRecord],
    wall_s: f64,
) -> ReuseReport {
    ReuseReport {
        enabled,
        camera_moves,
        frames_fully_reused: records
            .iter()
            .skip(1)
            .filter(|r| r.emulated_stages == 0 && r.tile_rows_emulated == 0)
            .count() as u32,
        stages_emulated: records.iter().map(|r| r.emulated_stages).sum(),
        stages_reused: records.iter().map(|r| r.reused_stages).sum(),
        tile_rows_off,
        tile_rows,
        tile_size,
        tile_rows_emulated: records.iter().skip(1).map(|r| r.tile_rows_emulated).sum(),
        tile_rows_reused: records.iter().skip(1).map(|r| r.tile_rows_reused).sum(),
        first_over_later_wall: first_over_later(records),
        wall_s,
        frames_per_s: records.len() as f64 / wall_s.max(1e-9),
    }
}
