//! `[coding]`: how intensity is coded in the sample buffer and the frame memory (linear, or
//! one of the two log-domain structures of docs/reference.md §1, Fig. 7).

use super::set;
use crate::fixed::{Overflow, Quant};
use serde::{Deserialize, Serialize};

/// Largest sample log-code width.
pub const MAX_LOG_BITS: u32 = 12;
/// Smallest sample log-code width.
pub const MIN_LOG_BITS: u32 = 3;
/// sb-table address width range.
pub const TABLE_ADDR_BITS: std::ops::RangeInclusive<u32> = 4..=16;
/// sb-table data fraction bits range.
pub const TABLE_FRAC_BITS: std::ops::RangeInclusive<u32> = 0..=12;
/// Extra fraction bits of the log frame word.
pub const ACC_FRAC_BITS: std::ops::RangeInclusive<u32> = 0..=8;

/// How intensity is coded in the sample buffer and the frame memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CodingKind {
    /// The spine's linear code everywhere; no log stage runs.
    Linear,
    /// Structure (a): log-coded samples, potentiation LUT, linear accumulation.
    LogPotentiate,
    /// Structure (b): log-coded samples, log adder and Gaussian-log accumulation, eq. 15 LUT.
    LogAdd,
}

/// The `[coding]` section of the hardware file.
///
/// ```toml
/// [coding]
/// kind = "log-add"        # "linear" | "log-potentiate" | "log-add"
/// log_bits = 8            # sample log code, 3..=12 bits (2^b - 1 grades)
/// acc_frac_bits = 2       # log frame word: extra fraction bits below a grade, 0..=8
/// table_addr_bits = 10    # sb table address, 4..=16 bits
/// table_frac_bits = 0     # sb table data: fraction bits below the frame LSB, 0..=12
/// interpolate = false     # linear interpolation between sb entries
/// quant = "RND"           # log adder: rounding of max + sb to the frame LSB (any mode)
/// overflow = "SAT"        # log frame word above full white: "SAT" (counted) or "ERROR"
/// ```
/// Defaults (all presets): `acc_frac_bits = 2` (`log7-logadd`: 3), `table_addr_bits = 10`,
/// `table_frac_bits = 0`, `interpolate = false`, `quant = "RND"`, `overflow = "SAT"`; linear
/// presets have `kind = "linear"`.
///
/// `quant` and `overflow` are the log adder's (structure b) quantisation point: the sum
/// `max + sb` carries `table_frac_bits` fraction bits below the frame LSB and is rounded to
/// it with `quant` (the sum is never negative, so `RND` = `RND_INF`, `RND_ZERO` =
/// `RND_MIN_INF` and `TRN` = `TRN_ZERO`; the RTL `log_adder.v` rounds `RND`). The frame word
/// holds `[0, max]` with `max = off + G 2^acc_frac_bits` (full white, not a power of two),
/// so a sum above full white (light points can exceed white, and rounding can push a
/// full-white sum one LSB over) overflows: `SAT` clamps it to full white and counts it in
/// the signal `logdomain.frame`, `ERROR` stops the render with an overflow error naming
/// that signal. The other overflow modes are refused: wrapping or zeroing a log code would
/// turn white into black.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CodingCfg {
    /// Linear or one of the two log structures.
    pub kind: CodingKind,
    /// Sample log-code width `b` (`MIN_LOG_BITS..=MAX_LOG_BITS`); `2^b - 1` grades.
    pub log_bits: u32,
    /// Extra fraction bits of the log frame word (structure b), 0..=8.
    pub acc_frac_bits: u32,
    /// sb-table address bits, 4..=16.
    pub table_addr_bits: u32,
    /// sb-table data fraction bits (below the frame LSB), 0..=12.
    pub table_frac_bits: u32,
    /// Linear interpolation between sb-table entries (else direct lookup).
    pub interpolate: bool,
    /// Rounding of the log adder's sum to the frame LSB (structure b); default `RND`.
    pub quant: Quant,
    /// Overflow of the log frame word above full white: `SAT` (default) or `ERROR`.
    pub overflow: Overflow,
}

impl CodingCfg {
    /// Linear coding (the spine).
    pub fn linear() -> Self {
        Self {
            kind: CodingKind::Linear,
            log_bits: 8,
            acc_frac_bits: 2,
            table_addr_bits: 10,
            table_frac_bits: 0,
            interpolate: false,
            quant: Quant::Rnd,
            overflow: Overflow::Sat,
        }
    }

    /// The log presets: `log8-potentiate`, `log8-logadd`, `log7-logadd`.
    pub fn preset(name: &str) -> Option<Self> {
        // Frame fraction bits chosen by measurement on the default scene (docs/logdomain.md):
        // 64-term chains per pixel need guard bits below the sample grade.
        let (kind, log_bits, acc_frac_bits) = match name {
            "log8-potentiate" => (CodingKind::LogPotentiate, 8, 2),
            "log8-logadd" => (CodingKind::LogAdd, 8, 2),
            "log7-logadd" => (CodingKind::LogAdd, 7, 3),
            _ => return None,
        };
        Some(Self {
            kind,
            log_bits,
            acc_frac_bits,
            ..Self::linear()
        })
    }

    /// Checks the ranges; returns the field and a message.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let chk = |field: &str, v: u32, r: std::ops::RangeInclusive<u32>| {
            if r.contains(&v) {
                Ok(())
            } else {
                Err((
                    format!("coding.{field}"),
                    format!("must be in {}..={}, got {v}", r.start(), r.end()),
                ))
            }
        };
        chk("log_bits", self.log_bits, MIN_LOG_BITS..=MAX_LOG_BITS)?;
        chk("acc_frac_bits", self.acc_frac_bits, ACC_FRAC_BITS)?;
        chk("table_addr_bits", self.table_addr_bits, TABLE_ADDR_BITS)?;
        chk("table_frac_bits", self.table_frac_bits, TABLE_FRAC_BITS)?;
        if !matches!(self.overflow, Overflow::Sat | Overflow::Error) {
            return Err((
                "coding.overflow".into(),
                format!(
                    "must be SAT or ERROR (the log frame word saturates at full white or stops the render), got {}",
                    self.overflow
                ),
            ));
        }
        Ok(())
    }
}

/// `[coding]` as read from TOML (all fields optional).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCoding {
    kind: Option<CodingKind>,
    log_bits: Option<u32>,
    acc_frac_bits: Option<u32>,
    table_addr_bits: Option<u32>,
    table_frac_bits: Option<u32>,
    interpolate: Option<bool>,
    quant: Option<Quant>,
    overflow: Option<Overflow>,
}

impl RawCoding {
    /// Overrides the given fields.
    pub(super) fn apply(self, c: &mut CodingCfg) {
        set(&mut c.kind, self.kind);
        set(&mut c.log_bits, self.log_bits);
        set(&mut c.acc_frac_bits, self.acc_frac_bits);
        set(&mut c.table_addr_bits, self.table_addr_bits);
        set(&mut c.table_frac_bits, self.table_frac_bits);
        set(&mut c.interpolate, self.interpolate);
        set(&mut c.quant, self.quant);
        set(&mut c.overflow, self.overflow);
    }
}
