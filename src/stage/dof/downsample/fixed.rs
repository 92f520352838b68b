//! The fixed-point downsample-and-blend datapath: the small image (box average over
//! `factor x factor` blocks), its separable Gaussian (two passes), the blend factor and CoC
//! radius planes, and the per-pixel Poisson-disc gather with the normaliser divide.

use super::plan::DownPlan;
use super::small::{box_sums, gauss_pass};
use crate::config::{DofCfg, LeakGuard};
use crate::fixed::{Overflow, QFormat, Quant, Quantized, Quantizer, SignalStats, round_shift};
use crate::stage::dof::SIGMA_FRAC;

/// Work counts and the instrumented signals of the fixed model.
#[derive(Clone, Debug)]
pub struct DownWork {
    /// Small-image pixels (box averages).
    pub small_pixels: u64,
    /// Multiply-accumulates: both Gaussian passes, the bilinear samples, the tap mixes and
    /// the weighted sums.
    pub macs: u64,
    /// Taps gathered (weight > 0; a tap off the frame reads its edge pixel).
    pub taps: u64,
    /// Normaliser divides.
    pub divides: u64,
    /// Pixels with CoC radius 0 (every tap on the centre: no divide).
    pub passthrough: u64,
    /// The small image (`dof.down.small`).
    pub small: SignalStats,
    /// The two Gaussian passes' outputs (`dof.down.blur`).
    pub blur: SignalStats,
    /// Overflows of the bilinear samples (`dof.down.tap`; convex, so none in a correct
    /// datapath).
    pub tap_overflows: u64,
    /// The output in the frame format (`dof.down.out`).
    pub out: SignalStats,
    /// The blurred small image (small format codes, raster order).
    pub blurred: Vec<u64>,
}

/// An overflow with overflow mode ERROR: the signal, its format and the rounded value.
pub type OverflowAt = (String, QFormat, i128);

/// The small image's word: the frame format with `guard_bits` more fraction bits.
pub fn small_format(frame_fmt: QFormat, guard_bits: u32) -> QFormat {
    QFormat::new(false, frame_fmt.int_bits, frame_fmt.frac_bits + guard_bits)
}

/// A quantisation point that records into `stats` and stops on overflow with mode ERROR.
struct Point<'a> {
    q: Quantizer,
    stats: &'a mut SignalStats,
}

impl Point<'_> {
    /// Quantises `raw 2^-raw_frac` (a non-negative value) and records it.
    #[inline]
    fn put(&mut self, raw: u128, raw_frac: u32) -> Result<i64, OverflowAt> {
        let r = self.q.round_raw(raw as i128, raw_frac as i32);
        let res = self.q.handle_overflow(r);
        let exact =
            raw as f64 * crate::fixed::pow2(self.q.format.frac_bits as i32 - raw_frac as i32);
        self.stats.record(exact, r, res.overflow);
        check(res, self.q, &self.stats.name, r)
    }
}

#[inline]
fn check(res: Quantized, q: Quantizer, name: &str, r: i128) -> Result<i64, OverflowAt> {
    if res.overflow && q.overflow == Overflow::Error {
        return Err((name.to_string(), q.format, r));
    }
    Ok(res.code)
}

/// The weight of a tap (`UQ1.<b>`, `one = 2^b`): 1 unless the tap lies in front of the
/// centre (smaller depth code), then by the rule `g`.
#[inline]
pub fn tap_weight(g: LeakGuard, key_c: u32, beta_c: u64, key_t: u32, beta_t: u64, one: u64) -> u64 {
    if key_t >= key_c {
        return one;
    }
    match g {
        LeakGuard::Difference => one - beta_c.saturating_sub(beta_t),
        LeakGuard::TapBlur => beta_t,
        LeakGuard::None => one,
    }
}

/// [`tap_weight`] in f64 (blend factors in [0, 1]).
#[inline]
pub fn tap_weight_f64(g: LeakGuard, key_c: u32, beta_c: f64, key_t: u32, beta_t: f64) -> f64 {
    if key_t >= key_c {
        return 1.0;
    }
    match g {
        LeakGuard::Difference => 1.0 - (beta_c - beta_t).max(0.0),
        LeakGuard::TapBlur => beta_t,
        LeakGuard::None => 1.0,
    }
}

/// A bilinear weight of a position with `pf` fraction bits, rounded to `bb` bits.
#[inline]
fn bl_weight(frac: i64, pf: u32, bb: u32, quant: Quant) -> u64 {
    if pf >= bb {
        round_shift(frac as i128, pf - bb, quant) as u64
    } else {
        (frac as u64) << (bb - pf)
    }
}

