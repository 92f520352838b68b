//! Float reference (2) and error measures: the per-pixel scatter filter, the theorem's
//! additive layered form, the depth-edge band and the errors of an image against a reference.

use super::kernel::{disc_f64, kernel_taps_f64};
use super::layers::{DepthImage, LayerPlan};
use super::lens::LensMap;
use super::mask::difference_degree;
use crate::config::DofKernel;
use crate::stage::LocalError;
use serde::Serialize;

/// Scatters `v` at `(px, py)` with separable taps, restricted to the image and renormalised.
#[inline]
fn scatter(out: &mut [f64], w: usize, h: usize, px: usize, py: usize, v: f64, c: &[f64]) {
    let m = (c.len() / 2) as i64;
    let (xa, xb) = ((px as i64 - m).max(0), (px as i64 + m).min(w as i64 - 1));
    let (ya, yb) = ((py as i64 - m).max(0), (py as i64 + m).min(h as i64 - 1));
    let sx: f64 = (xa..=xb).map(|x| c[(x - px as i64 + m) as usize]).sum();
    let sy: f64 = (ya..=yb).map(|y| c[(y - py as i64 + m) as usize]).sum();
    let v = v / (sx * sy);
    for y in ya..=yb {
        let vy = v * c[(y - py as i64 + m) as usize];
        let row = &mut out[y as usize * w..];
        for x in xa..=xb {
            row[x as usize] += vy * c[(x - px as i64 + m) as usize];
        }
    }
}

/// Scatters `v` at `(px, py)` with the 2-D weights `c` (odd square side), restricted to the
/// image and renormalised.
fn scatter2(out: &mut [f64], w: usize, h: usize, px: usize, py: usize, v: f64, c: &[f64]) {
    let n = (c.len() as f64).sqrt().round() as usize;
    let m = (n / 2) as i64;
    let (xa, xb) = ((px as i64 - m).max(0), (px as i64 + m).min(w as i64 - 1));
    let (ya, yb) = ((py as i64 - m).max(0), (py as i64 + m).min(h as i64 - 1));
    let tap = |x: i64, y: i64| c[(y - py as i64 + m) as usize * n + (x - px as i64 + m) as usize];
    let mut s = 0.0;
    for y in ya..=yb {
        for x in xa..=xb {
            s += tap(x, y);
        }
    }
    let v = v / s;
    for y in ya..=yb {
        let row = &mut out[y as usize * w..];
        for x in xa..=xb {
            row[x as usize] += v * tap(x, y);
        }
    }
}

/// A pixel's own mask: separable taps, or the disc's 2-D weights.
enum Own {
    Taps(Vec<f64>),
    Disc(Vec<f64>),
}

/// Float reference (2): the per-pixel scatter filter. Every pixel spreads its value with the
/// `dof.kernel` mask of its own depth (`sigma` = exact float sigma of its depth code), energy
/// preserving.
pub fn per_pixel_scatter(
    img: &DepthImage<f64>,
    lens: &LensMap,
    k: f64,
    kernel: DofKernel,
) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let mut out = vec![0.0; w * h];
    let mut cache: std::collections::HashMap<u32, Own> = Default::default();
    for y in 0..h {
        for x in 0..w {
            let pi = y * w + x;
            let own = cache.entry(img.key[pi]).or_insert_with(|| {
                let s = lens.sigma_f64(img.key[pi]);
                match kernel {
                    DofKernel::Disc => Own::Disc(disc_f64(s)),
                    _ => Own::Taps(kernel_taps_f64(kernel, s, k)),
                }
            });
            match own {
                Own::Taps(c) => scatter(&mut out, w, h, x, y, img.value[pi], c),
                Own::Disc(c) => scatter2(&mut out, w, h, x, y, img.value[pi], c),
            }
        }
    }
    out
}

/// The theorem's form: every pixel spread (energy preserving) with its layer's middle mask,
/// summed, no compositing. `quantised` uses the fixed coefficients (`coef / 2^f`).
pub fn additive_layered(
    img: &DepthImage<f64>,
    plan: &LayerPlan,
    coef_bits: u32,
    quantised: bool,
) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let taps: Vec<Own> = plan
        .layers
        .iter()
        .map(|l| match (&l.disc, quantised) {
            (Some(d), true) => Own::Disc(
                d.w.iter()
                    .map(|&c| c as f64 / (1u64 << (2 * coef_bits)) as f64)
                    .collect(),
            ),
            (Some(d), false) => Own::Disc(d.wf.clone()),
            (None, true) => Own::Taps(
                l.coef
                    .iter()
                    .map(|&c| c as f64 / (1u64 << coef_bits) as f64)
                    .collect(),
            ),
            (None, false) => Own::Taps(l.coef_f.clone()),
        })
        .collect();
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let pi = y * w + x;
            let v = img.value[pi];
            match &taps[plan.index[pi] as usize] {
                Own::Taps(c) => scatter(&mut out, w, h, x, y, v, c),
                Own::Disc(c) => scatter2(&mut out, w, h, x, y, v, c),
            }
        }
    }
    out
}

