//! The fixed-point model of the stage: the frame memory ([`Frame`]), its work counts, the
//! product rounding and overflow-mode add ([`AccParams`]), and the per-pixel window pass
//! (whole region or touched tiles only) followed by the additive light points.

use super::kernel::Kernel;
use super::points::{PointFrags, point_weights};
use super::span::{self, Build, Dst, Scratch, Span};
use super::stats::ProductStats;
use super::window::{WindowSums, sums_fit_u32};
use crate::error::{Error, Result};
use crate::fixed::{Overflow, Quantizer, RoundShift, SignalStats, round_shift_i64};
use crate::stage::visibility::{BACKGROUND, Samples};
use crate::stage::{Pool, Region};
use rayon::prelude::*;

/// Per-pixel outputs of the accumulate stage.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Frame-memory codes.
    pub acc: Vec<u32>,
    /// Nearest depth code in the pixel's own samples (`u32::MAX` for background only).
    pub depth: Vec<u32>,
    /// Covered samples in the pixel's own `n x n` block (alpha = coverage / n^2).
    pub coverage: Vec<u16>,
}

impl Frame {
    /// A frame of the background code `bg` (no depth, no coverage), its planes from `pool`.
    pub fn cleared(width: u32, height: u32, bg: u32, pool: &Pool) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            acc: pool.filled(n, bg),
            depth: pool.filled(n, u32::MAX),
            coverage: pool.filled(n, 0),
        }
    }
}

/// Work of the accumulate stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AccWork {
    /// Pixels computed (inside the region).
    pub pixels: u64,
    /// `w * I` multiply-accumulates.
    pub macs: u64,
    /// `I_F += I * S` read-modify-writes of the frame memory.
    pub fragments: u64,
    /// Light-point pixel updates.
    pub point_updates: u64,
    /// Frame-memory overflows (handled by the overflow mode), the clamps included.
    pub overflows: u64,
    /// Signed kernels: pixels whose sum left the frame word at the clamp (counted in
    /// `overflows` too).
    pub clamps: u64,
}

/// Parameters of the fixed model.
#[derive(Clone, Debug)]
pub struct AccParams {
    /// Filter kernel.
    pub kernel: Kernel,
    /// Fraction bits of the sample intensity codes.
    pub i_frac: u32,
    /// A bound on the sample intensity codes (the intensity format's largest code): where
    /// the window sums of codes up to it fit a `u32`, the sample buffer is not scanned for
    /// its largest code. `u32::MAX`: always scanned.
    pub i_max: u32,
    /// Frame-memory quantiser.
    pub frame: Quantizer,
}

impl AccParams {
    /// Bits dropped when rounding `sum w*I` to the frame format (negative: shift left).
    fn shift(&self) -> i32 {
        (self.kernel.f + self.i_frac) as i32 - self.frame.format.frac_bits as i32
    }

    /// Rounds a product sum to the frame format; records it.
    #[inline]
    fn product(&self, sum: i64, stats: &mut SignalStats) -> i64 {
        let sh = self.shift();
        if sh <= 0 {
            let v = (sum as i128) << (-sh);
            stats.record(v as f64, v, false);
            v as i64
        } else {
            let r = round_shift_i64(sum, sh as u32, self.frame.quant) as i128;
            stats.record(sum as f64 / (1u64 << sh) as f64, r, false);
            r as i64
        }
    }

    /// Frame-memory add with the overflow mode.
    #[inline]
    pub(super) fn add(&self, acc: i64, part: i64, overflows: &mut u64) -> Result<i64> {
        add_in(&self.frame, "accumulate.frame", acc, part, overflows)
    }

