//! The fixed-point luminance-aware datapath: the mean pre-blur ([`pre_blur_fixed`]), the
//! bleed of brighter neighbours ([`bleed_fixed`]) and the blend with the sharp frame
//! ([`blend_fixed`]); integer kernels over whole planes, work and signals in [`LumWork`].

use crate::config::DofCfg;
use crate::error::{Error, Result};
use crate::fixed::{Overflow, QFormat, Quant, Quantizer, SignalStats, round_shift};
use crate::stage::dof::fixed::border_sums;
use serde::Serialize;

/// The widths and modes of the datapath.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LumParams {
    /// Pre-blur half-width r.
    pub radius: u32,
    /// Width of the pre-blur window sum.
    pub pre_bits: u32,
    /// Fraction bits below the frame LSB of the pre-blurred image and the bleed result.
    pub guard_bits: u32,
    /// Fraction bits of alpha (`UQ1.<alpha_bits>`).
    pub alpha_bits: u32,
    /// Rounding of the divides and of the result to the frame format.
    pub quant: Quant,
    /// Overflow of the pre-blur sum: SAT or ERROR.
    pub overflow: Overflow,
    /// The frame format (input and output codes).
    pub frame: QFormat,
}

impl LumParams {
    /// From the `[dof]` section (`[dof.luminance]` and the shared `quant`, `overflow`).
    pub fn of(p: &DofCfg, frame: QFormat) -> Self {
        let l = &p.luminance;
        Self {
            radius: l.radius,
            pre_bits: l.pre_bits,
            guard_bits: l.guard_bits,
            alpha_bits: l.alpha_bits,
            quant: p.quant,
            overflow: p.overflow,
            frame,
        }
    }

    /// Format of the pre-blurred image and the bleed result: the frame format with
    /// `guard_bits` more fraction bits.
    pub fn mean_format(&self) -> QFormat {
        QFormat::new(
            false,
            self.frame.int_bits,
            self.frame.frac_bits + self.guard_bits,
        )
    }

    /// Format of the pre-blur window sum: `UQ<pre_bits>.0` frame codes (a label of the
    /// report: it may be wider than a quantiser's 32 bits).
    pub fn sum_format(&self) -> QFormat {
        QFormat::new(false, self.pre_bits, 0)
    }
}

/// Work, overflow counts and signals of the fixed model.
#[derive(Clone, Debug, Serialize)]
pub struct LumWork {
    /// Output pixels.
    pub pixels: u64,
    /// Additions of the pre-blur window (column and row adder trees, `4r` per pixel).
    pub pre_adds: u64,
    /// Multiplies: 8 bleed weights x neighbour values and the blend's one per pixel.
    pub macs: u64,
    /// Divides: the pre-blur mean (when r > 0) and the bleed, per pixel.
    pub divides: u64,
    /// Alpha ROM reads (one per pixel).
    pub rom_reads: u64,
    /// Pixels with a brighter neighbour (the bleed's result is used).
    pub bleeding: u64,
    /// The pre-blur window sum (signal `dof.lum.pre`, `UQ<pre_bits>.0`): range and
    /// saturations.
    pub pre: SignalStats,
    /// The pre-blurred image (signal `dof.lum.mean`): range and the divide's rounding error.
    pub mean: SignalStats,
    /// The bleed result (signal `dof.lum.blur`): range and the divide's rounding error.
    pub blur: SignalStats,
    /// The output in the frame format (signal `dof.lum.out`): range, rounding error,
    /// saturations.
    pub out: SignalStats,
}

impl LumWork {
    /// Empty counts and signals for `p`.
    pub fn new(p: &LumParams) -> Self {
        Self {
            pixels: 0,
            pre_adds: 0,
            macs: 0,
            divides: 0,
            rom_reads: 0,
            bleeding: 0,
            pre: SignalStats::new("dof.lum.pre", p.sum_format()),
            mean: SignalStats::new("dof.lum.mean", p.mean_format()),
            blur: SignalStats::new("dof.lum.blur", p.mean_format()),
            out: SignalStats::new("dof.lum.out", p.frame),
        }
    }
}

/// `n / d` (`d > 0`) rounded with mode `q`, through the shared [`round_shift`]: the quotient
/// with two more bits that say whether the remainder is zero, below, at or above half of
/// `d`, which is all any mode needs.
#[inline]
pub fn div_round(n: u128, d: u128, q: Quant) -> u128 {
    let (quo, rem) = (n / d, n % d);
    let frac = match (2 * rem).cmp(&d) {
        _ if rem == 0 => 0,
        std::cmp::Ordering::Less => 1,
        std::cmp::Ordering::Equal => 2,
        std::cmp::Ordering::Greater => 3,
    };
    round_shift((quo << 2 | frac) as i128, 2, q) as u128
}

