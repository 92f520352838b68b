//! The plan's memory estimate, made before any stage allocates: the sample buffers of the
//! modelled region, the fragment lists, and the per-pixel planes of the frame, depth of
//! field, gamma and the comparison, fixed and float. A plan over the limit is refused with
//! the fields that drive it (`image.width`, `image.height`, `raster.samples`, the number and
//! size of the primitives) instead of aborting on an allocation.
//!
//! The estimate is a sum of named parts in bytes, from the sizes of the model's buffers (a
//! fixed sample is 12 bytes, a float one 20; a float fragment 24; the fixed raster's run,
//! one per primitive and sample row, 72; see `docs/reliability.md` for the measured peak
//! against the estimate).

use super::plan::Plan;
use crate::scene::{HostScene, Primitive};
use crate::stage::{Layout, RunOptions, StageId};
use serde::Serialize;

/// One part of the estimate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Part {
    /// What it is.
    pub what: &'static str,
    /// Bytes.
    pub bytes: u64,
    /// The fields that drive it.
    pub drivers: &'static str,
}

/// The memory estimate of a plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// Total bytes.
    pub bytes: u64,
    /// The parts.
    pub parts: Vec<Part>,
}

/// Covered samples a primitive can emit: its area in samples (a triangle's exact area of
/// its host coordinates plus one sample along its perimeter, a line's length x width, a
/// point's square), at most the region's samples.
fn fragments(p: &Primitive, n: f64, region_samples: f64) -> f64 {
    let n2 = n * n;
    let area = match p {
        Primitive::Triangle(v) => {
            let a = ((v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[2].x - v[0].x) * (v[1].y - v[0].y))
                .abs()
                / 2.0;
            let per = (0..3)
                .map(|k| {
                    let (a, b) = (&v[k], &v[(k + 1) % 3]);
                    (b.x - a.x).hypot(b.y - a.y)
                })
                .sum::<f64>();
            a + per / n
        }
        Primitive::Line { a, b, width } => ((b.x - a.x).hypot(b.y - a.y) + width) * (width + 1.0),
        Primitive::Point { size, .. } => (size + 1.0) * (size + 1.0),
    };
    // Non-finite sizes are refused by the scene's validation; stay safe anyway.
    let f = area * n2;
    if f.is_finite() {
        f.min(region_samples)
    } else {
        region_samples
    }
}

/// Bytes per sample of the sample buffers: fixed (12 B) and float (20 B), the stage-local
/// float shadow, the log stage's re-coded copies.
fn per_sample(plan: &Plan, opts: RunOptions) -> f64 {
    let mut per_sample = 12.0 + 20.0;
    if opts.stage_local {
        per_sample += 20.0;
    }
    if plan.layout.has(StageId::Logdomain) {
        per_sample += 24.0;
    }
    per_sample
}

/// Bytes of a float fragment.
const FLOAT_FRAG: f64 = 24.0;

/// Bytes of a fixed run ([`crate::stage::raster::Run`]).
const RUN: f64 = std::mem::size_of::<crate::stage::raster::Run>() as f64;

/// The triangles the raster walks for a primitive: two for a line, one otherwise.
fn triangles(p: &Primitive) -> f64 {
    if matches!(p, Primitive::Line { .. }) {
        2.0
    } else {
        1.0
    }
}

/// Sample rows (of `n` per pixel) a primitive's runs can take: one per row of its bounding
/// box (two for a line, which is two triangles), at most one per fragment `f`.
fn runs(p: &Primitive, f: f64, n: f64) -> f64 {
    let [_, y0, _, y1] = bounds(p);
    let rows = triangles(p) * ((y1 - y0).max(0.0) + 2.0) * n;
    if rows.is_finite() { f.min(rows) } else { f }
}

/// The fragments (float) and the runs (fixed) every primitive of a host scene can emit on a
/// layout, summed ([`crate::pipeline::Plan::footprint`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Footprint {
    /// Covered samples.
    pub fragments: f64,
    /// Runs of the fixed raster.
    pub runs: f64,
}

