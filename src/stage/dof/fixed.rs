//! The fixed-point layered datapath: per layer the input planes, the horizontal and vertical
//! tap passes ([`row_mac`], the HDL model's reference), the layer colour and alpha, and the
//! back-to-front composite; work and overflow counts in [`DofWork`].

use super::fast::Plane;
use super::layers::{DepthImage, LayerPlan, layer_boxes};
use super::scratch::Scratch;
use super::strip::{LayerTaps, layer_macs, run_strip, strip_rows};
use super::stripes;
use super::uniform;
use crate::config::{AlphaNorm, DofCfg};
use crate::fixed::{Overflow, QFormat, Quant, Quantizer, RoundShift, round_shift, round_shift_i64};
use crate::stage::Pool;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Mutex;

/// Work and overflow counts of the fixed model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DofWork {
    /// Multiply-accumulates (both passes, every plane: [`planes`]).
    pub macs: u64,
    /// Layer colour divides.
    pub divides: u64,
    /// Composite (over) operations.
    pub composites: u64,
    /// Pixel-layer pairs passed through (sigma = 0 layers).
    pub passthrough: u64,
    /// Line-buffer overflows.
    pub line_overflows: u64,
    /// Accumulator overflows.
    pub acc_overflows: u64,
    /// Output pixels saturated to the frame format (signal `dof.out`).
    pub out_overflows: u64,
    /// Uniform 16x16 tiles skipped (`dof.skip_uniform_tiles`; else 0).
    pub skipped_tiles: u64,
}

impl DofWork {
    /// Adds another part's counts (strips of a layer).
    pub(super) fn add(&mut self, o: &DofWork) {
        self.macs += o.macs;
        self.divides += o.divides;
        self.composites += o.composites;
        self.passthrough += o.passthrough;
        self.line_overflows += o.line_overflows;
        self.acc_overflows += o.acc_overflows;
        self.out_overflows += o.out_overflows;
        self.skipped_tiles += o.skipped_tiles;
    }
}

/// In-image tap sums along one axis of length `n` for taps `c`.
pub(super) fn border_sums<T: Copy + Default + std::ops::AddAssign>(c: &[T], n: usize) -> Vec<T> {
    (0..n).map(|x| border_sum(c, x, n)).collect()
}

/// The in-line tap sum at position `x` of a line of length `n` (the border renormalisation
/// weight `Wx` or `Wy`): the sum of the taps `c[t]` whose sample `x + t - M` lies in
/// `[0, n)`, `M = c.len() / 2`.
pub fn border_sum<T: Copy + Default + std::ops::AddAssign>(c: &[T], x: usize, n: usize) -> T {
    let m = c.len() / 2;
    let mut s = T::default();
    for (t, &v) in c.iter().enumerate() {
        let xi = x as i64 + t as i64 - m as i64;
        if xi >= 0 && (xi as usize) < n {
            s += v;
        }
    }
    s
}

/// One output sample of a 1-D pass (see [`row_mac`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MacOut {
    /// Colour sum `sum c_t x_t`, saturated to the word's maximum.
    pub x: u128,
    /// Alpha sum `sum c_t a_t` (exact).
    pub a: u128,
    /// Behind sum `sum c_t d_t` (exact): the alpha normaliser.
    pub d: u128,
    /// The colour sum did not fit the word (counted; stops the run with overflow ERROR).
    pub overflow: bool,
}