/// Running sums of `2r + 1` consecutive entries of `src` (restricted to the line), into
/// `dst`: `dst[x] = sum src[x - r ..= x + r]`.
fn window_sums(src: &[u64], r: usize, dst: &mut [u64]) {
    let n = src.len();
    let mut s: u64 = src[..(r + 1).min(n)].iter().sum();
    for x in 0..n {
        dst[x] = s;
        if x + r + 1 < n {
            s += src[x + r + 1];
        }
        if x >= r {
            s -= src[x - r];
        }
    }
}

/// The mean pre-blur: per pixel the sum of the frame codes in the `(2r+1)^2` window inside
/// the image, saturated to `pre_bits` (counted; `Err` with overflow mode ERROR), divided by
/// the window's in-image pixel count (border renormalisation) with `guard_bits` more
/// fraction bits, rounded with `quant`, stored in [`LumParams::mean_format`] with SAT (signal
/// `dof.lum.mean`; the mean cannot exceed the largest code, so SAT does not act). With r = 0
/// it is the frame itself, shifted.
pub fn pre_blur_fixed(
    value: &[u32],
    w: usize,
    h: usize,
    p: &LumParams,
    work: &mut LumWork,
) -> Result<Vec<u64>> {
    let (r, g) = (p.radius as usize, p.guard_bits);
    if r == 0 {
        return Ok(value.iter().map(|&v| u64::from(v) << g).collect());
    }
    let ones = vec![1u64; 2 * r + 1];
    let (nx, ny) = (border_sums(&ones, w), border_sums(&ones, h));
    let max = (1u128 << p.pre_bits) - 1;
    let mq = Quantizer::new(p.mean_format(), p.quant, Overflow::Sat);
    // Column sums of 2r + 1 rows, kept running down the image.
    let mut col: Vec<u64> = vec![0; w];
    for row in value.chunks_exact(w).take(r + 1) {
        for (c, &v) in col.iter_mut().zip(row) {
            *c += u64::from(v);
        }
    }
    let mut sums = vec![0u64; w];
    let mut out = vec![0u64; w * h];
    for y in 0..h {
        window_sums(&col, r, &mut sums);
        for (x, &s) in sums.iter().enumerate() {
            let s = u128::from(s);
            let over = s > max;
            work.pre.record_code(s as i128);
            if over {
                work.pre.add_overflows(1);
                if p.overflow == Overflow::Error {
                    return Err(Error::Overflow {
                        signal: work.pre.name.clone(),
                        format: format!("UQ{}.0", p.pre_bits),
                        value: s as i128,
                        min: 0,
                        max: max as i64,
                    });
                }
            }
            let n = u128::from(nx[x] * ny[y]);
            let m = mq.handle_overflow(div_round(s.min(max) << g, n, p.quant) as i128);
            work.mean.record(
                (s.min(max) << g) as f64 / n as f64,
                i128::from(m.code),
                m.overflow,
            );
            out[y * w + x] = m.code as u64;
        }
        if y + r + 1 < h {
            let add = &value[(y + r + 1) * w..(y + r + 2) * w];
            col.iter_mut()
                .zip(add)
                .for_each(|(c, &v)| *c += u64::from(v));
        }
        if y >= r {
            let sub = &value[(y - r) * w..(y - r + 1) * w];
            col.iter_mut()
                .zip(sub)
                .for_each(|(c, &v)| *c -= u64::from(v));
        }
    }
    let px = (w * h) as u64;
    work.pre_adds += 4 * r as u64 * px;
    work.divides += px;
    Ok(out)
}

