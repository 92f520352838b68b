//! Log-domain intensity coding (Kovalev & Tokarev, REFERENCE.md §1, eq. 11-15, Fig. 7).
//!
//! **The code.** A sample's linear intensity `x` in [0, 1] (fraction of full white) is shown
//! with luminance `B = B_min (1 + (K - 1) x)`, so `B / B_min = K^I` with
//! `I = log_K(1 + (K - 1) x)` in [0, 1] (eq. 13). The `b`-bit log code holds `c = round(G I)`
//! with `G = 2^b - 1` grades over the contrast range: adjacent codes differ in luminance by
//! `K^(1/G)`, which is below `1 + delta` whenever `G >= m = ln K / ln(1 + delta)` (eq. 11).
//! Code 0 is exactly black (`x = 0`, `B = B_min`): the explicit zero of the linear intensity;
//! an intensity below half the first grade rounds to it.
//!
//! **Where it sits.** The raster keeps interpolating linear intensity; the per-sample value is
//! encoded to the log code where the sample is stored (the sample buffer is what the narrow
//! code saves). The encoder is a comparator search over `G` thresholds ([`LogEncoder`]).
//!
//! * Structure (a), `log-potentiate`: a potentiation LUT turns the log code into a linear
//!   code `W (K^I - 1)/(K - 1)` (`W` = full white of the linear frame, data width = the
//!   frame's integer bits); the spine's linear accumulate and gamma LUT follow unchanged.
//! * Structure (b), `log-add`: each sample's term `S K^I` (relative luminance weighted by
//!   the filter weight) is formed in log code by an adder, `I + log_K S` (the weight ROM holds
//!   `log_K S`); terms are accumulated by the Gaussian-logarithm adder
//!   `log(a + b) = max + sb(|la - lb|)`, `sb(d) = log_K(1 + K^-d)`, into a log-coded frame
//!   memory; the gamma LUT of eq. 15, `V = ((K^I - 1)/(K - 1))^(1/gamma)`, follows. With an
//!   equal-energy filter the weights sum to 1, so the sum is exactly the pixel's
//!   `B / B_min = K^(I_F)` and the frame code is the pixel's log intensity. No multiplier.
//!
//! **Frame log word (b).** Unsigned; code 0 = zero (empty sum); code `a >= 1` holds
//! `L = (a - off) / (G 2^fa)` with `fa` = `coding.acc_frac_bits` extra fraction bits and `off`
//! chosen so the smallest term (smallest nonzero filter weight times black, `log_K(w_min/2^f)`)
//! is code >= 1. Full scale is full white (`L = 1`, code `off + G 2^fa`); sums above it
//! saturate (light points can exceed white).
//!
//! **sb table.** `2^A` entries (`A` = `coding.table_addr_bits`, 4..=16) of `sb` in frame LSBs
//! with `coding.table_frac_bits` (0..=12) extra fraction bits (data width = the integer bits
//! of `sb(0)` plus those). The address is `d >> s` with the smallest `s` such that the table
//! reaches sb's essential zero (the first `d` where `sb` rounds to 0 in the data LSB); past
//! it `sb = 0`. Direct lookup rounds `d` to the nearest entry; linear interpolation uses
//! `s` low bits of `d` (one small multiplier, counted in the cost). The sum is rounded half up
//! to the frame LSB.
//!
//! The float references are exact f64: `K^I`, `log_K` and sums with the exact quantised
//! inputs for the stage-local errors; end to end every coding is compared against the same
//! float image the spine computes (linear intensities, exact weights, no rounding).

use super::gamma::GammaSpec;
use super::{Cost, LocalError, Unit};
use crate::compare::DisplayModel;
use crate::config::{CodingCfg, CodingKind};
use serde::Serialize;

/// Checks a contrast for log coding.
pub fn check_contrast(k: f64) -> std::result::Result<(), String> {
    if k.is_finite() && k > 1.0 {
        Ok(())
    } else {
        Err(format!(
            "contrast K = {k}: log coding needs a finite K > 1 (log base)"
        ))
    }
}

/// The sample log code: `G = 2^bits - 1` grades of `log_K` over [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogCode {
    /// Contrast K (the log base).
    pub k: f64,
    /// Code width.
    pub bits: u32,
}