    /// A pixel's end: a signed kernel's accumulator clamped to the frame word with its
    /// overflow mode (`SAT` clamps, `WRAP` wraps, `ERROR` stops; counted in `overflows`
    /// and `clamps`); the frame word as it is otherwise.
    #[inline]
    pub(super) fn finish(
        &self,
        accq: Option<&Quantizer>,
        acc: i64,
        w: &mut AccWork,
    ) -> Result<u32> {
        if accq.is_none() {
            return Ok(acc as u32);
        }
        let before = w.overflows;
        let v = self.add(0, acc, &mut w.overflows)?;
        w.clamps += w.overflows - before;
        Ok(v as u32)
    }

    /// One `w * I` term rounded to the frame format and added to `acc` with the overflow
    /// mode, as the HDL model `hdl-models/rtl/acc_mac.v` computes it: `(code, overflowed)`
    /// (the `ERROR` mode gives the saturated code and the flag instead of an error). For a
    /// signed kernel the sum is the signed accumulator's ([`Kernel::accumulator`]).
    pub fn mac_code(&self, acc: i64, w: i32, i: u32) -> (i64, bool) {
        let mut st = SignalStats::new("mac", self.frame.format);
        let part = self.product(w as i64 * i as i64, &mut st);
        let q = self
            .kernel
            .accumulator(&self.frame)
            .unwrap_or(self.frame)
            .handle_overflow(acc as i128 + part as i128);
        (q.code, q.overflow)
    }

    /// A signed kernel's accumulator `acc` clamped to the frame word with its overflow mode,
    /// as `acc_mac.v`'s `clamp_out` and `clamp_ovf`; `(acc, false)` for an unsigned kernel.
    pub fn clamp_code(&self, acc: i64) -> (i64, bool) {
        if !self.kernel.signed() {
            return (acc, false);
        }
        let q = self.frame.handle_overflow(acc as i128);
        (q.code, q.overflow)
    }

    /// Bits dropped when rounding a product to the frame format (negative: shift left).
    pub fn product_shift(&self) -> i32 {
        self.shift()
    }

    /// The frame code of a pixel that sees only the background.
    pub fn background_code(&self, bg_i: u32) -> Result<u32> {
        let mut st = SignalStats::new("bg", self.frame.format);
        let part = self.product(bg_i as i64 * (1i64 << self.kernel.f), &mut st);
        Ok(self.add(0, part, &mut 0)? as u32)
    }
}

/// `acc + part` in the word of `q` with its overflow mode, named `signal` in an error.
#[inline(always)]
fn add_in(q: &Quantizer, signal: &str, acc: i64, part: i64, overflows: &mut u64) -> Result<i64> {
    let r = q.handle_overflow(acc as i128 + part as i128);
    if r.overflow {
        *overflows += 1;
        if q.overflow == Overflow::Error {
            return Err(Error::Overflow {
                signal: signal.into(),
                format: q.format.to_string(),
                value: acc as i128 + part as i128,
                min: q.format.min_code(),
                max: q.format.max_code(),
            });
        }
    }
    Ok(r.code)
}

/// The arithmetic of a pixel's fragments with its constants taken once per row: each
/// window sum rounded to the frame format ([`AccParams::product`], the same codes and
/// statistics) and added with the overflow mode, into the signed accumulator of a signed
/// kernel ([`Kernel::accumulator`], which the sums cannot overflow), else into the frame
/// word.
pub(super) struct FragMath<'a> {
    p: &'a AccParams,
    /// The quantiser of the adds: the signed accumulator's when `signed_acc`, else the
    /// frame word's.
    add: Quantizer,
    signed_acc: bool,
    /// The add's results that need no overflow handling.
    lo: i64,
    hi: i64,
    /// Bits dropped by the rounding (negative: shift left), and the rounding when positive.
    sh: i32,
    round: Option<RoundShift>,
}

impl<'a> FragMath<'a> {
    /// The arithmetic of `p`.
    pub fn new(p: &'a AccParams) -> Self {
        let accq = p.kernel.accumulator(&p.frame);
        let add = accq.unwrap_or(p.frame);
        let f = &add.format;
        // SatSym maps a signed format's smallest code to its negation: that code takes the
        // overflow path.
        let sym = add.overflow == Overflow::SatSym && f.signed;
        let sh = p.shift();
        Self {
            p,
            add,
            signed_acc: accq.is_some(),
            lo: f.min_code() + i64::from(sym),
            hi: f.max_code(),
            sh,
            round: (sh > 0).then(|| RoundShift::new(sh as u32, p.frame.quant)),
        }
    }

