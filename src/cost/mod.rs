//! Cost model (docs/reference.md §7b): the stages' memories and arithmetic summed over the
//! plan, and the pack check of every memory's contents ([`pack`]).

pub mod pack;
pub mod rom;

pub use pack::PackCheck;

use crate::stage::StageReport;
use serde::Serialize;
use std::collections::BTreeMap;

/// Storage and arithmetic of the planned stages.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CostSummary {
    /// RAM bits per stage (frame memory, sample buffer, line buffers).
    pub storage_bits: BTreeMap<String, u64>,
    /// ROM bits per stage (filter weights, LUTs, coefficient ROMs).
    pub rom_bits: BTreeMap<String, u64>,
    /// Total RAM bits.
    pub total_storage_bits: u64,
    /// Total ROM bits.
    pub total_rom_bits: u64,
    /// Adders / comparators / accumulators (units).
    pub adders: u64,
    /// Sum over adders of count x width, bits.
    pub adder_bits: u64,
    /// Multipliers / dividers (units).
    pub multipliers: u64,
    /// Sum over multipliers of count x width x width_b (partial-product bits).
    pub multiplier_bit_products: u64,
    /// Memories packed with `bitvec` and read back.
    pub packed: Vec<PackCheck>,
    /// Line buffers of the streamed depth-of-field schedule (in `storage_bits` as
    /// [`LINE_BUFFERS`] and in the total; 0 on the finished frame).
    pub line_buffer_bits: u64,
}

/// The `storage_bits` key of the streamed schedule's line buffers between accumulate and
/// depth of field (docs/cycles.md, "Streamed depth of field").
pub const LINE_BUFFERS: &str = "dof stream line buffers";

impl CostSummary {
    /// Charges the streamed schedule's line buffers (`bits`: rows held x frame width x bits
    /// per pixel the depth of field reads; 0 adds nothing).
    pub fn with_line_buffers(mut self, bits: u64) -> Self {
        if bits > 0 {
            *self.storage_bits.entry(LINE_BUFFERS.into()).or_default() += bits;
            self.total_storage_bits += bits;
            self.line_buffer_bits += bits;
        }
        self
    }
}

/// Sums the stage costs.
pub fn summarize(stages: &[StageReport], packed: Vec<PackCheck>) -> CostSummary {
    let mut c = CostSummary {
        packed,
        ..Default::default()
    };
    for s in stages {
        if s.cost.storage_bits > 0 {
            // A colour render's lanes add their channel's memories to the stage's.
            *c.storage_bits.entry(s.name.clone()).or_default() += s.cost.storage_bits;
        }
        if s.cost.lut_bits > 0 {
            *c.rom_bits.entry(s.name.clone()).or_default() += s.cost.lut_bits;
        }
        c.total_storage_bits += s.cost.storage_bits;
        c.total_rom_bits += s.cost.lut_bits;
        for u in &s.cost.adders {
            c.adders += u.count as u64;
            c.adder_bits += u.count as u64 * u.width as u64;
        }
        for u in &s.cost.multipliers {
            c.multipliers += u.count as u64;
            c.multiplier_bit_products += u.count as u64 * u.width as u64 * u.width_b.max(1) as u64;
        }
    }
    c
}
