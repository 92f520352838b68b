//! Ordered dithering with a threshold [`Mask`]: the exact fixed-point rule of one value, its
//! float reference, and the whole-image passes (see the [`dither`](super) module docs for
//! the arithmetic).

use super::mask::Mask;
use crate::stage::gamma::{lookup_block, lookup_block_portable};
use crate::stage::parts::run_parts;
use rayon::prelude::*;

/// Ordered dither of one value (fixed): `floor(x / 2^s + (m + 0.5) / 2^b)`, unsaturated.
#[inline]
pub fn ordered_code(x: u32, s: u32, rank: u32, bits: u32) -> u64 {
    (((x as u64) << (bits + 1)) + (((2 * rank + 1) as u64) << s)) >> (s + bits + 1)
}

/// Ordered dither of one value (float): `floor(v + (m + 0.5) / 2^b)`, unsaturated.
#[inline]
pub fn ordered_f64(v: f64, rank: u32, bits: u32) -> f64 {
    (v + (rank as f64 + 0.5) / (1u64 << bits) as f64).floor()
}

/// The integer threshold of rank `m` for inputs with `s < 32` fraction bits: with
/// `x = q * 2^s + r` (`r < 2^s`), [`ordered_code`] is `q + (r >= t)` where
/// `t = 2^s - floor((2m + 1) * 2^s / 2^(b+1))`, in `1..=2^s` (the sum's fraction part
/// `r / 2^s + (2m + 1) / 2^(b+1)` reaches 1 exactly when `r` reaches `t`).
#[inline]
pub fn rank_threshold(s: u32, rank: u32, bits: u32) -> u32 {
    let one = 1u64 << s;
    (one - (((2 * rank as u64 + 1) << s) >> (bits + 1))) as u32
}

/// The per-column thresholds of one mask row, repeated to a multiple of the mask side at
/// least [`ROW_SPAN`] long (so the row kernel runs over long slices), for every mask row:
/// `rows[ry * span + j]` is the threshold at column `j` (mod span) of an image row that
/// reads mask row `ry`, with the mask offset `off` applied.
struct ThresholdRows {
    span: usize,
    rows: Vec<u32>,
}

/// Minimum length of a precomputed threshold row.
const ROW_SPAN: usize = 256;

impl ThresholdRows {
    fn new(mask: &Mask, s: u32, off: (u32, u32)) -> Self {
        let n = mask.n.max(1) as usize;
        let span = ROW_SPAN.max(n).div_ceil(n) * n;
        let t: Vec<u32> = mask
            .rank
            .iter()
            .map(|&r| rank_threshold(s, r, mask.bits))
            .collect();
        let m = n - 1;
        let rows = (0..n)
            .flat_map(|ry| {
                let t = &t;
                (0..span).map(move |j| t[ry * n + ((j + off.0 as usize) & m)])
            })
            .collect();
        Self { span, rows }
    }

    /// The thresholds of image row `y` (mask row `(y + off_y) mod n`).
    fn row(&self, y: usize, off_y: u32, n: u32) -> &[u32] {
        let ry = (y + off_y as usize) & (n as usize - 1);
        &self.rows[ry * self.span..(ry + 1) * self.span]
    }
}

/// One row of the ordered dither over slices: `out[i] = min(q + (r >= thr[i]), omax)` with
/// `x[i] = q * 2^s + r` (`s < 32`); returns the number of saturations. `thr` is indexed
/// modulo its length (a multiple of the mask side). `avx2`: run the AVX2 build of the same
/// loop (only when the CPU has it).
#[inline]
fn ordered_row(x: &[u32], thr: &[u32], s: u32, omax: u32, out: &mut [u32], avx2: bool) -> u64 {
    if avx2 {
        simd::row_avx2(x, thr, s, omax, out)
    } else {
        row_loop(x, thr, s, omax, out)
    }
}

/// The loop both builds of [`ordered_row`] compile (the saturations are counted per chunk of
/// the row, in a vector reduction).
#[inline(always)]
fn row_loop(x: &[u32], thr: &[u32], s: u32, omax: u32, out: &mut [u32]) -> u64 {
    let low = ((1u64 << s) - 1) as u32;
    let mut sat = 0u64;
    for (o, xs) in out.chunks_mut(thr.len()).zip(x.chunks(thr.len())) {
        let len = o.len().min(xs.len());
        let (o, xs, thr) = (&mut o[..len], &xs[..len], &thr[..len]);
        let mut n = 0u32;
        for i in 0..len {
            let v = xs[i];
            let c = (v >> s) + u32::from(v & low >= thr[i]);
            n += u32::from(c > omax);
            o[i] = c.min(omax);
        }
        sat += u64::from(n);
    }
    sat
}