    /// The statistics of a row of at most `width` pixels: the rounding errors summed as
    /// integers where every partial sum of the float recording is exact (see
    /// [`ProductStats`]).
    pub fn stats(&self, width: usize) -> ProductStats {
        let k = &self.p.kernel;
        // |sum| <= max(pos, neg) * I_max must convert to f64 exactly, and a row of at most
        // width * size^2 errors, each below 2^sh in magnitude, must keep its sum of
        // squares below 2^53 (so every partial sum of the float recording is exact too).
        let sums = k.pos.max(k.neg) as u128 * u128::from(self.p.i_max);
        let count = (width * k.size * k.size) as u128;
        let exact = (1..=15).contains(&self.sh)
            && sums < 1 << 53
            && count << (2 * self.sh as u32) < 1 << 53;
        ProductStats::new(self.sh.max(0) as u32, exact)
    }

    /// The frame code of a pixel from its fragments' window sums, counting overflows and
    /// clamps into `w`.
    #[inline(always)]
    pub fn pixel(
        &self,
        frags: &[(u32, i64)],
        stats: &mut ProductStats,
        w: &mut AccWork,
    ) -> Result<u32> {
        let mut acc = 0i64;
        for &(_, sum) in frags {
            let part = match self.round {
                Some(r) => {
                    let v = r.apply(sum);
                    stats.record_rounding(v, sum);
                    v
                }
                None => {
                    let v = ((sum as i128) << (-self.sh)) as i64;
                    stats.record(v as f64, v);
                    v
                }
            };
            let v = acc as i128 + part as i128;
            acc = if v >= i128::from(self.lo) && v <= i128::from(self.hi) {
                v as i64
            } else {
                let name = if self.signed_acc {
                    "accumulate.acc"
                } else {
                    "accumulate.frame"
                };
                add_in(&self.add, name, acc, part, &mut w.overflows)?
            };
        }
        let accq = self.signed_acc.then_some(&self.add);
        self.p.finish(accq, acc, w)
    }
}

/// Nearest depth code and covered-sample count of a pixel's own `n x n` samples, given the
/// buffer index `window` of its filter window's first sample.
#[inline]
pub fn own_depth_coverage(s: &Samples, k: &Kernel, window: usize, sw: usize) -> (u32, u16) {
    let own0 = window + k.off as usize * sw + k.off as usize;
    match k.n {
        1 => own_n::<1>(s, own0, sw),
        2 => own_n::<2>(s, own0, sw),
        4 => own_n::<4>(s, own0, sw),
        _ => own_n::<8>(s, own0, sw),
    }
}

/// [`own_depth_coverage`] of the `N x N` samples from buffer index `own0`.
#[inline(always)]
pub(super) fn own_n<const N: usize>(s: &Samples, own0: usize, sw: usize) -> (u32, u16) {
    let (mut zmin, mut cov) = (u32::MAX, 0u16);
    for j in 0..N {
        let row = own0 + j * sw;
        let ids: &[u32; N] = s.prim[row..row + N].try_into().expect("N samples");
        let zs: &[u32; N] = s.z[row..row + N].try_into().expect("N samples");
        for t in 0..N {
            let covered = ids[t] != BACKGROUND;
            cov += u16::from(covered);
            zmin = zmin.min(if covered { zs[t] } else { u32::MAX });
        }
    }
    (zmin, cov)
}

/// The most pixel rows a task of the threads accumulates.
const ROWS_PER_TASK: usize = 8;

/// One pixel row's counts, merged in row order (its codes go straight to the frame).
pub(super) struct RowOut {
    pub stats: SignalStats,
    pub work: AccWork,
    pub tile_rmw: Vec<u64>,
}

