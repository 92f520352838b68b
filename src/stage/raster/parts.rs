//! The fixed raster of a frame on the threads: bands of sample rows walked in parallel,
//! their runs kept in parts of a few rows, the parts visibility resolves one by one.

use super::fixed::{RasterParams, RasterWork, RunSink, raster_rows};
use super::runs::Run;
use crate::stage::setup::Setup;
use crate::stage::taps::{Frags, Span};
use crate::stage::{Pool, SampleRegion};
use rayon::prelude::*;

/// The bands of sample rows the fixed raster walks on the threads: about 256 sample rows
/// each, at most 8, a count that depends on the region alone (so the fragment lists and
/// every count are the same on any thread count). Narrower bands (64 rows, up to 16) made
/// the default frame slower: each band walks the edges of every primitive that crosses it
/// down to its rows.
fn band_rows(reg: &SampleRegion) -> Vec<(i64, i64)> {
    let h = reg.k1 - reg.k0;
    let n = (h / 256).clamp(1, 8);
    (0..n)
        .map(|j| (reg.k0 + h * j / n, reg.k0 + h * (j + 1) / n))
        .collect()
}

/// Sample rows per part of the fragment lists: a band's fragments are kept in parts of
/// this many rows, so that visibility clears and depth-tests one part's planes (32 rows
/// of the default screen's samples, about 1 MiB for depth, id and intensity) while
/// they sit in the core's cache.
pub const PART_ROWS: i64 = 32;

/// The parts of band `rows`: runs of [`PART_ROWS`] rows, the last one shorter.
fn part_rows(rows: (i64, i64)) -> impl Iterator<Item = (i64, i64)> {
    (rows.0..rows.1)
        .step_by(PART_ROWS as usize)
        .map(move |k| (k, (k + PART_ROWS).min(rows.1)))
}

/// The parts of one band as the walker fills them: a run goes to the part of its row,
/// and opens or extends the primitive's span there.
struct PartSink<'a> {
    /// The band's first sample row.
    k0: i64,
    data: &'a mut [Vec<Run>],
    spans: &'a mut [Vec<Span>],
    /// The primitive being walked.
    prim: u32,
}

impl RunSink for PartSink<'_> {
    #[inline]
    fn push(&mut self, k: i64, run: Run) {
        let j = ((k - self.k0) / PART_ROWS) as usize;
        let (data, spans) = (&mut self.data[j], &mut self.spans[j]);
        match spans.last_mut() {
            Some(last) if last.prim == self.prim => last.b += 1,
            _ => spans.push(Span {
                prim: self.prim,
                a: data.len(),
                b: data.len() + 1,
            }),
        }
        data.push(run);
    }
}

/// The sample indices of the rows `rows` of `reg`.
fn sample_range(reg: &SampleRegion, rows: (i64, i64)) -> (usize, usize) {
    let w = reg.width();
    let at = |k: i64| (k - reg.k0).max(0) as usize * w;
    (at(rows.0), at(rows.1))
}

/// The fixed raster of `setups` (scene order) over `reg`, on the threads: the runs of
/// every primitive in parts of [`PART_ROWS`] sample rows (the parts' lists from `pool`,
/// last frame's), the samples stepped per primitive and the work. `above`: count the walk
/// above the region's rows (not in a banded run's later bands).
///
/// Each band walks every primitive in scene order and keeps the runs of its rows, so the
/// parts are disjoint row ranges of the sample buffer, in order, and visibility reads
/// each run once; a part holds its runs in primitive order, each primitive's in the
/// walker's order (a sample lies in one part, so its runs meet it in the order of the
/// whole-region walk). The band and part counts depend on the region alone and the counts
/// are integers summed in band order: the same on any thread count.
pub fn walk(
    setups: &[Setup],
    p: &RasterParams,
    reg: &SampleRegion,
    above: bool,
    pool: &Pool,
) -> (Frags<Run>, Vec<u64>, RasterWork) {
    let bands = band_rows(reg);
    let parts: Vec<Vec<(i64, i64)>> = bands.iter().map(|&b| part_rows(b).collect()).collect();
    let n = setups.len();
    // Last frame's parts, whose sizes fit the same scene's.
    let mut bufs: Vec<Vec<Run>> = pool.reuse();
    let mut span_bufs: Vec<Vec<Span>> = pool.reuse();
    let total: usize = parts.iter().map(Vec::len).sum();
    bufs.resize_with(total, Vec::new);
    span_bufs.resize_with(total, Vec::new);
    let mut per_band = Vec::with_capacity(bands.len());
    let (mut data_rest, mut span_rest) = (&mut bufs[..], &mut span_bufs[..]);
    for band in &parts {
        let (d, dr) = std::mem::take(&mut data_rest).split_at_mut(band.len());
        let (sp, sr) = std::mem::take(&mut span_rest).split_at_mut(band.len());
        per_band.push((d, sp));
        (data_rest, span_rest) = (dr, sr);
    }
    let done: Vec<_> = bands
        .par_iter()
        .zip(per_band)
        .enumerate()
        // One band per task: a thread done early takes the next band.
        .with_max_len(1)
        .map(|(b, (&rows, (data, spans)))| {
            data.iter_mut().for_each(Vec::clear);
            spans.iter_mut().for_each(Vec::clear);
            let mut w = RasterWork::default();
            let mut stepped: Vec<(u32, u64)> = Vec::new();
            let mut sink = PartSink {
                k0: rows.0,
                data,
                spans,
                prim: 0,
            };
            for (q, s) in setups.iter().enumerate() {
                let before = w.samples + w.walked;
                sink.prim = q as u32;
                raster_rows(s, p, reg, rows, above && b == 0, &mut sink, &mut w);
                if w.samples + w.walked > before {
                    stepped.push((q as u32, w.samples + w.walked - before));
                }
            }
            (stepped, w)
        })
        .collect();
    let out = Frags {
        parts: bufs,
        spans: span_bufs,
        bounds: parts
            .iter()
            .flatten()
            .map(|r| sample_range(reg, *r))
            .collect(),
        prims: n,
        index: Default::default(),
    };
    let mut stepped = vec![0u64; n];
    let mut w = RasterWork::default();
    for (st, wk) in done {
        for (q, k) in st {
            stepped[q as usize] += k;
        }
        w.add(&wk);
    }
    (out, stepped, w)
}