/// One output sample of the horizontal or vertical pass: over the taps `t` whose sample
/// `pos + t - M` lies on the line `[0, len)` (`M = coef.len() / 2`; samples off the line are
/// zero), the colour sum saturated to `max` (the line-buffer or accumulator word) and the
/// exact alpha and behind sums. `sample(i)` gives the (colour, alpha, behind) samples at
/// line position `i`. The HDL model `hdl-models/rtl/dof_row_mac.v` is this function.
#[inline(always)]
pub fn row_mac(
    coef: &[u64],
    pos: usize,
    len: usize,
    max: u128,
    sample: impl Fn(usize) -> (u128, u128, u128),
) -> MacOut {
    let m = coef.len() / 2;
    let t0 = m.saturating_sub(pos);
    let t1 = coef.len().min((len + m).saturating_sub(pos));
    let (mut sx, mut sa, mut sd) = (0u128, 0u128, 0u128);
    for (t, &cv) in coef.iter().enumerate().take(t1).skip(t0) {
        let (x, a, d) = sample(pos + t - m);
        sx += cv as u128 * x;
        sa += cv as u128 * a;
        sd += cv as u128 * d;
    }
    MacOut {
        x: sx.min(max),
        a: sa,
        d: sd,
        overflow: sx > max,
    }
}

/// One layer's planes after the horizontal pass, over the layer's box (for the HDL vectors).
#[derive(Clone, Copy, Debug)]
pub struct LayerPlanes<'a> {
    /// Layer index.
    pub layer: usize,
    /// Box origin in the image.
    pub x0: usize,
    /// Box origin in the image.
    pub y0: usize,
    /// Box width.
    pub bw: usize,
    /// Box height.
    pub bh: usize,
    /// Input colour plane `x * m` (row-major over the box).
    pub xi: &'a [u64],
    /// Input alpha plane `m`.
    pub ai: &'a [u64],
    /// Input behind plane (the coverage of the layer and those behind it).
    pub di: &'a [u64],
    /// Line buffer: horizontal colour sums (saturated).
    pub hx: &'a [u64],
    /// Line buffer: horizontal alpha sums.
    pub ha: &'a [u64],
    /// Line buffer: horizontal behind sums.
    pub hd: &'a [u64],
}

/// The pixel's share in layer `l` and its share in `l` and every layer behind it (the
/// alpha normaliser's plane; with [`AlphaNorm::Image`] the whole pixel), in `1/n2` units.
#[inline]
pub(super) fn share(
    plan: &LayerPlan,
    img_key: u32,
    cov: u16,
    idx: u16,
    l: usize,
    n2: u32,
) -> (u32, u32) {
    Shares::new(plan, l, n2).of(img_key, cov, idx)
}

/// [`share`] of one layer, its pixel-independent tests made once (for a kernel over a row;
/// selects, no branches).
#[derive(Clone, Copy)]
pub(super) struct Shares {
    l: usize,
    n2: u32,
    /// The background layer is `l` or behind it / is `l`.
    bg_behind: bool,
    bg_here: bool,
    image_norm: bool,
}

impl Shares {
    pub(super) fn new(plan: &LayerPlan, l: usize, n2: u32) -> Self {
        Self {
            l,
            n2,
            bg_behind: plan.background.is_some_and(|bg| bg <= l),
            bg_here: plan.background == Some(l),
            image_norm: plan.alpha_norm == AlphaNorm::Image,
        }
    }

    /// The shares of a pixel of depth code `key`, coverage `cov` and layer index `idx`.
    #[inline(always)]
    pub(super) fn of(self, key: u32, cov: u16, idx: u16) -> (u32, u32) {
        let valid = key != u32::MAX;
        let own = if valid { u32::from(cov) } else { 0 };
        let rest = self.n2 - own.min(self.n2);
        let (idx, l) = (usize::from(idx), self.l);
        let m = if valid && idx == l { own } else { 0 } + if self.bg_here { rest } else { 0 };
        let b = if valid && idx <= l { own } else { 0 } + if self.bg_behind { rest } else { 0 };
        (m, if self.image_norm { self.n2 } else { b })
    }
}

/// The planes a blurred layer's passes multiply: colour and alpha, and with
/// [`AlphaNorm::Behind`] the behind share (the alpha's normaliser).
pub(super) fn planes(plan: &LayerPlan) -> u64 {
    match plan.alpha_norm {
        AlphaNorm::Behind => 3,
        AlphaNorm::Image => 2,
    }
}