/// The run-time AVX2 build of [`row_loop`] (the binary still runs on any x86-64): the
/// unsigned compare and minimum are single instructions there, which makes the dither pass
/// 2.4-3 times as fast as the portable SSE2 build on the development machine (docs/dither.md).
#[cfg(target_arch = "x86_64")]
mod simd {
    /// Whether the CPU has AVX2 (the standard library caches the answer).
    #[inline]
    pub fn avx2() -> bool {
        std::arch::is_x86_feature_detected!("avx2")
    }

    /// [`super::row_loop`] compiled with AVX2; call only when [`avx2`] holds.
    pub fn row_avx2(x: &[u32], thr: &[u32], s: u32, omax: u32, out: &mut [u32]) -> u64 {
        #[target_feature(enable = "avx2")]
        fn run(x: &[u32], thr: &[u32], s: u32, omax: u32, out: &mut [u32]) -> u64 {
            super::row_loop(x, thr, s, omax, out)
        }
        debug_assert!(avx2());
        // SAFETY: `run` is safe code compiled with AVX2 enabled; callers pass `avx2 = true`
        // to `ordered_row` only after `avx2()` found the feature on this CPU.
        unsafe { run(x, thr, s, omax, out) }
    }
}

/// Other targets: the portable build only.
#[cfg(not(target_arch = "x86_64"))]
mod simd {
    pub fn avx2() -> bool {
        false
    }

    pub fn row_avx2(x: &[u32], thr: &[u32], s: u32, omax: u32, out: &mut [u32]) -> u64 {
        super::row_loop(x, thr, s, omax, out)
    }
}

/// How the ordered dither runs: bands in parallel, or serially on the caller (with or
/// without the AVX2 build); the codes and the count are the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Run {
    /// Bands of rows on the rayon threads (the stage's way).
    Parallel,
    /// The calling thread only.
    Serial,
    /// The calling thread, the portable build only (baseline x86-64 on that target), for
    /// comparing the two builds.
    Portable,
}

/// Applies an ordered mask to a `width`-wide image of `s`-fraction-bit codes; returns the
/// codes saturated to `omax` and the number of saturations. Row-wise over slices with the
/// mask rows' thresholds precomputed ([`rank_threshold`]), bands of rows in parallel; the
/// same codes and count as [`ordered_code`] per pixel.
pub fn apply_ordered(
    x: &[u32],
    width: u32,
    s: u32,
    omax: u32,
    mask: &Mask,
    frame: u32,
    out: &mut [u32],
) -> u64 {
    apply_ordered_with(x, width, s, omax, mask, frame, out, Run::Parallel)
}

/// [`apply_ordered`] run as `run` says (the same codes and count).
#[allow(clippy::too_many_arguments)]
pub fn apply_ordered_with(
    x: &[u32],
    width: u32,
    s: u32,
    omax: u32,
    mask: &Mask,
    frame: u32,
    out: &mut [u32],
    run: Run,
) -> u64 {
    apply_ordered_from(Input::Codes(x), width, s, omax, mask, frame, out, run)
}

/// What an ordered dither reads: its input codes, or frame codes through a LUT (the gamma
/// LUT fused into the dither's pass: each row's codes are looked up into a row buffer that
/// stays in cache and dithered from there, so no LUT plane goes to memory).
#[derive(Clone, Copy, Debug)]
pub enum Input<'a> {
    /// The `s`-fraction-bit codes.
    Codes(&'a [u32]),
    /// The codes `table[min(acc[i] >> shift, len - 1)]` ([`crate::stage::gamma::lookup`]).
    Lut {
        /// Frame codes (the LUT's addresses before the shift).
        acc: &'a [u32],
        /// The LUT.
        table: &'a [u32],
        /// Fraction bits the address drops.
        shift: u32,
    },
}

impl<'a> Input<'a> {
    /// Pixels read.
    pub fn len(&self) -> usize {
        match self {
            Input::Codes(x) => x.len(),
            Input::Lut { acc, .. } => acc.len(),
        }
    }

    /// Whether there is no pixel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Pixels `from..to`.
    fn part(self, from: usize, to: usize) -> Input<'a> {
        match self {
            Input::Codes(x) => Input::Codes(&x[from..to]),
            Input::Lut { acc, table, shift } => Input::Lut {
                acc: &acc[from..to],
                table,
                shift,
            },
        }
    }

    /// The codes as a plane (a LUT input is looked up, the portable build when `portable`).
    pub fn to_codes(self, portable: bool) -> std::borrow::Cow<'a, [u32]> {
        match self {
            Input::Codes(x) => x.into(),
            Input::Lut { acc, table, shift } => {
                let mut v = vec![0u32; acc.len()];
                lut_row(table, acc, shift, &mut v, portable);
                v.into()
            }
        }
    }
}

/// One row of a LUT input into `out` (serial).
#[inline]
fn lut_row(table: &[u32], acc: &[u32], shift: u32, out: &mut [u32], portable: bool) {
    if portable {
        lookup_block_portable(table, acc, shift, out)
    } else {
        lookup_block(table, acc, shift, out)
    }
}