impl LogCode {
    /// Grades `G` (largest code = full white).
    pub fn grades(&self) -> u32 {
        (1u32 << self.bits) - 1
    }
    /// Exact log intensity `I = log_K(1 + (K - 1) x)` of a linear intensity `x` in [0, 1].
    pub fn log_of_linear(&self, x: f64) -> f64 {
        (1.0 + (self.k - 1.0) * x.clamp(0.0, 1.0)).ln() / self.k.ln()
    }
    /// Exact linear intensity `(K^I - 1)/(K - 1)` of a log intensity `I`.
    pub fn linear_of_log(&self, i: f64) -> f64 {
        (self.k.powf(i) - 1.0) / (self.k - 1.0)
    }
    /// Luminance ratio of adjacent codes, `K^(1/G)`.
    pub fn step_ratio(&self) -> f64 {
        self.k.powf(1.0 / self.grades() as f64)
    }
}

/// Linear intensity code to log code by integer comparison with `G` thresholds.
#[derive(Clone, Debug)]
pub struct LogEncoder {
    /// The code.
    pub code: LogCode,
    /// `thresholds[c - 1]`: smallest linear code that encodes to `c` or more.
    pub thresholds: Vec<u64>,
    /// Width of the linear input code.
    pub in_bits: u32,
}

impl LogEncoder {
    /// Builds the thresholds for a linear input whose full white is `white` (an integer code)
    /// in an `in_bits`-wide word: `T_c = ceil(white (K^((c - 1/2)/G) - 1)/(K - 1))`
    /// (round to the nearest grade in the log domain).
    pub fn new(code: LogCode, white: u64, in_bits: u32) -> Self {
        let g = code.grades() as f64;
        let thresholds = (1..=code.grades())
            .map(|c| {
                let x = code.linear_of_log((c as f64 - 0.5) / g) * white as f64;
                x.ceil().max(0.0) as u64
            })
            .collect();
        Self {
            code,
            thresholds,
            in_bits,
        }
    }
    /// The log code of a linear code (saturates at full white).
    #[inline]
    pub fn encode(&self, i: u64) -> u32 {
        self.thresholds.partition_point(|&t| t <= i) as u32
    }
    /// Cost: the threshold ROM and one comparator used `bits` times (binary search).
    pub fn cost(&self) -> Cost {
        Cost {
            lut_bits: self.thresholds.len() as u64 * self.in_bits as u64,
            adders: vec![Unit::adder("log encoder compare", 1, self.in_bits)],
            ..Cost::default()
        }
    }
}

/// Structure (a): log code to linear code `round(W (K^(c/G) - 1)/(K - 1))`.
#[derive(Clone, Debug)]
pub struct PotentiationLut {
    /// Entries, one per log code.
    pub table: Vec<u32>,
    /// Data width (bits of `W`).
    pub data_bits: u32,
}

impl PotentiationLut {
    /// Builds the LUT for a linear output of `data_bits` (full white `2^data_bits - 1`).
    pub fn build(code: LogCode, data_bits: u32) -> Self {
        let w = ((1u64 << data_bits) - 1) as f64;
        let g = code.grades() as f64;
        let table = (0..=code.grades())
            .map(|c| (code.linear_of_log(c as f64 / g) * w).round() as u32)
            .collect();
        Self { table, data_bits }
    }
    /// Exact (unrounded) entry, for tests and the float reference.
    pub fn exact(code: LogCode, data_bits: u32, c: u32) -> f64 {
        code.linear_of_log(c as f64 / code.grades() as f64) * ((1u64 << data_bits) - 1) as f64
    }
    /// Cost: one ROM.
    pub fn cost(&self) -> Cost {
        Cost {
            lut_bits: self.table.len() as u64 * self.data_bits as u64,
            ..Cost::default()
        }
    }
}

/// Structure (b): the log frame word, weight ROM and Gaussian-log adder.
#[derive(Clone, Debug)]
pub struct LogAdder {
    /// The sample code.
    pub code: LogCode,
    /// Extra fraction bits of the frame word.
    pub fa: u32,
    /// Code offset: code `a` holds `L = (a - off) / (G 2^fa)`.
    pub off: i64,
    /// Full-scale (full white) code; sums saturate here.
    pub max: i64,
    /// sb table, in frame LSBs times `2^tf`.
    pub sb: Vec<i64>,
    /// Data fraction bits.
    pub tf: u32,
    /// Address shift `s`: entry `j` is `sb(j 2^s)`.
    pub shift: u32,
    /// Address bits.
    pub addr_bits: u32,
    /// Linear interpolation.
    pub interpolate: bool,
    /// `log_K(w / 2^f)` in frame LSBs for `w` in 0..=2^f (entry 0 unused).
    pub log_w: Vec<i64>,
    /// Weight fraction bits `f`.
    pub wf: u32,
}

/// The zero code of the log frame word.
pub const ZERO: i64 = 0;

