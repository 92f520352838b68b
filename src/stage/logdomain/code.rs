//! The sample log code (docs/reference.md §1, eq. 11-13), the encoder's threshold ROM and
//! the potentiation LUT of structure (a). Both ROMs are built through the shared quantiser
//! and record their quantisation as signals (`logdomain.threshold`, `logdomain.potentiation`).

use crate::fixed::{Overflow, QFormat, Quant, Quantizer, SignalStats, quantize_slice_f64};
use crate::stage::{Cost, MemImage, Memory, Unit};
use std::sync::Arc;

/// Name of the encoder's threshold ROM.
pub const THRESHOLD_ROM: &str = "log encoder threshold ROM";
/// Name of the potentiation LUT (structure a).
pub const POTENTIATION_LUT: &str = "potentiation LUT";

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
    /// `logdomain.threshold`: the threshold ROM's quantisation, format `UQ<in_bits>.0`
    /// (errors `T_c - exact` are in [0, 1) LSB: a ceiling).
    pub stats: SignalStats,
}

impl LogEncoder {
    /// Builds the thresholds for a linear input whose full white is `white` (an integer code)
    /// in an `in_bits`-wide word: `T_c = ceil(white (K^((c - 1/2)/G) - 1)/(K - 1))`
    /// (round to the nearest grade in the log domain).
    ///
    /// The ceiling goes through the quantiser of [`LogEncoder::negated_quantizer`]:
    /// `T_c = -floor(-x_c)`. Every `x_c` is in `[0, white)`, so nothing overflows and the
    /// final clamp at 0 never acts.
    pub fn new(code: LogCode, white: u64, in_bits: u32) -> Self {
        let g = code.grades() as f64;
        let neg = Self::negated_quantizer(in_bits);
        let mut stats = SignalStats::new("logdomain.threshold", QFormat::new(false, in_bits, 0));
        let thresholds = (1..=code.grades())
            .map(|c| {
                let x = code.linear_of_log((c as f64 - 0.5) / g) * white as f64;
                let q = neg.quantize_f64(-x);
                let t = -q.code;
                stats.record(x, i128::from(t), q.overflow);
                t.max(0) as u64
            })
            .collect();
        Self {
            code,
            thresholds,
            in_bits,
            stats,
        }
    }
    /// The quantiser of the negated thresholds `-x_c`: `Q<in_bits + 1>.0` (the negated range
    /// of an `in_bits` word plus its sign), `TRN` (floor), `SAT`.
    pub fn negated_quantizer(in_bits: u32) -> Quantizer {
        Quantizer::new(
            QFormat::new(true, in_bits + 1, 0),
            Quant::Trn,
            Overflow::Sat,
        )
    }
    /// The log code of a linear code (saturates at full white).
    #[inline]
    pub fn encode(&self, i: u64) -> u32 {
        self.thresholds.partition_point(|&t| t <= i) as u32
    }
    /// Cost: the threshold ROM and one comparator used `bits` times (binary search).
    pub fn cost(&self) -> Cost {
        Cost::new(
            vec![Memory::rom(
                THRESHOLD_ROM,
                self.thresholds.len() as u64,
                self.in_bits,
            )],
            vec![Unit::adder("log encoder compare", 1, self.in_bits)],
            vec![],
        )
    }
    /// The threshold ROM's contents.
    pub fn image(&self) -> MemImage {
        MemImage::table(
            THRESHOLD_ROM,
            self.in_bits,
            Arc::new(self.thresholds.clone()),
        )
    }
}

/// Structure (a): log code to linear code `round(W (K^(c/G) - 1)/(K - 1))`.
#[derive(Clone, Debug)]
pub struct PotentiationLut {
    /// Entries, one per log code.
    pub table: Vec<u32>,
    /// Data width (bits of `W`).
    pub data_bits: u32,
    /// `logdomain.potentiation`: the entries' quantisation (format `UQ<data_bits>.0`).
    pub stats: SignalStats,
}

impl PotentiationLut {
    /// Builds the LUT for a linear output of `data_bits` (full white `2^data_bits - 1`):
    /// every [`PotentiationLut::exact`] entry through [`PotentiationLut::quantizer`].
    pub fn build(code: LogCode, data_bits: u32) -> Self {
        let q = Self::quantizer(data_bits);
        let xs: Vec<f64> = (0..=code.grades())
            .map(|c| Self::exact(code, data_bits, c))
            .collect();
        let mut codes = vec![0i64; xs.len()];
        let mut stats = SignalStats::new("logdomain.potentiation", q.format);
        quantize_slice_f64(&q, &xs, &mut codes, &mut stats);
        let table = codes.into_iter().map(|v| v as u32).collect();
        Self {
            table,
            data_bits,
            stats,
        }
    }
    /// The entries' quantiser: `UQ<data_bits>.0`, `RND_INF` (ties away from zero, as
    /// `f64::round`; the entries are in `[0, W]`, so nothing overflows), `SAT`.
    pub fn quantizer(data_bits: u32) -> Quantizer {
        Quantizer::new(
            QFormat::new(false, data_bits, 0),
            Quant::RndInf,
            Overflow::Sat,
        )
    }
    /// Exact (unrounded) entry, for tests and the float reference.
    pub fn exact(code: LogCode, data_bits: u32, c: u32) -> f64 {
        code.linear_of_log(c as f64 / code.grades() as f64) * ((1u64 << data_bits) - 1) as f64
    }
    /// Cost: one ROM.
    pub fn cost(&self) -> Cost {
        Cost::new(
            vec![Memory::rom(
                POTENTIATION_LUT,
                self.table.len() as u64,
                self.data_bits,
            )],
            vec![],
            vec![],
        )
    }
    /// The LUT's contents.
    pub fn image(&self) -> MemImage {
        MemImage::table(
            POTENTIATION_LUT,
            self.data_bits,
            Arc::new(self.table.clone()),
        )
    }
}
