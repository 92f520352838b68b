//! The fixed-point model of the stage: the frame memory ([`Frame`]), its work counts, the
//! product rounding and overflow-mode add ([`AccParams`]), and the per-pixel window pass
//! (whole region or touched tiles only) followed by the additive light points.

use super::kernel::Kernel;
use super::points::{PointFrags, point_weights};
use crate::error::{Error, Result};
use crate::fixed::{Overflow, Quantizer, SignalStats, round_shift_i64};
use crate::stage::Region;
use crate::stage::visibility::{BACKGROUND, Samples};
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
    /// Frame-memory overflows (handled by the overflow mode).
    pub overflows: u64,
}

/// Parameters of the fixed model.
#[derive(Clone, Debug)]
pub struct AccParams {
    /// Filter kernel.
    pub kernel: Kernel,
    /// Fraction bits of the sample intensity codes.
    pub i_frac: u32,
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
    fn add(&self, acc: i64, part: i64, overflows: &mut u64) -> Result<i64> {
        let q = self.frame.handle_overflow(acc as i128 + part as i128);
        if q.overflow {
            *overflows += 1;
            if self.frame.overflow == Overflow::Error {
                return Err(Error::Overflow {
                    signal: "accumulate.frame".into(),
                    format: self.frame.format.to_string(),
                    value: acc as i128 + part as i128,
                    min: self.frame.format.min_code(),
                    max: self.frame.format.max_code(),
                });
            }
        }
        Ok(q.code)
    }

