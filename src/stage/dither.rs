//! Dithering: hides the bits the DAC (or the gamma-LUT address) does not have.
//!
//! Kinds: `none`; ordered Bayer 2x2 / 4x4 / 8x8 (matrices from the recursive rule
//! `M2n = [[4M, 4M+2], [4M+3, 4M+1]]`); a blue-noise mask generated in the crate by
//! Ulichney's void-and-cluster method (seeded, integer energies, so it is the same on every
//! machine); and Floyd-Steinberg error diffusion in fixed point. Ordered and blue-noise
//! masks have temporal variants indexed by the frame number.
//!
//! Placement:
//! * `after_lut` (the default, as display hardware does it): the gamma LUT emits DAC bits
//!   plus `f` extra fraction bits (format `UQd.f`), the dither removes the `f` bits.
//! * `before_lut`: the dither removes `f` bits of the frame code, so the LUT has
//!   `2^(A - f)` entries instead of `2^A` (A = accumulator integer bits). Address `a` stands
//!   for the frame value `a * 2^f` (normalised by the frame's full white and clamped to 1);
//!   the dithered address saturates at `2^(A-f) - 1`, which costs the top `2^f - 1` frame
//!   codes their mean (counted as saturations).
//!
//! Arithmetic (the input `x` has `s` fraction bits; output max `omax`):
//! * Ordered, mask rank `m` of an `N x N` mask (`N^2 = 2^b`), zero-mean threshold
//!   `t = (m + 0.5) / N^2`: `y = floor(x / 2^s + t)`, computed exactly as
//!   `((x << (b+1)) + ((2m+1) << s)) >> (s + b + 1)`, then saturated to `omax`.
//!   Averaged over the mask, `y` equals `x / 2^s` exactly whenever `s <= b`, and rounds
//!   `x / 2^s` to the nearest multiple of `1/N^2` otherwise.
//! * Floyd-Steinberg, error format `Qi.fe` (output LSBs, `fe >= s`): `v = x * 2^(fe-s) + e`,
//!   `y = floor(v / 2^fe + 1/2)` saturated to `[0, omax]`, residual `r = v - y * 2^fe`.
//!   The shares `7r/16`, `3r/16`, `5r/16` are rounded half up (`RND`, never truncated toward
//!   zero) to the error format and the last share is `r` minus the other three, so no error is
//!   lost inside the image (only at its borders).
//!   Serpentine scanning reverses odd rows. Accumulated errors saturate to the error format
//!   (counted as overflows).
//! * Temporal masks: frame `t` shifts the mask by the position of rank `t mod N^2` in the
//!   mask, so over one period of `N^2` frames every pixel sees every rank exactly once.
//!
//! The float reference applies the same patterns to the ideal (unquantised) value, so fixed
//! and float are comparable code by code; stage-locally (the float dither fed the fixed
//! dither's input) ordered dithers are identical (the arithmetic above is exact).
//! Floyd-Steinberg's float reference diffuses exact shares: every step adds 4 fraction bits
//! to the error, so no finite error format is exact and the two diverge where a rounded share
//! tips a decision (the stage-local report counts those pixels; the image mean is kept).

use super::{Cost, LocalError, StageReport, Unit, ms_since};
use crate::config::{DitherCfg, DitherKind, Placement};
use crate::fixed::{Overflow, QFormat, Quant, Quantizer, SignalStats, round_shift};
use crate::stage::gamma::{GammaLut, GammaSpec};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// A threshold mask: ranks `0..N^2` (a permutation) on an `N x N` tile.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    /// Side `N` (a power of two).
    pub n: u32,
    /// `log2(N^2)`: bits of a rank.
    pub bits: u32,
    /// Ranks, row-major.
    pub rank: Vec<u32>,
}