impl Footprint {
    /// The sums over `host`'s primitives on `l`.
    pub fn of(l: &Layout, host: &HostScene) -> Self {
        let (n, region_samples) = (l.grid.n as f64, l.samples.len() as f64);
        host.prims.iter().fold(Self::default(), |s, p| {
            let f = fragments(p, n, region_samples);
            Self {
                fragments: s.fragments + f,
                runs: s.runs + runs(p, f, n),
            }
        })
    }
}

/// The sample side of a whole-region run: the sample buffers' and the fragment lists'
/// bytes (what a banded run divides into bands; see `super::bands`).
pub fn sample_side(plan: &Plan, opts: RunOptions) -> (f64, f64) {
    let region_samples = plan.layout.samples.len() as f64;
    let f = plan.footprint;
    (
        region_samples * per_sample(plan, opts),
        f.fragments * FLOAT_FRAG + f.runs * RUN,
    )
}

/// A primitive's pixel bounding box `[x0, y0, x1, y1]` (lines and points with their
/// width).
fn bounds(p: &Primitive) -> [f64; 4] {
    let box_of = |pts: &[(f64, f64)], r: f64| {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for &(x, y) in pts {
            b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
        }
        [b[0] - r, b[1] - r, b[2] + r, b[3] + r]
    };
    match p {
        Primitive::Triangle(v) => box_of(&v.map(|v| (v.x, v.y)), 0.0),
        Primitive::Line { a, b, width } => box_of(&[(a.x, a.y), (b.x, b.y)], width / 2.0),
        Primitive::Point { v, size } => box_of(&[(v.x, v.y)], size / 2.0 + 1.0),
    }
}

