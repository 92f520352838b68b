//! Perceptual metrics of a rendered image: visible contours (banding) through the display
//! model.
//!
//! **Definition.** For every pair of adjacent pixels `(p, p+e)` (`e` = one pixel right or
//! down) two side windows are compared: side A is the `L = 4` pixels ending at `p` along `e`,
//! side B the `L` pixels starting at `p+e`, both `2W+1 = 5` pixels wide across `e`. The eye is
//! modelled as averaging displayed luminance over each side (so a dither pattern finer than
//! the window is averaged away, as it is when viewed).
//! * The step is in a **smooth region** when the ideal (unquantised) DAC value of the float
//!   reference spans at most [`SMOOTH_CODES`] = 2 DAC codes over the whole `2L x (2W+1)`
//!   window: no edge of the scene is there, only shading.
//! * Its **excess step** is `|ln(A_out / B_out) - ln(A_ideal / B_ideal)|`: the luminance
//!   ratio across the step in the output, beyond the ratio the ideal image has there (the
//!   scene's own gradient is not a contour).
//! * A **visible contour step** is a smooth step whose excess exceeds `ln(1 + delta)` (the
//!   scene's Weber fraction) and is a local maximum along `e` (each contour line is counted
//!   once per pixel of its length, not once per window position).
//!
//! `contour_steps` counts such steps over both directions; `contour_pixels` the pixels on
//! either side of one.

use crate::compare::DisplayModel;
use rayon::prelude::*;
use serde::Serialize;

/// Half-length of a side window along the step, pixels.
pub const SIDE: usize = 4;
/// Half-width of a side window across the step, pixels (`2W+1` wide).
pub const HALF_WIDTH: usize = 2;
/// Largest span of the ideal DAC value over a window that is still "smooth", in DAC codes.
pub const SMOOTH_CODES: f64 = 2.0;

/// Contour report (part of every render report).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ContourReport {
    /// Weber fraction a step must exceed to be visible.
    pub delta: f64,
    /// Side window: length along the step and width across it, pixels.
    pub window: [usize; 2],
    /// Smooth-region threshold: span of the ideal DAC value over a window, codes.
    pub smooth_max_codes: f64,
    /// Adjacent-pixel steps in smooth regions.
    pub smooth_steps: u64,
    /// Visible contour steps of the fixed output.
    pub contour_steps: u64,
    /// Pixels next to a visible contour step (fixed output).
    pub contour_pixels: u64,
    /// Visible contour steps of the float reference's DAC codes (same metric).
    pub contour_steps_reference: u64,
}

impl ContourReport {
    /// Nothing counted yet, with the metric's settings (`delta` the display's Weber
    /// threshold).
    fn empty(delta: f64) -> Self {
        Self {
            delta,
            window: [SIDE, 2 * HALF_WIDTH + 1],
            smooth_max_codes: SMOOTH_CODES,
            ..Default::default()
        }
    }
}

/// The per-pixel result: contour mask of the fixed output.
pub struct Contours {
    /// The report.
    pub report: ContourReport,
    /// Per pixel: 0 not smooth, 1 smooth, 2 next to a visible contour step.
    pub map: Vec<u8>,
}

fn integral(v: impl Fn(usize) -> f64, w: usize, h: usize) -> Vec<f64> {
    let mut s = vec![0.0; (w + 1) * (h + 1)];
    for y in 0..h {
        let mut row = 0.0;
        for x in 0..w {
            row += v(y * w + x);
            s[(y + 1) * (w + 1) + x + 1] = s[y * (w + 1) + x + 1] + row;
        }
    }
    s
}

/// Sum over `[x0, x1) x [y0, y1)` of an integral image of width `w`.
#[inline]
fn rect(s: &[f64], w: usize, x0: usize, y0: usize, x1: usize, y1: usize) -> f64 {
    let w1 = w + 1;
    s[y1 * w1 + x1] - s[y0 * w1 + x1] - s[y1 * w1 + x0] + s[y0 * w1 + x0]
}

