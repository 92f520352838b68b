//! One blurred layer with a 2-D mask (`dof.kernel = "disc"`, docs/dof.md "Kernel shape"),
//! fixed and float: a direct 2-D filter of the layer's `x m` and `m` planes (one
//! accumulator, `dof.acc`; no line buffer), then the same colour, alpha and composite as the
//! separable passes. Reads off the image repeat its edge pixel (clamp-to-edge): a 2-D mask
//! cut by the border and renormalised would change the edge profile along the border (a
//! band of 29-45 LSB where a blurred edge meets it, docs/dof-compare.md); clamped, a scene
//! that continues past the border comes out as if it did.

use super::fixed::{DofWork, composite, planes, share, udiv};
use super::kernel::Mask2;
use super::layers::{DepthImage, LayerPlan};
use crate::config::{AlphaNorm, DofCfg};
use crate::fixed::Overflow;
use rayon::prelude::*;

/// The layer's input planes over its box `(x0, y0, bw, bh)`: `(x m, m, behind)` per pixel,
/// in units of `1/n2` of a sample share (fixed codes: exact integers).
fn input<T: Copy, O: Copy + Default>(
    img: &DepthImage<T>,
    plan: &LayerPlan,
    l: usize,
    (x0, y0, bw, bh): (usize, usize, usize, usize),
    mul: impl Fn(T, u32, u32) -> (O, O, O),
) -> [Vec<O>; 3] {
    let mut planes = [(); 3].map(|_| vec![O::default(); bw * bh]);
    for y in 0..bh {
        for x in 0..bw {
            let pi = (y + y0) * img.width + x + x0;
            let (s, d) = share(plan, img.key[pi], img.cov[pi], plan.index[pi], l, img.n2);
            let i = y * bw + x;
            (planes[0][i], planes[1][i], planes[2][i]) = mul(img.value[pi], s, d);
        }
    }
    planes
}

/// Per window position `t` in `0..n + 2m` (box-local sample `t - m`): the box-local sample
/// a clamp-to-edge read takes (the image's edge pixel for a read off the image), or `None`
/// where that lies outside the box (no share in the layer: zero).
fn tap_map(box0: usize, n: usize, len: usize, m: usize) -> Vec<Option<usize>> {
    (0..n + 2 * m)
        .map(|t| {
            let at = (box0 + t) as i64 - m as i64;
            let c = at.clamp(0, len as i64 - 1) as usize;
            (box0..box0 + n).contains(&c).then(|| c - box0)
        })
        .collect()
}