impl Mask {
    /// The Bayer matrix of side `n` (1, 2, 4, 8, ...) by the recursive rule.
    pub fn bayer(n: u32) -> Mask {
        assert!(n.is_power_of_two(), "Bayer side must be a power of two");
        let mut m = vec![0u32];
        let mut s = 1usize;
        while (s as u32) < n {
            let t = 2 * s;
            let mut next = vec![0u32; t * t];
            for y in 0..s {
                for x in 0..s {
                    let v = 4 * m[y * s + x];
                    next[y * t + x] = v;
                    next[y * t + x + s] = v + 2;
                    next[(y + s) * t + x] = v + 3;
                    next[(y + s) * t + x + s] = v + 1;
                }
            }
            m = next;
            s = t;
        }
        Mask {
            n,
            bits: 2 * n.trailing_zeros(),
            rank: m,
        }
    }

    /// A blue-noise mask of side `n` by void-and-cluster (Ulichney 1993), Gaussian
    /// sigma 1.5 on the torus, energies in integers (kernel `round(exp(-d^2/2s^2) * 2^20)`),
    /// ties broken by the lowest index, initial pattern of `n^2/10` seeded random points.
    pub fn blue_noise(n: u32, seed: u64) -> Mask {
        let nn = n as usize;
        let size = nn * nn;
        let sigma2 = 2.0 * 1.5f64 * 1.5;
        let mut kern = vec![0i64; size];
        for dy in 0..nn {
            for dx in 0..nn {
                let (ax, ay) = (dx.min(nn - dx) as f64, dy.min(nn - dy) as f64);
                kern[dy * nn + dx] =
                    ((-(ax * ax + ay * ay) / sigma2).exp() * 1048576.0).round() as i64;
            }
        }
        let mut energy = vec![0i64; size];
        let mut on = vec![false; size];
        let toggle = |on: &mut [bool], energy: &mut [i64], q: usize, add: bool| {
            on[q] = add;
            let (qx, qy) = (q % nn, q / nn);
            for py in 0..nn {
                let dy = (py + nn - qy) % nn;
                for px in 0..nn {
                    let dx = (px + nn - qx) % nn;
                    let k = kern[dy * nn + dx];
                    energy[py * nn + px] += if add { k } else { -k };
                }
            }
        };
        let cluster = |on: &[bool], energy: &[i64]| {
            (0..size)
                .filter(|&i| on[i])
                .max_by(|&a, &b| energy[a].cmp(&energy[b]).then(b.cmp(&a)))
        };
        let void = |on: &[bool], energy: &[i64]| {
            (0..size)
                .filter(|&i| !on[i])
                .min_by(|&a, &b| energy[a].cmp(&energy[b]).then(a.cmp(&b)))
        };
        // Initial pattern: seeded random points (xorshift64*).
        let mut state = seed ^ 0x9E37_79B9_7F4A_7C15;
        let ones = (size / 10).max(1);
        let mut placed = 0;
        while placed < ones {
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            let r = (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 33) as usize % size;
            if !on[r] {
                toggle(&mut on, &mut energy, r, true);
                placed += 1;
            }
        }
        // Relax: move the tightest cluster into the largest void until they coincide.
        for _ in 0..4 * size {
            let c = cluster(&on, &energy).expect("ones exist");
            toggle(&mut on, &mut energy, c, false);
            let v = void(&on, &energy).expect("zeros exist");
            toggle(&mut on, &mut energy, v, true);
            if v == c {
                break;
            }
        }
        let (proto_on, proto_e) = (on.clone(), energy.clone());
        let mut rank = vec![0u32; size];
        // Phase 1: remove the tightest clusters, ranks ones-1 down to 0.
        for r in (0..ones).rev() {
            let c = cluster(&on, &energy).expect("ones exist");
            rank[c] = r as u32;
            toggle(&mut on, &mut energy, c, false);
        }
        // Phases 2 and 3: fill the largest voids, ranks ones.. size. (The tightest cluster
        // of zeros is the largest void of ones: the torus kernel sums to a constant.)
        let (mut on, mut energy) = (proto_on, proto_e);
        for r in ones..size {
            let v = void(&on, &energy).expect("zeros exist");
            rank[v] = r as u32;
            toggle(&mut on, &mut energy, v, true);
        }
        Mask {
            n,
            bits: 2 * n.trailing_zeros(),
            rank,
        }
    }