impl LogAdder {
    /// Builds the adder for weights with `wf` fraction bits whose smallest nonzero weight is
    /// `w_min`.
    pub fn new(code: LogCode, cfg: &CodingCfg, wf: u32, w_min: u32) -> Self {
        let fa = cfg.acc_frac_bits;
        let unit = code.grades() as f64 * (1u64 << fa) as f64; // frame LSBs per log_K unit
        let lnk = code.k.ln();
        let lw_min = (w_min.max(1) as f64 / (1u64 << wf) as f64).ln() / lnk * unit;
        let off = (-lw_min).ceil() as i64 + 1;
        let max = off + unit as i64;
        let tf = cfg.table_frac_bits;
        let data_unit = unit * (1u64 << tf) as f64;
        let sbf = |d: f64| (1.0 + (-d / unit * lnk).exp()).ln() / lnk * data_unit;
        // Essential zero: first d (frame LSBs) with sb rounding to 0.
        let mut ez = 1i64;
        while sbf(ez as f64) >= 0.5 {
            ez *= 2;
        }
        let (mut lo, mut hi) = (ez / 2, ez);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if sbf(mid as f64) >= 0.5 {
                lo = mid
            } else {
                hi = mid
            }
        }
        let ez = hi.max(1);
        let a = cfg.table_addr_bits;
        let mut shift = 0;
        while ((1i64 << a) << shift) < ez {
            shift += 1;
        }
        let n = (1usize << a) + usize::from(cfg.interpolate);
        let sb = (0..n)
            .map(|j| sbf((j as i64 * (1 << shift)) as f64).round() as i64)
            .collect();
        let log_w = (0..=(1u64 << wf))
            .map(|w| {
                if w == 0 {
                    0
                } else {
                    ((w as f64 / (1u64 << wf) as f64).ln() / lnk * unit).round() as i64
                }
            })
            .collect();
        Self {
            code,
            fa,
            off,
            max,
            sb,
            tf,
            shift,
            addr_bits: a,
            interpolate: cfg.interpolate,
            log_w,
            wf,
        }
    }

    /// Frame LSBs per `log_K` unit, `G 2^fa`.
    pub fn unit(&self) -> f64 {
        self.code.grades() as f64 * (1u64 << self.fa) as f64
    }
    /// Bits of the frame word.
    pub fn frame_bits(&self) -> u32 {
        64 - (self.max as u64).leading_zeros()
    }
    /// Data width of the sb table.
    pub fn table_data_bits(&self) -> u32 {
        64 - (self.sb[0] as u64).leading_zeros()
    }
    /// sb(d) for `d` in frame LSBs, in frame LSBs times `2^tf`.
    #[inline]
    pub fn sb_lookup(&self, d: i64) -> i64 {
        let n = 1i64 << self.addr_bits;
        if self.interpolate {
            let j = d >> self.shift;
            if j >= n {
                return 0;
            }
            let fr = d & ((1 << self.shift) - 1);
            let (a, b) = (self.sb[j as usize], self.sb[j as usize + 1]);
            if self.shift == 0 {
                a
            } else {
                a + (((b - a) * fr + (1 << (self.shift - 1))) >> self.shift)
            }
        } else {
            let j = if self.shift == 0 {
                d
            } else {
                (d + (1 << (self.shift - 1))) >> self.shift
            };
            if j >= n { 0 } else { self.sb[j as usize] }
        }
    }
    /// Gaussian-log sum of two frame codes (zero code is the identity; saturates at full white).
    #[inline]
    pub fn add(&self, a: i64, b: i64) -> i64 {
        if a == ZERO {
            return b;
        }
        if b == ZERO {
            return a;
        }
        let (m, d) = if a >= b { (a, a - b) } else { (b, b - a) };
        let v = (m << self.tf) + self.sb_lookup(d);
        let r = if self.tf == 0 {
            v
        } else {
            (v + (1 << (self.tf - 1))) >> self.tf
        };
        r.min(self.max)
    }
    /// The term `S K^I` in frame code: sample code `c` plus `log_K(w/2^f)` (an adder; floor 1).
    #[inline]
    pub fn term(&self, c: u32, w: u32) -> i64 {
        if w == 0 {
            return ZERO;
        }
        ((c as i64) << self.fa) + self.log_w[w as usize] + self.off
    }
    /// Exact relative luminance `B / B_min` of a frame code (0 for the zero code).
    pub fn value(&self, a: i64) -> f64 {
        if a == ZERO {
            0.0
        } else {
            self.code.k.powf((a - self.off) as f64 / self.unit())
        }
    }
    /// Exact frame-code position (real) of a relative luminance `v > 0`.
    pub fn position(&self, v: f64) -> f64 {
        v.ln() / self.code.k.ln() * self.unit() + self.off as f64
    }
    /// Cost of the log arithmetic: weight ROM, sb table, adders (and the interpolation
    /// multiplier if enabled); storage is the frame memory of `pixels` words.
    pub fn cost(&self, pixels: u64) -> Cost {
        let fb = self.frame_bits();
        let db = self.table_data_bits();
        let mut c = Cost {
            storage_bits: pixels * fb as u64,
            lut_bits: self.log_w.len() as u64 * fb as u64 + self.sb.len() as u64 * db as u64,
            adders: vec![
                Unit::adder("log I + log S", 1, fb),
                Unit::adder("|la - lb| and max", 1, fb),
                Unit::adder("max + sb", 1, fb + self.tf),
            ],
            multipliers: vec![],
        };
        if self.interpolate && self.shift > 0 {
            c.adders.push(Unit::adder("sb interpolation", 2, db));
            c.multipliers
                .push(Unit::mul("sb slope x offset", 1, db, self.shift));
        }
        c
    }
}

