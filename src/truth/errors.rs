//! The errors against the truth, split three ways (total, algorithm, quantisation) and by
//! region (whole image, depth-edge band, interior), and the truth's own noise.

use super::frame::TruthFrame;
use crate::compare::DisplayModel;
use crate::config::HwConfig;
use crate::scene::Scene;
use crate::stage::accumulate::Frame;
use crate::stage::dof::{LensMap, depth_edge_band, half_size};
use crate::stage::gamma::{GammaSpec, apply_powers, powers};
use crate::stage::weber_of;
use serde::{Deserialize, Serialize};

/// DAC-code differences of an image against a reference over a set of pixels.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Diff {
    /// Pixels compared.
    pub pixels: u64,
    /// Fraction of identical codes, in `[0, 1]`.
    pub identical_fraction: f64,
    /// Mean |difference|, DAC codes.
    pub mean_abs: f64,
    /// Mean signed difference (image - reference), DAC codes.
    pub mean_signed: f64,
    /// Root mean square difference, DAC codes.
    pub rms: f64,
    /// Largest |difference|, DAC codes.
    pub max_abs: u32,
    /// Largest Weber fraction `|B - B_ref| / B_ref` of the displayed luminance.
    pub weber_max: f64,
    /// Mean Weber fraction.
    pub weber_mean: f64,
    /// Fraction of pixels whose Weber fraction exceeds the display's threshold (visible).
    pub weber_visible_fraction: f64,
}

/// A measure over the whole image, the depth-edge band and the interior.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Split<T> {
    /// Every pixel.
    pub whole: T,
    /// The pixels of the depth-edge band.
    pub edge: T,
    /// The other pixels.
    pub interior: T,
}

/// The size of a per-pixel standard error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Spread {
    /// Root mean square over the pixels.
    pub rms: f64,
    /// Largest.
    pub max: f64,
}

/// The truth's own noise: the per-pixel standard error of the lens average.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Noise {
    /// Interleaved groups the error is estimated from.
    pub groups: u32,
    /// In frame LSBs.
    pub frame_lsb: Split<Spread>,
    /// In DAC codes: half the float gamma curve's rise over the truth plus and minus one
    /// standard error (unrounded codes).
    pub dac: Split<Spread>,
}

impl Diff {
    /// `mean |diff| / RMS / max, mean Weber` as the reports show it (`0.412 / 0.700 /   5, 0.00123`).
    pub fn brief(&self) -> String {
        format!(
            "{:.3} / {:.3} / {:>3}, {:.5}",
            self.mean_abs, self.rms, self.max_abs, self.weber_mean
        )
    }
}

impl TruthReport {
    /// The lens points, the time and the truth's noise as the reports show them (`256 lens
    /// points (3288 ms) | noise (standard error, 8 groups): RMS ... DAC codes (... frame LSB),
    /// max ... codes`).
    pub fn summary(&self) -> String {
        let n = &self.noise;
        format!(
            "{} lens points ({:.0} ms{}) | noise (standard error, {} groups): RMS {:.4} DAC codes ({:.3} frame LSB), max {:.3} codes",
            self.lens_samples,
            self.ms,
            if self.reused { ", reused" } else { "" },
            n.groups,
            n.dac.whole.rms,
            n.frame_lsb.whole.rms,
            n.dac.whole.max
        )
    }