/// Estimates the memory a run of `plan` needs.
pub fn estimate(plan: &Plan, opts: RunOptions) -> Estimate {
    let host = &plan.host;
    let l = &plan.layout;
    let pixels = l.grid.pixels();
    let mut parts = Vec::new();
    let mut part = |what, bytes: f64, drivers| {
        parts.push(Part {
            what,
            bytes: bytes.ceil() as u64,
            drivers,
        })
    };
    let all_frags = plan.footprint.fragments;
    match super::bands::rows(plan, opts) {
        None => {
            let (buffers, f) = sample_side(plan, opts);
            part(
                "sample buffers",
                buffers,
                "the region the primitives touch (image.width x image.height) and raster.samples",
            );
            part(
                "fragments",
                f,
                "the primitives' screen area with overdraw and raster.samples",
            );
        }
        Some(rows) => {
            // One band at a time: its own sample rows (at most the band's rows and the
            // filter's reach below them), and the accumulate input that adds the rows
            // above them (fixed 12 B, float 20 B per sample, the stage-local f64 copy).
            let n = l.grid.n as f64;
            let reach =
                (l.samples.height() as f64 - f64::from(l.region.y1 - l.region.y0) * n).max(0.0);
            let band = l.samples.width() as f64 * (f64::from(rows) * n + reach);
            let band = band.min(l.samples.len() as f64);
            part(
                "sample buffers (one band)",
                band * (per_sample(plan, opts) + 12.0 + 20.0 + 8.0),
                "the band's rows (the tile size, cycles.tile) x the region's width (image.width) and raster.samples",
            );
            // The fragments of the band with the most: a primitive gives a band at most one
            // fragment per sample of its bounding box's rows in the band (two for a line,
            // which is two triangles), and at most its whole area; and a run per row.
            let all: Vec<(f64, [f64; 4], f64)> = host
                .prims
                .iter()
                .map(|p| {
                    let f = fragments(p, n, l.samples.len() as f64);
                    (f, bounds(p), triangles(p))
                })
                .collect();
            let h = f64::from(l.grid.height);
            let reach_px = reach / n;
            let frags = (0..l.grid.height.div_ceil(rows))
                .map(|b| {
                    let (y0, y1) = (
                        f64::from(b * rows) - reach_px,
                        (f64::from((b + 1) * rows) + reach_px).min(h + reach_px),
                    );
                    all.iter()
                        .map(|&(f, [x0, ya, x1, yb], per)| {
                            let rows_in = (yb.min(y1) - ya.max(y0) + 2.0).max(0.0);
                            if yb < y0 - 1.0 || ya > y1 + 1.0 {
                                0.0
                            } else {
                                let frags = f.min(per * (x1 - x0 + 2.0) * n * rows_in * n);
                                frags * FLOAT_FRAG + frags.min(per * rows_in * n) * RUN
                            }
                        })
                        .sum::<f64>()
                })
                .fold(0.0, f64::max);
            part(
                "fragments (one band)",
                frags,
                "the primitives' screen area in one band with overdraw and raster.samples",
            );
        }
    }
    // Frame codes, depth and coverage (10 B) and the float frame (8 B), twice (a stage's
    // result and its tap); gamma's codes and float codes (8 B) and the powers of the float
    // frame (8 B, which the contour metric reads); the DAC codes fixed and float (4 B); the
    // contour map (1 B) and the PNG (4 B). The contour metric's planes (`crate::perceptual`):
    // whole-image up to `WHOLE_MAX` pixels (integral images, spans, excesses: 90 B), else
    // one band of rows (about 100 B per pixel of 70 rows).
    let mut per_pixel = 2.0 * (10.0 + 8.0) + 8.0 + 8.0 + 4.0 + 1.0 + 4.0;
    if pixels <= crate::perceptual::WHOLE_MAX as u64 {
        per_pixel += 90.0;
    } else {
        part(
            "contour metric (one band)",
            70.0 * f64::from(l.grid.width) * 100.0,
            "image.width",
        );
    }
    if l.has(StageId::Dof) {
        // The composite (16 B) and the widest layer's four u128 planes (64 B), fixed; the
        // float layers' planes (48 B) and the new frame (8 B); the stage-local copy.
        per_pixel += 16.0 + 64.0 + 56.0 + if opts.stage_local { 64.0 } else { 0.0 };
    }
    if l.has(StageId::Dither) {
        per_pixel += 4.0 + 8.0 + 8.0;
    }
    part(
        "per-pixel planes",
        pixels as f64 * per_pixel,
        "image.width x image.height",
    );
    if opts.dof_truth_samples > 0 && l.has(StageId::Dof) {
        // The lens points rendered at once, each with a float sample buffer (at most the
        // screen's) and float fragments; the group sums, the batch's frames, the mean and
        // its error.
        let batch = crate::truth::batch_size(opts.dof_truth_samples) as f64;
        let groups = f64::from(crate::truth::GROUPS);
        part(
            "depth-of-field truth",
            batch * (l.grid.samples() as f64 * 20.0 + all_frags * FLOAT_FRAG)
                + (groups + batch + 2.0) * pixels as f64 * 8.0,
            "--dof-truth: the threads, image.width x image.height and raster.samples",
        );
    }
    Estimate {
        bytes: parts.iter().map(|p| p.bytes).sum(),
        parts,
    }
}

/// A safe default limit: half the machine's physical memory (`/proc/meminfo`, read once
/// per process), or 4 GiB where that cannot be read.
pub fn default_limit() -> u64 {
    static LIMIT: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *LIMIT.get_or_init(read_limit)
}

fn read_limit() -> u64 {
    let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find_map(|l| l.strip_prefix("MemTotal:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
    });
    total.map_or(4 << 30, |kb| kb * 1024 / 2)
}

/// Bytes in a readable unit.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.2} GiB", b / (1u64 << 30) as f64)
    } else {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    }
}

/// The peak resident memory of this process so far (`VmHWM` of `/proc/self/status`), where
/// the system tells it.
pub fn peak_memory() -> Option<u64> {
    let t = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: u64 = t
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}
