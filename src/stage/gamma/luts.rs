//! The gamma LUTs a dither placement needs: the extended-output LUT (`UQd.f`) of the
//! after-LUT placement and the reduced-address LUT of the before-LUT placement.

use super::{GammaLut, GammaSpec};
use crate::fixed::{Overflow, QFormat, Quantizer};

/// The gamma LUT with `f` extra output fraction bits (`UQd.f`), for the after-LUT placement.
pub fn extended_lut(spec: &GammaSpec, addr_bits: u32, f: u32) -> Vec<u32> {
    let d = spec.dac.format.int_bits;
    let q = Quantizer::new(QFormat::new(false, d, f), spec.dac.quant, Overflow::Sat);
    let white = ((1u64 << addr_bits) - 1) as f64;
    (0..1u64 << addr_bits)
        .map(|c| q.quantize_f64(spec.ideal(c as f64 / white)).code as u32)
        .collect()
}

/// The reduced-address gamma LUT of the before-LUT placement: address `a` is the frame
/// value `a * 2^f` of a frame whose full white is `2^acc_bits - 1`.
pub fn reduced_lut(spec: &GammaSpec, acc_bits: u32, f: u32) -> GammaLut {
    let white = ((1u64 << acc_bits) - 1) as f64;
    let table = (0..1u64 << (acc_bits - f))
        .map(|a| spec.code(((a << f) as f64 / white).min(1.0)))
        .collect();
    GammaLut {
        addr_bits: acc_bits - f,
        dac_bits: spec.dac.format.int_bits,
        table,
    }
}