/// How the emulator computes a layer's passes; the outputs and work counts are the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exec {
    /// Every tap of both passes at every box pixel (the straightforward reference).
    Full,
    /// Uniform mask windows take their value without MACs, the vertical pass runs row by
    /// row ([`super::fast`]), over the whole layer box at once (the planes the HDL bench
    /// observes).
    SkipUniform,
    /// [`Exec::SkipUniform`] in strips of at least this many output rows (each with the `M`
    /// rows above and below it that its vertical taps read), so the planes take a strip,
    /// not the frame: the default ([`STRIP_ROWS`]). A strip is at least `8 M` rows (the
    /// rows read twice stay a quarter at most) and starts at an image row that is a
    /// multiple of its height, itself a multiple of 16, so the 16x16 tiles of
    /// `dof.skip_uniform_tiles` never straddle two. All layers run in one parallel region of
    /// row stripes ([`super::stripes`]), except with overflow ERROR, where a layer is one
    /// strip (the first overflow stops the run, so the passes keep their whole-box order),
    /// or with disc layers. `observe` is only called for a layer run as one strip.
    Strips(usize),
}

/// The stage's strip height ([`Exec::Strips`]).
pub const STRIP_ROWS: usize = 128;

/// The fixed-point layered DoF. Returns the output codes in `frame_fmt` (rounded with
/// `p.quant`, saturated and counted in [`DofWork::out_overflows`]) and the work counts; `Err`
/// names the overflowing line-buffer or accumulator signal when the overflow mode is ERROR.
pub fn layered_fixed(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
) -> Result<(Vec<u32>, DofWork), (String, u32)> {
    let pool = Pool::new();
    layered_fixed_exec(
        img,
        plan,
        p,
        frame_fmt,
        Exec::Strips(STRIP_ROWS),
        |_| {},
        &pool,
    )
    .map(|r| (r.0, r.1))
}

/// [`layered_fixed`], showing `observe` each blurred layer's planes after its horizontal
/// pass (the HDL bench's scene taps).
pub fn layered_fixed_observed(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
    observe: impl FnMut(&LayerPlanes),
) -> Result<(Vec<u32>, DofWork), (String, u32)> {
    let pool = Pool::new();
    layered_fixed_exec(img, plan, p, frame_fmt, Exec::SkipUniform, observe, &pool)
        .map(|r| (r.0, r.1))
}

/// The output codes, the work counts and per layer the pixels of skipped uniform tiles.
pub type FixedRun = (Vec<u32>, DofWork, Vec<u64>);

/// [`layered_fixed_observed`] computed as `exec` says. Also returns per layer the box pixels
/// in skipped uniform tiles (all 0 unless `dof.skip_uniform_tiles`; the same for any `exec`).
/// The planes and the threads' scratch come from `pool`.
pub fn layered_fixed_exec(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
    exec: Exec,
    observe: impl FnMut(&LayerPlanes),
    pool: &Pool,
) -> Result<FixedRun, (String, u32)> {
    // In strips, the planes are u32 words where every value fits: the input colour (a code
    // times n2), the saturated line buffer and the alpha sums (the taps' sum times n2).
    let n2 = u64::from(img.n2);
    let vmax = u64::from(img.value.iter().copied().max().unwrap_or(0));
    let csum = plan
        .layers
        .iter()
        .map(|l| l.coef.iter().sum::<u64>())
        .max()
        .unwrap_or(0);
    let fits = |v: u64| v <= u64::from(u32::MAX);
    let narrow = matches!(exec, Exec::Strips(_))
        && fits(vmax * n2)
        && fits(csum.saturating_mul(n2))
        && p.line_bits <= 32;
    if narrow {
        exec_with::<u32>(img, plan, p, frame_fmt, (exec, pool), observe)
    } else {
        exec_with::<u64>(img, plan, p, frame_fmt, (exec, pool), observe)
    }
}

