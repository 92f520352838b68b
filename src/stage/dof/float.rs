//! Float reference (1): the fixed datapath's layers and masks in f64 arithmetic.

use super::fixed::Exec;
use super::fixed::{border_sums, share};
use super::layers::{DepthImage, LayerPlan, layer_boxes};
use super::uniform::{self, FULL, MIXED};
use crate::config::AlphaNorm;
use crate::fnv::Fnv;

/// The float taps on the fixed mask's support (taps that quantise to 0 are 0), renormalised
/// to sum 1. The support decides which layers reach a pixel and hence which one fills it
/// first (the normalised convolution's hole fill); a float tap of 1e-5 where the hardware's
/// is 0 would otherwise pick a different back layer and move the pixel by hundreds of LSBs
/// (a depth ramp crossing thin layers, docs/dof.md).
fn on_fixed_support(tf: &[f64], t: &[u64]) -> Vec<f64> {
    let kept: Vec<f64> = tf
        .iter()
        .zip(t)
        .map(|(&v, &q)| if q == 0 { 0.0 } else { v })
        .collect();
    let sum: f64 = kept.iter().sum();
    kept.into_iter().map(|v| v / sum).collect()
}

/// A digest of everything [`layered_f64`] reads of `plan` besides the image: each layer's
/// half-size, float taps and the fixed taps' support (not their values: the float does not
/// read them), the pixels' layers, the background layer and the alpha normaliser. Two
/// plans with the same digest give the same float output on the same image, so a sweep of
/// the fixed datapath's widths (`dof.coef_bits`, `dof.alpha_bits`, `dof.guard_bits`) runs
/// the float reference once per distinct plan.
pub fn layered_f64_key(plan: &LayerPlan) -> u64 {
    let support = |f: Fnv, q: &[u64]| {
        let bits: Vec<u8> = q.iter().map(|&v| u8::from(v != 0)).collect();
        f.part(&bits)
    };
    let mut f = Fnv::new().str("layered_f64");
    for l in &plan.layers {
        f = f.u64(l.m as u64);
        for &c in &l.coef_f {
            f = f.u64(c.to_bits());
        }
        f = support(f.str("support"), &l.coef);
        if let Some(d) = &l.disc {
            f = f.str("disc").u64(d.m as u64);
            for &c in &d.wf {
                f = f.u64(c.to_bits());
            }
            f = support(f, &d.w);
        }
        f = f.str("layer");
    }
    let index: Vec<u8> = plan.index.iter().flat_map(|i| i.to_le_bytes()).collect();
    f.part(&index)
        .u64(plan.background.map_or(u64::MAX, |b| b as u64))
        .u64(u64::from(plan.alpha_norm == AlphaNorm::Behind))
        .finish()
}

/// Float reference (1): the same layers and masks (float taps on the fixed taps' support),
/// f64 arithmetic.
pub fn layered_f64(img: &DepthImage<f64>, plan: &LayerPlan) -> Vec<f64> {
    layered_f64_exec(img, plan, Exec::SkipUniform)
}

/// The sum `sum_t c[t] v` over the taps `t0..t1`, in tap order from 0 (the passes' order).
#[inline]
fn fold(c: &[f64], (t0, t1): (usize, usize), v: f64) -> f64 {
    let mut s = 0.0;
    for &cv in &c[t0..t1] {
        s += cv * v;
    }
    s
}

/// The taps of position `pos` on a line of `len` samples that fall on the line.
#[inline]
fn tap_range(c: &[f64], pos: usize, len: usize) -> (usize, usize) {
    let m = c.len() / 2;
    (
        m.saturating_sub(pos),
        c.len().min((len + m).saturating_sub(pos)),
    )
}

