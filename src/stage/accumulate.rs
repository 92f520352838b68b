//! Accumulate: filtering and sampling in one step, into the frame memory.
//!
//! For every pixel a filter is centred on it; each primitive `j` visible in the filter's
//! window gets the weight `S_j` (the sum of the filter weights of its samples) and the
//! frame memory accumulates `I_F += I_j * S_j` (Kovalev & Tokarev, eq. 2-3). With
//! Gouraud shading the intensity varies per sample, so the product is the exact sum
//! `sum_s w_s * I_s` over the primitive's samples in the window, rounded once to the
//! frame format (its rounding mode), then added with the frame's overflow mode.
//! Primitives are accumulated in arrival order (the background first), light points
//! last, as additive `I * S` terms.
//!
//! Filter weights are quantised to `weight_bits` fraction bits with their sum kept
//! exact: for the equal-energy filters (box, tent) by largest remainder *within each
//! sample's group* (the weights one sub-pixel sample gives to the pixels around it), so
//! every sample gives exactly `2^f / n^2` and the filters stay equal-energy bit for bit;
//! for the Gaussian by largest remainder over the whole kernel (sum `2^f`).

use super::raster::SampleRegion;
use super::visibility::{BACKGROUND, Samples};
use super::{Cost, Region, Unit};
use crate::config::FilterKind;
use crate::error::{Error, Result};
use crate::fixed::{Overflow, Quantizer, SignalStats, round_shift_i64};
use rayon::prelude::*;

/// A quantised filter kernel over the `size x size` samples of one pixel's window.
#[derive(Clone, Debug, PartialEq)]
pub struct Kernel {
    /// Filter.
    pub kind: FilterKind,
    /// Samples per pixel per axis.
    pub n: u32,
    /// Window size in samples per axis (`base * n`).
    pub size: usize,
    /// Offset of the window's first sample left of / above the pixel's first sample.
    pub off: i64,
    /// Weight fraction bits: the weights sum to `2^f`.
    pub f: u32,
    /// Quantised weights, row-major.
    pub w: Vec<u32>,
    /// Exact weights (sum 1), row-major: the float reference.
    pub wf: Vec<f64>,
}

impl Kernel {
    /// Builds and quantises the kernel.
    pub fn new(kind: FilterKind, n: u32, f: u32, sigma: f64) -> Self {
        let base = kind.base();
        let size = (base * n) as usize;
        let off = ((base - 1) * n / 2) as i64;
        let nf = n as f64;
        let profile = |j: usize| {
            let u = (j as f64 - off as f64 + 0.5) / nf - 0.5;
            match kind {
                FilterKind::Box => 1.0,
                FilterKind::Tent => 1.0 - u.abs(),
                FilterKind::Gaussian => (-u * u / (2.0 * sigma * sigma)).exp(),
            }
        };
        let p: Vec<f64> = (0..size).map(profile).collect();
        let total: f64 = p.iter().sum::<f64>().powi(2);
        let wf: Vec<f64> = (0..size * size)
            .map(|e| p[e / size] * p[e % size] / total)
            .collect();
        let one = 1u64 << f;
        let mut w = vec![0u32; size * size];
        if kind.equal_energy() {
            let share = one / (n as u64 * n as u64);
            for gj in 0..n as usize {
                for gi in 0..n as usize {
                    let members: Vec<usize> = (0..base as usize)
                        .flat_map(|a| {
                            (0..base as usize)
                                .map(move |b| (gj + a * n as usize) * size + gi + b * n as usize)
                        })
                        .collect();
                    largest_remainder(&members, &wf, one as f64, share, &mut w);
                }
            }
        } else {
            let all: Vec<usize> = (0..size * size).collect();
            largest_remainder(&all, &wf, one as f64, one, &mut w);
        }
        Self {
            kind,
            n,
            size,
            off,
            f,
            w,
            wf,
        }
    }

    /// Sum of the quantised weights one sample gives to all pixels, for each sample phase
    /// (all equal to `2^f / n^2` for an equal-energy filter).
    pub fn group_sums(&self) -> Vec<u64> {
        let n = self.n as usize;
        let mut out = vec![0u64; n * n];
        for (e, &w) in self.w.iter().enumerate() {
            out[(e / self.size % n) * n + e % self.size % n] += w as u64;
        }
        out
    }
}

