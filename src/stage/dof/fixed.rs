//! The fixed-point layered datapath: per layer the input planes, the horizontal and vertical
//! tap passes ([`row_mac`], the HDL model's reference), the layer colour and alpha, and the
//! back-to-front composite; work and overflow counts in [`DofWork`].

use super::fast::{self, Plane};
use super::layers::{DepthImage, LayerPlan, layer_boxes};
use super::scratch::Scratch;
use super::uniform;
use crate::config::DofCfg;
use crate::fixed::{Overflow, QFormat, Quant, Quantizer, round_shift, round_shift_i64};
use serde::Serialize;

/// Work and overflow counts of the fixed model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DofWork {
    /// Multiply-accumulates (both passes, intensity and alpha planes).
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
    /// The colour sum did not fit the word (counted; stops the run with overflow ERROR).
    pub overflow: bool,
}

/// One output sample of the horizontal or vertical pass: over the taps `t` whose sample
/// `pos + t - M` lies on the line `[0, len)` (`M = coef.len() / 2`; samples off the line are
/// zero), the colour sum saturated to `max` (the line-buffer or accumulator word) and the
/// exact alpha sum. `sample(i)` gives the (colour, alpha) samples at line position `i`.
/// The HDL model `hdl-models/rtl/dof_row_mac.v` is this function.
#[inline(always)]
pub fn row_mac(
    coef: &[u64],
    pos: usize,
    len: usize,
    max: u128,
    sample: impl Fn(usize) -> (u128, u128),
) -> MacOut {
    let m = coef.len() / 2;
    let t0 = m.saturating_sub(pos);
    let t1 = coef.len().min((len + m).saturating_sub(pos));
    let (mut sx, mut sa) = (0u128, 0u128);
    for (t, &cv) in coef.iter().enumerate().take(t1).skip(t0) {
        let (x, a) = sample(pos + t - m);
        sx += cv as u128 * x;
        sa += cv as u128 * a;
    }
    MacOut {
        x: sx.min(max),
        a: sa,
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
    /// Line buffer: horizontal colour sums (saturated).
    pub hx: &'a [u64],
    /// Line buffer: horizontal alpha sums.
    pub ha: &'a [u64],
}

/// The pixel's share in a layer (in `1/n2` units).
#[inline]
pub(super) fn share(plan: &LayerPlan, img_key: u32, cov: u16, idx: u16, l: usize, n2: u32) -> u32 {
    let own = if img_key == u32::MAX { 0 } else { cov as u32 };
    let mut m = if idx as usize == l && img_key != u32::MAX {
        own
    } else {
        0
    };
    if plan.background == Some(l) {
        m += n2 - own.min(n2);
    }
    m
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
    /// `dof.skip_uniform_tiles` never straddle two. With overflow ERROR a layer is one
    /// strip (the first overflow stops the run, so the passes keep their whole-box order).
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
    layered_fixed_exec(img, plan, p, frame_fmt, Exec::Strips(STRIP_ROWS), |_| {})
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
    layered_fixed_exec(img, plan, p, frame_fmt, Exec::SkipUniform, observe).map(|r| (r.0, r.1))
}

/// The output codes, the work counts and per layer the pixels of skipped uniform tiles.
pub type FixedRun = (Vec<u32>, DofWork, Vec<u64>);

/// [`layered_fixed_observed`] computed as `exec` says. Also returns per layer the box pixels
/// in skipped uniform tiles (all 0 unless `dof.skip_uniform_tiles`; the same for any `exec`).
pub fn layered_fixed_exec(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
    exec: Exec,
    observe: impl FnMut(&LayerPlanes),
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
        exec_with::<u32>(img, plan, p, frame_fmt, exec, observe)
    } else {
        exec_with::<u64>(img, plan, p, frame_fmt, exec, observe)
    }
}