/// The gamma LUT of eq. 15 for a log-coded frame: `V = ((K^L - 1)/(K - 1))^(1/gamma)`,
/// where `L` is clamped to [0, 1]; the zero code gives `V = 0`.
pub fn log_gamma_lut(add: &LogAdder, spec: &GammaSpec) -> Vec<u16> {
    (0..=add.max)
        .map(|a| spec.code(log_gamma_linear(add, a)))
        .collect()
}

/// The normalised linear intensity an eq. 15 LUT entry shows (before the `1/gamma` power).
pub fn log_gamma_linear(add: &LogAdder, a: i64) -> f64 {
    if a == ZERO {
        0.0
    } else {
        let l = ((a - add.off) as f64 / add.unit()).clamp(0.0, 1.0);
        add.code.linear_of_log(l)
    }
}

/// Work of the log stage.
#[derive(Clone, Copy, Debug, Default)]
pub struct LogWork {
    /// Samples encoded to log code.
    pub encoded: u64,
    /// Potentiation LUT lookups (structure a).
    pub potentiations: u64,
    /// `log I + log S` additions (structure b).
    pub term_adds: u64,
    /// Gaussian-log additions (sb lookups) (structure b).
    pub log_adds: u64,
    /// Pixels (structure b).
    pub pixels: u64,
    /// Sums that hit full scale.
    pub saturations: u64,
}

/// Accumulates one pixel in log code: `terms` are `(sample code, weight)` pairs in arrival
/// order. Returns the frame code; counts work.
pub fn accumulate_pixel(
    add: &LogAdder,
    terms: impl Iterator<Item = (u32, u32)>,
    work: &mut LogWork,
) -> i64 {
    let mut acc = ZERO;
    for (c, w) in terms {
        if w == 0 {
            continue;
        }
        let t = add.term(c, w).max(1);
        work.term_adds += 1;
        if acc != ZERO {
            work.log_adds += 1;
        }
        let r = add.add(acc, t);
        if r == add.max && acc != add.max {
            work.saturations += 1;
        }
        acc = r;
    }
    acc
}

/// Exact reference of [`accumulate_pixel`]: `sum S K^(c/G)` (relative luminance) with the
/// same quantised codes and weights.
pub fn accumulate_pixel_f64(
    code: LogCode,
    wf: u32,
    terms: impl Iterator<Item = (u32, u32)>,
) -> f64 {
    let g = code.grades() as f64;
    terms
        .map(|(c, w)| w as f64 / (1u64 << wf) as f64 * code.k.powf(c as f64 / g))
        .sum()
}

/// Adds one fixed/exact pair of log frame positions to a stage-local error (frame LSBs).
pub fn local_add(e: &mut LocalError, add: &LogAdder, fixed: i64, exact_value: f64) {
    if exact_value <= 0.0 {
        e.add(fixed as f64, 0.0);
    } else {
        e.add(fixed as f64, add.position(exact_value).min(add.max as f64));
    }
}

/// Visible contours along a ramp of DAC codes: adjacent output steps (code changes) whose
/// luminance ratio in the display model exceeds `1 + delta`.
pub fn ramp_visible_contours(dac: &[u16], display: &DisplayModel) -> usize {
    dac.windows(2)
        .filter(|w| w[0] != w[1])
        .filter(|w| {
            let (a, b) = (display.luminance(w[0]), display.luminance(w[1]));
            let r = if a > b { a / b } else { b / a };
            r > 1.0 + display.weber
        })
        .count()
}

// ---------------------------------------------------------------------------------------
// Pipeline glue: the `logdomain` stage between visibility and accumulate / gamma.
// ---------------------------------------------------------------------------------------

