//! Fixed-point semantics shared by every pipeline stage.
//!
//! * [`QFormat`]: a runtime format descriptor (`Q4.12`, `UQ12.0`), total width 1..=32 bits.
//! * [`Quant`] / [`Overflow`]: the SystemC / `ac_fixed` / `ap_fixed` quantisation and overflow
//!   modes, by the names hardware engineers know (`TRN`, `RND_CONV`, `SAT_SYM`, ...).
//! * [`Quantizer`]: format + modes; turns an exact dyadic value (an integer and a binary point,
//!   or any finite `f64`) into a canonical integer code, reporting overflow.
//! * [`SignalStats`]: per-signal instrumentation (range, overflow count, quantisation error) and
//!   the narrowest format that holds the observed range.
//!
//! Codes are always canonical: within `[min_code, max_code]` of their format (wrapping
//! sign-extends for signed formats and masks for unsigned ones).

mod instrument;
mod quant;

pub use instrument::SignalStats;
pub use quant::{
    Quantized, Quantizer, RoundShift, quantize_slice_f64, round_shift, round_shift_i64,
};

use std::fmt;
use std::str::FromStr;

/// A fixed-point format: signedness, integer bits and fraction bits.
///
/// The total width is `int_bits + frac_bits` and must be 1..=32 bits. For signed formats
/// `int_bits` includes the sign bit, so `Q4.12` is 16 bits (`ac_fixed<16,4,true>`) and needs
/// `int_bits >= 1`; `UQ12.0` is a 12-bit unsigned integer (`ac_fixed<12,12,false>`).
/// The value of a code is `code * 2^-frac_bits`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct QFormat {
    /// Two's complement (true) or unsigned (false).
    pub signed: bool,
    /// Integer bits, including the sign bit for signed formats.
    pub int_bits: u32,
    /// Fraction bits.
    pub frac_bits: u32,
}

impl QFormat {
    /// Builds a format without validation (see [`QFormat::validate`]).
    pub const fn new(signed: bool, int_bits: u32, frac_bits: u32) -> Self {
        Self {
            signed,
            int_bits,
            frac_bits,
        }
    }

    /// Checks the width (1..=32 bits) and that signed formats have a sign bit.
    pub fn validate(&self) -> Result<(), String> {
        let total = u64::from(self.int_bits) + u64::from(self.frac_bits);
        if !(1..=32).contains(&total) {
            return Err(format!(
                "format {self}: total width {total} bits is outside 1..=32"
            ));
        }
        if self.signed && self.int_bits < 1 {
            return Err(format!(
                "format {self}: a signed format needs int_bits >= 1 (the integer bits include the sign bit); int_bits may be 1..={}",
                32 - self.frac_bits.min(31)
            ));
        }
        Ok(())
    }

    /// Parses `Q<int>.<frac>` (signed) or `UQ<int>.<frac>` (unsigned), case-insensitive,
    /// e.g. `Q4.12`, `UQ12.0`, `uq0.24`, and validates the result.
    pub fn parse(s: &str) -> Result<QFormat, String> {
        const SYNTAX: &str = "expected Q<int>.<frac> (signed, int bits include the sign bit, >= 1) or UQ<int>.<frac> (unsigned), total 1..=32 bits, e.g. Q4.12 or UQ12.0";
        let t = s.trim();
        let upper = t.to_ascii_uppercase();
        let (signed, rest) = if let Some(r) = upper.strip_prefix("UQ") {
            (false, r)
        } else if let Some(r) = upper.strip_prefix('Q') {
            (true, r)
        } else {
            return Err(format!("bad fixed-point format `{s}`: {SYNTAX}"));
        };
        let Some((i, f)) = rest.split_once('.') else {
            return Err(format!("bad fixed-point format `{s}`: {SYNTAX}"));
        };
        let num = |d: &str| -> Option<u32> {
            if d.is_empty() || d.len() > 3 || !d.bytes().all(|b| b.is_ascii_digit()) {
                None
            } else {
                d.parse().ok()
            }
        };
        let (Some(int_bits), Some(frac_bits)) = (num(i), num(f)) else {
            return Err(format!("bad fixed-point format `{s}`: {SYNTAX}"));
        };
        let q = QFormat::new(signed, int_bits, frac_bits);
        q.validate()
            .map_err(|e| format!("bad fixed-point format `{s}`: {e}"))?;
        Ok(q)
    }