/// The region's part of each of its rows of a `w`-wide frame plane.
fn region_rows<'a, T>(v: &'a mut [T], region: &Region, w: usize) -> Vec<&'a mut [T]> {
    let (x0, x1) = (region.x0 as usize, region.x1 as usize);
    v[region.y0 as usize * w..region.y1 as usize * w]
        .chunks_mut(w)
        .map(|r| &mut r[x0..x1])
        .collect()
}

/// Fixed model: accumulates every pixel of `region`; the rest is background.
pub fn accumulate(
    s: &Samples,
    region: &Region,
    points: &[PointFrags<u32>],
    p: &AccParams,
    bg_i: u32,
    size: (u32, u32),
) -> Result<(Frame, AccWork, Vec<SignalStats>)> {
    accumulate_tiles(s, region, None, points, p, bg_i, size, &Pool::new())
        .map(|(f, w, st, _)| (f, w, st))
}

/// Fixed model limited to the touched tiles of `region` (all of it with `None`): a pixel
/// of an untouched tile sees only background samples, so it takes the background code
/// (the kernel's weights sum to exactly `2^f`, so the result is the same bit for bit).
/// Also returns the frame read-modify-writes (fragments and point updates) per tile
/// (empty with `None`). The frame's planes come from `pool`.
#[allow(clippy::too_many_arguments)]
pub fn accumulate_tiles(
    s: &Samples,
    region: &Region,
    tiles: Option<&crate::stage::Tiles>,
    points: &[PointFrags<u32>],
    p: &AccParams,
    bg_i: u32,
    size: (u32, u32),
    pool: &Pool,
) -> Result<(Frame, AccWork, Vec<SignalStats>, Vec<u64>)> {
    accumulate_build(s, region, tiles, points, p, bg_i, (size, pool), None)
}