    /// The mask of a configuration (`None` for error diffusion and no dither).
    pub fn of(cfg: &DitherCfg) -> Option<Mask> {
        match cfg.kind {
            DitherKind::Bayer2 => Some(Mask::bayer(2)),
            DitherKind::Bayer4 => Some(Mask::bayer(4)),
            DitherKind::Bayer8 => Some(Mask::bayer(8)),
            DitherKind::BlueNoise => Some(Mask::blue_noise(cfg.blue_noise_size, cfg.seed)),
            _ => None,
        }
    }

    /// Frames in one temporal period (`N^2`).
    pub fn period(&self) -> u32 {
        self.n * self.n
    }

    /// The mask offset of frame `t`: the position of rank `t mod N^2`.
    pub fn offset(&self, t: u32) -> (u32, u32) {
        let r = t % self.period();
        let i = self
            .rank
            .iter()
            .position(|&v| v == r)
            .expect("a permutation") as u32;
        (i % self.n, i / self.n)
    }

    /// The rank at pixel `(x, y)` with offset `off`.
    #[inline]
    pub fn at(&self, x: u32, y: u32, off: (u32, u32)) -> u32 {
        let m = self.n - 1;
        self.rank[(((y + off.1) & m) * self.n + ((x + off.0) & m)) as usize]
    }
}

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

/// Applies an ordered mask to a `width`-wide image of `s`-fraction-bit codes; returns the
/// codes saturated to `omax` and the number of saturations.
pub fn apply_ordered(
    x: &[u32],
    width: u32,
    s: u32,
    omax: u32,
    mask: &Mask,
    frame: u32,
    out: &mut [u32],
) -> u64 {
    let off = mask.offset(frame);
    let w = width.max(1) as usize;
    out.par_chunks_mut(w)
        .zip(x.par_chunks(w))
        .enumerate()
        .map(|(y, (o, xr))| {
            let mut sat = 0;
            for (i, (o, &v)) in o.iter_mut().zip(xr).enumerate() {
                let c = ordered_code(v, s, mask.at(i as u32, y as u32, off), mask.bits);
                if c > omax as u64 {
                    sat += 1;
                }
                *o = c.min(omax as u64) as u32;
            }
            sat
        })
        .sum()
}

/// Float reference of [`apply_ordered`] on real values (output LSBs).
pub fn apply_ordered_f64(v: &[f64], width: u32, omax: u32, mask: &Mask, frame: u32) -> Vec<u32> {
    let off = mask.offset(frame);
    let w = width.max(1) as usize;
    v.par_iter()
        .enumerate()
        .map(|(i, &v)| {
            let r = mask.at((i % w) as u32, (i / w) as u32, off);
            ordered_f64(v, r, mask.bits).clamp(0.0, omax as f64) as u32
        })
        .collect()
}

/// Floyd-Steinberg parameters (fixed).
#[derive(Clone, Copy, Debug)]
pub struct FsParams {
    /// Fraction bits of the input.
    pub s: u32,
    /// Largest output code.
    pub omax: u32,
    /// Error format (output LSBs).
    pub error: QFormat,
    /// Reverse odd rows.
    pub serpentine: bool,
}