/// Sliding (minimum, maximum) of `v` over `n` elements at stride `stride`: `out[p]` covers
/// `v[p], v[p + stride], ..., v[p + (n-1) stride]` (fewer past the end of `v`).
fn sliding_min_max(v: &[(f64, f64)], n: usize, stride: usize) -> Vec<(f64, f64)> {
    (0..v.len())
        .map(|p| {
            let mut m = (f64::MAX, f64::MIN);
            for &(lo, hi) in v[p..].iter().step_by(stride).take(n) {
                m = (m.0.min(lo), m.1.max(hi));
            }
            m
        })
        .collect()
}

/// The excess factors `exp(excess) >= 1` of the two outputs (integral images `so`) at the
/// pair whose first pixel is `(x, y)` along one direction (`horizontal`: `(x, y)-(x+1, y)`);
/// `None` where the window leaves the image or is not smooth.
#[inline]
fn excess_at(
    (x, y): (usize, usize),
    so: [&[f64]; 2],
    ideal: &WholeIdeal,
    max_code: f64,
    horizontal: bool,
) -> Option<[f64; 2]> {
    let (w, h) = (ideal.width, ideal.height);
    let d = usize::from(!horizontal);
    let (ra, rb) = step_windows(x, y, (w, h), horizontal)?;
    // Smoothness of the ideal signal over the whole window, in DAC codes (scaling commutes
    // with min and max: this is the span of the ideal codes themselves).
    let (lo, hi) = ideal.span[d][ra.1 * w + ra.0];
    if hi * max_code - lo * max_code > SMOOTH_CODES {
        return None;
    }
    // |ln(A_out / B_out) - ln(A_ideal / B_ideal)| = ln(max(q, 1/q)) with q the ratio of the
    // two ratios; kept as max(q, 1/q) (ln is monotone), so one division per output instead
    // of two logarithms; the caller compares with exp(threshold).
    let ideal = ideal.ratio[d][y * w + x];
    Some(so.map(|s| {
        let o = rect(s, w, ra.0, ra.1, ra.2, ra.3) / rect(s, w, rb.0, rb.1, rb.2, rb.3);
        let q = o / ideal;
        q.max(1.0 / q)
    }))
}

/// What the contour metric needs of the ideal (float reference, unquantised) image, none of
/// it depending on the DAC width: its normalised values (`powers`, shared with the gamma
/// stage's float reference) and the display's luminance curve. Built once per gamma
/// exponent and shared by every DAC width and dither of a sweep; [`contours`] derives the
/// integral image and the windows' spans from it band by band of rows, so the metric holds
/// a few rows of planes, not the screen's.
pub struct IdealImage {
    width: usize,
    height: usize,
    powers: std::sync::Arc<Vec<f64>>,
    b_min: f64,
    b_max: f64,
    gamma: f64,
    /// The whole-image planes, built once for a screen of at most [`WHOLE_MAX`] pixels
    /// (faster, and shared by every DAC width of a sweep).
    whole: Option<WholeIdeal>,
}

/// Pixels up to which the contour metric keeps whole-image planes (about 90 bytes per
/// pixel); a larger screen is measured band by band.
pub const WHOLE_MAX: usize = 1 << 20;

impl IdealImage {
    /// From the ideal values normalised to [0, 1] of full scale (`powers`: the float
    /// frame through the gamma curve, before the DAC scale) on a `width x height` image.
    pub fn new(
        powers: std::sync::Arc<Vec<f64>>,
        display: &DisplayModel,
        width: u32,
        height: u32,
    ) -> Self {
        let whole = (width as usize * height as usize <= WHOLE_MAX)
            .then(|| WholeIdeal::new(&powers, display, width, height));
        Self {
            width: width as usize,
            height: height as usize,
            powers,
            b_min: display.b_min,
            b_max: display.b_max,
            gamma: display.gamma,
            whole,
        }
    }

