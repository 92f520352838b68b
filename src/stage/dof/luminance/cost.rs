//! Cost of the luminance-aware datapath (docs/reference.md §7b), exact from the formats: a
//! streaming row pipeline (input row `y + r + 1` in, output row `y` out) with line buffers
//! for the pre-blur window, the bleed's 3x3 window and alpha's delay, the alpha ROM, and the
//! arithmetic units by width; the ROM's contents for the pack check.

use super::alpha::AlphaMap;
use super::fixed::LumParams;
use super::luma::Luma;
use crate::stage::{Cost, MemImage, Memory, Unit};
use std::sync::Arc;

/// Name of the pre-blur window's line buffers.
pub const PRE_LINES: &str = "dof luminance pre-blur line buffers";
/// Name of the bleed window's line buffers.
pub const BLEED_LINES: &str = "dof luminance bleed line buffers";
/// Name of alpha's delay line buffers.
pub const ALPHA_LINES: &str = "dof luminance alpha delay";
/// Name of the luminance pre-blur's line buffers (a colour frame's shared luminance unit).
pub const LUMA_PRE_LINES: &str = "dof luminance Y pre-blur line buffers";
/// Name of the luminance bleed window's line buffers.
pub const LUMA_BLEED_LINES: &str = "dof luminance Y bleed line buffers";
/// Name of the alpha ROM.
pub const ALPHA_ROM: &str = "dof luminance alpha ROM";

/// Bits of an unsigned word holding `n`.
fn bits_of(n: u64) -> u32 {
    64 - n.leading_zeros()
}

/// Cost of the datapath for a screen `width` pixels wide:
/// * the pre-blur window holds `2r` rows of frame codes (the `2r + 1`-th streams in); the
///   sharp pixel of output row `y` is among them (for r = 0 it is the bleed's centre row);
/// * the bleed's 3x3 window holds 2 rows of the pre-blurred image (the third streams in);
/// * alpha is read from the ROM as a pixel streams in and waits `r + 1` rows for its output;
/// * per pixel: a column and a row adder tree of `2r` adders (`pre_bits`), the mean's divide
///   by the in-image window count, 8 differences, 8 weight x value multipliers, two adder
///   trees (weights, products), the bleed's divide, and the blend's subtract, multiply, add;
/// * with `luma` (a colour frame): the bleed's weights come from the luminance `Y`. The
///   luminance unit (charged by lane 0: three constant multipliers and an adder forming `Y`,
///   its pre-blur window and adder trees, its 3x3 window's line buffers, the 8 differences
///   and the weight sum) serves the three channels, which keep their own pre-blur, products,
///   divide and blend.
pub fn cost(alpha: &AlphaMap, p: &LumParams, luma: Option<&Luma>, width: u64) -> Cost {
    let r = p.radius;
    let code = p.frame.total_bits();
    let mean = code + p.guard_bits;
    let a = alpha.entry_bits();
    let wmean = luma.map_or(mean, |y| y.format.total_bits());
    let (wsum, num) = (wmean + 3, wmean + mean + 3);
    let mut memories = Vec::new();
    if r > 0 {
        memories.push(Memory::ram(PRE_LINES, 2 * u64::from(r) * width, code));
    }
    memories.extend([
        Memory::ram(BLEED_LINES, 2 * width, mean),
        Memory::ram(ALPHA_LINES, (u64::from(r) + 1) * width, a),
        Memory::rom(ALPHA_ROM, alpha.rom.len() as u64, a),
    ]);
    let mut adders = Vec::new();
    let mut multipliers = Vec::new();
    if r > 0 {
        adders.extend([
            Unit::adder("pre-blur column sum", 2 * r, p.pre_bits),
            Unit::adder("pre-blur row sum", 2 * r, p.pre_bits),
        ]);
        let count = u64::from(2 * r + 1).pow(2);
        multipliers.push(Unit::mul(
            "pre-blur mean (divide sum / count)",
            1,
            p.pre_bits + p.guard_bits,
            bits_of(count),
        ));
    }
    if luma.is_none() {
        adders.extend([
            Unit::adder("bleed differences P_i - P_c", 8, mean + 1),
            Unit::adder("bleed weight sum", 7, wsum),
        ]);
    }
    adders.extend([
        Unit::adder("bleed numerator sum", 7, num),
        Unit::adder("blend difference blur - x", 1, mean + 1),
        Unit::adder("blend sum", 1, mean + p.alpha_bits + 1),
    ]);
    multipliers.extend([
        Unit::mul("bleed weights x values", 8, wmean, mean),
        Unit::mul("bleed divide (numerator / weight sum)", 1, num, wsum),
        Unit::mul("blend alpha x (blur - x)", 1, mean + 1, a),
    ]);
    if let Some(y) = luma.filter(|y| y.charges()) {
        let ybits = y.format.total_bits();
        let ysum = p.pre_bits + p.guard_bits;
        let widest = ybits - p.guard_bits;
        if r > 0 {
            memories.push(Memory::ram(LUMA_PRE_LINES, 2 * u64::from(r) * width, ybits));
            adders.extend([
                Unit::adder("Y pre-blur column sum", 2 * r, ysum),
                Unit::adder("Y pre-blur row sum", 2 * r, ysum),
            ]);
            let count = u64::from(2 * r + 1).pow(2);
            multipliers.push(Unit::mul(
                "Y pre-blur mean (divide sum / count)",
                1,
                ysum,
                bits_of(count),
            ));
        }
        memories.push(Memory::ram(LUMA_BLEED_LINES, 2 * width, ybits));
        adders.extend([
            Unit::adder("Y = 77 R + 150 G + 29 B", 2, widest + 8),
            Unit::adder("bleed differences Y_i - Y_c", 8, ybits + 1),
            Unit::adder("bleed weight sum", 7, wsum),
        ]);
        multipliers.push(Unit::mul("Y weights x channels", 3, widest, 8));
    }
    Cost::new(memories, adders, multipliers)
}

/// The alpha ROM's contents: `UQ1.<alpha_bits>` entries by the top depth-code bits, then
/// the entry of infinity.
pub fn alpha_image(alpha: &AlphaMap) -> MemImage {
    MemImage::table(ALPHA_ROM, alpha.entry_bits(), Arc::new(alpha.rom.clone()))
}
