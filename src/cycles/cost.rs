//! Cost summary (DESIGN.md §6): storage and ROM bits exact from the formats, adders and
//! multipliers by width, and a packing check: the real contents (frame memory, sample
//! buffer, gamma ROM) are stored with `bitvec` into a bit vector of exactly the computed
//! length and read back.

use crate::stage::StageReport;
use bitvec::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

/// One memory packed and read back.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct PackCheck {
    /// Memory.
    pub name: String,
    /// Words stored.
    pub words: u64,
    /// Field widths of one word, bits.
    pub fields: Vec<u32>,
    /// Bits of the bit vector (exactly `words x sum(fields)`).
    pub bits: u64,
    /// Whether every field fitted its width and read back equal, and the length matched
    /// the computed size.
    pub verified: bool,
}

/// Packs `words` records of `fields` widths (`get(record, field)`) into a `BitVec` of
/// exactly `expected_bits` and reads every field back.
///
/// The write fills the bit vector's `u64` storage word by word (LSB first, as `Lsb0`); the
/// read-back goes through `bitvec`'s own bit addressing (`load_le` of each record's span,
/// split into its fields), so the two sides are independent.
pub fn pack(
    name: &str,
    words: usize,
    fields: &[u32],
    expected_bits: u64,
    get: impl Fn(usize, usize) -> u64,
) -> PackCheck {
    let wb: usize = fields.iter().map(|&f| f as usize).sum();
    let mut ok =
        (words * wb) as u64 == expected_bits && fields.iter().all(|&f| (1..=64).contains(&f));
    let mut bv: BitVec<u64, Lsb0> = BitVec::repeat(false, expected_bits as usize);
    let mask = |f: u32| if f == 64 { u64::MAX } else { (1u64 << f) - 1 };
    if ok {
        let raw = bv.as_raw_mut_slice();
        let (mut acc, mut n, mut wi) = (0u128, 0u32, 0usize);
        for r in 0..words {
            for (k, &f) in fields.iter().enumerate() {
                let v = get(r, k);
                ok &= v & !mask(f) == 0;
                // n < 64 and f <= 64: the shifted field fits the 128-bit accumulator.
                acc |= ((v & mask(f)) as u128) << n;
                n += f;
                if n >= 64 {
                    raw[wi] = acc as u64;
                    wi += 1;
                    acc >>= 64;
                    n -= 64;
                }
            }
        }
        if n > 0 {
            raw[wi] = acc as u64;
        }
        let mut at = 0;
        for r in 0..words {
            if wb <= 64 {
                let mut rec = bv[at..at + wb].load_le::<u64>();
                for (k, &f) in fields.iter().enumerate() {
                    ok &= rec & mask(f) == get(r, k) & mask(f);
                    rec = if f == 64 { 0 } else { rec >> f };
                }
                at += wb;
            } else {
                for (k, &f) in fields.iter().enumerate() {
                    ok &= bv[at..at + f as usize].load_le::<u64>() == get(r, k) & mask(f);
                    at += f as usize;
                }
            }
        }
    }
    PackCheck {
        name: name.into(),
        words: words as u64,
        fields: fields.to_vec(),
        bits: bv.len() as u64,
        verified: ok && bv.len() as u64 == expected_bits,
    }
}

/// Storage and arithmetic of the planned stages.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CostSummary {
    /// RAM bits per stage (frame memory, sample buffer / z-buffer).
    pub storage_bits: BTreeMap<String, u64>,
    /// ROM bits per stage (filter weights, gamma LUT).
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
}

/// Sums the stage costs.
pub fn summarize(stages: &[StageReport], packed: Vec<PackCheck>) -> CostSummary {
    let mut c = CostSummary {
        packed,
        ..Default::default()
    };
    for s in stages {
        if s.cost.storage_bits > 0 {
            c.storage_bits.insert(s.name.clone(), s.cost.storage_bits);
        }
        if s.cost.lut_bits > 0 {
            c.rom_bits.insert(s.name.clone(), s.cost.lut_bits);
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