    /// Displayed luminance of pixel `i`.
    #[inline]
    fn lum(&self, i: usize) -> f64 {
        self.b_min + (self.b_max - self.b_min) * self.powers[i].powf(self.gamma)
    }
}

/// Rows `first..` of an integral image of width `w` (row `r` sums the pixel rows before
/// `r`), computed row after row exactly as the whole-image one.
struct Integral {
    w: usize,
    first: usize,
    rows: Vec<f64>,
}

impl Integral {
    fn new(w: usize) -> Self {
        Self {
            w,
            first: 0,
            rows: vec![0.0; w + 1],
        }
    }
    fn last(&self) -> usize {
        self.first + self.rows.len() / (self.w + 1) - 1
    }
    /// Keeps the rows from `lo` (at least the last) and computes them up to `hi`.
    fn advance(&mut self, lo: usize, hi: usize, v: impl Fn(usize) -> f64) {
        let w1 = self.w + 1;
        let lo = lo.min(self.last());
        if lo > self.first {
            self.rows.drain(..(lo - self.first) * w1);
            self.first = lo;
        }
        while self.last() < hi {
            let y = self.last();
            let up = self.rows.len() - w1;
            self.rows.push(0.0);
            let mut row = 0.0;
            for x in 0..self.w {
                row += v(y * self.w + x);
                let s = self.rows[up + x + 1] + row;
                self.rows.push(s);
            }
        }
    }
    /// Sum over `[x0, x1) x [y0, y1)` (as [`rect`]).
    #[inline]
    fn rect(&self, x0: usize, y0: usize, x1: usize, y1: usize) -> f64 {
        let w1 = self.w + 1;
        let at = |y: usize, x: usize| self.rows[(y - self.first) * w1 + x];
        at(y1, x1) - at(y0, x1) - at(y1, x0) + at(y0, x0)
    }
}

/// Pixel rows per band of the banded contour metric.
const BAND: usize = 64;

/// Minimum and maximum of `v` over `n` elements from `p` at `stride`.
#[inline]
fn min_max(v: &[f64], p: usize, n: usize, stride: usize) -> (f64, f64) {
    let mut m = (f64::MAX, f64::MIN);
    for &x in v[p..].iter().step_by(stride).take(n) {
        m = (m.0.min(x), m.1.max(x));
    }
    m
}

/// Measures visible contours of `dac` (and of `dac_ref`) against the ideal image: on the
/// whole-image planes for a screen of at most [`WHOLE_MAX`] pixels, else band by band of
/// rows ([`contours_banded`]; the same result, tested).
pub fn contours(
    dac: &[u16],
    dac_ref: &[u16],
    ideal: &IdealImage,
    display: &DisplayModel,
) -> Contours {
    match &ideal.whole {
        Some(w) => contours_whole(dac, dac_ref, w, display),
        None => contours_banded(dac, dac_ref, ideal, display),
    }
}

