//! Gamma correction: a LUT from frame-memory code to DAC code, `U = I^(1/gamma)`
//! (Kovalev & Tokarev eq. 7), built from the formula with the configured rounding.
//!
//! The float reference applies the same formula to the real-valued frame intensity
//! (clamped to [0, 1] of full white) and quantises only at the DAC, with the same rounding.

use super::{Cost, Memory, Unit};
use crate::config::HwConfig;
use crate::fixed::{Overflow, QFormat, Quant, Quantizer};
use crate::fnv::Fnv;
use crate::scene::Scene;
use rayon::prelude::*;

/// The LUT and what it can reach.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GammaLut {
    /// Address width (frame integer bits).
    pub addr_bits: u32,
    /// DAC width.
    pub dac_bits: u32,
    /// One DAC code per address.
    pub table: Vec<u16>,
}

/// How the LUT maps: exponent and rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GammaSpec {
    /// Exponent applied to the normalised intensity (1/gamma, or 1 without correction).
    pub exponent: f64,
    /// DAC quantiser (UQd.0, saturating).
    pub dac: Quantizer,
}

impl GammaSpec {
    /// The spec of a scene's display and the `[gamma]` section (the LUT corrects
    /// `gamma.gamma`, or the display's gamma when it is not given).
    pub fn of(scene: &Scene, hw: &HwConfig) -> Self {
        Self::new(
            hw.gamma.gamma.unwrap_or(scene.display.gamma),
            hw.gamma.correction,
            hw.gamma.dac_bits,
            hw.gamma.quant,
        )
    }

    /// Builds the spec; `correction = false` gives a linear LUT.
    pub fn new(gamma: f64, correction: bool, dac_bits: u32, quant: Quant) -> Self {
        Self {
            exponent: if correction { 1.0 / gamma } else { 1.0 },
            dac: Quantizer::new(QFormat::new(false, dac_bits, 0), quant, Overflow::Sat),
        }
    }

    /// The ideal DAC value (before rounding) of a normalised intensity in [0, 1].
    #[inline]
    pub fn ideal(&self, v: f64) -> f64 {
        self.scale(self.power(v))
    }

    /// The DAC-independent part of [`GammaSpec::ideal`]: `clamp(v, 0, 1)^exponent`.
    #[inline]
    pub fn power(&self, v: f64) -> f64 {
        v.clamp(0.0, 1.0).powf(self.exponent)
    }

    /// The DAC-dependent part of [`GammaSpec::ideal`]: a [`GammaSpec::power`] in DAC codes.
    #[inline]
    pub fn scale(&self, p: f64) -> f64 {
        p * self.dac.format.max_code() as f64
    }

    /// The DAC code of a normalised intensity (the float reference's only rounding).
    #[inline]
    pub fn code(&self, v: f64) -> u16 {
        self.dac.quantize_f64(self.ideal(v)).code as u16
    }
}

impl GammaLut {
    /// Builds the LUT for `addr_bits` frame bits (full white = `2^addr_bits - 1`).
    pub fn build(spec: &GammaSpec, addr_bits: u32) -> Self {
        let white = ((1u64 << addr_bits) - 1) as f64;
        let table = (0..1u64 << addr_bits)
            .map(|c| spec.code(c as f64 / white))
            .collect();
        Self {
            addr_bits,
            dac_bits: spec.dac.format.int_bits,
            table,
        }
    }

    /// Whether the table never decreases.
    pub fn is_monotone(&self) -> bool {
        self.table.windows(2).all(|w| w[0] <= w[1])
    }

    /// DAC codes no address reaches.
    pub fn unreachable_codes(&self) -> Vec<u16> {
        let mut seen = vec![false; 1 << self.dac_bits];
        for &c in &self.table {
            seen[c as usize] = true;
        }
        (0..seen.len())
            .filter(|&c| !seen[c])
            .map(|c| c as u16)
            .collect()
    }

    /// Applies the LUT to frame codes (`frac_bits` of the frame are dropped by truncation
    /// of the address, i.e. the LUT is addressed by the integer part).
    pub fn apply(&self, acc: &[u32], frac_bits: u32, out: &mut [u16]) {
        lookup(&self.table, acc, frac_bits, out);
    }

    /// [`GammaLut::apply`] into 32-bit pixel codes (the pixel tap's type).
    pub fn apply_u32(&self, acc: &[u32], frac_bits: u32, out: &mut [u32]) {
        lookup(&self.table, acc, frac_bits, out);
    }

    /// Cost: one ROM (named `name`) and its address register.
    pub fn cost(&self, name: &str) -> Cost {
        Cost::new(
            vec![Memory::rom(name, self.table.len() as u64, self.dac_bits)],
            vec![Unit::adder("LUT address", 1, self.addr_bits)],
            vec![],
        )
    }
}

/// Float reference: frame intensity in frame LSBs (real) to DAC codes.
pub fn apply_f64(spec: &GammaSpec, acc: &[f64], white_lsb: f64, out: &mut [u16]) {
    out.par_iter_mut()
        .zip(acc.par_iter())
        .for_each(|(o, &a)| *o = spec.code(a / white_lsb));
}

/// The float reference from precomputed [`GammaSpec::power`]s (`powers[i]` =
/// `spec.power(acc[i] / white_lsb)`): the same codes as [`apply_f64`], without the `powf`
/// per pixel when several DAC widths share one exponent.
pub fn apply_powers(spec: &GammaSpec, powers: &[f64], out: &mut [u16]) {
    out.par_iter_mut()
        .zip(powers.par_iter())
        .for_each(|(o, &p)| *o = spec.dac.quantize_f64(spec.scale(p)).code as u16);
}

/// The memo key of a frame's [`powers`]: the frame's key (the key of the stage that last
/// wrote it, or any stage after it) and the exponent.
pub fn powers_key(frame_key: u64, spec: &GammaSpec) -> u64 {
    Fnv::new()
        .u64(frame_key)
        .str("gamma powers")
        .u64(spec.exponent.to_bits())
        .finish()
}

/// Full white of `hw`'s frame in the float frame's units (frame LSBs): the integer part's
/// largest value, in units of the fraction LSB.
pub fn frame_white(hw: &HwConfig) -> f64 {
    let ff = hw.accumulate.frame.format;
    (ff.max_code() >> ff.frac_bits) as f64 * (1u64 << ff.frac_bits) as f64
}

/// The DAC-independent part of the float reference after the gamma curve:
/// `clamp(frame_ref / white, 0, 1)^exponent` per pixel ([`GammaSpec::power`]), with
/// `white` the frame's full white in frame LSBs. Shared by every DAC width and dither of a
/// sweep (and by the contour metric's ideal image).
pub fn powers(frame_ref: &[f64], hw: &HwConfig, spec: &GammaSpec) -> Vec<f64> {
    let white_lsb = frame_white(hw);
    frame_ref
        .par_iter()
        .map(|&v| spec.power(v / white_lsb))
        .collect()
}

mod kernel;
mod luts;
mod stage;
pub use kernel::{BLOCK, lookup, lookup_block, lookup_block_portable};
pub use luts::{extended_lut, reduced_lut};
pub use stage::Gamma;