/// [`layered_f64`] computed as `exec` says (bit-identical either way): with
/// `Exec::SkipUniform` a uniform window's sums are one [`fold`] of its value (remembered for
/// the last value), the vertical pass runs row by row.
pub fn layered_f64_exec(img: &DepthImage<f64>, plan: &LayerPlan, exec: Exec) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let mut out = vec![0.0f64; w * h];
    let mut def = vec![false; w * h];
    let boxes = layer_boxes(w, h, plan);
    for (l, layer) in plan.layers.iter().enumerate() {
        let Some((x0, y0, x1, y1)) = boxes[l] else {
            continue;
        };
        let (bw, bh) = (x1 - x0, y1 - y0);
        if let Some(mask) = &layer.disc {
            super::disc::layer_f64(img, plan, l, mask, (x0, y0, bw, bh), &mut out, &mut def);
            continue;
        }
        let c = &on_fixed_support(&layer.coef_f, &layer.coef);
        let m = layer.m as i64;
        let wx = border_sums(c, w);
        let wy = border_sums(c, h);
        let mut xi = vec![0.0; bw * bh];
        let mut ai = vec![0.0; bw * bh];
        let mut di = vec![0.0; bw * bh];
        for y in 0..bh {
            for x in 0..bw {
                let pi = (y + y0) * w + x + x0;
                let (s, d) = share(plan, img.key[pi], img.cov[pi], plan.index[pi], l, img.n2);
                let (s, d) = (s as f64 / img.n2 as f64, d as f64 / img.n2 as f64);
                xi[y * bw + x] = img.value[pi] * s;
                ai[y * bw + x] = s;
                di[y * bw + x] = d;
            }
        }
        let (fx, fa, fd) = match exec {
            Exec::Full => {
                let pass = |src: &[f64], horizontal: bool| -> Vec<f64> {
                    let mut dst = vec![0.0; bw * bh];
                    for y in 0..bh {
                        for x in 0..bw {
                            let mut s = 0.0;
                            for (t, &cv) in c.iter().enumerate() {
                                let (xx, yy) = if horizontal {
                                    (x as i64 + t as i64 - m, y as i64)
                                } else {
                                    (x as i64, y as i64 + t as i64 - m)
                                };
                                if xx < 0 || yy < 0 || xx >= bw as i64 || yy >= bh as i64 {
                                    continue;
                                }
                                s += cv * src[yy as usize * bw + xx as usize];
                            }
                            dst[y * bw + x] = s;
                        }
                    }
                    dst
                };
                let both = |p: &[f64]| pass(&pass(p, true), false);
                (both(&xi), both(&ai), both(&di))
            }
            Exec::SkipUniform | Exec::Strips(_) => fast_passes(c, (bw, bh), [&xi, &ai, &di]),
        };
        for y in 0..bh {
            for x in 0..bw {
                let a = fa[y * bw + x];
                if a <= 0.0 {
                    continue;
                }
                let pi = (y + y0) * w + x + x0;
                let col = fx[y * bw + x] / a;
                let an = match plan.alpha_norm {
                    AlphaNorm::Behind => a / fd[y * bw + x],
                    AlphaNorm::Image => a / (wx[x + x0] * wy[y + y0]),
                }
                .min(1.0);
                if !def[pi] {
                    out[pi] = col;
                    def[pi] = true;
                } else {
                    out[pi] = col * an + out[pi] * (1.0 - an);
                }
            }
        }
    }
    out
}

/// Both passes of the three planes (colour, alpha, behind) over a `bw x bh` box, the same
/// sums in the same order as the per-sample passes: uniform windows (docs/dof.md) by
/// [`fold`], the rest row by row.
fn fast_passes(
    c: &[f64],
    (bw, bh): (usize, usize),
    [xi, ai, di]: [&[f64]; 3],
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let m = c.len() / 2;
    // Full windows only: zero-share windows are summed like the rest.
    let class: Vec<u8> = ai
        .iter()
        .map(|&a| if a == 1.0 { FULL } else { MIXED })
        .collect();
    let val: Vec<u64> = xi.iter().map(|v| v.to_bits()).collect();
    let win = uniform::windows(bw, bh, m, &class, &val);
    let bsx = border_sums(c, bw);
    // Horizontal pass.
    let mut h = [(); 3].map(|_| vec![0.0; bw * bh]);
    let mut last = (u64::MAX, 0.0f64); // (value bits, interior row sum)
    for y in 0..bh {
        #[allow(clippy::needless_range_loop)] // x is the position, not only an index
        for x in 0..bw {
            let i = y * bw + x;
            let r = tap_range(c, x, bw);
            if win.hu[i] == FULL {
                let v = xi[i];
                h[0][i] = if r == (0, c.len()) {
                    if last.0 != v.to_bits() {
                        last = (v.to_bits(), fold(c, r, v));
                    }
                    last.1
                } else {
                    fold(c, r, v)
                };
                // A uniform window is fully covered: its alpha and behind shares are 1.
                h[1][i] = bsx[x];
                h[2][i] = bsx[x];
                continue;
            }
            let base = y * bw + x + r.0 - m;
            let mut s = [0.0; 3];
            for (k, &cv) in c[r.0..r.1].iter().enumerate() {
                for (sp, p) in s.iter_mut().zip([xi, ai, di]) {
                    *sp += cv * p[base + k];
                }
            }
            for (hp, sp) in h.iter_mut().zip(s) {
                hp[i] = sp;
            }
        }
    }
    // Vertical pass: all the window's line sums of a uniform pixel equal its own.
    let ga: Vec<f64> = bsx.iter().map(|&b| fold(c, (0, c.len()), b)).collect();
    let mut f = [(); 3].map(|_| vec![0.0; bw * bh]);
    let mut last = (u64::MAX, 0.0f64);
    for y in 0..bh {
        let r = tap_range(c, y, bh);
        let interior = r == (0, c.len());
        let row = y * bw..(y + 1) * bw;
        let ur = &win.u[row.clone()];
        let [fx, fa, fd] = &mut f;
        let (ox, oa, od) = (&mut fx[row.clone()], &mut fa[row.clone()], &mut fd[row]);
        let mut x = 0;
        while x < bw {
            if interior && ur[x] == FULL {
                let hv = h[0][y * bw + x];
                if last.0 != hv.to_bits() {
                    last = (hv.to_bits(), fold(c, r, hv));
                }
                ox[x] = last.1;
                oa[x] = ga[x];
                od[x] = ga[x];
                x += 1;
                continue;
            }
            let xa = x;
            while x < bw && !(interior && ur[x] == FULL) {
                x += 1;
            }
            for (t, &cv) in c.iter().enumerate().take(r.1).skip(r.0) {
                let src = (y + t - m) * bw;
                for k in xa..x {
                    ox[k] += cv * h[0][src + k];
                    oa[k] += cv * h[1][src + k];
                    od[k] += cv * h[2][src + k];
                }
            }
        }
    }
    let [fx, fa, fd] = f;
    (fx, fa, fd)
}