/// Floyd-Steinberg in fixed point (see the module docs); returns the error-signal stats.
pub fn floyd_steinberg(
    x: &[u32],
    width: u32,
    height: u32,
    p: &FsParams,
    out: &mut [u32],
) -> SignalStats {
    let mut st = SignalStats::new("dither.error", p.error);
    let (w, fe) = (width as usize, p.error.frac_bits);
    let up = fe - p.s;
    let (lo, hi) = (p.error.min_code(), p.error.max_code());
    let mut cur = vec![0i64; w + 2];
    let mut next = vec![0i64; w + 2];
    let mut overflows = 0u64;
    let mut add = |slot: &mut i64, v: i64, inside: bool| {
        let s = *slot + v;
        if inside && (s < lo || s > hi) {
            overflows += 1;
        }
        *slot = s.clamp(lo, hi);
    };
    for y in 0..height as usize {
        let rev = p.serpentine && y % 2 == 1;
        for k in 0..w {
            let xi = if rev { w - 1 - k } else { k };
            let v = ((x[y * w + xi] as i64) << up) + cur[xi + 1];
            let q = ((v + (1i64 << (fe - 1))) >> fe).clamp(0, p.omax as i64);
            out[y * w + xi] = q as u32;
            let r = v - (q << fe);
            st.record_code(r as i128);
            let share = |m: i64| round_shift((m * r) as i128, 4, Quant::Rnd) as i64;
            let (e7, e3, e5) = (share(7), share(3), share(5));
            let e1 = r - e7 - e3 - e5;
            // Ahead, behind-below, below, ahead-below; slots 0 and w+1 are outside the image.
            let (ahead, behind) = if rev { (xi, xi + 2) } else { (xi + 2, xi) };
            add(&mut cur[ahead], e7, (1..=w).contains(&ahead));
            add(&mut next[behind], e3, (1..=w).contains(&behind));
            add(&mut next[xi + 1], e5, true);
            add(&mut next[ahead], e1, (1..=w).contains(&ahead));
        }
        std::mem::swap(&mut cur, &mut next);
        next.iter_mut().for_each(|e| *e = 0);
    }
    st.add_overflows(overflows);
    st
}

/// Float reference of Floyd-Steinberg on real values (output LSBs), exact weights.
pub fn floyd_steinberg_f64(
    v: &[f64],
    width: u32,
    height: u32,
    omax: u32,
    serpentine: bool,
) -> Vec<u32> {
    let w = width as usize;
    let mut out = vec![0u32; v.len()];
    let mut cur = vec![0f64; w + 2];
    let mut next = vec![0f64; w + 2];
    for y in 0..height as usize {
        let rev = serpentine && y % 2 == 1;
        for k in 0..w {
            let xi = if rev { w - 1 - k } else { k };
            let a = v[y * w + xi] + cur[xi + 1];
            let q = (a + 0.5).floor().clamp(0.0, omax as f64);
            out[y * w + xi] = q as u32;
            let r = a - q;
            let (ahead, behind) = if rev { (xi, xi + 2) } else { (xi + 2, xi) };
            cur[ahead] += r * 7.0 / 16.0;
            next[behind] += r * 3.0 / 16.0;
            next[xi + 1] += r * 5.0 / 16.0;
            next[ahead] += r / 16.0;
        }
        std::mem::swap(&mut cur, &mut next);
        next.iter_mut().for_each(|e| *e = 0.0);
    }
    out
}

/// A configured dither: kind, mask and arithmetic.
#[derive(Clone, Debug)]
pub struct Dither {
    /// The configuration.
    pub cfg: DitherCfg,
    /// The mask (ordered and blue noise).
    pub mask: Option<Mask>,
}

impl Dither {
    /// Builds the dither (generates the mask).
    pub fn new(cfg: &DitherCfg) -> Self {
        Self {
            cfg: cfg.clone(),
            mask: Mask::of(cfg),
        }
    }

    /// Fixed model: `s`-fraction-bit codes to codes in `0..=omax`; returns the error stats
    /// (error diffusion) or the saturation count as a signal.
    pub fn apply(
        &self,
        x: &[u32],
        width: u32,
        height: u32,
        s: u32,
        omax: u32,
        out: &mut [u32],
    ) -> SignalStats {
        match &self.mask {
            Some(m) => {
                let sat = apply_ordered(x, width, s, omax, m, self.frame(), out);
                let mut st = SignalStats::new(
                    "dither.out",
                    QFormat::new(false, 32 - omax.leading_zeros(), 0),
                );
                st.add_overflows(sat);
                st
            }
            None => floyd_steinberg(
                x,
                width,
                height,
                &FsParams {
                    s,
                    omax,
                    error: self.cfg.error,
                    serpentine: self.cfg.serpentine,
                },
                out,
            ),
        }
    }