/// [`layered_fixed_exec`] with planes of `P` words.
fn exec_with<P: Plane>(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    p: &DofCfg,
    frame_fmt: QFormat,
    exec: Exec,
    mut observe: impl FnMut(&LayerPlanes),
) -> Result<FixedRun, (String, u32)> {
    let (w, h) = (img.width, img.height);
    let (q, g) = (p.alpha_bits, p.guard_bits);
    let line_max: u128 = (1u128 << p.line_bits) - 1;
    let acc_max: u128 = (1u128 << p.acc_bits) - 1;
    let mut work = DofWork::default();
    let mut skipped = vec![0u64; plan.layers.len()];
    // A composite never exceeds the largest code times 2^g (every colour is a weighted mean
    // of codes, docs/dof.md): u64 words.
    let mut out = vec![0u64; w * h];
    let mut def = vec![false; w * h];
    let one_q = 1u128 << q;
    let n2 = u64::from(img.n2);
    let boxes = layer_boxes(w, h, plan);
    let mut s = Scratch::<P>::new();
    for (l, layer) in plan.layers.iter().enumerate() {
        let Some((x0, y0, x1, y1)) = boxes[l] else {
            continue;
        };
        let (bw, bh) = (x1 - x0, y1 - y0);
        let c = &layer.coef;
        let wx = border_sums(c, w);
        let wy = border_sums(c, h);
        if layer.m == 0 {
            // sigma = 0: the mask is the identity; pass through.
            s.input(img, plan, l, (x0, y0, bw, bh));
            for y in 0..bh {
                for x in 0..bw {
                    let (a, v) = (
                        s.ai[y * bw + x].get() as u128,
                        s.xi[y * bw + x].get() as u128,
                    );
                    if a == 0 {
                        continue;
                    }
                    let pi = (y + y0) * w + x + x0;
                    work.passthrough += 1;
                    let col = round_shift(((v << g) / a) as i128, 0, p.quant) as u128;
                    let aq = (a << q) / img.n2 as u128;
                    composite(&mut out[pi], &mut def[pi], col, aq, one_q, q, p.quant);
                    work.composites += 1;
                }
            }
            continue;
        }
        let strip = match exec {
            Exec::Strips(rows) if p.overflow != Overflow::Error => rows
                .max(8 * layer.m)
                .next_multiple_of(uniform::UNIFORM_TILE),
            _ => usize::MAX,
        };
        let (bsx, bsy) = (border_sums(c, bw), border_sums(c, bh));
        let cp: Vec<P> = c.iter().map(|&v| P::put(v)).collect();
        let cp = &cp[..];
        // Output rows [r0, r1) of the box per strip; the planes cover [e0, e1), M more rows
        // each side (clipped to the box), whose uniform windows and sums for [r0, r1) are
        // those of the whole box (docs/dof.md, "Strips").
        let mut r0 = 0;
        while r0 < bh {
            let r1 = if strip >= bh {
                bh
            } else {
                ((y0 + r0) / strip * strip + strip - y0).min(bh)
            };
            let (e0, e1) = (r0.saturating_sub(layer.m), (r1 + layer.m).min(bh));
            let eh = e1 - e0;
            s.input(img, plan, l, (x0, y0 + e0, bw, eh));
            let (xi, ai, val) = (&s.xi[..], &s.ai[..], &s.val[..]);
            // Uniform windows (docs/dof.md): exact without MACs where, besides the window
            // being uniform, neither word saturates and the box's tap sums are the image's.
            s.full.clear();
            s.full.extend(ai.iter().map(|&a| a.get() == n2));
            s.win.compute(bw, eh, layer.m, &s.full, val);
            let u = &mut s.win.u;
            for yy in 0..eh {
                let y = e0 + yy;
                for x in 0..bw {
                    let i = yy * bw + x;
                    if u[i] {
                        let hxv = xi[i].get() as u128 * bsx[x] as u128;
                        u[i] = hxv <= line_max
                            && hxv * bsy[y] as u128 <= acc_max
                            && bsx[x] == wx[x + x0]
                            && bsy[y] == wy[y + y0];
                    }
                }
            }
            let (u, hu) = (&s.win.u[..], &s.win.hu[..]);
            // The hardware option: 16x16 tiles of uniform pixels skip both passes.
            let tile_skip = if p.skip_uniform_tiles {
                let (tiles, mask) = uniform::skipped_tiles(
                    &u[(r0 - e0) * bw..(r1 - e0) * bw],
                    (x0, y0 + r0, bw, r1 - r0),
                );
                work.skipped_tiles += tiles;
                skipped[l] += mask.iter().filter(|&&b| b).count() as u64;
                Some(mask)
            } else {
                None
            };
            // Horizontal pass into the line buffer: a saturated sum fits u64
            // (`line_bits` <= 64) and so does an alpha sum (taps of at most 2^20 times n2).
            let (hx, ha) = (&mut s.hx, &mut s.ha);
            hx.clear();
            ha.clear();
            // `x * m` is at most a u32 code times n2: a bound, not a scan.
            let wide_h = !fast::fits_u64(u128::from(u32::MAX) * u128::from(n2), p.coef_bits);
            let mut hmax = 0u64;
            for yy in 0..eh {
                let (rx, ra) = (&xi[yy * bw..(yy + 1) * bw], &ai[yy * bw..(yy + 1) * bw]);
                // Rows of the neighbouring strips are computed again, counted there.
                let counted = (r0..r1).contains(&(e0 + yy));
                for x in 0..bw {
                    let i = yy * bw + x;
                    let r = match exec {
                        Exec::Full => row_mac(c, x, bw, line_max, |i| {
                            (rx[i].get() as u128, ra[i].get() as u128)
                        }),
                        _ if hu[i] => fast::mac_out(
                            rx[x].get() as u128 * bsx[x] as u128,
                            ra[x].get() as u128 * bsx[x] as u128,
                            line_max,
                        ),
                        _ => {
                            let (sx, sa) = if wide_h {
                                fast::hsum::<u128, P>(cp, rx, ra, x)
                            } else {
                                fast::hsum::<u64, P>(cp, rx, ra, x)
                            };
                            fast::mac_out(sx, sa, line_max)
                        }
                    };
                    if r.overflow && counted {
                        work.line_overflows += 1;
                        if p.overflow == Overflow::Error {
                            return Err(("dof.line".into(), p.line_bits));
                        }
                    }
                    hx.push(P::put(r.x as u64));
                    ha.push(P::put(r.a as u64));
                    hmax = hmax.max(r.x as u64).max(r.a as u64);
                }
            }
            let (hx, ha) = (&hx[..], &ha[..]);
            if let (true, Some(xi), Some(ai), Some(hx), Some(ha)) = (
                strip >= bh,
                P::as_u64(xi),
                P::as_u64(ai),
                P::as_u64(hx),
                P::as_u64(ha),
            ) {
                observe(&LayerPlanes {
                    layer: l,
                    x0,
                    y0,
                    bw,
                    bh,
                    xi,
                    ai,
                    hx,
                    ha,
                });
            }
            // Vertical pass, colour, alpha, composite.
            let wide_v = !fast::fits_u64(hmax as u128, p.coef_bits);
            s.rows.reset(bw, wide_v);
            for y in r0..r1 {
                let yy = y - e0;
                let ur = &u[yy * bw..(yy + 1) * bw];
                if exec != Exec::Full {
                    s.rows.fill(cp, hx, ha, (bw, eh), yy, ur);
                }
                for x in 0..bw {
                    let i = yy * bw + x;
                    let pi = (y + y0) * w + x + x0;
                    let skip = tile_skip.as_ref().is_some_and(|t| t[(y - r0) * bw + x]);
                    if exec != Exec::Full && ur[x] {
                        // Uniform window: colour v exactly, alpha one (docs/dof.md).
                        if !skip {
                            work.divides += 1;
                        }
                        composite(
                            &mut out[pi],
                            &mut def[pi],
                            (val[i] as u128) << g,
                            one_q,
                            one_q,
                            q,
                            p.quant,
                        );
                        work.composites += 1;
                        continue;
                    }
                    let r = match exec {
                        Exec::Full => row_mac(c, yy, eh, acc_max, |i| {
                            (hx[i * bw + x].get() as u128, ha[i * bw + x].get() as u128)
                        }),
                        _ => {
                            let (sx, sa) = s.rows.get(x);
                            fast::mac_out(sx, sa, acc_max)
                        }
                    };
                    if r.overflow {
                        work.acc_overflows += 1;
                        if p.overflow == Overflow::Error {
                            return Err(("dof.acc".into(), p.acc_bits));
                        }
                    }
                    let (sx, sa) = (r.x, r.a);
                    if sa == 0 {
                        continue;
                    }
                    if !skip {
                        work.divides += 1;
                    }
                    // colour = round(F 2^g / A): half-up integer divide
                    let col = udiv(sx << (g + 1), sa).div_ceil(2);
                    let ws = wx[x + x0] as u128 * wy[y + y0] as u128 * img.n2 as u128;
                    let aq = udiv(sa << (q + 1), ws).div_ceil(2).min(one_q);
                    composite(&mut out[pi], &mut def[pi], col, aq, one_q, q, p.quant);
                    work.composites += 1;
                }
            }
            r0 = r1;
        }
        let active = (bw * bh) as u64 - skipped[l];
        // Both passes, colour and alpha planes.
        work.macs += 2 * 2 * c.len() as u64 * active;
    }
    // The composite carries `g` guard bits below the frame LSB.
    let frame_q = Quantizer::new(frame_fmt, p.quant, Overflow::Sat);
    let raw_frac = (g + frame_fmt.frac_bits) as i32;
    let res = out
        .iter()
        .map(|&v| {
            let r = frame_q.quantize_raw(i128::from(v), raw_frac);
            work.out_overflows += u64::from(r.overflow);
            r.code as u32
        })
        .collect();
    Ok((res, work, skipped))
}

/// `o = col` over `o` with alpha `aq / one`: `round((col aq + o (one - aq)) / one)`; the
/// first layer at a pixel, or an opaque one (`aq = one`: the quotient is exact), writes
/// `col`.
#[inline]
fn composite(o: &mut u64, d: &mut bool, col: u128, aq: u128, one: u128, q: u32, quant: Quant) {
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
fn udiv(a: u128, b: u128) -> u128 {
    if (a | b) >> 64 == 0 {
        u128::from(a as u64 / b as u64)
    } else {
        a / b
    }
}