/// Pixels within `r` of a pixel of another layer (the depth-edge band of a layer plan).
pub fn edge_band(w: usize, h: usize, index: &[u16], r: usize) -> Vec<bool> {
    let mut edge = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let l = index[y * w + x];
            let right = x + 1 < w && index[y * w + x + 1] != l;
            let down = y + 1 < h && index[(y + 1) * w + x] != l;
            if right || down {
                edge[y * w + x] = true;
            }
        }
    }
    dilate(&edge, w, h, r)
}

/// The depth-edge band of a frame, the same for every method: pixels within `r` of a
/// depth edge, where a depth edge is a partly covered pixel (a silhouette) or a pixel whose
/// blur differs by more than one pixel from its right or lower neighbour's (`|sigma|` of the
/// depth codes, the background at infinity).
pub fn depth_edge_band(
    w: usize,
    h: usize,
    key: &[u32],
    cov: &[u16],
    n2: u32,
    lens: &LensMap,
    r: usize,
) -> Vec<bool> {
    let sigma: Vec<f64> = key.iter().map(|&k| lens.sigma_f64(k)).collect();
    let mut edge = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let partial = cov[i] > 0 && u32::from(cov[i]) < n2;
            let right = x + 1 < w && (sigma[i] - sigma[i + 1]).abs() > 1.0;
            let down = y + 1 < h && (sigma[i] - sigma[i + w]).abs() > 1.0;
            edge[i] = partial || right || down;
        }
    }
    dilate(&edge, w, h, r)
}

/// `edge` dilated by `r` pixels (a square window), separably.
fn dilate(edge: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    let mut tmp = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (x.saturating_sub(r), (x + r + 1).min(w));
            tmp[y * w + x] = edge[y * w + a..y * w + b].iter().any(|&e| e);
        }
    }
    let mut out = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (y.saturating_sub(r), (y + r + 1).min(h));
            out[y * w + x] = (a..b).any(|yy| tmp[yy * w + x]);
        }
    }
    out
}

/// Error of an image against a reference, overall and split into depth-edge band and interior.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RegionError {
    /// Difference degree over the whole image.
    pub difference_degree: f64,
    /// Largest |a - b| (frame LSBs).
    pub max_abs: f64,
    /// Mean |a - b| (frame LSBs).
    pub mean_abs: f64,
    /// Pixels in the depth-edge band.
    pub edge_pixels: u64,
    /// Difference degree inside the depth-edge band.
    pub edge_difference_degree: f64,
    /// Largest |a - b| in the band.
    pub edge_max_abs: f64,
    /// Difference degree in the interior.
    pub interior_difference_degree: f64,
    /// Largest |a - b| in the interior.
    pub interior_max_abs: f64,
}

/// Compares `a` with the reference `b` overall and by region.
pub fn region_error(a: &[f64], b: &[f64], edge: &[bool]) -> RegionError {
    let mut r = RegionError {
        difference_degree: difference_degree(a, b),
        ..Default::default()
    };
    let (mut ed, mut es, mut id, mut is) = (0.0, 0.0, 0.0, 0.0);
    let mut sum = 0.0;
    for i in 0..a.len() {
        let d = (a[i] - b[i]).abs();
        sum += d;
        r.max_abs = r.max_abs.max(d);
        if edge[i] {
            r.edge_pixels += 1;
            ed += d;
            es += a[i].abs() + b[i].abs();
            r.edge_max_abs = r.edge_max_abs.max(d);
        } else {
            id += d;
            is += a[i].abs() + b[i].abs();
            r.interior_max_abs = r.interior_max_abs.max(d);
        }
    }
    if !a.is_empty() {
        r.mean_abs = sum / a.len() as f64;
    }
    r.edge_difference_degree = if es > 0.0 { ed / es } else { 0.0 };
    r.interior_difference_degree = if is > 0.0 { id / is } else { 0.0 };
    r
}

/// Stage-local comparison of fixed codes with a float image in the same units.
pub fn local_error(fixed: &[u32], float: &[f64], max: f64) -> LocalError {
    let mut e = LocalError::default();
    for (&a, &b) in fixed.iter().zip(float) {
        e.add(a as f64, b.min(max));
    }
    e.finish()
}

/// Weber error of linear frame intensities through the display (the gamma LUT makes the
/// displayed luminance linear in the frame code: `B = B_min + (B_max - B_min) v / white`).
pub fn weber_linear(
    a: &[f64],
    b: &[f64],
    white: f64,
    d: &crate::scene::Display,
) -> crate::stage::WeberCompare {
    let (lo, hi) = (d.b_min(), d.b_max);
    let lum = |v: f64| lo + (hi - lo) * (v / white).clamp(0.0, 1.0);
    crate::stage::weber_of(a.iter().zip(b).map(|(&x, &y)| (lum(x), lum(y))), d.weber)
}