use super::accumulate::{self, AccRef, Frame};
use super::{StageReport, ms_since};
use crate::config::HwConfig;
use crate::error::{Error, FileError, Result};
use crate::pipeline::{Accumulated, Front, Geometry, Post, RenderOptions};
use crate::scene::Scene;
use rayon::prelude::*;
use std::time::Instant;

/// The log code of a scene and hardware config (K from the scene's display block).
pub fn log_code(scene: &Scene, hw: &HwConfig) -> Result<LogCode> {
    let k = scene.display.contrast;
    check_contrast(k).map_err(|msg| {
        Error::File(FileError {
            file: scene.name.clone(),
            line: None,
            col: None,
            field: "display.contrast".into(),
            msg,
        })
    })?;
    Ok(LogCode {
        k,
        bits: hw.coding.log_bits,
    })
}

/// Encodes the stored samples (and light points and the background) to the log code in
/// place; for structure (a) it then potentiates them back to linear codes, so the spine's
/// accumulate runs unchanged. Returns the stage report and, for structure (b), the encoder.
pub fn encode_phase(
    f: &mut Front,
    g: &mut Geometry,
    scene: &Scene,
    hw: &HwConfig,
) -> Result<StageReport> {
    let code = log_code(scene, hw)?;
    let i_fmt = hw.input.intensity.format;
    let white_i = ((1u64 << i_fmt.int_bits) - 1) << i_fmt.frac_bits;
    let enc = LogEncoder::new(code, white_i, i_fmt.total_bits());
    let mut r = StageReport {
        name: "logdomain".into(),
        ..Default::default()
    };
    let mut work = LogWork::default();
    let t = Instant::now();
    // Stage-local error: log-stage output vs its linear input, in output LSBs.
    let lin_in: Vec<u32> = g.samples.i.clone();
    g.samples
        .i
        .par_iter_mut()
        .for_each(|v| *v = enc.encode(*v as u64));
    for p in g.points.iter_mut() {
        p.i = enc.encode(p.i as u64);
    }
    f.bg.0 = enc.encode(f.bg.0 as u64);
    work.encoded = g.samples.i.len() as u64 + g.points.len() as u64 + 1;
    let mut cost = enc.cost();
    let mut e = LocalError::default();
    if hw.coding.kind == CodingKind::LogPotentiate {
        let frame_bits = hw.accumulate.frame.format.int_bits;
        let lut = PotentiationLut::build(code, frame_bits);
        let sh = i_fmt.frac_bits;
        let pot = |c: u32| lut.table[c as usize] << sh;
        g.samples.i.par_iter_mut().for_each(|v| *v = pot(*v));
        for p in g.points.iter_mut() {
            p.i = pot(p.i);
        }
        f.bg.0 = pot(f.bg.0);
        work.potentiations = work.encoded;
        r.fixed_ms = ms_since(t);
        let t = Instant::now();
        // Float: the exact linear input in the potentiated code's LSBs.
        let scale = ((1u64 << frame_bits) - 1) as f64 / white_i as f64;
        for (&a, &b) in g.samples.i.iter().zip(&lin_in) {
            e.add((a >> sh) as f64, b as f64 * scale);
        }
        r.float_ms = ms_since(t);
        let max_lut = (0..=code.grades())
            .map(|c| {
                (lut.table[c as usize] as f64 - PotentiationLut::exact(code, frame_bits, c)).abs()
            })
            .fold(0.0, f64::max);
        r.notes
            .insert("potentiation_lut_max_error_lsb".into(), max_lut.into());
        let c2 = lut.cost();
        cost.lut_bits += c2.lut_bits;
    } else {
        r.fixed_ms = ms_since(t);
        let t = Instant::now();
        for (&a, &b) in g.samples.i.iter().zip(&lin_in) {
            let exact = code.log_of_linear(b as f64 / white_i as f64) * code.grades() as f64;
            e.add(a as f64, exact);
        }
        r.float_ms = ms_since(t);
    }
    r.local = Some(e.finish());
    // The sample buffer stores the log code instead of the linear one.
    let grid = f.grid;
    let full_samples = grid.sw() as u64 * grid.sh() as u64;
    let saved = full_samples * (i_fmt.total_bits() - code.bits.min(i_fmt.total_bits())) as u64;
    g.reports[2].cost.storage_bits = g.reports[2].cost.storage_bits.saturating_sub(saved);
    r.notes
        .insert("sample_buffer_bits_saved".into(), saved.into());
    r.notes.insert("log_grades".into(), code.grades().into());
    r.notes
        .insert("grade_luminance_ratio".into(), code.step_ratio().into());
    let m = scene.display.contrast.ln() / scene.display.weber.ln_1p();
    r.notes.insert("scene_grades_needed_eq11".into(), m.into());
    r.cost = cost;
    r.work.insert("encoded".into(), work.encoded);
    r.work.insert("potentiations".into(), work.potentiations);
    Ok(r)
}

