//! Hardware cost of the accumulate stage: frame memory, weight ROM, window adder and the
//! weight x intensity multiplier; for a signed kernel (Catmull-Rom, Mitchell) the signed
//! weight ROM, the signed multiplier and the wider signed accumulator with its clamp.

use super::fixed::AccParams;
use crate::stage::{Cost, Memory, Unit};

/// Name of the frame memory.
pub const FRAME_MEMORY: &str = "frame memory";
/// Name of the filter weight ROM.
pub const WEIGHT_ROM: &str = "filter weight ROM";

/// Cost of the stage.
pub fn cost(p: &AccParams, i_bits: u32, pixels: u64) -> Cost {
    let k = &p.kernel;
    let fb = p.frame.format.total_bits();
    let wb = k.rom_bits();
    let prod = wb + i_bits;
    let sum_bits = prod + (k.size * k.size).next_power_of_two().trailing_zeros();
    let rom = Memory::rom(WEIGHT_ROM, k.w.len() as u64, wb);
    match k.accumulator(&p.frame) {
        None => Cost::new(
            vec![Memory::ram(FRAME_MEMORY, pixels, fb), rom],
            vec![
                Unit::adder("window sum (w*I)", 1, sum_bits),
                Unit::adder("frame read-modify-write", 1, fb),
            ],
            vec![Unit::mul("weight x intensity", 1, wb, i_bits)],
        ),
        Some(q) => {
            // The partial sums live in the frame memory between a pixel's fragments (they
            // arrive in primitive order), so its word is the accumulator's; the clamp to
            // the frame word is on the way out.
            let ab = q.format.total_bits();
            Cost::new(
                vec![Memory::ram(FRAME_MEMORY, pixels, ab), rom],
                vec![
                    Unit::adder("window sum (signed w*I)", 1, sum_bits),
                    Unit::adder("frame read-modify-write (signed)", 1, ab),
                    Unit::adder("clamp to the frame word", 1, ab),
                ],
                vec![Unit::mul("signed weight x intensity", 1, wb, i_bits + 1)],
            )
        }
    }
}