    /// Float reference on real values in output LSBs.
    pub fn apply_f64(&self, v: &[f64], width: u32, height: u32, omax: u32) -> Vec<u32> {
        match &self.mask {
            Some(m) => apply_ordered_f64(v, width, omax, m, self.frame()),
            None => floyd_steinberg_f64(v, width, height, omax, self.cfg.serpentine),
        }
    }

    fn frame(&self) -> u32 {
        if self.cfg.temporal { self.cfg.frame } else { 0 }
    }

    /// Cost of the dither unit for an image `width` pixels wide with `s` input fraction
    /// bits and `out_bits` output bits.
    pub fn cost(&self, width: u32, s: u32, out_bits: u32) -> Cost {
        match &self.mask {
            Some(m) => {
                let mut adders = vec![
                    Unit::adder("threshold add", 1, out_bits + s + m.bits + 1),
                    Unit::adder("saturate", 1, out_bits + 1),
                ];
                if self.cfg.temporal {
                    adders.push(Unit::adder("frame counter", 1, m.bits));
                    adders.push(Unit::adder("mask offset", 2, m.bits / 2));
                }
                Cost {
                    lut_bits: m.period() as u64 * m.bits as u64,
                    adders,
                    ..Cost::default()
                }
            }
            None => {
                let eb = self.cfg.error.total_bits();
                Cost {
                    storage_bits: (width as u64 + 2) * eb as u64,
                    adders: vec![
                        Unit::adder("pixel + error", 1, out_bits + self.cfg.error.frac_bits + 2),
                        Unit::adder("round and saturate", 1, out_bits + 1),
                        Unit::adder("3r, 5r, 7r (shift-add)", 3, eb + 3),
                        Unit::adder("error accumulate", 4, eb),
                    ],
                    ..Cost::default()
                }
            }
        }
    }
}

/// The temporal-dither check: a static frame over one period of the mask.
#[derive(Clone, Debug, Serialize)]
pub struct PeriodMean {
    /// Frames in the period.
    pub period: u32,
    /// Pixels checked.
    pub pixels: u64,
    /// Pixels whose period mean equals their dither input exactly.
    pub exact_pixels: u64,
    /// Largest |period mean - input| in output LSBs.
    pub max_abs_error: f64,
    /// Whether every pixel is exact.
    pub exact: bool,
}

/// Runs the fixed dither on a static frame for every frame of the period and compares each
/// pixel's mean with its input. Over one period the offsets visit every mask position once,
/// so every pixel sees every rank once whatever its position: the period sum depends on the
/// input value alone, and pixels with the same input share one run.
pub fn period_mean(d: &Dither, x: &[u32], s: u32, omax: u32) -> Option<PeriodMean> {
    let m = d.mask.as_ref()?;
    if !d.cfg.temporal {
        return None;
    }
    let period = m.period();
    let mut res = PeriodMean {
        period,
        pixels: x.len() as u64,
        exact_pixels: 0,
        max_abs_error: 0.0,
        exact: true,
    };
    // One run per distinct input: frame t puts rank t on the pixel (the offset of frame t is
    // the position of rank t, and a shifted mask is a permutation of the ranks).
    let vmax = x.iter().copied().max().unwrap_or(0) as usize;
    let mut memo = vec![u64::MAX; vmax + 1];
    for &v in x {
        let sum = &mut memo[v as usize];
        if *sum == u64::MAX {
            *sum = (0..period)
                .map(|r| ordered_code(v, s, r, m.bits).min(omax as u64))
                .sum();
        }
        // Exact comparison: sum * 2^s == v * period.
        if (*sum << s) == v as u64 * period as u64 {
            res.exact_pixels += 1;
        } else {
            res.exact = false;
            let e = (*sum as f64 / period as f64 - v as f64 / (1u64 << s) as f64).abs();
            res.max_abs_error = res.max_abs_error.max(e);
        }
    }
    Some(res)
}

