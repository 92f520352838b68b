//! Width validation by emulation (`igemu widths`): a smooth ramp through the intensity path,
//! linear or log coded (docs/reference.md §1, eq. 9-11), and the visible contours it shows.

use crate::compare::DisplayModel;
use crate::stage::gamma::GammaSpec;
use crate::stage::logdomain::LogCode;
use serde::Serialize;

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

/// Emulates the recommended widths of [`crate::analysis::calc::widths`] and one bit narrower
/// in each (a row whose code or DAC would be 0 bits, or wider than 24 code or 16 DAC bits,
/// is left out).
pub fn validate_widths(w: &crate::analysis::calc::Widths) -> Vec<RampCheck> {
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
    // One bit narrower where there is a narrower width (0 bits has none: `run` skips 0).
    let less = |b: u32| b.saturating_sub(1);
    run("linear", lb, db, true);
    run("linear", less(lb), db, false);
    run("linear", lb, less(db), false);
    run("log", gb, db, true);
    run("log", less(gb), db, false);
    run("log", gb, less(db), false);
    out
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