    /// One `w * I` term rounded to the frame format and added to `acc` with the overflow
    /// mode, as the HDL model `hdl-models/rtl/acc_mac.v` computes it: `(code, overflowed)`
    /// (the `ERROR` mode gives the saturated code and the flag instead of an error).
    pub fn mac_code(&self, acc: i64, w: u32, i: u32) -> (i64, bool) {
        let mut st = SignalStats::new("mac", self.frame.format);
        let part = self.product(w as i64 * i as i64, &mut st);
        let q = self.frame.handle_overflow(acc as i128 + part as i128);
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

/// Nearest depth code and covered-sample count of a pixel's own `n x n` samples, given the
/// buffer index `window` of its filter window's first sample.
#[inline]
pub fn own_depth_coverage(s: &Samples, k: &Kernel, window: usize, sw: usize) -> (u32, u16) {
    let n = k.n as usize;
    let own0 = window + k.off as usize * sw + k.off as usize;
    let (mut zmin, mut cov) = (u32::MAX, 0u16);
    for j in 0..n {
        for i in 0..n {
            let idx = own0 + j * sw + i;
            if s.prim[idx] != BACKGROUND {
                cov += 1;
                zmin = zmin.min(s.z[idx]);
            }
        }
    }
    (zmin, cov)
}

/// Sums `w * I` per primitive over a pixel's window starting at buffer index `base`.
fn group_window(s: &Samples, k: &Kernel, base: usize, sw: usize, frags: &mut Vec<(u32, i64)>) {
    let mut last = usize::MAX;
    for j in 0..k.size {
        let row = base + j * sw;
        for (i, &w) in k.w[j * k.size..(j + 1) * k.size].iter().enumerate() {
            if w == 0 {
                continue;
            }
            let id = s.prim[row + i];
            let slot = if last < frags.len() && frags[last].0 == id {
                last
            } else {
                match frags.iter().position(|f| f.0 == id) {
                    Some(x) => x,
                    None => {
                        frags.push((id, 0));
                        frags.len() - 1
                    }
                }
            };
            last = slot;
            frags[slot].1 += w as i64 * s.i[row + i] as i64;
        }
    }
}

struct RowOut {
    acc: Vec<u32>,
    depth: Vec<u32>,
    cov: Vec<u16>,
    stats: SignalStats,
    work: AccWork,
    tile_rmw: Vec<u64>,
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
    accumulate_tiles(s, region, None, points, p, bg_i, size).map(|(f, w, st, _)| (f, w, st))
}

/// Fixed model limited to the touched tiles of `region` (all of it with `None`): a pixel
/// of an untouched tile sees only background samples, so it takes the background code
/// (the kernel's weights sum to exactly `2^f`, so the result is the same bit for bit).
/// Also returns the frame read-modify-writes (fragments and point updates) per tile
/// (empty with `None`).
pub fn accumulate_tiles(
    s: &Samples,
    region: &Region,
    tiles: Option<&crate::stage::Tiles>,
    points: &[PointFrags<u32>],
    p: &AccParams,
    bg_i: u32,
    size: (u32, u32),
) -> Result<(Frame, AccWork, Vec<SignalStats>, Vec<u64>)> {
    let (width, height) = size;
    let npix = width as usize * height as usize;
    let bg = p.background_code(bg_i)?;
    let mut frame = Frame {
        width,
        height,
        acc: vec![bg; npix],
        depth: vec![u32::MAX; npix],
        coverage: vec![0; npix],
    };
    let k = &p.kernel;
    let size_w = k.size;
    let sw = s.reg.width();
    let rows: Vec<Result<RowOut>> = (region.y0..region.y1)
        .into_par_iter()
        .map(|py| {
            let mut out = RowOut {
                acc: Vec::with_capacity((region.x1 - region.x0) as usize),
                depth: Vec::with_capacity((region.x1 - region.x0) as usize),
                cov: Vec::with_capacity((region.x1 - region.x0) as usize),
                stats: SignalStats::new("accumulate.product", p.frame.format),
                work: AccWork::default(),
                tile_rmw: vec![0; tiles.map_or(0, |t| t.cols as usize)],
            };
            let mut frags: Vec<(u32, i64)> = Vec::with_capacity(16);
            for px in region.x0..region.x1 {
                if let Some(t) = tiles
                    && !t.is_touched(px, py)
                {
                    out.acc.push(bg);
                    out.depth.push(u32::MAX);
                    out.cov.push(0);
                    continue;
                }
                out.work.pixels += 1;
                frags.clear();
                let c0 = (px as i64 * k.n as i64 - k.off - s.reg.c0) as usize;
                let r0 = (py as i64 * k.n as i64 - k.off - s.reg.k0) as usize;
                // Fast path: one scan sums w*I and checks whether a single primitive
                // fills the window (most pixels); otherwise group by primitive.
                let first = s.prim[r0 * sw + c0];
                let (mut total, mut uniform) = (0i64, true);
                for j in 0..size_w {
                    let row = (r0 + j) * sw + c0;
                    let wrow = &k.w[j * size_w..(j + 1) * size_w];
                    let ids = &s.prim[row..row + size_w];
                    let is = &s.i[row..row + size_w];
                    for ((&w, &id), &iv) in wrow.iter().zip(ids).zip(is) {
                        total += w as i64 * iv as i64;
                        uniform &= id == first;
                    }
                }
                if uniform {
                    frags.push((first, total));
                } else {
                    group_window(s, k, r0 * sw + c0, sw, &mut frags);
                }
                out.work.macs += (size_w * size_w) as u64;
                frags.sort_unstable_by_key(|f| f.0);
                let mut acc = 0i64;
                for &(_, sum) in &frags {
                    let part = p.product(sum, &mut out.stats);
                    acc = p.add(acc, part, &mut out.work.overflows)?;
                }
                out.work.fragments += frags.len() as u64;
                if let Some(t) = tiles {
                    out.tile_rmw[(px / t.size) as usize] += frags.len() as u64;
                }
                // Depth and coverage of the pixel's own samples.
                let (zmin, cov) = own_depth_coverage(s, k, r0 * sw + c0, sw);
                out.acc.push(acc as u32);
                out.depth.push(zmin);
                out.cov.push(cov);
            }
            Ok(out)
        })
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
        let base = py as usize * width as usize + region.x0 as usize;
        let len = r.acc.len();
        frame.acc[base..base + len].copy_from_slice(&r.acc);
        frame.depth[base..base + len].copy_from_slice(&r.depth);
        frame.coverage[base..base + len].copy_from_slice(&r.cov);
        stats.merge(&r.stats);
        work.pixels += r.work.pixels;
        work.macs += r.work.macs;
        work.fragments += r.work.fragments;
        work.overflows += r.work.overflows;
    }
    // Light points: additive I * S, in arrival order.
    for pt in points {
        for (px, py, sw_sum) in point_weights(pt, &s.reg, region, k, |e| k.w[e] as f64) {
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
    for &a in &frame.acc {
        frame_stats.record_code(a as i128);
    }
    frame_stats.add_overflows(work.overflows);
    Ok((frame, work, vec![stats, frame_stats], tile_rmw))
}