/// The fixed layer `l` with 2-D mask `mask` over its box: composites into `out`/`def` (the
/// whole image) and counts into `work`; `Err` names `dof.acc` in overflow mode ERROR.
#[allow(clippy::too_many_arguments)]
pub(super) fn layer_fixed(
    img: &DepthImage<u32>,
    plan: &LayerPlan,
    l: usize,
    mask: &Mask2,
    boxr: (usize, usize, usize, usize),
    p: &DofCfg,
    out: &mut [u64],
    def: &mut [bool],
    work: &mut DofWork,
) -> Result<(), (String, u32)> {
    let (x0, y0, bw, bh) = boxr;
    let (w, h) = (img.width, img.height);
    let (q, g) = (p.alpha_bits, p.guard_bits);
    let acc_max: u128 = (1u128 << p.acc_bits) - 1;
    let one_q = 1u128 << q;
    let n2 = u128::from(img.n2);
    let [xi, ai, di] = input(img, plan, l, boxr, |v, s, d| {
        (u64::from(v) * u64::from(s), u64::from(s), u64::from(d))
    });
    let (m, side) = (mask.m, mask.side());
    let (cols, rows_at) = (tap_map(x0, bw, w, m), tap_map(y0, bh, h, m));
    // Clamped reads see a whole window everywhere: the border weight is the mask's sum.
    let whole = u128::from(mask.w.iter().sum::<u64>()) * n2;
    // The box's rows, in parallel; counts summed in row order (the same on any thread
    // count).
    let rows: Vec<(usize, &mut [u64], &mut [bool])> = out[y0 * w..(y0 + bh) * w]
        .chunks_mut(w)
        .zip(def[y0 * w..(y0 + bh) * w].chunks_mut(w))
        .enumerate()
        .map(|(y, (o, d))| (y, o, d))
        .collect();
    let done: Vec<Result<DofWork, (String, u32)>> = rows
        .into_par_iter()
        .map(|(y, orow, drow)| {
            let mut wk = DofWork::default();
            for x in 0..bw {
                let (mut sx, mut sa, mut sd) = (0u128, 0u128, 0u128);
                for ty in 0..side {
                    let Some(r) = rows_at[y + ty] else { continue };
                    let wr = &mask.w[ty * side..(ty + 1) * side];
                    for (tx, &cv) in wr.iter().enumerate() {
                        let Some(c) = cols[x + tx] else { continue };
                        let (cv, j) = (u128::from(cv), r * bw + c);
                        sx += cv * u128::from(xi[j]);
                        sa += cv * u128::from(ai[j]);
                        sd += cv * u128::from(di[j]);
                    }
                }
                if sx > acc_max {
                    wk.acc_overflows += 1;
                    if p.overflow == Overflow::Error {
                        return Err(("dof.acc".into(), p.acc_bits));
                    }
                    sx = acc_max;
                }
                if sa == 0 {
                    continue;
                }
                wk.divides += 1;
                let col = udiv(sx << (g + 1), sa).div_ceil(2);
                let ws = match plan.alpha_norm {
                    AlphaNorm::Behind => sd,
                    AlphaNorm::Image => whole,
                };
                let aq = udiv(sa << (q + 1), ws).div_ceil(2).min(one_q);
                let xo = x + x0;
                composite(&mut orow[xo], &mut drow[xo], col, aq, one_q, q, p.quant);
                wk.composites += 1;
            }
            Ok(wk)
        })
        .collect();
    for r in done {
        work.add(&r?);
    }
    // Every tap at every box pixel, every plane (taps off the image multiply zeros).
    work.macs += planes(plan) * (side * side * bw * bh) as u64;
    Ok(())
}

/// The float layer `l` with the 2-D mask's float weights on its fixed support (as the
/// separable reference, docs/dof.md), clamped reads, composited into `out`/`def`.
pub(super) fn layer_f64(
    img: &DepthImage<f64>,
    plan: &LayerPlan,
    l: usize,
    mask: &Mask2,
    boxr: (usize, usize, usize, usize),
    out: &mut [f64],
    def: &mut [bool],
) {
    let (x0, y0, bw, bh) = boxr;
    let (w, h) = (img.width, img.height);
    let n2 = f64::from(img.n2);
    let [xi, ai, di] = input(img, plan, l, boxr, |v, s, d| {
        let s = f64::from(s) / n2;
        (v * s, s, f64::from(d) / n2)
    });
    let (m, side) = (mask.m, mask.side());
    // Float weights where the fixed ones are non-zero, renormalised to sum 1.
    let kept: Vec<f64> = mask
        .wf
        .iter()
        .zip(&mask.w)
        .map(|(&f, &q)| if q == 0 { 0.0 } else { f })
        .collect();
    let total: f64 = kept.iter().sum();
    let kept: Vec<f64> = kept.into_iter().map(|v| v / total).collect();
    let (cols, rows_at) = (tap_map(x0, bw, w, m), tap_map(y0, bh, h, m));
    for y in 0..bh {
        for x in 0..bw {
            let (mut sx, mut sa, mut sd) = (0.0, 0.0, 0.0);
            for ty in 0..side {
                let Some(r) = rows_at[y + ty] else { continue };
                for (tx, &cv) in kept[ty * side..(ty + 1) * side].iter().enumerate() {
                    let Some(c) = cols[x + tx] else { continue };
                    let j = r * bw + c;
                    sx += cv * xi[j];
                    sa += cv * ai[j];
                    sd += cv * di[j];
                }
            }
            if sa <= 0.0 {
                continue;
            }
            let pi = (y + y0) * w + x + x0;
            let col = sx / sa;
            let an = match plan.alpha_norm {
                AlphaNorm::Behind => sa / sd,
                AlphaNorm::Image => sa,
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