    /// Total width in bits (`int_bits + frac_bits`).
    #[inline]
    pub fn total_bits(&self) -> u32 {
        self.int_bits + self.frac_bits
    }

    /// Smallest raw code: `-2^(W-1)` for signed formats, 0 for unsigned. The format must be valid.
    #[inline]
    pub fn min_code(&self) -> i64 {
        if self.signed {
            -(1i64 << (self.total_bits() - 1))
        } else {
            0
        }
    }

    /// Largest raw code: `2^(W-1) - 1` for signed formats, `2^W - 1` for unsigned.
    /// The format must be valid.
    #[inline]
    pub fn max_code(&self) -> i64 {
        if self.signed {
            (1i64 << (self.total_bits() - 1)) - 1
        } else {
            (1i64 << self.total_bits()) - 1
        }
    }

    /// Value of one LSB: `2^-frac_bits`.
    #[inline]
    pub fn lsb(&self) -> f64 {
        pow2(-(self.frac_bits as i32))
    }

    /// Real value of a code: `code * 2^-frac_bits` (exact for codes of up to 53 bits).
    #[inline]
    pub fn to_f64(&self, code: i64) -> f64 {
        code as f64 * self.lsb()
    }
}

/// `2^e` as f64, exact for -1074 <= e <= 1023.
pub(crate) fn pow2(e: i32) -> f64 {
    if e >= -1022 {
        f64::from_bits(((e + 1023) as u64) << 52)
    } else {
        f64::from_bits(1u64 << (e + 1074))
    }
}

impl fmt::Display for QFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let u = if self.signed { "" } else { "U" };
        write!(f, "{u}Q{}.{}", self.int_bits, self.frac_bits)
    }
}

impl FromStr for QFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        QFormat::parse(s)
    }
}

impl serde::Serialize for QFormat {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for QFormat {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        QFormat::parse(&s).map_err(serde::de::Error::custom)
    }
}

/// Quantisation (rounding) mode, SystemC / `ac_fixed` / `ap_fixed` semantics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Quant {
    /// Truncate toward minus infinity (floor).
    #[serde(rename = "TRN")]
    Trn,
    /// Truncate toward zero.
    #[serde(rename = "TRN_ZERO")]
    TrnZero,
    /// Round to nearest, ties toward plus infinity.
    #[serde(rename = "RND")]
    Rnd,
    /// Round to nearest, ties toward zero.
    #[serde(rename = "RND_ZERO")]
    RndZero,
    /// Round to nearest, ties away from zero.
    #[serde(rename = "RND_INF")]
    RndInf,
    /// Round to nearest, ties toward minus infinity.
    #[serde(rename = "RND_MIN_INF")]
    RndMinInf,
    /// Round to nearest, ties to even (convergent rounding).
    #[serde(rename = "RND_CONV")]
    RndConv,
}

impl Quant {
    /// Every quantisation mode.
    pub const ALL: [Quant; 7] = [
        Quant::Trn,
        Quant::TrnZero,
        Quant::Rnd,
        Quant::RndZero,
        Quant::RndInf,
        Quant::RndMinInf,
        Quant::RndConv,
    ];

    /// The hardware name (`TRN`, `RND_CONV`, ...).
    pub const fn name(self) -> &'static str {
        match self {
            Quant::Trn => "TRN",
            Quant::TrnZero => "TRN_ZERO",
            Quant::Rnd => "RND",
            Quant::RndZero => "RND_ZERO",
            Quant::RndInf => "RND_INF",
            Quant::RndMinInf => "RND_MIN_INF",
            Quant::RndConv => "RND_CONV",
        }
    }
}

impl fmt::Display for Quant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Quant {
    type Err = String;
    /// Case-insensitive; an `AC_` prefix is accepted.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let u = s.trim().to_ascii_uppercase();
        let u = u.strip_prefix("AC_").unwrap_or(&u);
        Quant::ALL
            .into_iter()
            .find(|q| q.name() == u)
            .ok_or_else(|| {
                format!(
                    "unknown quantisation mode `{s}`: expected one of TRN, TRN_ZERO, RND, RND_ZERO, RND_INF, RND_MIN_INF, RND_CONV"
                )
            })
    }
}