/// [`contours`] band by band of rows (the same steps, excesses and map as
/// [`contours_whole`], tested), holding a few rows of planes, not the screen's.
pub fn contours_banded(
    dac: &[u16],
    dac_ref: &[u16],
    ideal: &IdealImage,
    display: &DisplayModel,
) -> Contours {
    let (w, h) = (ideal.width, ideal.height);
    let (l, hw) = (SIDE, HALF_WIDTH);
    let table = display.luminance_table();
    let thr = 1.0 + display.weber;
    let max_code = display.max_code;
    let mut rep = ContourReport::empty(display.weber);
    let mut map = vec![0u8; w * h];
    let mut si = Integral::new(w);
    let mut sf = Integral::new(w);
    let mut sr = Integral::new(w);
    let pw = &ideal.powers[..];
    let mut y0 = 0;
    while y0 < h {
        let y1 = (y0 + BAND).min(h);
        // Excesses of the band's rows and the rows either side (the local-maximum test).
        let (e0, e1) = (y0.saturating_sub(1), (y1 + 1).min(h));
        let lo = e0.saturating_sub(hw.max(l - 1));
        let hi = (e1 + hw.max(l) + 1).min(h);
        si.advance(lo, hi, |i| ideal.lum(i));
        sf.advance(lo, hi, |i| table[dac[i] as usize]);
        sr.advance(lo, hi, |i| table[dac_ref[i] as usize]);
        let rows: Vec<[Vec<[Option<f64>; 2]>; 2]> = (e0..e1)
            .into_par_iter()
            .map(|y| {
                [true, false].map(|horizontal| {
                    (0..w)
                        .map(|x| {
                            let Some((ra, rb)) = step_windows(x, y, (w, h), horizontal) else {
                                return [None; 2];
                            };
                            // The span over the 2L x (2W+1) window, along then across.
                            let (along, across) = if horizontal { (1, w) } else { (w, 1) };
                            let q = ra.1 * w + ra.0;
                            let mut m = (f64::MAX, f64::MIN);
                            for c in 0..2 * hw + 1 {
                                let s = min_max(pw, q + c * across, 2 * l, along);
                                m = (m.0.min(s.0), m.1.max(s.1));
                            }
                            let (lo, hi) = m;
                            if hi * max_code - lo * max_code > SMOOTH_CODES {
                                return [None; 2];
                            }
                            let ideal =
                                si.rect(ra.0, ra.1, ra.2, ra.3) / si.rect(rb.0, rb.1, rb.2, rb.3);
                            [&sf, &sr].map(|s| {
                                let o =
                                    s.rect(ra.0, ra.1, ra.2, ra.3) / s.rect(rb.0, rb.1, rb.2, rb.3);
                                let q = o / ideal;
                                Some(q.max(1.0 / q))
                            })
                        })
                        .collect()
                })
            })
            .collect();
        for (d, horizontal) in [true, false].into_iter().enumerate() {
            let ex = |x: usize, y: usize| -> &[Option<f64>; 2] { &rows[y - e0][d][x] };
            let get = |x: Option<usize>, y: Option<usize>, k: usize| match (x, y) {
                (Some(x), Some(y)) if x < w && y >= e0 && y < e1 => ex(x, y)[k],
                _ => None,
            };
            for y in y0..y1 {
                for x in 0..w {
                    let e = ex(x, y);
                    if e[0].is_none() {
                        continue;
                    }
                    let p = y * w + x;
                    rep.smooth_steps += 1;
                    map[p] = map[p].max(1);
                    let (prev, next) = if horizontal {
                        ((x.checked_sub(1), Some(y)), (Some(x + 1), Some(y)))
                    } else {
                        ((Some(x), y.checked_sub(1)), (Some(x), Some(y + 1)))
                    };
                    for (k, v) in e.iter().enumerate() {
                        let v = v.unwrap_or(1.0);
                        if v > thr
                            && get(prev.0, prev.1, k).is_none_or(|u| v >= u)
                            && get(next.0, next.1, k).is_none_or(|u| v > u)
                        {
                            if k == 0 {
                                rep.contour_steps += 1;
                                map[p] = 2;
                                map[if horizontal { p + 1 } else { p + w }] = 2;
                            } else {
                                rep.contour_steps_reference += 1;
                            }
                        }
                    }
                }
            }
        }
        y0 = y1;
    }
    rep.contour_pixels = map.iter().filter(|&&m| m == 2).count() as u64;
    Contours { report: rep, map }
}

/// The whole-image form of the contour metric's inputs (the spans of every window and the
/// ideal luminance ratio across every step, 48 bytes per pixel plus 40 while it is built):
/// the reference [`contours_banded`] is tested against.
pub struct WholeIdeal {
    width: usize,
    height: usize,
    /// Per direction (along x, along y), indexed by the pair's first pixel: `A_ideal /
    /// B_ideal`, the ideal luminance ratio of the two side windows (0 where they leave the
    /// image).
    ratio: [Vec<f64>; 2],
    span: [Vec<(f64, f64)>; 2],
}