/// One pixel of the log frame: code, nearest depth, coverage.
type PixelOut = (u32, u32, u16);

/// Structure (b): log-domain accumulation of the (log-coded) samples into a log frame
/// memory, fixed model and exact reference; the float image is the spine's.
pub fn accumulate_phase(
    f: &Front,
    g: &Geometry,
    scene: &Scene,
    hw: &HwConfig,
    enc_report: &mut StageReport,
    opts: RenderOptions,
) -> Result<(Accumulated, LogAdder)> {
    let code = log_code(scene, hw)?;
    let k = &f.kernel;
    let w_min = k.w.iter().copied().filter(|&w| w > 0).min().unwrap_or(1);
    let add = LogAdder::new(code, &hw.coding, k.f, w_min);
    let (width, height) = (f.grid.width, f.grid.height);
    let npix = width as usize * height as usize;
    let t = Instant::now();
    let s = &g.samples;
    let sw = s.reg.width();
    let mut work = LogWork::default();
    let bg_code = accumulate_pixel(
        &add,
        k.w.iter().map(|&w| (f.bg.0, w)),
        &mut LogWork::default(),
    );
    let mut frame = Frame {
        width,
        height,
        acc: vec![bg_code as u32; npix],
        depth: vec![u32::MAX; npix],
        coverage: vec![0; npix],
    };
    let region = f.region;
    let window = |px: u32, py: u32| {
        let c0 = (px as i64 * k.n as i64 - k.off - s.reg.c0) as usize;
        let r0 = (py as i64 * k.n as i64 - k.off - s.reg.k0) as usize;
        (c0, r0)
    };
    let rows: Vec<(Vec<PixelOut>, LogWork)> = (region.y0..region.y1)
        .into_par_iter()
        .map(|py| {
            let mut wk = LogWork::default();
            let row = (region.x0..region.x1)
                .map(|px| {
                    let (c0, r0) = window(px, py);
                    let terms = (0..k.size).flat_map(|j| (0..k.size).map(move |i| (j, i)));
                    let a = accumulate_pixel(
                        &add,
                        terms.map(|(j, i)| (s.i[(r0 + j) * sw + c0 + i], k.w[j * k.size + i])),
                        &mut wk,
                    );
                    let (zmin, cov) = accumulate::own_depth_coverage(s, k, r0 * sw + c0, sw);
                    (a as u32, zmin, cov)
                })
                .collect();
            wk.pixels = (region.x1 - region.x0) as u64;
            (row, wk)
        })
        .collect();
    for (py, (row, wk)) in (region.y0..region.y1).zip(rows) {
        let base = py as usize * width as usize + region.x0 as usize;
        for (o, (a, z, c)) in row.into_iter().enumerate() {
            frame.acc[base + o] = a;
            frame.depth[base + o] = z;
            frame.coverage[base + o] = c;
        }
        work.pixels += wk.pixels;
        work.term_adds += wk.term_adds;
        work.log_adds += wk.log_adds;
        work.saturations += wk.saturations;
    }
    // Light points: their summed weight's log plus the point's code, added in arrival order.
    for pt in &g.points {
        for (px, py, ssum) in accumulate::point_weights(pt, &s.reg, &region, k, |e| k.w[e] as f64) {
            let at = py as usize * width as usize + px as usize;
            let w = (ssum as u32).min(1 << k.f);
            let t = add.term(pt.i, w).max(1);
            work.term_adds += 1;
            work.log_adds += 1;
            frame.acc[at] = add.add(frame.acc[at] as i64, t) as u32;
        }
    }
    enc_report.fixed_ms += ms_since(t);
    // Stage-local: exact log/exp sums of the same codes and weights.
    if opts.stage_local {
        let t = Instant::now();
        let mut e = LocalError::default();
        for py in region.y0..region.y1 {
            for px in region.x0..region.x1 {
                let (c0, r0) = window(px, py);
                let terms = (0..k.size)
                    .flat_map(|j| (0..k.size).map(move |i| (j, i)))
                    .map(|(j, i)| (s.i[(r0 + j) * sw + c0 + i], k.w[j * k.size + i]));
                let v = accumulate_pixel_f64(code, k.f, terms);
                local_add(
                    &mut e,
                    &add,
                    frame.acc[py as usize * width as usize + px as usize] as i64,
                    v,
                );
            }
        }
        enc_report.float_ms += ms_since(t);
        enc_report.local = Some(e.finish());
    }
    // The float image: the spine's exact linear reference.
    let t = Instant::now();
    let frame_fmt = hw.accumulate.frame.format;
    let frame_ref = accumulate::accumulate_f64(
        &g.samples_ref.i,
        &f.sreg,
        &f.region,
        &g.points_ref,
        &AccRef {
            kernel: k,
            i_frac: hw.input.intensity.format.frac_bits,
            frame_frac: frame_fmt.frac_bits,
            bg_i: f.bg.1,
            size: (width, height),
        },
    );
    enc_report.float_ms += ms_since(t);
    enc_report.record_work(&[
        ("pixels", work.pixels),
        ("term_adds", work.term_adds),
        ("log_adds", work.log_adds),
        ("saturations", work.saturations),
    ]);
    let c = add.cost(npix as u64);
    enc_report.cost.storage_bits += c.storage_bits;
    enc_report.cost.lut_bits += c.lut_bits;
    enc_report.cost.adders.extend(c.adders);
    enc_report.cost.multipliers.extend(c.multipliers);
    for (key, v) in [
        ("frame_bits", add.frame_bits() as u64),
        ("frame_offset", add.off as u64),
        ("sb_table_entries", add.sb.len() as u64),
        ("sb_table_data_bits", add.table_data_bits() as u64),
        ("sb_address_shift", add.shift as u64),
    ] {
        enc_report.notes.insert(key.into(), v.into());
    }
    // The cycle model's plan: the same touched tiles as the linear path. Structure (b)
    // accumulates a pixel's log sums in a register and writes the frame word once, so each
    // touched pixel is one frame write.
    let tiles = crate::cycles::Tiles::touched_by(
        hw.cycles.tile,
        &f.region,
        k,
        &g.samples,
        &g.points,
        width,
        height,
    );
    let tile_rmw = (0..tiles.rows)
        .flat_map(|r| (0..tiles.cols).map(move |c| (r, c)))
        .map(|(r, c)| {
            if !tiles.touched[(r * tiles.cols + c) as usize] {
                return 0;
            }
            let w = tiles.size.min(width - c * tiles.size) as u64;
            let h = tiles.size.min(height - r * tiles.size) as u64;
            w * h
        })
        .collect();
    Ok((
        Accumulated {
            frame,
            frame_ref,
            report: StageReport::default(),
            tiles,
            tile_rmw,
        },
        add,
    ))
}

