//! One strip of one blurred layer of the fixed layered datapath ([`super::fixed`]): the
//! strip's input planes (with the `M` rows either side its vertical taps read), its uniform
//! windows, the horizontal pass into the line buffer, the vertical pass, the layer colour
//! and alpha, and the composite into the strip's output rows. Strips write disjoint rows,
//! so they run in parallel: the strips of a layer ([`super::fixed::layered_fixed_exec`]),
//! or every layer's strip of a stripe of rows, in layer order ([`super::stripes`]).

use super::fast::{self, Plane};
use super::fixed::{DofWork, Exec, LayerPlanes, border_sums, composite, planes, row_mac, udiv};
use super::layers::{DepthImage, LayerPlan};
use super::scratch::{Scratch, runs};
use super::uniform;
use crate::config::{AlphaNorm, DofCfg};
use crate::fixed::Overflow;

/// What every strip of one blurred layer shares.
pub(super) struct LayerCx<'a, P> {
    pub img: &'a DepthImage<'a, u32>,
    pub plan: &'a LayerPlan,
    pub p: &'a DofCfg,
    pub exec: Exec,
    /// Layer index.
    pub l: usize,
    /// Mask half-size.
    pub m: usize,
    /// The 1-D taps, and in plane words.
    pub c: &'a [u64],
    pub cp: &'a [P],
    /// The layer's box `(x0, y0, bw, bh)`.
    pub boxr: (usize, usize, usize, usize),
    /// In-image tap sums along the image's rows and columns, and along the box's.
    pub wx: &'a [u64],
    pub wy: &'a [u64],
    pub bsx: &'a [u64],
    pub bsy: &'a [u64],
}

/// What a blurred layer's strips read, owned: its taps as plane words and the in-image and
/// in-box tap sums along both axes.
pub(super) struct LayerTaps<P> {
    cp: Vec<P>,
    wx: Vec<u64>,
    wy: Vec<u64>,
    bsx: Vec<u64>,
    bsy: Vec<u64>,
}

impl<P: Plane> LayerTaps<P> {
    /// Layer `l` of `plan` over its box `boxr = (x0, y0, bw, bh)` of an image of `w x h`.
    pub fn new(plan: &LayerPlan, l: usize, (w, h): (usize, usize), boxr: Box4) -> Self {
        let c = &plan.layers[l].coef;
        Self {
            cp: c.iter().map(|&v| P::put(v)).collect(),
            wx: border_sums(c, w),
            wy: border_sums(c, h),
            bsx: border_sums(c, boxr.2),
            bsy: border_sums(c, boxr.3),
        }
    }

    /// The strips' shared context of layer `l` over `boxr`, computed as `exec` says.
    pub fn cx<'a>(
        &'a self,
        (img, plan, p): (&'a DepthImage<'a, u32>, &'a LayerPlan, &'a DofCfg),
        exec: Exec,
        l: usize,
        boxr: Box4,
    ) -> LayerCx<'a, P> {
        let layer = &plan.layers[l];
        LayerCx {
            img,
            plan,
            p,
            exec,
            l,
            m: layer.m,
            c: &layer.coef,
            cp: &self.cp,
            boxr,
            wx: &self.wx,
            wy: &self.wy,
            bsx: &self.bsx,
            bsy: &self.bsy,
        }
    }
}

/// A box `(x0, y0, width, height)`.
type Box4 = (usize, usize, usize, usize);

/// The multiply-accumulates of a blurred layer over `active` box pixels: both passes, every
/// plane.
pub(super) fn layer_macs(plan: &LayerPlan, l: usize, active: u64) -> u64 {
    2 * planes(plan) * plan.layers[l].coef.len() as u64 * active
}

/// The output rows `[r0, r1)` of the box per strip of `strip` rows: strips start at image
/// rows that are multiples of `strip` (one strip when `strip >= bh`).
pub(super) fn strip_rows(y0: usize, bh: usize, strip: usize) -> Vec<(usize, usize)> {
    let mut rows = Vec::new();
    let mut r0 = 0;
    while r0 < bh {
        let r1 = if strip >= bh {
            bh
        } else {
            ((y0 + r0) / strip * strip + strip - y0).min(bh)
        };
        rows.push((r0, r1));
        r0 = r1;
    }
    rows
}

