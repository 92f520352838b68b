//! The per-pixel CIEDE2000 colour difference between the fixed and the reference image.

use super::{ColourDisplay, RgbCodes, check_pair, quantile};
use palette::color_difference::{Ciede2000, DeltaE as Cie76};
use rayon::prelude::*;
use serde::Serialize;

/// The just-noticeable colour difference, 2.3: measured by Mahy, Van Eycken and Oosterlinck
/// (1994, "Evaluation of uniform color spaces developed after the adoption of CIELAB and
/// CIELUV", Color Res. Appl. 19) and quoted by Sharma (2003, "Digital Color Imaging
/// Handbook", ch. 1) as the CIELAB JND. It was measured as a Euclidean `Delta E*ab` (CIE
/// 1976); applied to `Delta E_00` it is a conventional threshold (for saturated colours
/// `Delta E_00` is smaller than `Delta E*ab`, so fewer pixels pass it), which is why
/// [`DeltaE`] counts both.
pub const JND: f64 = 2.3;

/// Colour difference statistics of a fixed image against its reference.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct DeltaE {
    /// Pixels compared.
    pub pixels: u64,
    /// Mean CIEDE2000 `Delta E_00` over the pixels.
    pub mean: f64,
    /// The 99th percentile (nearest rank) of `Delta E_00`.
    pub p99: f64,
    /// Largest `Delta E_00` (of the map's values, as the 99th percentile).
    pub max: f64,
    /// Pixels with `Delta E_00 > 1` (about one just-noticeable difference of CIEDE2000).
    pub over_1: u64,
    /// Pixels with `Delta E_00 >` [`JND`] (2.3).
    pub over_jnd: u64,
    /// Pixels with `Delta E*ab >` [`JND`]: the Euclidean CIELAB difference the 2.3 was
    /// measured as.
    pub over_jnd_ab: u64,
    /// Per pixel, row-major: `Delta E_00` (0 exactly where the codes are equal).
    #[serde(skip)]
    pub map: Vec<f32>,
}

/// One row's sums, folded in row order (the result does not depend on the thread count).
#[derive(Clone, Copy, Default)]
struct RowStats {
    sum: f64,
    max: f32,
    over_1: u64,
    over_jnd: u64,
    over_jnd_ab: u64,
}

/// The per-pixel CIEDE2000 difference `Delta E_00` between the `fixed` image and its float
/// `reference` (rounded to the same DAC codes) on the display `d`, with its mean, 99th
/// percentile, maximum and the pixels over 1 and over [`JND`]. Panics if the two images
/// differ in size or their DAC widths are not the display's.
pub fn delta_e(fixed: &RgbCodes, reference: &RgbCodes, d: &ColourDisplay) -> DeltaE {
    check_pair(fixed, reference, d);
    let n = fixed.pixels();
    if n == 0 {
        return DeltaE::default();
    }
    let w = fixed.width as usize;
    let mut map = vec![0f32; n];
    let rows: Vec<RowStats> = map
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            let mut s = RowStats::default();
            for (x, out) in row.iter_mut().enumerate() {
                let i = y * w + x;
                let (f, r) = (fixed.pixel(i), reference.pixel(i));
                if f == r {
                    continue;
                }
                let (lf, lr) = (d.lab(f), d.lab(r));
                let e = lf.difference(lr);
                *out = e as f32;
                s.sum += e;
                s.max = s.max.max(*out);
                s.over_1 += u64::from(e > 1.0);
                s.over_jnd += u64::from(e > JND);
                s.over_jnd_ab += u64::from(lf.delta_e(lr) > JND);
            }
            s
        })
        .collect();
    let mut out = DeltaE {
        pixels: n as u64,
        ..Default::default()
    };
    let (mut sum, mut max) = (0.0, 0f32);
    for r in &rows {
        sum += r.sum;
        max = max.max(r.max);
        out.over_1 += r.over_1;
        out.over_jnd += r.over_jnd;
        out.over_jnd_ab += r.over_jnd_ab;
    }
    out.mean = sum / n as f64;
    out.max = f64::from(max);
    out.p99 = quantile(&mut map.clone(), 0.99);
    out.map = map;
    out
}