/// What a read of the blurred small image needs besides the position: the image, the plan,
/// the position's fraction bits `pf`, the weights' fraction bits `bb` and rounding
/// `quant`, and the small format's quantiser `q` with its fraction bits `frac`.
pub(super) struct TexelRead<'a> {
    pub blur: &'a [u64],
    pub plan: &'a DownPlan,
    pub pf: u32,
    pub bb: u32,
    pub quant: Quant,
    pub q: Quantizer,
    pub frac: u32,
}

impl TexelRead<'_> {
    /// The texel left of and above the full-resolution position `(px, py) 2^-pf` (texel
    /// centres at `(i + 1/2) factor`) and the position's fractions past it, each rounded to
    /// `bb` bits: `(i0, j0, wx, wy)`.
    #[inline]
    pub fn origin(&self, px: i64, py: i64) -> (i64, i64, u64, u64) {
        let sf = self.pf + self.plan.factor_log2;
        let half = 1i64 << (sf - 1);
        let (u, v) = (px - half, py - half);
        let (i0, j0) = (u >> sf, v >> sf);
        let wx = bl_weight(u - (i0 << sf), sf, self.bb, self.quant);
        let wy = bl_weight(v - (j0 << sf), sf, self.bb, self.quant);
        (i0, j0, wx, wy)
    }

    /// A weighted sum with `2 bb` weight fraction bits rounded to the small format:
    /// `(code, overflowed)`.
    #[inline]
    pub fn round(&self, sum: i128) -> (i64, bool) {
        let r = self.q.quantize_raw(sum, (self.frac + 2 * self.bb) as i32);
        (r.code, r.overflow)
    }
}

/// The bilinear sample of the blurred small image at the full-resolution position
/// `(px, py) 2^-pf` (pixel `x` spans `[x, x + 1)`), texel centres at `(i + 1/2) factor`,
/// coordinates clamped; weights `UQ1.<bb>`, the sample rounded to the small format.
#[inline]
fn bilinear(t: &TexelRead, px: i64, py: i64) -> (i64, bool) {
    let (plan, blur) = (t.plan, t.blur);
    let (i0, j0, wx, wy) = t.origin(px, py);
    let one = 1u64 << t.bb;
    let (sw, sh) = (plan.small_width as i64, plan.small_height as i64);
    let cx = |i: i64| i.clamp(0, sw - 1) as usize;
    let cy = |j: i64| j.clamp(0, sh - 1) as usize * plan.small_width;
    let (x0, x1, y0, y1) = (cx(i0), cx(i0 + 1), cy(j0), cy(j0 + 1));
    let s = |w: u64, i: usize| w as u128 * blur[i] as u128;
    let sum = s((one - wx) * (one - wy), y0 + x0)
        + s(wx * (one - wy), y0 + x1)
        + s((one - wx) * wy, y1 + x0)
        + s(wx * wy, y1 + x1);
    t.round(sum as i128)
}

