//! The cubic reconstruction of the blurred small image (`dof.downsample.reconstruction`
//! other than bilinear): 4x4 texels around a full-resolution position, separable weights
//! of the cubic at the position's fraction. Fixed: a weight ROM indexed by the fraction
//! rounded to `bilinear_bits` bits, four signed weights per entry summing to exactly
//! `2^bilinear_bits` (largest remainder), the sample rounded once to the small format with
//! its overflow mode (a negative lobe can take it below black or above white: counted as a
//! tap overflow). Float: the exact cubic at the exact fraction.

use super::fixed::TexelRead;
use super::plan::DownPlan;
use crate::config::MitchellBc;

/// The cubic's four weights at fraction `t` in [0, 1] of the texel spacing, for the texels
/// at offsets -1, 0, 1, 2 from the one left of (above) the position.
pub fn weights_f64(bc: MitchellBc, t: f64) -> [f64; 4] {
    [
        bc.eval(1.0 + t),
        bc.eval(t),
        bc.eval(1.0 - t),
        bc.eval(2.0 - t),
    ]
}

/// The weight ROM: `2^bb + 1` entries (fraction `e / 2^bb`), four signed weights each,
/// summing to exactly `2^bb`.
pub fn rom(bc: MitchellBc, bb: u32) -> Vec<[i64; 4]> {
    let one = 1i64 << bb;
    (0..=one)
        .map(|e| {
            let w = weights_f64(bc, e as f64 / one as f64).map(|x| x * one as f64);
            let mut q = w.map(|x| x.floor() as i64);
            let mut left = one - q.iter().sum::<i64>();
            let mut order = [0usize, 1, 2, 3];
            order.sort_by(|&a, &b| {
                let (fa, fb) = (w[a] - w[a].floor(), w[b] - w[b].floor());
                fb.partial_cmp(&fa)
                    .unwrap_or(std::cmp::Ordering::Equal)
                    .then(a.cmp(&b))
            });
            for &k in order.iter().cycle().take(8) {
                if left == 0 {
                    break;
                }
                q[k] += 1;
                left -= 1;
            }
            q
        })
        .collect()
}

/// The fixed cubic sample of the blurred small image at the full-resolution position
/// `(px, py) 2^-pf` (texel centres at `(i + 1/2) factor`, texel indices clamped to the
/// image), weights from `rom` at the fraction rounded to `bb` bits, rounded to the small
/// format: `(code, overflowed)`.
pub(super) fn sample_fixed(t: &TexelRead, rom: &[[i64; 4]], px: i64, py: i64) -> (i64, bool) {
    let plan = t.plan;
    let (i0, j0, fx, fy) = t.origin(px, py);
    let (wx, wy) = (rom[fx as usize], rom[fy as usize]);
    let (sw, sh) = (plan.small_width as i64, plan.small_height as i64);
    let mut sum = 0i128;
    for (b, &wyb) in wy.iter().enumerate() {
        let row = (j0 - 1 + b as i64).clamp(0, sh - 1) as usize * plan.small_width;
        for (a, &wxa) in wx.iter().enumerate() {
            let col = (i0 - 1 + a as i64).clamp(0, sw - 1) as usize;
            sum += i128::from(wyb * wxa) * i128::from(t.blur[row + col]);
        }
    }
    t.round(sum)
}

/// The float cubic sample at the full-resolution position `(px, py)` (pixels).
pub fn sample_f64(blur: &[f64], plan: &DownPlan, bc: MitchellBc, px: f64, py: f64) -> f64 {
    let f = plan.factor as f64;
    let (u, v) = (px / f - 0.5, py / f - 0.5);
    let (i0, j0) = (u.floor(), v.floor());
    let (wx, wy) = (weights_f64(bc, u - i0), weights_f64(bc, v - j0));
    let (sw, sh) = (plan.small_width as i64, plan.small_height as i64);
    let mut sum = 0.0;
    for (b, &wyb) in wy.iter().enumerate() {
        let row = (j0 as i64 - 1 + b as i64).clamp(0, sh - 1) as usize * plan.small_width;
        for (a, &wxa) in wx.iter().enumerate() {
            let col = (i0 as i64 - 1 + a as i64).clamp(0, sw - 1) as usize;
            sum += wyb * wxa * blur[row + col];
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rom_entries_sum_exactly_and_match_the_cubic() {
        for bc in [
            MitchellBc { b: 1.0, c: 0.0 },
            MitchellBc { b: 0.0, c: 0.5 },
            MitchellBc::THIRD,
        ] {
            for bb in [2u32, 8, 12] {
                let r = rom(bc, bb);
                assert_eq!(r.len(), (1 << bb) + 1);
                for (e, w) in r.iter().enumerate() {
                    assert_eq!(w.iter().sum::<i64>(), 1 << bb, "{bc:?} bb={bb} e={e}");
                    let x = weights_f64(bc, e as f64 / (1 << bb) as f64);
                    for k in 0..4 {
                        assert!((w[k] as f64 - x[k] * (1 << bb) as f64).abs() < 1.0);
                    }
                }
            }
        }
        // Catmull-Rom interpolates: at fraction 0 the weight is all on the texel itself.
        assert_eq!(rom(MitchellBc { b: 0.0, c: 0.5 }, 8)[0], [0, 256, 0, 0]);
    }
}
