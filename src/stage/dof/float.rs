//! Float reference (1): the fixed datapath's layers and masks in f64 arithmetic.

use super::fixed::{border_sums, share};
use super::layers::{DepthImage, LayerPlan, layer_box};

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

/// Float reference (1): the same layers and masks (float taps on the fixed taps' support),
/// f64 arithmetic.
pub fn layered_f64(img: &DepthImage<f64>, plan: &LayerPlan) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let mut out = vec![0.0f64; w * h];
    let mut def = vec![false; w * h];
    for (l, layer) in plan.layers.iter().enumerate() {
        let all = plan.background == Some(l);
        let Some((x0, y0, x1, y1)) = layer_box(w, h, &plan.index, l, layer.m, all) else {
            continue;
        };
        let (bw, bh) = (x1 - x0, y1 - y0);
        let c = &on_fixed_support(&layer.coef_f, &layer.coef);
        let m = layer.m as i64;
        let wx = border_sums(c, w);
        let wy = border_sums(c, h);
        let mut xi = vec![0.0; bw * bh];
        let mut ai = vec![0.0; bw * bh];
        for y in 0..bh {
            for x in 0..bw {
                let pi = (y + y0) * w + x + x0;
                let s = share(plan, img.key[pi], img.cov[pi], plan.index[pi], l, img.n2) as f64
                    / img.n2 as f64;
                xi[y * bw + x] = img.value[pi] * s;
                ai[y * bw + x] = s;
            }
        }
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
        let fx = pass(&pass(&xi, true), false);
        let fa = pass(&pass(&ai, true), false);
        for y in 0..bh {
            for x in 0..bw {
                let a = fa[y * bw + x];
                if a <= 0.0 {
                    continue;
                }
                let pi = (y + y0) * w + x + x0;
                let col = fx[y * bw + x] / a;
                let an = (a / (wx[x + x0] * wy[y + y0])).min(1.0);
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