/// Rounds `wf[m] * scale` for the members to integers that sum to exactly `target`:
/// floors, then +1 to the largest fractional parts (ties to the lower index).
fn largest_remainder(members: &[usize], wf: &[f64], scale: f64, target: u64, w: &mut [u32]) {
    let mut fl: Vec<(usize, u64, f64)> = members
        .iter()
        .map(|&m| {
            let v = wf[m] * scale;
            let f = v.floor();
            (m, f as u64, v - f)
        })
        .collect();
    let sum: u64 = fl.iter().map(|x| x.1).sum();
    let mut left = target.saturating_sub(sum);
    fl.sort_by(|a, b| {
        b.2.partial_cmp(&a.2)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(a.0.cmp(&b.0))
    });
    for x in fl.iter_mut() {
        if left == 0 {
            break;
        }
        x.1 += 1;
        left -= 1;
    }
    for (m, v, _) in fl {
        w[m] = v as u32;
    }
}

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

/// A light point's visible samples and intensity, for the additive pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PointFrags<T> {
    /// Intensity (code or float).
    pub i: T,
    /// Visible sample indices in the sample region.
    pub samples: Vec<u32>,
}

/// The sample region needed for a pixel region with this kernel.
pub fn sample_region(r: &Region, k: &Kernel) -> SampleRegion {
    let n = k.n as i64;
    SampleRegion {
        c0: r.x0 as i64 * n - k.off,
        k0: r.y0 as i64 * n - k.off,
        c1: r.x1 as i64 * n + k.off,
        k1: r.y1 as i64 * n + k.off,
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
    tiles: Option<&crate::cycles::Tiles>,
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

/// For a light point: each pixel of the region it touches with the summed filter weight
/// `S` of its visible samples (`weight(e)` gives the kernel entry `e`).
pub fn point_weights(
    pt: &PointFrags<impl Copy>,
    reg: &SampleRegion,
    region: &Region,
    k: &Kernel,
    weight: impl Fn(usize) -> f64,
) -> Vec<(u32, u32, f64)> {
    let mut out = Vec::new();
    if pt.samples.is_empty() {
        return out;
    }
    let sw = reg.width() as i64;
    let n = k.n as i64;
    let coords: Vec<(i64, i64)> = pt
        .samples
        .iter()
        .map(|&s| (reg.c0 + s as i64 % sw, reg.k0 + s as i64 / sw))
        .collect();
    let (cmin, cmax) = coords
        .iter()
        .fold((i64::MAX, i64::MIN), |a, c| (a.0.min(c.0), a.1.max(c.0)));
    let (kmin, kmax) = coords
        .iter()
        .fold((i64::MAX, i64::MIN), |a, c| (a.0.min(c.1), a.1.max(c.1)));
    // Pixels whose window [p n - off, p n - off + size) meets the samples.
    let px0 = (cmin + k.off - k.size as i64 + 1)
        .div_euclid(n)
        .max(region.x0 as i64);
    let px1 = ((cmax + k.off).div_euclid(n) + 1).min(region.x1 as i64);
    let py0 = ((kmin + k.off - k.size as i64 + 1).div_euclid(n)).max(region.y0 as i64);
    let py1 = ((kmax + k.off).div_euclid(n) + 1).min(region.y1 as i64);
    for py in py0..py1 {
        for px in px0..px1 {
            let (wc, wk) = (px * n - k.off, py * n - k.off);
            let mut sum = 0.0;
            for &(c, kk) in &coords {
                let (i, j) = (c - wc, kk - wk);
                if (0..k.size as i64).contains(&i) && (0..k.size as i64).contains(&j) {
                    sum += weight(j as usize * k.size + i as usize);
                }
            }
            if sum != 0.0 {
                out.push((px as u32, py as u32, sum));
            }
        }
    }
    out
}

/// Parameters of the float reference.
#[derive(Clone, Copy, Debug)]
pub struct AccRef<'a> {
    /// Kernel (its exact weights are used).
    pub kernel: &'a Kernel,
    /// Fraction bits of the intensity codes the input is expressed in.
    pub i_frac: u32,
    /// Fraction bits of the frame format the output is expressed in.
    pub frame_frac: u32,
    /// Background intensity (intensity LSBs).
    pub bg_i: f64,
    /// Image size.
    pub size: (u32, u32),
}

/// Float reference: exact weights, no rounding, no saturation. `i` holds each sample's
/// intensity in intensity-format LSBs; the result is in frame-format LSBs.
pub fn accumulate_f64(
    i: &[f64],
    reg: &SampleRegion,
    region: &Region,
    points: &[PointFrags<f64>],
    p: &AccRef<'_>,
) -> Vec<f64> {
    let (width, height) = p.size;
    let k = p.kernel;
    let scale = 2f64.powi(p.frame_frac as i32 - p.i_frac as i32);
    let mut acc = vec![p.bg_i * scale; width as usize * height as usize];
    let sw = reg.width();
    let rows: Vec<Vec<f64>> = (region.y0..region.y1)
        .into_par_iter()
        .map(|py| {
            (region.x0..region.x1)
                .map(|px| {
                    let c0 = (px as i64 * k.n as i64 - k.off - reg.c0) as usize;
                    let r0 = (py as i64 * k.n as i64 - k.off - reg.k0) as usize;
                    let mut sum = 0.0;
                    for j in 0..k.size {
                        let row = &i[(r0 + j) * sw + c0..(r0 + j) * sw + c0 + k.size];
                        let wrow = &k.wf[j * k.size..(j + 1) * k.size];
                        sum += row.iter().zip(wrow).map(|(a, b)| a * b).sum::<f64>();
                    }
                    sum * scale
                })
                .collect()
        })
        .collect();
    for (py, r) in (region.y0..region.y1).zip(rows) {
        let base = py as usize * width as usize + region.x0 as usize;
        acc[base..base + r.len()].copy_from_slice(&r);
    }
    for pt in points {
        for (px, py, s) in point_weights(pt, reg, region, k, |e| k.wf[e]) {
            acc[py as usize * width as usize + px as usize] += pt.i * s * scale;
        }
    }
    acc
}

/// Cost of the stage.
pub fn cost(p: &AccParams, i_bits: u32, pixels: u64) -> Cost {
    let fb = p.frame.format.total_bits();
    let prod = p.kernel.f + 1 + i_bits;
    let sum_bits = prod
        + (p.kernel.size * p.kernel.size)
            .next_power_of_two()
            .trailing_zeros();
    Cost {
        storage_bits: pixels * fb as u64,
        lut_bits: (p.kernel.w.len() as u64) * (p.kernel.f as u64 + 1),
        adders: vec![
            Unit::adder("window sum (w*I)", 1, sum_bits),
            Unit::adder("frame read-modify-write", 1, fb),
        ],
        multipliers: vec![Unit::mul("weight x intensity", 1, p.kernel.f + 1, i_bits)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_sum_exactly_and_equal_energy_groups_are_equal() {
        for kind in [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian] {
            for n in [2u32, 4, 8] {
                for f in [2 * n.trailing_zeros(), 8, 10, 16] {
                    let k = Kernel::new(kind, n, f, 0.5);
                    assert_eq!(
                        k.w.iter().map(|&w| w as u64).sum::<u64>(),
                        1u64 << f,
                        "{kind:?} n={n} f={f}"
                    );
                    let g = k.group_sums();
                    if kind.equal_energy() {
                        assert!(
                            g.iter().all(|&s| s == (1u64 << f) / (n * n) as u64),
                            "{kind:?} n={n} f={f}: {g:?}"
                        );
                    }
                }
            }
        }
        // The Gaussian is not equal energy: its groups differ.
        let g = Kernel::new(FilterKind::Gaussian, 4, 12, 0.5).group_sums();
        assert!(g.iter().min() != g.iter().max());
    }

    #[test]
    fn tent_4x4_weights_are_the_bed_of_nails() {
        // 1-D tent weights at the 8 sample positions: 1,3,5,7,7,5,3,1 (/32).
        let k = Kernel::new(FilterKind::Tent, 4, 10, 0.5);
        let row: Vec<u32> = (0..8).map(|i| k.w[3 * 8 + i]).collect();
        assert_eq!(row, [7, 21, 35, 49, 49, 35, 21, 7]);
    }
}