/// Computes output rows `[r0, r1)` of the layer's box into `out` and `def`, the image rows
/// from `y0 + r0` on (whole rows of the image); counts into `work` and `skipped` (pixels of
/// skipped uniform tiles). `observe` sees the planes (a layer of one strip). `Err` names the
/// overflowing signal in overflow mode ERROR.
#[allow(clippy::too_many_arguments)]
pub(super) fn run_strip<P: Plane>(
    cx: &LayerCx<P>,
    s: &mut Scratch<P>,
    (r0, r1): (usize, usize),
    out: &mut [u64],
    def: &mut [bool],
    work: &mut DofWork,
    skipped: &mut u64,
    observe: Option<&mut dyn FnMut(&LayerPlanes)>,
) -> Result<(), (String, u32)> {
    let LayerCx {
        img,
        plan,
        p,
        exec,
        l,
        m,
        c,
        cp,
        wx,
        wy,
        bsx,
        bsy,
        ..
    } = *cx;
    let (x0, y0, bw, bh) = cx.boxr;
    let w = img.width;
    let (q, g) = (p.alpha_bits, p.guard_bits);
    let line_max: u128 = (1u128 << p.line_bits) - 1;
    let acc_max: u128 = (1u128 << p.acc_bits) - 1;
    let one_q = 1u128 << q;
    let n2 = u64::from(img.n2);
    // The planes cover [e0, e1), M more rows each side (clipped to the box), whose uniform
    // windows and sums for [r0, r1) are those of the whole box (docs/dof.md, "Strips").
    let (e0, e1) = (r0.saturating_sub(m), (r1 + m).min(bh));
    let eh = e1 - e0;
    s.input(img, plan, l, (x0, y0 + e0, bw, eh));
    let (xi, ai, di, val) = (&s.xi[..], &s.ai[..], &s.di[..], &s.val[..]);
    // Window classes (docs/dof.md, "Uniform windows"): a full window is exact without
    // MACs where, besides, neither word saturates and the box's tap sums are the image's; a
    // zero window's colour and alpha sums are zero.
    s.win.compute(bw, eh, m, &s.class, val);
    // `h <= line_max && h * bsy <= acc_max` is `h <= lim`, the row's limit.
    for (yy, (u, xi)) in s
        .win
        .u
        .chunks_exact_mut(bw)
        .zip(xi.chunks_exact(bw))
        .enumerate()
    {
        let y = e0 + yy;
        let demote = |u: &mut u8| {
            if *u == uniform::FULL {
                *u = uniform::MIXED;
            }
        };
        if bsy[y] != wy[y + y0] {
            u.iter_mut().for_each(demote);
            continue;
        }
        let lim = match bsy[y] {
            0 => line_max,
            b => line_max.min(acc_max / b as u128),
        };
        // `lim` fits a u64 (`line_bits` <= 64), so a product above u64 is above it.
        let lim = lim as u64;
        let cols = bsx.iter().zip(&wx[x0..x0 + bw]);
        for ((u, xi), (&bx, &wxx)) in u.iter_mut().zip(xi).zip(cols) {
            if !(bx == wxx && xi.get().checked_mul(bx).is_some_and(|v| v <= lim)) {
                demote(u);
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
        *skipped += mask.iter().filter(|&&b| b).count() as u64;
        Some(mask)
    } else {
        None
    };
    // Horizontal pass into the line buffer: a saturated sum fits u64
    // (`line_bits` <= 64) and so does an alpha sum (taps of at most 2^20 times n2).
    let (hx, ha, hd) = (&mut s.hx, &mut s.ha, &mut s.hd);
    // Every word is written below (no clearing pass).
    for v in [&mut *hx, &mut *ha, &mut *hd] {
        v.resize(eh * bw, P::default());
    }
    // `x * m` is at most a u32 code times n2: a bound, not a scan.
    let wide_h = !fast::fits_u64(u128::from(u32::MAX) * u128::from(n2), p.coef_bits);
    s.hrow.reset(bw, wide_h);
    let mut hmax = 0u64;
    for yy in 0..eh {
        let row = yy * bw..(yy + 1) * bw;
        let (rx, ra, rd) = (&xi[row.clone()], &ai[row.clone()], &di[row.clone()]);
        let (hx, ha, hd) = (
            &mut hx[row.clone()],
            &mut ha[row.clone()],
            &mut hd[row.clone()],
        );
        // Rows of the neighbouring strips are computed again, counted there.
        let counted = (r0..r1).contains(&(e0 + yy));
        let overflows = if exec == Exec::Full {
            let mut n = 0;
            for x in 0..bw {
                let r = row_mac(c, x, bw, line_max, |i| {
                    let v = |p: &[P]| p[i].get() as u128;
                    (v(rx), v(ra), v(rd))
                });
                n += u64::from(r.overflow);
                hx[x] = P::put(r.x as u64);
                ha[x] = P::put(r.a as u64);
                hd[x] = P::put(r.d as u64);
                hmax = hmax.max(r.x as u64).max(r.d as u64);
            }
            n
        } else {
            s.hrow.hfill(cp, (rx, ra, rd), &hu[row], bsx);
            let (n, top) = s.hrow.saturate(line_max, (hx, ha, hd));
            hmax = hmax.max(top);
            n
        };
        if overflows > 0 && counted {
            work.line_overflows += overflows;
            if p.overflow == Overflow::Error {
                return Err(("dof.line".into(), p.line_bits));
            }
        }
    }
    let (hx, ha, hd) = (&hx[..], &ha[..], &hd[..]);
    if let (Some(observe), Some(xi), Some(ai), Some(di), Some(hx), Some(ha), Some(hd)) = (
        observe,
        P::as_u64(xi),
        P::as_u64(ai),
        P::as_u64(di),
        P::as_u64(hx),
        P::as_u64(ha),
        P::as_u64(hd),
    ) {
        observe(&LayerPlanes {
            layer: l,
            x0,
            y0,
            bw,
            bh,
            xi,
            ai,
            di,
            hx,
            ha,
            hd,
        });
    }
    // Vertical pass, colour, alpha, composite.
    let wide_v = !fast::fits_u64(hmax as u128, p.coef_bits);
    s.rows.reset(bw, wide_v);
    for y in r0..r1 {
        let yy = y - e0;
        let ur = &u[yy * bw..(yy + 1) * bw];
        let orow = (y - r0) * w + x0..(y - r0) * w + x0 + bw;
        let (out, def) = (&mut out[orow.clone()], &mut def[orow]);
        let skip = |x: usize| tile_skip.as_ref().is_some_and(|t| t[(y - r0) * bw + x]);
        // The whole row as one mixed run for the reference, else by window class.
        let full = exec == Exec::Full;
        if !full {
            s.rows.fill(cp, (hx, ha, hd), (bw, eh), yy, ur);
        }
        let whole = full.then_some((uniform::MIXED, 0, bw));
        for (k, xa, xb) in whole.into_iter().chain(runs(ur).filter(|_| !full)) {
            match k {
                // Zero window: no colour and no alpha, nothing to composite.
                uniform::ZERO => {}
                // Full window: colour v exactly, alpha one (docs/dof.md), so the composite
                // writes the colour.
                uniform::FULL => {
                    let v = &val[yy * bw + xa..yy * bw + xb];
                    for (o, &v) in out[xa..xb].iter_mut().zip(v) {
                        *o = u64::from(v) << g;
                    }
                    def[xa..xb].fill(true);
                    work.divides += (xa..xb).filter(|&x| !skip(x)).count() as u64;
                    work.composites += (xb - xa) as u64;
                }
                _ => {
                    for x in xa..xb {
                        let r = match exec {
                            Exec::Full => row_mac(c, yy, eh, acc_max, |i| {
                                let v = |p: &[P]| p[i * bw + x].get() as u128;
                                (v(hx), v(ha), v(hd))
                            }),
                            _ => fast::mac_out(s.rows.get(x), acc_max),
                        };
                        if r.overflow {
                            work.acc_overflows += 1;
                            if p.overflow == Overflow::Error {
                                return Err(("dof.acc".into(), p.acc_bits));
                            }
                        }
                        let (sx, sa, sd) = (r.x, r.a, r.d);
                        if sa == 0 {
                            continue;
                        }
                        if !skip(x) {
                            work.divides += 1;
                        }
                        // colour = round(F 2^g / A): half-up integer divide
                        let col = udiv(sx << (g + 1), sa).div_ceil(2);
                        let ws = match plan.alpha_norm {
                            AlphaNorm::Behind => sd,
                            AlphaNorm::Image => {
                                wx[x + x0] as u128 * wy[y + y0] as u128 * img.n2 as u128
                            }
                        };
                        let aq = udiv(sa << (q + 1), ws).div_ceil(2).min(one_q);
                        composite(&mut out[x], &mut def[x], col, aq, one_q, q, p.quant);
                        work.composites += 1;
                    }
                }
            }
        }
    }
    Ok(())
}