/// The gamma LUT with `f` extra output fraction bits (`UQd.f`), for the after-LUT placement.
pub fn extended_lut(spec: &GammaSpec, addr_bits: u32, f: u32) -> Vec<u32> {
    let d = spec.dac.format.int_bits;
    let q = Quantizer::new(QFormat::new(false, d, f), spec.dac.quant, Overflow::Sat);
    let white = ((1u64 << addr_bits) - 1) as f64;
    (0..1u64 << addr_bits)
        .map(|c| q.quantize_f64(spec.ideal(c as f64 / white)).code as u32)
        .collect()
}

/// The reduced-address gamma LUT of the before-LUT placement: address `a` is the frame
/// value `a * 2^f` of a frame whose full white is `2^acc_bits - 1`.
pub fn reduced_lut(spec: &GammaSpec, acc_bits: u32, f: u32) -> GammaLut {
    let white = ((1u64 << acc_bits) - 1) as f64;
    let table = (0..1u64 << (acc_bits - f))
        .map(|a| spec.code(((a << f) as f64 / white).min(1.0)))
        .collect();
    GammaLut {
        addr_bits: acc_bits - f,
        dac_bits: spec.dac.format.int_bits,
        table,
    }
}

/// Outputs of the gamma + dither post phase.
pub struct DitheredPost {
    /// Fixed DAC codes.
    pub dac: Vec<u16>,
    /// Float reference DAC codes.
    pub dac_ref: Vec<u16>,
    /// Gamma and dither reports, in flow order.
    pub reports: Vec<StageReport>,
}