impl WholeIdeal {
    /// From the ideal values normalised to [0, 1] of full scale (`powers`: the float
    /// frame through the gamma curve, before the DAC scale) on a `width x height` image.
    pub fn new(powers: &[f64], display: &DisplayModel, width: u32, height: u32) -> Self {
        let (w, h) = (width as usize, height as usize);
        let lum_integral = integral(
            |i| display.b_min + (display.b_max - display.b_min) * powers[i].powf(display.gamma),
            w,
            h,
        );
        // The span over every 2L x (2W+1) window, separably: along the step, then across
        // it. `span[d][q]` covers the window whose first corner (smallest x, y) is q.
        let pairs: Vec<(f64, f64)> = powers.iter().map(|&v| (v, v)).collect();
        let (l, hw) = (SIDE, HALF_WIDTH);
        let span = [(1, w), (w, 1)].map(|(along, across)| {
            sliding_min_max(&sliding_min_max(&pairs, 2 * l, along), 2 * hw + 1, across)
        });
        let si = &lum_integral;
        let ratio = [true, false].map(|horizontal| {
            (0..w * h)
                .into_par_iter()
                .map(|p| match step_windows(p % w, p / w, (w, h), horizontal) {
                    Some((a, b)) => {
                        rect(si, w, a.0, a.1, a.2, a.3) / rect(si, w, b.0, b.1, b.2, b.3)
                    }
                    None => 0.0,
                })
                .collect()
        });
        Self {
            width: w,
            height: h,
            ratio,
            span,
        }
    }
}

/// Pixel rows per chunk of [`contours_whole`] (each chunk also computes the excesses of
/// the row either side, for the local-maximum test across rows).
const CHUNK: usize = 32;

/// Per-pixel flags of [`contours_whole`]: a smooth step starts at the pixel, a visible
/// contour step of the fixed output starts there along x, along y.
const SMOOTH: u8 = 1;
const CONTOUR_X: u8 = 2;
const CONTOUR_Y: u8 = 4;

