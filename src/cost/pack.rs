//! The pack check: the contents of every memory the plan uses (frame memory, sample
//! buffer, the gamma LUT actually built, the potentiation and eq. 15 LUTs, the DoF
//! coefficient ROM, ...) are stored with `bitvec` into a bit vector of exactly the size the
//! stage's cost model charges for that memory, and every entry is read back.
//!
//! It fails when the cost model and the contents disagree: a word wider than the cost's
//! width, a depth other than the cost's (a region image may be smaller), an entry that does
//! not fit its field, or an entry that does not read back.

use crate::stage::{Cost, MemImage};
use bitvec::prelude::*;
use serde::Serialize;

/// One memory packed and read back.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct PackCheck {
    /// Memory.
    pub name: String,
    /// Words stored.
    pub words: u64,
    /// Field widths of one word, bits.
    pub fields: Vec<u32>,
    /// Bits the cost model charges for the memory (for a region image: its words at the
    /// cost's width).
    pub cost_bits: u64,
    /// Bits of the bit vector the contents were packed into.
    pub bits: u64,
    /// Whether the image matched the cost model and every entry fitted and read back.
    pub verified: bool,
    /// Why not, when not verified.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub problem: Option<String>,
}

/// Checks every image against the memory of the same name in `cost`.
pub fn check(cost: &Cost, images: &[MemImage]) -> Vec<PackCheck> {
    images.iter().map(|im| check_one(cost, im)).collect()
}

fn check_one(cost: &Cost, im: &MemImage) -> PackCheck {
    let wb: u32 = im.fields.iter().sum();
    let mut out = PackCheck {
        name: im.name.clone(),
        words: im.words as u64,
        fields: im.fields.clone(),
        cost_bits: 0,
        bits: 0,
        verified: false,
        problem: None,
    };
    let Some(m) = cost.memories.iter().find(|m| m.name == im.name) else {
        out.problem = Some("no memory of this name in the stage's cost".into());
        return out;
    };
    out.cost_bits = if im.region_only {
        im.words as u64 * m.width as u64
    } else {
        m.bits()
    };
    if wb != m.width {
        out.problem = Some(format!(
            "the fields sum to {wb} bits but the cost charges {}-bit words",
            m.width
        ));
        return out;
    }
    let depth_ok = if im.region_only {
        im.words as u64 <= m.depth
    } else {
        im.words as u64 == m.depth
    };
    if !depth_ok {
        out.problem = Some(format!(
            "{} words but the cost charges {}",
            im.words, m.depth
        ));
        return out;
    }
    match pack(im, out.cost_bits) {
        Ok(bits) => {
            out.bits = bits;
            out.verified = true;
        }
        Err(p) => out.problem = Some(p),
    }
    out
}

/// Packs the image into a `BitVec` of exactly `bits` and reads every field back; returns
/// the vector's length.
///
/// The write fills the bit vector's `u64` storage word by word (LSB first, as `Lsb0`); the
/// read-back goes through `bitvec`'s own bit addressing (`load_le` of each record's span,
/// split into its fields), so the two sides are independent.
pub fn pack(im: &MemImage, bits: u64) -> Result<u64, String> {
    let fields = &im.fields;
    let wb: usize = fields.iter().map(|&f| f as usize).sum();
    if (im.words * wb) as u64 != bits {
        return Err(format!(
            "{} words of {wb} bits do not make {bits} bits",
            im.words
        ));
    }
    if let Some(f) = fields.iter().find(|&&f| !(1..=64).contains(&f)) {
        return Err(format!("a field of {f} bits (1..=64 supported)"));
    }
    let mask = |f: u32| if f == 64 { u64::MAX } else { (1u64 << f) - 1 };
    let mut bv: BitVec<u64, Lsb0> = BitVec::repeat(false, bits as usize);
    let raw = bv.as_raw_mut_slice();
    let (mut acc, mut n, mut wi) = (0u128, 0u32, 0usize);
    for r in 0..im.words {
        for (k, &f) in fields.iter().enumerate() {
            let v = (im.get)(r, k);
            if v & !mask(f) != 0 {
                return Err(format!(
                    "word {r} field {k}: value {v} does not fit {f} bits"
                ));
            }
            // n < 64 and f <= 64: the shifted field fits the 128-bit accumulator.
            acc |= (v as u128) << n;
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
    for r in 0..im.words {
        if wb <= 64 {
            let mut rec = bv[at..at + wb].load_le::<u64>();
            for (k, &f) in fields.iter().enumerate() {
                if rec & mask(f) != (im.get)(r, k) {
                    return Err(format!("word {r} field {k} does not read back"));
                }
                rec = if f == 64 { 0 } else { rec >> f };
            }
            at += wb;
        } else {
            for (k, &f) in fields.iter().enumerate() {
                if bv[at..at + f as usize].load_le::<u64>() != (im.get)(r, k) {
                    return Err(format!("word {r} field {k} does not read back"));
                }
                at += f as usize;
            }
        }
    }
    Ok(bv.len() as u64)
}