/// The fixed-point method on frame codes `code` (in `frame_fmt`) and depth codes `key`:
/// the output codes in `frame_fmt` and the work, or the first overflow with mode ERROR.
pub fn downsample_fixed(
    code: &[u32],
    key: &[u32],
    plan: &DownPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
) -> Result<(Vec<u32>, DownWork), OverflowAt> {
    let d = &p.downsample;
    let (w, h) = (plan.width, plan.height);
    let (g, b, bb) = (d.guard_bits, d.blend_bits, d.bilinear_bits);
    let sfmt = small_format(frame_fmt, g);
    let sq = Quantizer::new(sfmt, p.quant, p.overflow);
    let sfrac = sfmt.frac_bits;
    let mut work = DownWork {
        small_pixels: (plan.small_width * plan.small_height) as u64,
        macs: 0,
        taps: 0,
        divides: 0,
        passthrough: 0,
        small: SignalStats::new("dof.down.small", sfmt),
        blur: SignalStats::new("dof.down.blur", sfmt),
        tap_overflows: 0,
        out: SignalStats::new("dof.down.out", frame_fmt),
        blurred: vec![],
    };
    // Small image and its two Gaussian passes.
    let (sw, sh) = (plan.small_width, plan.small_height);
    let mut small = vec![0u64; sw * sh];
    let mut pt = Point {
        q: sq,
        stats: &mut work.small,
    };
    let box_frac = frame_fmt.frac_bits + 2 * plan.factor_log2;
    box_sums(code, plan, |i, s: u128| {
        small[i] = pt.put(s, box_frac)? as u64;
        Ok(())
    })?;
    let mut pt = Point {
        q: sq,
        stats: &mut work.blur,
    };
    let mul = |c: u64, v: u64| c as u128 * v as u128;
    let pass_frac = sfrac + p.coef_bits;
    let mut hp = vec![0u64; sw * sh];
    gauss_pass(&small, sw, sh, &plan.coef, true, mul, |i, s| {
        hp[i] = pt.put(s, pass_frac)? as u64;
        Ok(())
    })?;
    let mut blurred = vec![0u64; sw * sh];
    gauss_pass(&hp, sw, sh, &plan.coef, false, mul, |i, s| {
        blurred[i] = pt.put(s, pass_frac)? as u64;
        Ok(())
    })?;
    work.macs += 2 * (small.len() * plan.coef.len()) as u64;
    // Blend factor and CoC radius of every pixel (as the pixels enter the blend window).
    let beta: Vec<u64> = key.iter().map(|&k| plan.blend_fixed(k, p.quant)).collect();
    let radius: Vec<i64> = beta.iter().map(|&bt| plan.radius_fixed(bt)).collect();
    // The gather.
    let one = 1u64 << b;
    // Tap positions: pixels with the radius's and the offsets' fraction bits (exact).
    let pf = SIGMA_FRAC + b + d.offset_bits;
    let centre = 1i64 << (pf - 1);
    let out_frac = frame_fmt.frac_bits + g + b;
    let mut out_pt = Point {
        q: Quantizer::new(frame_fmt, p.quant, p.overflow),
        stats: &mut work.out,
    };
    let mut out = vec![0u32; w * h];
    let offs = &plan.taps.codes;
    // The reconstruction: bilinear, or a cubic's weight ROM; its MACs per blurred sample.
    let recon = d.reconstruction.cubic().map(|bc| super::recon::rom(bc, bb));
    let read = TexelRead {
        blur: &blurred,
        plan,
        pf,
        bb,
        quant: p.quant,
        q: sq,
        frac: sfrac,
    };
    let rmacs = d.reconstruction.texels().pow(2) as u64;
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let (kc, bc, rc) = (key[i], beta[i], radius[i]);
            let (cx, cy) = (((x as i64) << pf) + centre, ((y as i64) << pf) + centre);
            let sample = |px: i64, py: i64, bt: u64, j: usize, tap_ovf: &mut u64| -> u128 {
                let sharp = (code[j] as u128) << g;
                let blur = if bt > 0 {
                    let (v, o) = match &recon {
                        None => bilinear(&read, px, py),
                        Some(rom) => super::recon::sample_fixed(&read, rom, px, py),
                    };
                    *tap_ovf += u64::from(o);
                    v as u128
                } else {
                    0
                };
                (one - bt) as u128 * sharp + bt as u128 * blur
            };
            if rc == 0 {
                // Every tap reads the centre: the mean is the centre tap, no divide.
                let t = sample(cx, cy, bc, i, &mut work.tap_overflows);
                work.passthrough += 1;
                work.taps += 1;
                work.macs += 2 + if bc > 0 { rmacs } else { 0 };
                out[i] = out_pt.put(t, out_frac)? as u32;
                continue;
            }
            let (mut num, mut den) = (0u128, 0u128);
            for &(dx, dy) in offs {
                // A tap off the frame reads its edge pixel (clamp-to-edge): dropping it
                // would skew the remaining taps and band the border (docs/dof-downsample.md).
                let (px, py) = (cx + rc * dx, cy + rc * dy);
                let (ix, iy) = (
                    (px >> pf).clamp(0, w as i64 - 1),
                    (py >> pf).clamp(0, h as i64 - 1),
                );
                let (px, py) = (
                    px.clamp(0, ((w as i64) << pf) - 1),
                    py.clamp(0, ((h as i64) << pf) - 1),
                );
                let j = iy as usize * w + ix as usize;
                let wt = tap_weight(d.leak_guard, kc, bc, key[j], beta[j], one);
                if wt == 0 {
                    continue;
                }
                let t = sample(px, py, beta[j], j, &mut work.tap_overflows);
                work.taps += 1;
                work.macs += 3 + if beta[j] > 0 { rmacs } else { 0 };
                num += wt as u128 * t;
                den += wt as u128;
            }
            work.divides += 1;
            // The normaliser divide: quotient truncated (TRN) at out_frac fraction bits,
            // then rounded to the frame format by the output quantiser.
            out[i] = out_pt.put(num / den, out_frac)? as u32;
        }
    }
    work.blurred = blurred;
    Ok((out, work))
}
