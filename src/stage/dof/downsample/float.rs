//! The float reference of the downsample method: the same steps in f64 with the exact
//! blend factors `|sigma| / scale`, the exact CoC radii `|sigma|` (0 and no blend where the
//! fixed path passes a pixel through), the exact Poisson
//! offsets, float Gaussian taps, exact bilinear (or cubic) weights and an exact normaliser
//! divide.

use super::fixed::tap_weight_f64;
use super::plan::{Blur, DownPlan};
use super::small::{box_sums, gauss_pass};
use crate::config::DofCfg;

/// The bilinear sample of the blurred small image at the full-resolution position
/// `(px, py)`, texel centres at `(i + 1/2) factor`, coordinates clamped.
fn bilinear(blur: &[f64], plan: &DownPlan, px: f64, py: f64) -> f64 {
    let f = plan.factor as f64;
    let (u, v) = (px / f - 0.5, py / f - 0.5);
    let (i0, j0) = (u.floor(), v.floor());
    let (wx, wy) = (u - i0, v - j0);
    let (sw, sh) = (plan.small_width as i64, plan.small_height as i64);
    let cx = |i: f64| (i as i64).clamp(0, sw - 1) as usize;
    let cy = |j: f64| (j as i64).clamp(0, sh - 1) as usize * plan.small_width;
    let (x0, x1, y0, y1) = (cx(i0), cx(i0 + 1.0), cy(j0), cy(j0 + 1.0));
    (1.0 - wx) * (1.0 - wy) * blur[y0 + x0]
        + wx * (1.0 - wy) * blur[y0 + x1]
        + (1.0 - wx) * wy * blur[y1 + x0]
        + wx * wy * blur[y1 + x1]
}

/// The float method on `value` (frame LSBs) with depth codes `key`.
pub fn downsample_f64(
    value: &[f64],
    key: &[u32],
    plan: &DownPlan,
    blur: &dyn Blur,
    p: &DofCfg,
) -> Vec<f64> {
    let (w, h) = (plan.width, plan.height);
    let (sw, sh) = (plan.small_width, plan.small_height);
    let area = (plan.factor * plan.factor) as f64;
    let mut small = vec![0.0; sw * sh];
    let _: Result<(), ()> = box_sums(value, plan, |i, s: f64| {
        small[i] = s / area;
        Ok(())
    });
    let mut hp = vec![0.0; sw * sh];
    let mut blurred = vec![0.0; sw * sh];
    let mul = |c: f64, v: f64| c * v;
    let _: Result<(), ()> = gauss_pass(&small, sw, sh, &plan.coef_f, true, mul, |i, s| {
        hp[i] = s;
        Ok(())
    });
    let _: Result<(), ()> = gauss_pass(&hp, sw, sh, &plan.coef_f, false, mul, |i, s| {
        blurred[i] = s;
        Ok(())
    });
    // The fixed path's decisions: no blend where its factor is 0, no gather where its
    // radius is 0 (a pass-through pixel).
    let fixed: Vec<u64> = key.iter().map(|&k| plan.blend_fixed(k, p.quant)).collect();
    let beta: Vec<f64> = key
        .iter()
        .zip(&fixed)
        .map(|(&k, &b)| plan.blend_f64(blur, k, b))
        .collect();
    let radius: Vec<f64> = key
        .iter()
        .zip(&fixed)
        .map(|(&k, &b)| {
            if plan.radius_fixed(b) == 0 {
                0.0
            } else {
                blur.sigma_f64(k).abs()
            }
        })
        .collect();
    let guard = p.downsample.leak_guard;
    let recon = p.downsample.reconstruction.cubic();
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let (kc, bc, rc) = (key[i], beta[i], radius[i]);
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            let (mut num, mut den) = (0.0, 0.0);
            for &(dx, dy) in &plan.taps.points {
                // Clamp-to-edge, as the fixed path: the position moves to the frame's
                // last representable point, the pixel to its edge pixel.
                let (px, py) = (cx + rc * dx, cy + rc * dy);
                let (ix, iy) = (
                    px.floor().clamp(0.0, w as f64 - 1.0),
                    py.floor().clamp(0.0, h as f64 - 1.0),
                );
                let (px, py) = (px.clamp(0.0, w as f64), py.clamp(0.0, h as f64));
                let j = iy as usize * w + ix as usize;
                let wt = tap_weight_f64(guard, kc, bc, key[j], beta[j]);
                if wt == 0.0 {
                    continue;
                }
                let bt = beta[j];
                let b = match (bt > 0.0, recon) {
                    (false, _) => 0.0,
                    (true, None) => bilinear(&blurred, plan, px, py),
                    (true, Some(bc)) => super::recon::sample_f64(&blurred, plan, bc, px, py),
                };
                num += wt * ((1.0 - bt) * value[j] + bt * b);
                den += wt;
            }
            out[i] = num / den;
        }
    }
    out
}