/// [`layered_fixed_exec`] with planes of `P` words.
fn exec_with<P: Plane>(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
    (exec, buffers): (Exec, &Pool),
    mut observe: impl FnMut(&LayerPlanes),
) -> Result<FixedRun, (String, u32)> {
    let (w, h) = (img.width, img.height);
    let mut work = DofWork::default();
    let mut skipped = vec![0u64; plan.layers.len()];
    // A composite never exceeds the largest code times 2^g (every colour is a weighted mean
    // of codes, docs/dof.md): u64 words.
    let mut out = buffers.filled(w * h, 0u64);
    let mut def = buffers.filled(w * h, false);
    let boxes = layer_boxes(w, h, plan);
    // One scratch per thread, kept across strips and layers.
    let threads = rayon::current_num_threads().max(1);
    let mut pool: Vec<Mutex<Scratch<P>>> = buffers.reuse();
    pool.resize_with(threads, || Mutex::new(Scratch::new()));
    // The default: all layers in one parallel region of row stripes.
    let stripe_rows = match exec {
        Exec::Strips(rows)
            if p.overflow != Overflow::Error && plan.layers.iter().all(|l| l.disc.is_none()) =>
        {
            Some(rows)
        }
        _ => None,
    };
    if let Some(rows) = stripe_rows {
        let (wk, sk) = stripes::run(img, plan, p, rows, &boxes, &pool, &mut out, &mut def)?;
        work.add(&wk);
        skipped = sk;
    } else {
        for (l, layer) in plan.layers.iter().enumerate() {
            let Some((x0, y0, x1, y1)) = boxes[l] else {
                continue;
            };
            let (bw, bh) = (x1 - x0, y1 - y0);
            let boxr = (x0, y0, bw, bh);
            if let Some(mask) = &layer.disc {
                super::disc::layer_fixed(
                    img, plan, l, mask, boxr, p, &mut out, &mut def, &mut work,
                )?;
                continue;
            }
            if layer.m == 0 {
                // sigma = 0: the mask is the identity; pass through.
                let rows = y0 * w..(y0 + bh) * w;
                let (o, d) = (&mut out[rows.clone()], &mut def[rows]);
                let n = stripes::passthrough(img, plan, l, boxr, (0, bh), p, o, d);
                work.passthrough += n;
                work.composites += n;
                continue;
            }
            let strip = match exec {
                Exec::Strips(rows) if p.overflow != Overflow::Error => rows
                    .max(8 * layer.m)
                    .next_multiple_of(uniform::UNIFORM_TILE),
                _ => usize::MAX,
            };
            let taps = LayerTaps::<P>::new(plan, l, (w, h), boxr);
            let cx = taps.cx((img, plan, p), exec, l, boxr);
            let strips = strip_rows(y0, bh, strip);
            // The box's rows of the image, one slice per strip.
            let rows = &mut out[y0 * w..(y0 + bh) * w];
            let drows = &mut def[y0 * w..(y0 + bh) * w];
            if strips.len() == 1 {
                let mut sk = 0;
                run_strip(
                    &cx,
                    &mut pool[0].lock().expect("scratch"),
                    (0, bh),
                    rows,
                    drows,
                    &mut work,
                    &mut sk,
                    Some(&mut observe),
                )?;
                skipped[l] += sk;
            } else {
                let mut parts = Vec::with_capacity(strips.len());
                let (mut rest, mut drest) = (rows, drows);
                for &(r0, r1) in &strips {
                    let (o, r) = rest.split_at_mut((r1 - r0) * w);
                    let (d, dr) = drest.split_at_mut((r1 - r0) * w);
                    parts.push(((r0, r1), o, d));
                    (rest, drest) = (r, dr);
                }
                // Each strip on a thread with that thread's scratch; counts summed in strip
                // order (integers: the same on any thread count).
                let done: Vec<Result<(DofWork, u64), (String, u32)>> = parts
                    .into_par_iter()
                    .map(|(r, o, d)| {
                        let t = rayon::current_thread_index().unwrap_or(0) % pool.len();
                        let mut s = pool[t].lock().expect("scratch");
                        let (mut wk, mut sk) = (DofWork::default(), 0);
                        run_strip(&cx, &mut s, r, o, d, &mut wk, &mut sk, None)?;
                        Ok((wk, sk))
                    })
                    .collect();
                for r in done {
                    let (wk, sk) = r?;
                    work.add(&wk);
                    skipped[l] += sk;
                }
            }
            work.macs += layer_macs(plan, l, (bw * bh) as u64 - skipped[l]);
        }
    }
    let mut res = buffers.scratch(out.len(), 0u32);
    work.out_overflows = to_frame(&out, &mut res, frame_fmt, p.guard_bits, p.quant);
    buffers.give(out);
    buffers.give(def);
    buffers.give(pool);
    Ok((res, work, skipped))
}