/// [`accumulate_tiles`], with the window kernel's build forced by `force` (tests compare
/// every build; `None`: the word the data allows and AVX2 when the CPU has it).
#[allow(clippy::too_many_arguments)]
pub(super) fn accumulate_build(
    s: &Samples,
    region: &Region,
    tiles: Option<&crate::stage::Tiles>,
    points: &[PointFrags<u32>],
    p: &AccParams,
    bg_i: u32,
    (size, pool): ((u32, u32), &Pool),
    force: Option<Build>,
) -> Result<(Frame, AccWork, Vec<SignalStats>, Vec<u64>)> {
    let (width, height) = size;
    let bg = p.background_code(bg_i)?;
    let mut frame = Frame::cleared(width, height, bg, pool);
    let k = &p.kernel;
    let template = SignalStats::new("accumulate.product", p.frame.format);
    // The word of the window sums: from the codes' bound, else from the largest intensity
    // code in the buffer. Every word gives the same sums.
    let narrow =
        || sums_fit_u32(k, p.i_max) || sums_fit_u32(k, s.i.par_iter().copied().max().unwrap_or(0));
    let build = force.unwrap_or_else(|| Build {
        narrow: narrow(),
        avx2: span::has_avx2(),
    });
    let w = width as usize;
    let math = FragMath::new(p);
    let acc_rows = region_rows(&mut frame.acc, region, w);
    let depth_rows = region_rows(&mut frame.depth, region, w);
    let cov_rows = region_rows(&mut frame.coverage, region, w);
    let rows: Vec<Result<RowOut>> = acc_rows
        .into_par_iter()
        .zip(depth_rows)
        .zip(cov_rows)
        .enumerate()
        // Tasks of a few rows, so that a thread done early takes over rows from the other
        // (the rows' work is as uneven as the scene).
        .with_max_len(ROWS_PER_TASK)
        // A task's rows are consecutive and in order: its scratch keeps each span's block
        // ids for the next row (`BlockIds`; the same ids whatever the tasks).
        .map_init(
            || Scratch {
                win: WindowSums::new(k),
                ids: Vec::new(),
                stats: math.stats((region.x1 - region.x0) as usize),
                own: (Vec::new(), Vec::new()),
            },
            |sc, (j, ((acc_row, depth_row), cov_row))| {
                // A row's statistics start afresh (after a row that failed too).
                sc.stats = math.stats((region.x1 - region.x0) as usize);
                let py = region.y0 + j as u32;
                let mut out = RowOut {
                    stats: SignalStats::new("accumulate.product", p.frame.format),
                    work: AccWork::default(),
                    tile_rmw: vec![0; tiles.map_or(0, |t| t.cols as usize)],
                };
                let r0 = (py as i64 * k.n as i64 - k.off - s.reg.k0) as usize;
                // Spans of pixels in one tile column: binned or not (no division per pixel).
                // Untouched tiles keep the background the frame starts with.
                let spans: Vec<(u32, u32, Option<usize>)> = match tiles {
                    None => vec![(region.x0, region.x1, None)],
                    Some(t) => {
                        let row0 = (py / t.size * t.cols) as usize;
                        (region.x0 / t.size..region.x1.div_ceil(t.size))
                            .filter(|&tc| t.touched[row0 + tc as usize])
                            .map(|tc| {
                                let a = (tc * t.size).max(region.x0);
                                let b = ((tc + 1) * t.size).min(region.x1);
                                (a, b, Some(tc as usize))
                            })
                            .collect()
                    }
                };
                for (xa, xb, tc) in spans {
                    let sp = Span {
                        s,
                        p,
                        math: &math,
                        r0,
                        xa,
                        xb,
                        tc,
                    };
                    let (a, b) = ((xa - region.x0) as usize, (xb - region.x0) as usize);
                    let dst = Dst {
                        acc: &mut acc_row[a..b],
                        depth: &mut depth_row[a..b],
                        cov: &mut cov_row[a..b],
                    };
                    span::run(&sp, sc, dst, &mut out, build)?;
                }
                let done = std::mem::replace(&mut sc.stats, math.stats(0));
                out.stats = done.into_stats(&template);
                Ok(out)
            },
        )
        .collect();
    let mut work = AccWork::default();
    let mut stats = SignalStats::new("accumulate.product", p.frame.format);
    let mut frame_stats = SignalStats::new("accumulate.frame", p.frame.format);
    let mut tile_rmw = vec![0u64; tiles.map_or(0, |t| t.touched.len())];
    for (py, r) in (region.y0..region.y1).zip(rows) {
        let r = r?;
        if let Some(t) = tiles {
            let row0 = (py / t.size * t.cols) as usize;
            for (c, &v) in r.tile_rmw.iter().enumerate() {
                tile_rmw[row0 + c] += v;
            }
        }
        stats.merge(&r.stats);
        work.pixels += r.work.pixels;
        work.macs += r.work.macs;
        work.fragments += r.work.fragments;
        work.overflows += r.work.overflows;
        work.clamps += r.work.clamps;
    }
    // Light points: additive I * S, in arrival order.
    for pt in points {
        for (px, py, sw_sum) in point_weights(pt, &s.reg, region, k, |e| f64::from(k.w[e])) {
            let sum = pt.i as i64 * sw_sum as i64;
            let part = p.product(sum, &mut stats);
            let at = py as usize * width as usize + px as usize;
            frame.acc[at] = p.add(frame.acc[at] as i64, part, &mut work.overflows)? as u32;
            work.point_updates += 1;
            if let Some(t) = tiles {
                tile_rmw[t.index(px, py)] += 1;
            }
        }
    }
    let (lo, hi) = frame
        .acc
        .iter()
        .fold((u32::MAX, 0), |(lo, hi), &a| (lo.min(a), hi.max(a)));
    frame_stats.record_range(frame.acc.len() as u64, lo.into(), hi.into());
    frame_stats.add_overflows(work.overflows);
    Ok((frame, work, vec![stats, frame_stats], tile_rmw))
}