/// The 8 neighbours' offsets `(dx, dy)`.
pub const NEIGHBOURS: [(i64, i64); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// The bleed (docs/reference.md §4, eq. 8) on the pre-blurred image `pre`: per pixel the
/// neighbours i inside the image with `Δ_i = P_c - P_i < 0` (brighter) weighted by `|Δ_i|`,
/// `blur = sum |Δ_i| P_i / sum |Δ_i|` rounded with `quant` (one divide), `P_c` when no
/// neighbour is brighter. Exact integer sums (weights `W + g` bits, their sum 3 bits more,
/// the numerator `2 (W + g) + 3` bits), stored in the mean format with SAT (signal
/// `dof.lum.blur`; a weighted mean of values of that format fits it, so SAT does not act).
pub fn bleed_fixed(pre: &[u64], w: usize, h: usize, p: &LumParams, work: &mut LumWork) -> Vec<u64> {
    bleed_fixed_by(pre, pre, w, h, p, work)
}

/// [`bleed_fixed`] with the weights `|Δ_i|` taken from the pre-blurred luminance `lum` and
/// the values from the pre-blurred channel `pre` (a colour frame: one luminance, three
/// channels). `blur = sum |Δ_i| P_i / sum |Δ_i|`, `P_c` when no neighbour is brighter.
pub fn bleed_fixed_by(
    lum: &[u64],
    pre: &[u64],
    w: usize,
    h: usize,
    p: &LumParams,
    work: &mut LumWork,
) -> Vec<u64> {
    let bq = Quantizer::new(p.mean_format(), p.quant, Overflow::Sat);
    let mut out = vec![0u64; w * h];
    for y in 0..h {
        for x in 0..w {
            let c = lum[y * w + x];
            let (mut num, mut den) = (0u128, 0u128);
            for (dx, dy) in NEIGHBOURS {
                let (xx, yy) = (x as i64 + dx, y as i64 + dy);
                if xx < 0 || yy < 0 || xx >= w as i64 || yy >= h as i64 {
                    continue;
                }
                let i = yy as usize * w + xx as usize;
                let wt = u128::from(lum[i].saturating_sub(c));
                num += wt * u128::from(pre[i]);
                den += wt;
            }
            let b = if den == 0 {
                let c = pre[y * w + x];
                work.blur.record_code(i128::from(c));
                c
            } else {
                work.bleeding += 1;
                let b = bq.handle_overflow(div_round(num, den, p.quant) as i128);
                work.blur
                    .record(num as f64 / den as f64, i128::from(b.code), b.overflow);
                b.code as u64
            };
            out[y * w + x] = b;
        }
    }
    let px = (w * h) as u64;
    work.macs += 8 * px;
    work.divides += px;
    out
}

/// The blend (eq. 9) `out = x + alpha (blur - x)` with `alpha` = `alpha[i] / 2^alpha_bits`
/// (`UQ1.<alpha_bits>` codes, at most 1): the exact `x 2^g (2^b - a) + a blur` (one multiply
/// of alpha by the difference in hardware), quantised to the frame format with `quant` and
/// SAT (counted as overflows of `dof.lum.out`; a convex combination of frame codes does not
/// exceed the largest code, so SAT does not act).
pub fn blend_fixed(
    value: &[u32],
    blur: &[u64],
    alpha: &[u32],
    p: &LumParams,
    work: &mut LumWork,
) -> Vec<u32> {
    let (g, b) = (p.guard_bits, p.alpha_bits);
    let q = Quantizer::new(p.frame, p.quant, Overflow::Sat);
    let one = 1u128 << b;
    let scale = (1u128 << (g + b)) as f64;
    let out = value
        .iter()
        .zip(blur)
        .zip(alpha)
        .map(|((&x, &bl), &a)| {
            let a = u128::from(a).min(one);
            let raw = (u128::from(x) << g) * (one - a) + a * u128::from(bl);
            let rounded = round_shift(raw as i128, g + b, p.quant);
            let r = q.handle_overflow(rounded);
            work.out.record(raw as f64 / scale, rounded, r.overflow);
            r.code as u32
        })
        .collect();
    let px = value.len() as u64;
    work.pixels += px;
    work.macs += px;
    work.rom_reads += px;
    out
}

/// The whole fixed model on a `w x h` frame: codes `value` in `p.frame`, alpha codes per
/// pixel (the alpha ROM read at each pixel's depth code). `Err` is the pre-blur sum's
/// overflow with overflow mode ERROR.
pub fn luminance_fixed(
    value: &[u32],
    alpha: &[u32],
    w: usize,
    h: usize,
    p: &LumParams,
) -> Result<(Vec<u32>, LumWork)> {
    let mut work = LumWork::new(p);
    let pre = pre_blur_fixed(value, w, h, p, &mut work)?;
    let blur = bleed_fixed(&pre, w, h, p, &mut work);
    let out = blend_fixed(value, &blur, alpha, p, &mut work);
    Ok((out, work))
}

/// The fixed model of one channel of a colour frame: the channel's codes `value` in
/// `p.frame`, its bleed weighted by the luminance `lum` (codes of the word `lum_frame`, which
/// holds the guard bits already: pre-blurred with the same window, a sum `guard_bits` wider
/// and no more guard bits). Returns the channel's output, its work and the
/// luminance pre-blur's work (signals `dof.lum.luma.pre` and `dof.lum.luma`).
pub fn luminance_colour_fixed(
    value: &[u32],
    lum: &[u32],
    lum_frame: QFormat,
    alpha: &[u32],
    w: usize,
    h: usize,
    p: &LumParams,
) -> Result<(Vec<u32>, LumWork, LumWork)> {
    let mut work = LumWork::new(p);
    let lp = LumParams {
        frame: lum_frame,
        pre_bits: p.pre_bits + p.guard_bits,
        guard_bits: 0,
        ..*p
    };
    let mut lwork = LumWork::new(&lp);
    lwork.pre.name = "dof.lum.luma.pre".into();
    lwork.mean.name = "dof.lum.luma".into();
    let pre_y = pre_blur_fixed(lum, w, h, &lp, &mut lwork)?;
    let pre = pre_blur_fixed(value, w, h, p, &mut work)?;
    let blur = bleed_fixed_by(&pre_y, &pre, w, h, p, &mut work);
    let out = blend_fixed(value, &blur, alpha, p, &mut work);
    Ok((out, work, lwork))
}