/// The composite `out` (with `g` guard bits below the frame LSB) as codes of `frame_fmt`
/// into `res`: rounded with `quant`, saturated; returns the saturations. In chunks on the
/// threads (a count: the same on any thread count). A composite is never negative, and
/// every format's smallest code is at most 0, so the words up to the largest that rounds
/// to the top code (found once: the rounding is monotonic) take a branch-free rounding
/// that vectorises; a chunk holding a larger word then takes the quantiser for those.
fn to_frame(out: &[u64], res: &mut [u32], frame_fmt: QFormat, g: u32, quant: Quant) -> u64 {
    const CHUNK: usize = 1 << 14;
    let frame_q = Quantizer::new(frame_fmt, quant, Overflow::Sat);
    let raw_frac = (g + frame_fmt.frac_bits) as i32;
    // `guard_bits` is at most 24 (config); wider guards take the quantiser throughout.
    let round = RoundShift::new(g.min(62), quant);
    let hi = frame_fmt.max_code().clamp(0, i64::from(u32::MAX));
    let limit = match round.raw_range(0, hi) {
        Some((_, top)) if g < 63 => Some(top as u64),
        _ => None,
    };
    out.par_chunks(CHUNK)
        .zip(res.par_chunks_mut(CHUNK))
        .map(|(o, r)| {
            if let Some(limit) = limit
                && !simd::round_words(o, r, round, limit)
            {
                return 0;
            }
            let mut overflows = 0;
            for (&v, c) in o.iter().zip(r) {
                if limit.is_some_and(|l| v <= l) {
                    continue;
                }
                let q = frame_q.quantize_raw(i128::from(v), raw_frac);
                overflows += u64::from(q.overflow);
                *c = q.code as u32;
            }
            overflows
        })
        .sum()
}

/// Rounds the words of `o` up to `limit` into `r` (the larger ones are left to the
/// caller), branch-free; whether any word was larger.
#[inline(always)]
fn round_words(o: &[u64], r: &mut [u32], round: RoundShift, limit: u64) -> bool {
    let mut beyond = false;
    for (&v, c) in o.iter().zip(r.iter_mut()) {
        *c = round.apply_nonneg(v.min(limit)) as u32;
        beyond |= v > limit;
    }
    beyond
}

#[cfg(target_arch = "x86_64")]
mod simd {
    use crate::fixed::RoundShift;

    /// [`super::round_words`], compiled with AVX2 where the CPU has it.
    pub fn round_words(o: &[u64], r: &mut [u32], round: RoundShift, limit: u64) -> bool {
        #[target_feature(enable = "avx2")]
        fn avx2(o: &[u64], r: &mut [u32], round: RoundShift, limit: u64) -> bool {
            super::round_words(o, r, round, limit)
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: `avx2` is safe code compiled with AVX2, called only where the CPU
            // has it.
            unsafe { avx2(o, r, round, limit) }
        } else {
            super::round_words(o, r, round, limit)
        }
    }
}

