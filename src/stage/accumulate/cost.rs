//! Hardware cost of the accumulate stage: frame memory, weight ROM, window adder and the
//! weight x intensity multiplier.

use super::fixed::AccParams;
use crate::stage::{Cost, Memory, Unit};

/// Name of the frame memory.
pub const FRAME_MEMORY: &str = "frame memory";
/// Name of the filter weight ROM.
pub const WEIGHT_ROM: &str = "filter weight ROM";

/// Cost of the stage.
pub fn cost(p: &AccParams, i_bits: u32, pixels: u64) -> Cost {
    let fb = p.frame.format.total_bits();
    let prod = p.kernel.f + 1 + i_bits;
    let sum_bits = prod
        + (p.kernel.size * p.kernel.size)
            .next_power_of_two()
            .trailing_zeros();
    Cost::new(
        vec![
            Memory::ram(FRAME_MEMORY, pixels, fb),
            Memory::rom(WEIGHT_ROM, p.kernel.w.len() as u64, p.kernel.f + 1),
        ],
        vec![
            Unit::adder("window sum (w*I)", 1, sum_bits),
            Unit::adder("frame read-modify-write", 1, fb),
        ],
        vec![Unit::mul("weight x intensity", 1, p.kernel.f + 1, i_bits)],
    )
}
