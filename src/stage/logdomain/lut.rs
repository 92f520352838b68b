//! The gamma LUT of eq. 15 (docs/reference.md §1) for a log-coded frame (structure b).

use super::adder::{LogAdder, ZERO};
use crate::fixed::{Overflow, QFormat, Quantizer};
use crate::stage::gamma::GammaSpec;

/// The gamma LUT of eq. 15 for a log-coded frame: `V = ((K^L - 1)/(K - 1))^(1/gamma)`,
/// where `L` is clamped to [0, 1]; the zero code gives `V = 0`.
pub fn log_gamma_lut(add: &LogAdder, spec: &GammaSpec) -> Vec<u16> {
    (0..=add.max)
        .map(|a| spec.code(log_gamma_linear(add, a)))
        .collect()
}

/// The eq. 15 LUT with `f` extra output fraction bits (`UQd.f`, the DAC quantiser's
/// rounding, saturating): the LUT a dither after it reads, as the linear frame's
/// [`extended_lut`](crate::stage::gamma::extended_lut).
pub fn log_gamma_lut_extended(add: &LogAdder, spec: &GammaSpec, f: u32) -> Vec<u32> {
    let d = spec.dac.format.int_bits;
    let q = Quantizer::new(QFormat::new(false, d, f), spec.dac.quant, Overflow::Sat);
    (0..=add.max)
        .map(|a| q.quantize_f64(spec.ideal(log_gamma_linear(add, a))).code as u32)
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