/// The post phase with a dither: gamma LUT and dither, fixed and float, in the configured
/// order. `acc` are frame codes with `frame_frac` fraction bits and `acc_bits` integer bits,
/// `frame_ref` the float frame in frame LSBs, `powers` its [`GammaSpec::power`]s
/// (`spec.power(frame_ref[i] / white)`, computed once per exponent by the caller).
#[allow(clippy::too_many_arguments)]
pub fn post(
    acc: &[u32],
    frame_ref: &[f64],
    size: (u32, u32),
    acc_bits: u32,
    frame_frac: u32,
    spec: &GammaSpec,
    cfg: &DitherCfg,
    stage_local: bool,
    powers: &[f64],
) -> DitheredPost {
    let (width, height) = size;
    let d = Dither::new(cfg);
    let f = cfg.frac_bits;
    let dac_bits = spec.dac.format.int_bits;
    let dac_max = spec.dac.format.max_code() as u32;
    let white = (1u64 << acc_bits) - 1;
    let mut rg = StageReport {
        name: "gamma".into(),
        ..Default::default()
    };
    let mut rd = StageReport {
        name: "dither".into(),
        ..Default::default()
    };
    let n = acc.len();
    let mut dac = vec![0u16; n];
    let mut codes = vec![0u32; n];
    let (din, s, omax) = match cfg.placement {
        Placement::AfterLut => {
            let t = Instant::now();
            let lut = extended_lut(spec, acc_bits, f);
            let amax = lut.len() - 1;
            let x: Vec<u32> = acc
                .par_iter()
                .map(|&a| lut[((a >> frame_frac) as usize).min(amax)])
                .collect();
            rg.fixed_ms = ms_since(t);
            rg.cost = Cost {
                lut_bits: lut.len() as u64 * (dac_bits + f) as u64,
                adders: vec![Unit::adder("LUT address", 1, acc_bits)],
                ..Cost::default()
            };
            rg.work.insert("lookups".into(), n as u64);
            rg.work.insert("lut_entries".into(), lut.len() as u64);
            rg.notes.insert(
                "monotone".into(),
                lut.windows(2).all(|w| w[0] <= w[1]).into(),
            );
            rg.notes
                .insert("output_format".into(), format!("UQ{dac_bits}.{f}").into());
            if stage_local {
                let mut e = LocalError::default();
                for (&a, &v) in acc.iter().zip(&x) {
                    let ideal = spec.ideal((a >> frame_frac) as f64 / white as f64);
                    e.add(v as f64, ideal * (1u64 << f) as f64);
                }
                rg.local = Some(e.finish());
            }
            (x, f, dac_max)
        }
        Placement::BeforeLut => (acc.to_vec(), f + frame_frac, (1u32 << (acc_bits - f)) - 1),
    };
    let t = Instant::now();
    let st = d.apply(&din, width, height, s, omax, &mut codes);
    rd.fixed_ms = ms_since(t);
    rd.signals.push(st);
    match cfg.placement {
        Placement::AfterLut => dac.iter_mut().zip(&codes).for_each(|(o, &c)| *o = c as u16),
        Placement::BeforeLut => {
            let t = Instant::now();
            let lut = reduced_lut(spec, acc_bits, f);
            dac.par_iter_mut()
                .zip(codes.par_iter())
                .for_each(|(o, &a)| *o = lut.table[a as usize]);
            rg.fixed_ms = ms_since(t);
            rg.cost = lut.cost();
            rg.work.insert("lookups".into(), n as u64);
            rg.work.insert("lut_entries".into(), lut.table.len() as u64);
            rg.notes.insert("monotone".into(), lut.is_monotone().into());
            if stage_local {
                let mut e = LocalError::default();
                for (&a, &c) in codes.iter().zip(&dac) {
                    e.add(
                        c as f64,
                        spec.ideal(((a << f) as f64 / white as f64).min(1.0)),
                    );
                }
                rg.local = Some(e.finish());
            }
        }
    }
    rd.work.insert("pixels".into(), n as u64);
    rd.cost = d.cost(width, s, 32 - omax.leading_zeros());
    rd.notes.insert(
        "input_format".into(),
        format!("UQ{}.{s}", 32 - omax.leading_zeros()).into(),
    );
    if let Some(m) = &d.mask {
        rd.notes.insert("mask_size".into(), m.n.into());
    }
    if stage_local {
        let scale = (1u64 << s) as f64;
        let v: Vec<f64> = din.iter().map(|&x| x as f64 / scale).collect();
        let fl = d.apply_f64(&v, width, height, omax);
        let mut e = LocalError::default();
        for (&a, &b) in codes.iter().zip(&fl) {
            e.add(a as f64, b as f64);
        }
        rd.local = Some(e.finish());
    }
    if let Some(pm) = period_mean(&d, &din, s, omax) {
        rd.notes.insert(
            "temporal_period_mean".into(),
            serde_json::to_value(pm).unwrap_or_default(),
        );
    }
    // Float reference: the ideal value, the same pattern, quantised only by the dither.
    let t = Instant::now();
    let dac_ref: Vec<u16> = match cfg.placement {
        Placement::AfterLut => {
            let v: Vec<f64> = powers.par_iter().map(|&p| spec.scale(p)).collect();
            d.apply_f64(&v, width, height, dac_max)
                .into_iter()
                .map(|c| c as u16)
                .collect()
        }
        Placement::BeforeLut => {
            let scale = (1u64 << (f + frame_frac)) as f64;
            let v: Vec<f64> = frame_ref.iter().map(|&a| a / scale).collect();
            let amax = (1u32 << (acc_bits - f)) - 1;
            d.apply_f64(&v, width, height, amax)
                .into_par_iter()
                .map(|a| spec.code(((a << f) as f64 / white as f64).min(1.0)))
                .collect()
        }
    };
    rd.float_ms = ms_since(t);
    DitheredPost {
        dac,
        dac_ref,
        reports: match cfg.placement {
            Placement::AfterLut => vec![rg, rd],
            Placement::BeforeLut => vec![rd, rg],
        },
    }
}
