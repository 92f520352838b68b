//! The hue shift on smooth chromatic surfaces: the colour-mix distortion of words too
//! narrow for a shaded surface.
//!
//! When a channel's word is too narrow, the three channels of a smooth shaded surface step
//! at different places, so the mix of the primaries, and with it the hue, wanders along the
//! shading. The metric is the absolute CIELAB hue angle difference `|h_ab(fixed) -
//! h_ab(reference)|`, in degrees wrapped to `[0, 180]`, on the pixels where
//! * the reference is **smooth**: in every channel its codes span at most
//!   [`SMOOTH_CODES`] = 2 codes of that channel over the `5 x 5` window around the pixel
//!   (the window clipped to the image at its borders), the same threshold as the banding
//!   metric's ([`crate::perceptual`]); no edge of the scene is there, only shading;
//! * the reference is **chromatic**: its chroma `C*ab >=` [`MIN_CHROMA`]. The hue of a grey
//!   (`a* = b* = 0`) is undefined and that of a near-grey is dominated by rounding, so greys
//!   are not counted.

use super::{ColourDisplay, RgbCodes, check_pair, quantile};
use crate::perceptual::SMOOTH_CODES;
use rayon::prelude::*;
use serde::Serialize;

/// Half-width of the smoothness window, pixels: the window is `2 R + 1 = 5` pixels square.
pub const WINDOW_RADIUS: usize = 2;

/// Smallest CIELAB chroma `C*ab` of the reference for its hue to count.
pub const MIN_CHROMA: f64 = 5.0;

/// Hue shift statistics on the smooth chromatic pixels of the reference.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HueShift {
    /// Pixels where the reference is smooth (any chroma).
    pub smooth_pixels: u64,
    /// Pixels counted: smooth, and the reference's chroma at least [`MIN_CHROMA`].
    pub pixels: u64,
    /// Mean absolute hue angle difference over the counted pixels, degrees.
    pub mean_deg: f64,
    /// Its 99th percentile (nearest rank), degrees.
    pub p99_deg: f64,
    /// Its largest value, degrees (at most 180).
    pub max_deg: f64,
}

/// Sliding minimum and maximum of `v` over the `2 R + 1` elements centred on each one along
/// lines of `len` elements at `stride` (`lines` lines starting every `line_step`), clipped to
/// the line: each output element takes `2 (2 R + 1)` comparisons, whatever the image.
fn sliding(
    v: &[(u16, u16)],
    (len, stride): (usize, usize),
    (lines, line_step): (usize, usize),
) -> Vec<(u16, u16)> {
    let r = WINDOW_RADIUS;
    let mut out = vec![(0, 0); v.len()];
    for l in 0..lines {
        let base = l * line_step;
        for k in 0..len {
            let (k0, k1) = (k.saturating_sub(r), (k + r).min(len - 1));
            let mut m = (u16::MAX, 0);
            for j in k0..=k1 {
                let (lo, hi) = v[base + j * stride];
                m = (m.0.min(lo), m.1.max(hi));
            }
            out[base + k * stride] = m;
        }
    }
    out
}

/// Per pixel, row-major: whether `img` is smooth there, its codes spanning at most
/// [`SMOOTH_CODES`] codes in every channel over the `5 x 5` window around the pixel
/// (clipped to the image). Separable: a row pass and a column pass of sliding minima and
/// maxima, `O(pixels)`.
pub fn smooth_mask(img: &RgbCodes) -> Vec<bool> {
    let (w, h) = (img.width as usize, img.height as usize);
    let mut mask = vec![true; w * h];
    if w == 0 || h == 0 {
        return mask;
    }
    for plane in img.planes {
        let pairs: Vec<(u16, u16)> = plane.iter().map(|&c| (c, c)).collect();
        let rows = sliding(&pairs, (w, 1), (h, w));
        let span = sliding(&rows, (h, w), (w, 1));
        for (m, (lo, hi)) in mask.iter_mut().zip(span) {
            *m &= f64::from(hi - lo) <= SMOOTH_CODES;
        }
    }
    mask
}

/// The hue shift of `fixed` against its float `reference` (rounded to the same DAC codes) on
/// the display `d`, over the reference's smooth chromatic pixels (see the module's docs).
/// Where the fixed pixel is an exact grey its hue is taken as `h_ab = 0` (the angle of
/// `a* = b* = 0`), a large shift, as it should be. Panics if the two images differ in size or
/// their DAC widths are not the display's.
pub fn hue_shift(fixed: &RgbCodes, reference: &RgbCodes, d: &ColourDisplay) -> HueShift {
    check_pair(fixed, reference, d);
    let mask = smooth_mask(reference);
    let smooth_pixels = mask.iter().filter(|&&m| m).count() as u64;
    let angles: Vec<Option<f32>> = mask
        .par_iter()
        .enumerate()
        .map(|(i, &smooth)| {
            if !smooth {
                return None;
            }
            let r = reference.pixel(i);
            let lr = d.lch(r);
            if lr.chroma < MIN_CHROMA {
                return None;
            }
            let f = fixed.pixel(i);
            if f == r {
                return Some(0.0);
            }
            let lf = d.lch(f);
            Some((lf.hue - lr.hue).into_degrees().abs() as f32)
        })
        .collect();
    let mut values: Vec<f32> = angles.into_iter().flatten().collect();
    let n = values.len();
    let sum: f64 = values.iter().map(|&v| f64::from(v)).sum();
    let max = values.iter().copied().fold(0f32, f32::max);
    HueShift {
        smooth_pixels,
        pixels: n as u64,
        mean_deg: if n > 0 { sum / n as f64 } else { 0.0 },
        p99_deg: quantile(&mut values, 0.99),
        max_deg: f64::from(max),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// The smoothness test pixel by pixel over the whole clipped window (25 codes a channel).
    fn brute_force(img: &RgbCodes) -> Vec<bool> {
        let (w, h) = (img.width as i64, img.height as i64);
        let r = WINDOW_RADIUS as i64;
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                img.planes.iter().all(|p| {
                    let mut v = Vec::new();
                    for yy in (y - r).max(0)..=(y + r).min(h - 1) {
                        for xx in (x - r).max(0)..=(x + r).min(w - 1) {
                            v.push(p[(yy * w + xx) as usize]);
                        }
                    }
                    let (lo, hi) = (v.iter().min().unwrap(), v.iter().max().unwrap());
                    f64::from(hi - lo) <= SMOOTH_CODES
                })
            })
            .collect()
    }

    #[test]
    fn colour_smooth_mask_matches_the_whole_window() {
        let mut rng = Rng::new(7);
        let mut seen = [0usize; 2];
        for (w, h) in [(1, 1), (3, 2), (7, 9), (16, 5), (1, 12)] {
            let n = w * h;
            // Gentle random walks, so that both smooth and not smooth pixels occur.
            let planes: Vec<Vec<u16>> = (0..3)
                .map(|_| {
                    let mut c = 20i32;
                    (0..n)
                        .map(|_| {
                            c = (c + (rng.next_u64() % 3) as i32 - 1).clamp(0, 63);
                            c as u16
                        })
                        .collect()
                })
                .collect();
            let img = RgbCodes {
                planes: [&planes[0], &planes[1], &planes[2]],
                bits: [6, 6, 6],
                width: w as u32,
                height: h as u32,
            };
            let mask = smooth_mask(&img);
            assert_eq!(mask, brute_force(&img), "{w}x{h}");
            for m in mask {
                seen[usize::from(m)] += 1;
            }
        }
        assert!(
            seen[0] > 0 && seen[1] > 0,
            "smooth and not smooth pixels: {seen:?}"
        );
    }
}
