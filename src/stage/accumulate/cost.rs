//! Hardware cost of the accumulate stage: frame memory, weight ROM, window adder and the
//! weight x intensity multiplier.

use super::fixed::AccParams;
use crate::stage::{Cost, Unit};

/// Cost of the stage.
pub fn cost(p: &AccParams, i_bits: u32, pixels: u64) -> Cost {
    let fb = p.frame.format.total_bits();
    let prod = p.kernel.f + 1 + i_bits;
    let sum_bits = prod
        + (p.kernel.size * p.kernel.size)
            .next_power_of_two()
            .trailing_zeros();
    Cost {
        storage_bits: pixels * fb as u64,
        lut_bits: (p.kernel.w.len() as u64) * (p.kernel.f as u64 + 1),
        adders: vec![
            Unit::adder("window sum (w*I)", 1, sum_bits),
            Unit::adder("frame read-modify-write", 1, fb),
        ],
        multipliers: vec![Unit::mul("weight x intensity", 1, p.kernel.f + 1, i_bits)],
    }
}