/// Other targets: the portable build only.
#[cfg(not(target_arch = "x86_64"))]
mod simd {
    use crate::fixed::RoundShift;

    pub fn round_words(o: &[u64], r: &mut [u32], round: RoundShift, limit: u64) -> bool {
        super::round_words(o, r, round, limit)
    }
}

/// `o = col` over `o` with alpha `aq / one`: `round((col aq + o (one - aq)) / one)`; the
/// first layer at a pixel, or an opaque one (`aq = one`: the quotient is exact), writes
/// `col`.
#[inline]
pub(super) fn composite(
    o: &mut u64,
    d: &mut bool,
    col: u128,
    aq: u128,
    one: u128,
    q: u32,
    quant: Quant,
) {
    debug_assert!(col <= u128::from(u64::MAX));
    if !*d || aq == one {
        *o = col as u64;
        *d = true;
    } else {
        let num = col * aq + u128::from(*o) * (one - aq);
        *o = if num >> 63 == 0 {
            round_shift_i64(num as i64, q, quant) as u64
        } else {
            round_shift(num as i128, q, quant) as u64
        };
    }
}

/// `a / b`, in 64-bit words when both fit (the common case; the same quotient).
#[inline(always)]
pub(super) fn udiv(a: u128, b: u128) -> u128 {
    if (a | b) >> 64 == 0 {
        u128::from(a as u64 / b as u64)
    } else {
        a / b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The portable and the run-time (AVX2 where the CPU has it) builds of the
        /// branch-free rounding give the same codes and the same "beyond" answer.
        #[test]
        fn round_words_builds_agree(
            words in proptest::collection::vec(any::<u64>(), 1..64),
            small in 0u32..40,
            g in 0u32..=24,
            q in 0usize..Quant::ALL.len(),
            limit_shift in 0u32..63,
        ) {
            let words: Vec<u64> = words.iter().map(|&v| v >> small).collect();
            let round = RoundShift::new(g, Quant::ALL[q]);
            let limit = (1u64 << 62) >> limit_shift;
            let (mut a, mut b) = (vec![0u32; words.len()], vec![0u32; words.len()]);
            let beyond = round_words(&words, &mut a, round, limit);
            prop_assert_eq!(simd::round_words(&words, &mut b, round, limit), beyond);
            prop_assert_eq!(beyond, words.iter().any(|&v| v > limit));
            prop_assert_eq!(a, b);
        }

        /// The fast frame quantisation gives the codes and saturation count of the
        /// general quantiser, word by word, for any format, guard bits and rounding.
        #[test]
        fn to_frame_matches_the_quantiser(
            words in proptest::collection::vec(any::<u64>(), 1..64),
            small in 0u32..40,
            signed in any::<bool>(),
            int_bits in 1u32..=20,
            frac_bits in 0u32..=12,
            g in 0u32..=24,
            q in 0usize..Quant::ALL.len(),
        ) {
            let fmt = QFormat::new(signed, int_bits, frac_bits);
            let quant = Quant::ALL[q];
            // Both huge words and words near the format's range.
            let words: Vec<u64> = words.iter().map(|&v| v >> small).collect();
            let mut res = vec![0u32; words.len()];
            let n = to_frame(&words, &mut res, fmt, g, quant);
            let fq = Quantizer::new(fmt, quant, Overflow::Sat);
            let mut want = 0;
            for (&v, &c) in words.iter().zip(&res) {
                let r = fq.quantize_raw(i128::from(v), (g + frac_bits) as i32);
                want += u64::from(r.overflow);
                prop_assert_eq!(c, r.code as u32, "word {} fmt {} g {}", v, fmt, g);
            }
            prop_assert_eq!(n, want);
        }
    }
}