/// [`contours`] computed on whole-image integral images and window spans (the reference of
/// the banded form; about 60 bytes per pixel). Chunks of [`CHUNK`] rows run in parallel,
/// each holding the excesses of its rows (and one row either side) only.
pub fn contours_whole(
    dac: &[u16],
    dac_ref: &[u16],
    ideal: &WholeIdeal,
    display: &DisplayModel,
) -> Contours {
    let (w, h) = (ideal.width, ideal.height);
    let table = display.luminance_table();
    let (sf, sr) = rayon::join(
        || integral(|i| table[dac[i] as usize], w, h),
        || integral(|i| table[dac_ref[i] as usize], w, h),
    );
    // Excess steps are kept as luminance-ratio factors >= 1 (see `excess_at`); a missing
    // one (not smooth, or the window leaves the image) as -inf, below every factor.
    let thr = 1.0 + display.weber;
    let so = [&sf[..], &sr[..]];
    let mut flags = vec![0u8; w * h];
    let chunk = CHUNK * w.max(1);
    let zero = || (0u64, 0u64, 0u64);
    let (smooth, steps, steps_ref) = flags
        .par_chunks_mut(chunk)
        .enumerate()
        .map_init(Vec::new, |ex: &mut Vec<[f64; 2]>, (ci, fl)| {
            let (y0, y1) = (ci * CHUNK, (ci * CHUNK + CHUNK).min(h));
            let (e0, e1) = (y0.saturating_sub(1), (y1 + 1).min(h));
            let n = (e1 - e0) * w;
            ex.clear();
            ex.resize(2 * n, [f64::NEG_INFINITY; 2]);
            for (d, horizontal) in [true, false].into_iter().enumerate() {
                for y in e0..e1 {
                    for x in 0..w {
                        if let Some(e) = excess_at((x, y), so, ideal, display.max_code, horizontal)
                        {
                            ex[d * n + (y - e0) * w + x] = e;
                        }
                    }
                }
            }
            let mut count = zero();
            for (d, horizontal) in [true, false].into_iter().enumerate() {
                let at = |x: usize, y: usize| &ex[d * n + (y - e0) * w + x];
                let flag = if horizontal { CONTOUR_X } else { CONTOUR_Y };
                for y in y0..y1 {
                    for x in 0..w {
                        let e = at(x, y);
                        if e[0] == f64::NEG_INFINITY {
                            continue;
                        }
                        count.0 += 1;
                        fl[(y - y0) * w + x] |= SMOOTH;
                        // The neighbours along the direction (none outside the image).
                        let (prev, next) = if horizontal {
                            (
                                x.checked_sub(1).map(|x| at(x, y)),
                                (x + 1 < w).then(|| at(x + 1, y)),
                            )
                        } else {
                            (
                                y.checked_sub(1).map(|y| at(x, y)),
                                (y + 1 < h).then(|| at(x, y + 1)),
                            )
                        };
                        for k in 0..2 {
                            let v = e[k];
                            if v > thr
                                && prev.is_none_or(|u| v >= u[k])
                                && next.is_none_or(|u| v > u[k])
                            {
                                if k == 0 {
                                    count.1 += 1;
                                    fl[(y - y0) * w + x] |= flag;
                                } else {
                                    count.2 += 1;
                                }
                            }
                        }
                    }
                }
            }
            count
        })
        .reduce(zero, |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
    // The map: a pixel is next to a contour step that starts at it or at the pixel before
    // it along x or y.
    let mut map = vec![0u8; w * h];
    map.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            for (x, m) in row.iter_mut().enumerate() {
                let p = y * w + x;
                let f = flags[p];
                let near = f & (CONTOUR_X | CONTOUR_Y) != 0
                    || (x > 0 && flags[p - 1] & CONTOUR_X != 0)
                    || (y > 0 && flags[p - w] & CONTOUR_Y != 0);
                *m = if near { 2 } else { f & SMOOTH };
            }
        });
    let mut rep = ContourReport::empty(display.weber);
    rep.smooth_steps = smooth;
    rep.contour_steps = steps;
    rep.contour_steps_reference = steps_ref;
    rep.contour_pixels = map.iter().filter(|&&m| m == 2).count() as u64;
    Contours { report: rep, map }
}

/// The banding-map image (8-bit grey): the output dimmed to 0..=100, smooth regions lifted by
/// 20 grey levels, pixels next to a visible contour step white.
pub fn banding_image(dac: &[u16], map: &[u8], max_code: u32) -> Vec<u8> {
    dac.iter()
        .zip(map)
        .map(|(&c, &m)| match m {
            2 => 255,
            1 => 20 + (c as u32 * 100 / max_code.max(1)) as u8,
            _ => (c as u32 * 100 / max_code.max(1)) as u8,
        })
        .collect()
}

/// A window `(x0, y0, x1, y1)`, exclusive.
type Rect = (usize, usize, usize, usize);

/// The two `L`-pixel windows either side of pixel `(x, y)` along an axis (`horizontal`: along
/// x), `2W + 1` pixels across; `None` where they leave the `w x h` image.
fn step_windows(
    x: usize,
    y: usize,
    (w, h): (usize, usize),
    horizontal: bool,
) -> Option<(Rect, Rect)> {
    let (l, hw) = (SIDE, HALF_WIDTH);
    // Along-axis coordinate a, across-axis b.
    let (a, b, na, nb) = if horizontal {
        (x, y, w, h)
    } else {
        (y, x, h, w)
    };
    if a + 1 < l || a + l >= na || b < hw || b + hw >= nb {
        return None;
    }
    let (a0, a1, a2) = (a + 1 - l, a + 1, a + 1 + l);
    let (b0, b1) = (b - hw, b + hw + 1);
    let r = |a0: usize, a1: usize| {
        if horizontal {
            (a0, b0, a1, b1)
        } else {
            (b0, a0, b1, a1)
        }
    };
    Some((r(a0, a1), r(a1, a2)))
}