/// [`apply_ordered_with`] on an [`Input`]: the same codes and count as looking the LUT up
/// over the frame first and dithering that.
#[allow(clippy::too_many_arguments)]
pub fn apply_ordered_from(
    x: Input,
    width: u32,
    s: u32,
    omax: u32,
    mask: &Mask,
    frame: u32,
    out: &mut [u32],
    run: Run,
) -> u64 {
    let off = mask.offset(frame);
    let w = width.max(1) as usize;
    if s >= 32 || !mask.n.is_power_of_two() {
        let x = x.to_codes(run == Run::Portable);
        return apply_ordered_per_value(&x, w, s, omax, mask, off, out);
    }
    let thr = ThresholdRows::new(mask, s, off);
    let avx2 = run != Run::Portable && simd::avx2();
    let rows = |y0: usize, o: &mut [u32], xb: Input| -> u64 {
        match xb {
            Input::Codes(xb) => o
                .chunks_mut(w)
                .zip(xb.chunks(w))
                .enumerate()
                .map(|(k, (o, xr))| {
                    let t = thr.row(y0 + k, off.1, mask.n);
                    ordered_row(xr, t, s, omax, o, avx2)
                })
                .sum(),
            Input::Lut { acc, table, shift } => {
                // The row's LUT codes, in cache between the lookup and the dither.
                let mut buf = vec![0u32; w];
                o.chunks_mut(w)
                    .zip(acc.chunks(w))
                    .enumerate()
                    .map(|(k, (o, ar))| {
                        let b = &mut buf[..ar.len()];
                        lut_row(table, ar, shift, b, run == Run::Portable);
                        let t = thr.row(y0 + k, off.1, mask.n);
                        ordered_row(b, t, s, omax, o, avx2)
                    })
                    .sum()
            }
        }
    };
    // Bands of whole rows (at least BAND_PIXELS), BANDS_PER_THREAD per thread, the first
    // on the calling thread: a thread that starts late (asleep, or its core busy with
    // another process) still takes the bands left, rather than the caller doing half the
    // frame after its own half. The count is a sum of integers, the same in any order.
    let n = out.len().min(x.len());
    let height = n.div_ceil(w);
    let threads = rayon::current_num_threads().max(1);
    let band = height
        .div_ceil(threads * BANDS_PER_THREAD)
        .max(BAND_PIXELS.div_ceil(w))
        .max(1);
    if run != Run::Parallel || band >= height {
        return rows(0, &mut out[..n], x.part(0, n));
    }
    let parts = out[..n].chunks_mut(w * band).enumerate().map(|(b, o)| {
        let from = b * w * band;
        let xb = x.part(from, from + o.len());
        (b, (o, xb))
    });
    run_parts(parts.collect(), |(b, (o, xb))| rows(b * band, o, xb))
        .into_iter()
        .sum()
}

/// Smallest band of [`apply_ordered`] handed to a thread, in pixels (rounded up to rows).
const BAND_PIXELS: usize = 1 << 14;

/// Bands of [`apply_ordered`] per thread (when the frame has that many of `BAND_PIXELS`).
const BANDS_PER_THREAD: usize = 4;

/// The per-value form (inputs with 32 or more fraction bits).
fn apply_ordered_per_value(
    x: &[u32],
    w: usize,
    s: u32,
    omax: u32,
    mask: &Mask,
    off: (u32, u32),
    out: &mut [u32],
) -> u64 {
    let mut sat = 0;
    for (i, (o, &v)) in out.iter_mut().zip(x).enumerate() {
        let c = ordered_code(
            v,
            s,
            mask.at((i % w) as u32, (i / w) as u32, off),
            mask.bits,
        );
        sat += u64::from(c > omax as u64);
        *o = c.min(omax as u64) as u32;
    }
    sat
}

/// Float reference of [`apply_ordered`] on real values (output LSBs): [`ordered_f64`] per
/// pixel, with each rank's threshold `(m + 0.5) / 2^b` computed once (the same `f64`).
pub fn apply_ordered_f64(v: &[f64], width: u32, omax: u32, mask: &Mask, frame: u32) -> Vec<u32> {
    let off = mask.offset(frame);
    let w = width.max(1) as usize;
    let t: Vec<f64> = mask
        .rank
        .iter()
        .map(|&r| (r as f64 + 0.5) / (1u64 << mask.bits) as f64)
        .collect();
    let (n, m) = (mask.n as usize, mask.n as usize - 1);
    let mut out = vec![0u32; v.len()];
    out.par_chunks_mut(w)
        .zip(v.par_chunks(w))
        .enumerate()
        .for_each(|(y, (o, vr))| {
            let tr = &t[((y + off.1 as usize) & m) * n..][..n];
            for (i, (o, &v)) in o.iter_mut().zip(vr).enumerate() {
                let th = tr[(i + off.0 as usize) & m];
                *o = (v + th).floor().clamp(0.0, omax as f64) as u32;
            }
        });
    out
}