/// Structure (b) post stage: the eq. 15 gamma LUT on the log frame; the float image goes
/// through the spine's float gamma.
pub fn post(
    a: &Accumulated,
    add: &LogAdder,
    scene: &Scene,
    hw: &HwConfig,
    opts: RenderOptions,
) -> Post {
    let gamma_value = hw.gamma.gamma.unwrap_or(scene.display.gamma);
    let spec = GammaSpec::new(
        gamma_value,
        hw.gamma.correction,
        hw.gamma.dac_bits,
        hw.gamma.quant,
    );
    let mut r = StageReport {
        name: "gamma".into(),
        ..Default::default()
    };
    let t = Instant::now();
    let lut = log_gamma_lut(add, &spec);
    let max = lut.len() - 1;
    let dac: Vec<u16> = a
        .frame
        .acc
        .par_iter()
        .map(|&c| lut[(c as usize).min(max)])
        .collect();
    r.fixed_ms = ms_since(t);
    r.work.insert("lookups".into(), dac.len() as u64);
    r.work.insert("lut_entries".into(), lut.len() as u64);
    let fb = add.frame_bits();
    r.cost = Cost {
        lut_bits: lut.len() as u64 * hw.gamma.dac_bits as u64,
        adders: vec![Unit::adder("LUT address", 1, fb)],
        ..Cost::default()
    };
    r.notes.insert(
        "monotone".into(),
        lut.windows(2).all(|w| w[0] <= w[1]).into(),
    );
    r.notes.insert("log_input_eq15".into(), true.into());
    if opts.stage_local {
        let mut e = LocalError::default();
        for (&c, &d) in a.frame.acc.iter().zip(&dac) {
            e.add(d as f64, spec.ideal(log_gamma_linear(add, c as i64)));
        }
        r.local = Some(e.finish());
    }
    let t = Instant::now();
    let frame_fmt = hw.accumulate.frame.format;
    let white = frame_fmt.max_code() >> frame_fmt.frac_bits;
    let white_lsb = white as f64 * (1u64 << frame_fmt.frac_bits) as f64;
    let mut dac_ref = vec![0u16; a.frame_ref.len()];
    super::gamma::apply_f64(&spec, &a.frame_ref, white_lsb, &mut dac_ref);
    r.float_ms = ms_since(t);
    Post {
        dac,
        dac_ref,
        reports: vec![r],
    }
}