/// Overflow mode, SystemC / `ac_fixed` semantics, plus `ERROR`.
///
/// `SAT_SYM` follows `ac_fixed` exactly for W >= 2: a signed result is clamped to
/// `[-max, max]`, and the one in-range value `-2^(W-1)` is also mapped to `-max` (and flagged
/// as an overflow), as `ac_fixed.h` does (`underflow |= neg_src && low W-1 bits zero`).
/// For a 1-bit signed format (`Q1.f`, range {-1, 0}) `max = 0`, so the symmetric range is {0}:
/// every negative value gives 0 (ac_fixed's `set_val<AC_VAL_MIN>` agrees; its
/// `overflow_adjust` would produce the bit pattern `1`, i.e. -1, which is not symmetric).
/// For unsigned formats `SAT_SYM` equals `SAT`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Overflow {
    /// Two's complement wrap (unsigned: modulo 2^W).
    #[serde(rename = "WRAP")]
    Wrap,
    /// Clamp to `[min_code, max_code]`.
    #[serde(rename = "SAT")]
    Sat,
    /// Any overflow gives 0.
    #[serde(rename = "SAT_ZERO")]
    SatZero,
    /// Symmetric saturation: signed results clamp to `[-max, max]` (see the type docs).
    #[serde(rename = "SAT_SYM")]
    SatSym,
    /// The caller must stop with an error; the quantiser returns the `SAT` value and flags it.
    #[serde(rename = "ERROR")]
    Error,
}

impl Overflow {
    /// Every overflow mode.
    pub const ALL: [Overflow; 5] = [
        Overflow::Wrap,
        Overflow::Sat,
        Overflow::SatZero,
        Overflow::SatSym,
        Overflow::Error,
    ];

    /// The hardware name (`WRAP`, `SAT`, ...).
    pub const fn name(self) -> &'static str {
        match self {
            Overflow::Wrap => "WRAP",
            Overflow::Sat => "SAT",
            Overflow::SatZero => "SAT_ZERO",
            Overflow::SatSym => "SAT_SYM",
            Overflow::Error => "ERROR",
        }
    }
}

impl fmt::Display for Overflow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Overflow {
    type Err = String;
    /// Case-insensitive; an `AC_` prefix is accepted.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let u = s.trim().to_ascii_uppercase();
        let u = u.strip_prefix("AC_").unwrap_or(&u);
        Overflow::ALL
            .into_iter()
            .find(|o| o.name() == u)
            .ok_or_else(|| {
                format!(
                    "unknown overflow mode `{s}`: expected one of WRAP, SAT, SAT_ZERO, SAT_SYM, ERROR"
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_and_display() {
        let q = QFormat::new(true, 4, 12);
        assert_eq!(q.total_bits(), 16);
        assert_eq!((q.min_code(), q.max_code()), (-32768, 32767));
        assert_eq!(q.to_string(), "Q4.12");
        let u = QFormat::new(false, 12, 0);
        assert_eq!((u.min_code(), u.max_code()), (0, 4095));
        assert_eq!(u.to_string(), "UQ12.0");
        assert_eq!(q.lsb(), 1.0 / 4096.0);
        assert_eq!(q.to_f64(-4096), -1.0);
        assert_eq!(pow2(-1074), f64::from_bits(1));
        assert_eq!(pow2(0), 1.0);
    }

    #[test]
    fn mode_names_round_trip() {
        for q in Quant::ALL {
            assert_eq!(q.to_string().parse::<Quant>().unwrap(), q);
            let j = serde_json::to_string(&q).unwrap();
            assert_eq!(j, format!("\"{q}\""));
        }
        for o in Overflow::ALL {
            assert_eq!(o.to_string().parse::<Overflow>().unwrap(), o);
            let j = serde_json::to_string(&o).unwrap();
            assert_eq!(j, format!("\"{o}\""));
        }
        assert_eq!("ac_rnd_conv".parse::<Quant>().unwrap(), Quant::RndConv);
        assert!(
            "RND_EVEN"
                .parse::<Quant>()
                .unwrap_err()
                .contains("RND_CONV")
        );
        assert!("CLAMP".parse::<Overflow>().unwrap_err().contains("SAT_SYM"));
    }
}
