//! The float reference of the luminance-aware method: the same pre-blur, bleed and blend in
//! f64 with exact divides and the exact alpha of every depth code.

use super::fixed::NEIGHBOURS;
use crate::stage::dof::fixed::border_sums;

/// The mean pre-blur: the mean of the `(2r+1)^2` window inside the image (border
/// renormalised), exact.
pub fn pre_blur_f64(value: &[f64], w: usize, h: usize, r: usize) -> Vec<f64> {
    if r == 0 {
        return value.to_vec();
    }
    let ones = vec![1.0f64; 2 * r + 1];
    let (nx, ny) = (border_sums(&ones, w), border_sums(&ones, h));
    // Separable exact sums (no running sums: every sum starts afresh, no cancellation).
    let mut rows = vec![0.0; w * h];
    for y in 0..h {
        let src = &value[y * w..(y + 1) * w];
        for x in 0..w {
            let (a, b) = (x.saturating_sub(r), (x + r + 1).min(w));
            rows[y * w + x] = src[a..b].iter().sum();
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        let (a, b) = (y.saturating_sub(r), (y + r + 1).min(h));
        for x in 0..w {
            let s: f64 = (a..b).map(|yy| rows[yy * w + x]).sum();
            out[y * w + x] = s / (nx[x] * ny[y]);
        }
    }
    out
}

/// The bleed on the pre-blurred image: `sum |Δ_i| P_i / sum |Δ_i|` over the brighter
/// neighbours inside the image, `P_c` when there is none.
pub fn bleed_f64(pre: &[f64], w: usize, h: usize) -> Vec<f64> {
    bleed_f64_by(pre, pre, w, h)
}

/// [`bleed_f64`] with the weights from the pre-blurred luminance `lum` and the values from
/// the pre-blurred channel `pre`.
pub fn bleed_f64_by(lum: &[f64], pre: &[f64], w: usize, h: usize) -> Vec<f64> {
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let c = lum[y * w + x];
            let (mut num, mut den) = (0.0, 0.0);
            for (dx, dy) in NEIGHBOURS {
                let (xx, yy) = (x as i64 + dx, y as i64 + dy);
                if xx < 0 || yy < 0 || xx >= w as i64 || yy >= h as i64 {
                    continue;
                }
                let i = yy as usize * w + xx as usize;
                if lum[i] > c {
                    num += (lum[i] - c) * pre[i];
                    den += lum[i] - c;
                }
            }
            out[y * w + x] = if den > 0.0 { num / den } else { pre[y * w + x] };
        }
    }
    out
}

/// The whole float reference: `x + alpha (blur - x)` with the exact `alpha` per pixel.
pub fn luminance_f64(value: &[f64], alpha: &[f64], w: usize, h: usize, r: usize) -> Vec<f64> {
    let blur = bleed_f64(&pre_blur_f64(value, w, h, r), w, h);
    blend_f64(value, &blur, alpha)
}

/// The blend `x + alpha (blur - x)`.
fn blend_f64(value: &[f64], blur: &[f64], alpha: &[f64]) -> Vec<f64> {
    value
        .iter()
        .zip(blur)
        .zip(alpha)
        .map(|((&x, &b), &a)| x + a * (b - x))
        .collect()
}

/// The float reference of one channel of a colour frame: its bleed weighted by the
/// luminance `lum` (pre-blurred with the same window).
pub fn luminance_colour_f64(
    value: &[f64],
    lum: &[f64],
    alpha: &[f64],
    w: usize,
    h: usize,
    r: usize,
) -> Vec<f64> {
    let pre_y = pre_blur_f64(lum, w, h, r);
    let blur = bleed_f64_by(&pre_y, &pre_blur_f64(value, w, h, r), w, h);
    blend_f64(value, &blur, alpha)
}