// ---------------------------------------------------------------------------------------
// Width validation by emulation (`igemu widths`): a smooth ramp through the intensity path.
// ---------------------------------------------------------------------------------------

/// Samples of the built-in ramp.
pub const RAMP_SAMPLES: usize = 1 << 16;

/// One emulated configuration of the ramp check.
#[derive(Clone, Debug, Serialize)]
pub struct RampCheck {
    /// `linear` or `log`.
    pub coding: String,
    /// Frame (linear accumulator) or log-code bits.
    pub code_bits: u32,
    /// DAC bits.
    pub dac_bits: u32,
    /// Whether these are the recommended widths (else one bit narrower in one of them).
    pub recommended: bool,
    /// Adjacent output steps on the ramp whose luminance ratio exceeds `1 + delta`.
    pub contours: usize,
    /// Distinct DAC codes on the ramp.
    pub levels: usize,
    /// What the theory (eq. 9-11) predicts: 0 contours at the recommendation, more below.
    pub theory_expects_contours: bool,
    /// `contours > 0` differs from the theory's expectation.
    pub disagrees: bool,
}

/// The built-in ramp: `RAMP_SAMPLES` linear intensities in [0, 1] whose luminance
/// `B_min (1 + (K - 1) x)` rises uniformly in log from `B_min` to `B_max` (the full contrast).
pub fn ramp(k: f64) -> Vec<f64> {
    let c = LogCode { k, bits: 8 };
    (0..RAMP_SAMPLES)
        .map(|j| c.linear_of_log(j as f64 / (RAMP_SAMPLES - 1) as f64))
        .collect()
}

/// The ramp through a linear frame of `bits` (round to nearest) and the gamma LUT to a
/// `dac_bits` DAC.
pub fn ramp_linear(x: &[f64], bits: u32, dac_bits: u32, gamma: f64) -> Vec<u16> {
    let spec = GammaSpec::new(gamma, true, dac_bits, crate::fixed::Quant::RndConv);
    let w = ((1u64 << bits) - 1) as f64;
    x.iter().map(|&v| spec.code((v * w).round() / w)).collect()
}

/// The ramp through a `bits` log code (round to nearest grade) and the eq. 15 LUT.
pub fn ramp_log(x: &[f64], k: f64, bits: u32, dac_bits: u32, gamma: f64) -> Vec<u16> {
    let spec = GammaSpec::new(gamma, true, dac_bits, crate::fixed::Quant::RndConv);
    let c = LogCode { k, bits };
    let g = c.grades() as f64;
    x.iter()
        .map(|&v| spec.code(c.linear_of_log((c.log_of_linear(v) * g).round() / g)))
        .collect()
}

/// Emulates the recommended widths of [`crate::calc::widths`] and one bit narrower in each.
pub fn validate_widths(w: &crate::calc::Widths) -> Vec<RampCheck> {
    let x = ramp(w.contrast);
    let display = DisplayModel {
        b_min: 1.0,
        b_max: w.contrast,
        gamma: w.gamma,
        weber: w.weber,
        max_code: 0.0,
    };
    let (lb, db, gb) = (w.linear.bits, w.dac.bits, w.log_grades.bits);
    let mut out = Vec::new();
    let mut run = |coding: &str, bits: u32, dac: u32, rec: bool| {
        if bits == 0 || dac == 0 || bits > 24 || dac > 16 {
            return;
        }
        let codes = if coding == "linear" {
            ramp_linear(&x, bits, dac, w.gamma)
        } else {
            ramp_log(&x, w.contrast, bits, dac, w.gamma)
        };
        let d = DisplayModel {
            max_code: ((1u64 << dac) - 1) as f64,
            ..display
        };
        let contours = ramp_visible_contours(&codes, &d);
        let mut levels = codes.clone();
        levels.dedup();
        out.push(RampCheck {
            coding: coding.into(),
            code_bits: bits,
            dac_bits: dac,
            recommended: rec,
            contours,
            levels: levels.len(),
            theory_expects_contours: !rec,
            disagrees: (contours > 0) == rec,
        });
    };
    run("linear", lb, db, true);
    run("linear", lb - 1, db, false);
    run("linear", lb, db - 1, false);
    run("log", gb, db, true);
    run("log", gb - 1, db, false);
    run("log", gb, db - 1, false);
    out
}