    /// The three-way split as the reports show it: (name, the part) for the total (fixed
    /// against the truth), the algorithm (float against the truth) and the quantisation
    /// (fixed against float).
    pub fn rows(&self) -> [(&'static str, &Split<Diff>); 3] {
        [
            ("total (fixed)", &self.total),
            ("algorithm (float)", &self.algorithm),
            ("quantisation", &self.quantisation),
        ]
    }
}

/// The `dof_truth` object of the render report.
#[derive(Clone, Debug, Serialize)]
pub struct TruthReport {
    /// Lens points averaged.
    pub lens_samples: u32,
    /// Wall time of the truth frame, ms (of the run that computed it).
    pub ms: f64,
    /// Whether the truth frame came from the cache (an earlier render of a sweep).
    pub reused: bool,
    /// Half-width of the depth-edge band, pixels: the mask half-size of the largest |sigma|
    /// in the frame.
    pub edge_band_px: usize,
    /// Pixels in the band.
    pub edge_pixels: u64,
    /// The truth's noise.
    pub noise: Noise,
    /// Fixed pipeline DAC codes against the truth's.
    pub total: Split<Diff>,
    /// Float reference pipeline DAC codes against the truth's (the method's approximation).
    pub algorithm: Split<Diff>,
    /// Fixed against float reference (the hardware's quantisation); per pixel
    /// `total = algorithm + quantisation` as signed code differences.
    pub quantisation: Split<Diff>,
}

/// The float gamma of the scene and hardware (no dither).
fn spec(scene: &Scene, hw: &HwConfig) -> GammaSpec {
    GammaSpec::of(scene, hw)
}

/// A frame (frame LSBs) through the float reference's gamma curve and DAC: the codes.
pub fn dac_codes(frame: &[f64], scene: &Scene, hw: &HwConfig) -> Vec<u16> {
    let s = spec(scene, hw);
    let p = powers(frame, hw, &s);
    let mut dac = vec![0u16; p.len()];
    apply_powers(&s, &p, &mut dac);
    dac
}

/// The truth's DAC codes for `hw`: its frame scaled to `hw`'s full white, through the float
/// reference's gamma curve and DAC (what [`assess`] compares with).
pub fn truth_dac(truth: &TruthFrame, scene: &Scene, hw: &HwConfig) -> Vec<u16> {
    dac_codes(&in_frame_lsb(&truth.mean, hw), scene, hw)
}

/// Values in units of full white (the truth's) in `hw`'s frame LSBs.
fn in_frame_lsb(v: &[f64], hw: &HwConfig) -> Vec<f64> {
    let white = super::frame_white(hw);
    v.iter().map(|x| x * white).collect()
}

/// The standard error `se` of `mean` (frame LSBs) in DAC codes: half the float gamma
/// curve's rise from `mean - se` to `mean + se`.
pub fn dac_error(mean: &[f64], se: &[f64], scene: &Scene, hw: &HwConfig) -> Vec<f64> {
    let s = spec(scene, hw);
    let shifted = |sign: f64| -> Vec<f64> {
        let f: Vec<f64> = mean.iter().zip(se).map(|(m, e)| m + sign * e).collect();
        powers(&f, hw, &s)
    };
    let (hi, lo) = (shifted(1.0), shifted(-1.0));
    hi.iter()
        .zip(&lo)
        .map(|(&a, &b)| (s.scale(a) - s.scale(b)) / 2.0)
        .collect()
}

/// The depth-edge band of the frame's depth and coverage and its half-width:
/// [`depth_edge_band`] with the mask half-size (`dof.k`) of the largest |sigma| among the
/// frame's depth codes (the background's included when it shows).
pub fn edge_band(scene: &Scene, hw: &HwConfig, frame: &Frame) -> (Vec<bool>, usize) {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let Some(lens) = LensMap::of(scene, hw, frame.height) else {
        return (vec![false; w * h], 0);
    };
    let mut keys = frame.depth.clone();
    keys.sort_unstable();
    keys.dedup();
    let max = keys
        .iter()
        .map(|&k| lens.sigma_f64(k).abs())
        .fold(0.0, f64::max);
    let r = half_size(max, hw.dof.k);
    let n2 = hw.raster.samples * hw.raster.samples;
    let band = depth_edge_band(w, h, &frame.depth, &frame.coverage, n2, &lens, r);
    (band, r)
}

/// The differences of `a` against the reference `b` over the pixels `keep` selects.
fn diff(a: &[u16], b: &[u16], keep: impl Fn(usize) -> bool, display: &DisplayModel) -> Diff {
    let lum = display.luminance_table();
    let mut d = Diff::default();
    let (mut same, mut sum_abs, mut sum, mut sq) = (0u64, 0.0, 0.0, 0.0);
    let mut pairs = Vec::new();
    for i in (0..a.len()).filter(|&i| keep(i)) {
        let x = i32::from(a[i]) - i32::from(b[i]);
        d.pixels += 1;
        same += u64::from(x == 0);
        sum_abs += f64::from(x.unsigned_abs());
        sum += f64::from(x);
        sq += f64::from(x) * f64::from(x);
        d.max_abs = d.max_abs.max(x.unsigned_abs());
        pairs.push((lum[a[i] as usize], lum[b[i] as usize]));
    }
    if d.pixels > 0 {
        let n = d.pixels as f64;
        d.identical_fraction = same as f64 / n;
        d.mean_abs = sum_abs / n;
        d.mean_signed = sum / n;
        d.rms = (sq / n).sqrt();
    }
    let w = weber_of(pairs.into_iter(), display.weber);
    d.weber_max = w.max;
    d.weber_mean = w.mean;
    d.weber_visible_fraction = w.over_delta_fraction;
    d
}

/// [`diff`] over the whole image, the band and the interior.
fn split(a: &[u16], b: &[u16], edge: &[bool], display: &DisplayModel) -> Split<Diff> {
    Split {
        whole: diff(a, b, |_| true, display),
        edge: diff(a, b, |i| edge[i], display),
        interior: diff(a, b, |i| !edge[i], display),
    }
}

/// The RMS and largest of `v` over the pixels `keep` selects.
fn spread(v: &[f64], keep: impl Fn(usize) -> bool) -> Spread {
    let (mut n, mut sq, mut max) = (0u64, 0.0, 0.0f64);
    for i in (0..v.len()).filter(|&i| keep(i)) {
        n += 1;
        sq += v[i] * v[i];
        max = max.max(v[i].abs());
    }
    Spread {
        rms: if n > 0 { (sq / n as f64).sqrt() } else { 0.0 },
        max,
    }
}

fn spread_split(v: &[f64], edge: &[bool]) -> Split<Spread> {
    Split {
        whole: spread(v, |_| true),
        edge: spread(v, |i| edge[i]),
        interior: spread(v, |i| !edge[i]),
    }
}

/// The images an assessment compares, row-major over the screen.
pub struct Images<'a> {
    /// The fixed pipeline's DAC codes.
    pub fixed: &'a [u16],
    /// The float reference pipeline's DAC codes.
    pub float: &'a [u16],
    /// The accumulate stage's frame (its depth and coverage give the depth-edge band).
    pub frame: &'a Frame,
}

/// The errors of the fixed and float pipelines against the truth, and the truth's noise.
pub fn assess(
    scene: &Scene,
    hw: &HwConfig,
    truth: &TruthFrame,
    reused: bool,
    img: &Images,
) -> TruthReport {
    let display = DisplayModel::new(&scene.display, hw.gamma.dac_bits);
    let (edge, r) = edge_band(scene, hw, img.frame);
    // The truth in this hardware's frame LSBs.
    let (mean, se) = (in_frame_lsb(&truth.mean, hw), in_frame_lsb(&truth.se, hw));
    let truth_dac = dac_codes(&mean, scene, hw);
    let dac_se = dac_error(&mean, &se, scene, hw);
    TruthReport {
        lens_samples: truth.lens_samples,
        ms: truth.ms,
        reused,
        edge_band_px: r,
        edge_pixels: edge.iter().filter(|&&e| e).count() as u64,
        noise: Noise {
            groups: super::GROUPS,
            frame_lsb: spread_split(&se, &edge),
            dac: spread_split(&dac_se, &edge),
        },
        total: split(img.fixed, &truth_dac, &edge, &display),
        algorithm: split(img.float, &truth_dac, &edge, &display),
        quantisation: split(img.fixed, img.float, &edge, &display),
    }
}
