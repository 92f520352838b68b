//! Exact quantisation: rounding of dyadic rationals and overflow handling.

use super::{Overflow, QFormat, Quant, SignalStats};

/// Rounds the exact rational value `raw * 2^-shift` to an integer with mode `q`.
///
/// Pure integer arithmetic, exact for every `raw` and every `shift` (0..=100 is the intended
/// range; larger shifts are handled too: the value is then below one in magnitude).
#[inline]
pub fn round_shift(raw: i128, shift: u32, q: Quant) -> i128 {
    if shift == 0 {
        return raw;
    }
    if shift >= 127 {
        // |raw * 2^-shift| <= 1, with equality only for i128::MIN at shift 127.
        if shift == 127 && raw == i128::MIN {
            return -1;
        }
        // Otherwise |value| < 1/2 and every mode rounds it like +-1/4 (sticky reduction).
        return round_shift(raw.signum(), 2, q);
    }
    let floor = raw >> shift;
    let rem = raw & ((1i128 << shift) - 1);
    if rem == 0 {
        return floor;
    }
    let half = 1i128 << (shift - 1);
    floor
        + i128::from(rounds_up(
            q,
            raw < 0,
            floor < 0,
            floor & 1 != 0,
            rem.cmp(&half),
        ))
}

/// Whether a value with a non-zero discarded part rounds up from its floor. `rem_vs_half`
/// compares the discarded part with one half; on an exact tie the value is `floor + 1/2`,
/// negative iff `floor < 0`.
#[inline]
fn rounds_up(
    q: Quant,
    negative: bool,
    floor_negative: bool,
    floor_odd: bool,
    rem_vs_half: std::cmp::Ordering,
) -> bool {
    use std::cmp::Ordering::Equal;
    match q {
        Quant::Trn => false,
        Quant::TrnZero => negative,
        _ if rem_vs_half != Equal => rem_vs_half == std::cmp::Ordering::Greater,
        Quant::Rnd => true,
        Quant::RndZero => floor_negative,
        Quant::RndInf => !floor_negative,
        Quant::RndMinInf => false,
        Quant::RndConv => floor_odd,
    }
}

/// [`round_shift`] for the hot loops: the same rounding on `i64` (`shift` in 0..=62).
/// Exhaustively checked against [`round_shift`] in the tests.
#[inline]
pub fn round_shift_i64(raw: i64, shift: u32, q: Quant) -> i64 {
    RoundShift::new(shift, q).apply(raw)
}

/// [`round_shift_i64`] with its mode turned into constants once: `raw * 2^-shift` is
/// rounded as `(raw + bias) >> shift` (an arithmetic shift is the floor), the bias set by
/// the sign of `raw` and, for convergent rounding, by the parity of the floor. No branch
/// on the mode per value; a sum that would leave `i64` takes [`round_shift`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RoundShift {
    shift: u32,
    q: Quant,
    /// Bias for `raw >= 0` and for `raw < 0`.
    pos: i64,
    neg: i64,
    /// 1 for ties to even (the floor's lowest bit joins the bias), else 0.
    conv: i64,
}

impl RoundShift {
    /// The rounding of `raw * 2^-shift` in mode `q` (`shift` in 0..=62).
    pub const fn new(shift: u32, q: Quant) -> Self {
        assert!(shift < 63);
        let (pos, neg, conv) = if shift == 0 {
            (0, 0, 0)
        } else {
            let half = 1i64 << (shift - 1);
            match q {
                Quant::Trn => (0, 0, 0),
                Quant::TrnZero => (0, 2 * half - 1, 0),
                Quant::Rnd => (half, half, 0),
                Quant::RndZero => (half - 1, half, 0),
                Quant::RndInf => (half, half - 1, 0),
                Quant::RndMinInf => (half - 1, half - 1, 0),
                Quant::RndConv => (half - 1, half - 1, 1),
            }
        };
        Self {
            shift,
            q,
            pos,
            neg,
            conv,
        }
    }

    /// The bits dropped.
    pub const fn shift(&self) -> u32 {
        self.shift
    }

    /// Whether [`RoundShift::apply_small`] rounds `raw` (its bias cannot leave `i64`).
    #[inline(always)]
    pub fn is_small(raw: i64) -> bool {
        raw.unsigned_abs() <= 1 << 62
    }

    /// [`RoundShift::apply`] for a `raw` that [`RoundShift::is_small`] accepts: no overflow
    /// check, so a loop over such values vectorises.
    #[inline(always)]
    pub fn apply_small(&self, raw: i64) -> i64 {
        raw.wrapping_add(self.bias(raw)) >> self.shift
    }

    /// [`RoundShift::apply`] for `0 <= raw <= 2^62` (so [`RoundShift::is_small`] holds),
    /// in `u64`: the positive bias only, and logical shifts (a loop over such values
    /// vectorises with 64-bit lanes, which have no arithmetic shift before AVX-512).
    #[inline(always)]
    pub fn apply_nonneg(&self, raw: u64) -> u64 {
        let conv = self.conv as u64;
        raw.wrapping_add(self.pos as u64 + ((raw >> self.shift) & conv)) >> self.shift
    }

    /// The raw values `v` with `|v| <= 2^62` ([`RoundShift::is_small`]) whose rounding lies
    /// in `lo..=hi`: one range, since every mode's rounding is monotonic (`None` if empty).
    pub fn raw_range(&self, lo: i64, hi: i64) -> Option<(i64, i64)> {
        const EDGE: i64 = 1 << 62;
        let r = |v: i64| self.apply_small(v);
        if lo > hi || r(EDGE) < lo || r(-EDGE) > hi {
            return None;
        }
        // The smallest v with r(v) >= lo, and the largest with r(v) <= hi (the bounds in
        // i128: the two edges are 2^63 apart).
        let (mut a, mut b) = (-i128::from(EDGE), i128::from(EDGE));
        while a < b {
            let m = (a + b).div_euclid(2);
            if r(m as i64) >= lo { b = m } else { a = m + 1 }
        }
        let first = a as i64;
        let (mut a, mut b) = (-i128::from(EDGE), i128::from(EDGE));
        while a < b {
            let m = (a + b + 1).div_euclid(2);
            if r(m as i64) <= hi { a = m } else { b = m - 1 }
        }
        let a = a as i64;
        (first <= a).then_some((first, a))
    }

    /// The bias added to `raw` before the shift.
    #[inline(always)]
    fn bias(&self, raw: i64) -> i64 {
        let sign = if raw < 0 { self.neg } else { self.pos };
        sign + ((raw >> self.shift) & self.conv)
    }

    /// `raw * 2^-shift` rounded.
    #[inline(always)]
    pub fn apply(&self, raw: i64) -> i64 {
        match raw.checked_add(self.bias(raw)) {
            Some(v) => v >> self.shift,
            None => round_shift(i128::from(raw), self.shift, self.q) as i64,
        }
    }
}

/// A quantised code and whether the overflow mode had to act.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quantized {
    /// The canonical code, within `[min_code, max_code]` of the format.
    pub code: i64,
    /// True when the rounded value was outside the format's range (for `SAT_SYM` also when it
    /// was exactly `-2^(W-1)`), i.e. the overflow mode changed it. With [`Overflow::Error`] the
    /// caller must stop.
    pub overflow: bool,
}

/// A quantisation point: target format, rounding mode and overflow mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct Quantizer {
    /// Target format.
    pub format: QFormat,
    /// Rounding mode.
    pub quant: Quant,
    /// Overflow mode.
    pub overflow: Overflow,
}

impl Quantizer {
    /// Builds a quantiser (the format is not validated here).
    pub const fn new(format: QFormat, quant: Quant, overflow: Overflow) -> Self {
        Self {
            format,
            quant,
            overflow,
        }
    }

    /// Quantises the exact value `raw * 2^-raw_frac` (a negative `raw_frac` means
    /// `raw << -raw_frac`). Exact for every input, including shifts that overflow `i128`.
    #[inline]
    pub fn quantize_raw(&self, raw: i128, raw_frac: i32) -> Quantized {
        self.handle_overflow(self.round_raw(raw, raw_frac))
    }

    /// Rounds `raw * 2^-raw_frac` to an integer number of LSBs of the format, before overflow
    /// handling. Values too large for `i128` come back as a proxy that is far outside any
    /// format's range, has the right sign and is congruent to the exact value modulo 2^32
    /// (so `WRAP` still gives the exact result).
    #[inline]
    pub(crate) fn round_raw(&self, raw: i128, raw_frac: i32) -> i128 {
        let shift = i64::from(raw_frac) - i64::from(self.format.frac_bits);
        if shift >= 0 {
            round_shift(raw, shift.min(1 << 20) as u32, self.quant)
        } else {
            let k = (-shift) as u32;
            if raw == 0 {
                0
            } else if k < 127 && (raw.unsigned_abs().leading_zeros() > k + 1) {
                raw << k
            } else {
                // |raw << k| >= 2^126: out of range for every format.
                let low = if k < 128 {
                    raw.wrapping_shl(k) & 0xFFFF_FFFF
                } else {
                    0
                };
                if raw > 0 {
                    (i128::MAX & !0xFFFF_FFFF) | low
                } else {
                    i128::MIN | low
                }
            }
        }
    }

    /// Quantises a real value, exactly for every finite `f64` (an `f64` is a dyadic rational).
    /// NaN gives code 0 with `overflow = true`; `+-inf` overflow with their sign (`WRAP` gives 0,
    /// the limit of huge values, which are all multiples of 2^W).
    #[inline]
    pub fn quantize_f64(&self, x: f64) -> Quantized {
        match self.round_f64(x) {
            Some(r) => self.handle_overflow(r),
            None => Quantized {
                code: 0,
                overflow: true,
            },
        }
    }

    /// Rounds `x` to an integer number of LSBs before overflow handling; `None` for NaN.
    #[inline]
    pub(crate) fn round_f64(&self, x: f64) -> Option<i128> {
        let bits = x.to_bits();
        let neg = bits >> 63 != 0;
        let exp = ((bits >> 52) & 0x7FF) as i32;
        let frac = (bits & ((1u64 << 52) - 1)) as i128;
        if exp == 0x7FF {
            if frac != 0 {
                return None;
            }
            return Some(if neg {
                i128::MIN
            } else {
                i128::MAX & !0xFFFF_FFFF
            });
        }
        let (mant, e) = if exp == 0 {
            (frac, -1074)
        } else {
            (frac | (1i128 << 52), exp - 1075)
        };
        let m = if neg { -mant } else { mant };
        Some(self.round_raw(m, -e))
    }

    /// Applies the overflow mode to an integer number of LSBs (e.g. after a saturating add).
    #[inline]
    pub fn handle_overflow(&self, v: i128) -> Quantized {
        let f = &self.format;
        let min = i128::from(f.min_code());
        let max = i128::from(f.max_code());
        if v >= min && v <= max {
            if self.overflow == Overflow::SatSym && f.signed && v == min {
                return Quantized {
                    code: -max as i64,
                    overflow: true,
                };
            }
            return Quantized {
                code: v as i64,
                overflow: false,
            };
        }
        let code = match self.overflow {
            Overflow::Wrap => {
                let w = f.total_bits();
                if f.signed {
                    ((v << (128 - w)) >> (128 - w)) as i64
                } else {
                    (v & ((1i128 << w) - 1)) as i64
                }
            }
            Overflow::Sat | Overflow::Error => {
                if v > max {
                    max as i64
                } else {
                    min as i64
                }
            }
            Overflow::SatZero => 0,
            Overflow::SatSym => {
                if v > max {
                    max as i64
                } else if f.signed {
                    -max as i64
                } else {
                    0
                }
            }
        };
        Quantized {
            code,
            overflow: true,
        }
    }
}

/// Quantises `xs` into `out` (same length) and records every value in `stats`.
///
/// The recorded error is `rounded - exact` in LSBs, before overflow handling. NaN and
/// infinite inputs count as values and overflows but do not touch range or error sums.
pub fn quantize_slice_f64(q: &Quantizer, xs: &[f64], out: &mut [i64], stats: &mut SignalStats) {
    assert_eq!(xs.len(), out.len(), "quantize_slice_f64: length mismatch");
    let scale = q.format.lsb().recip();
    for (x, o) in xs.iter().zip(out.iter_mut()) {
        if x.is_finite() {
            let r = q.round_f64(*x).unwrap_or(0);
            let res = q.handle_overflow(r);
            stats.record(x * scale, r, res.overflow);
            *o = res.code;
        } else {
            let res = q.quantize_f64(*x);
            stats.count += 1;
            stats.overflows += 1;
            *o = res.code;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_shift_ties() {
        // value 5/2 and -5/2
        let cases = [
            (Quant::Trn, 2, -3),
            (Quant::TrnZero, 2, -2),
            (Quant::Rnd, 3, -2),
            (Quant::RndZero, 2, -2),
            (Quant::RndInf, 3, -3),
            (Quant::RndMinInf, 2, -3),
            (Quant::RndConv, 2, -2),
        ];
        for (q, p, n) in cases {
            assert_eq!(round_shift(5, 1, q), p, "{q} +2.5");
            assert_eq!(round_shift(-5, 1, q), n, "{q} -2.5");
        }
        assert_eq!(round_shift(7, 1, Quant::RndConv), 4);
        assert_eq!(round_shift(-1, 100, Quant::Trn), -1);
        assert_eq!(round_shift(-1, 500, Quant::Trn), -1);
        assert_eq!(round_shift(1, 500, Quant::Rnd), 0);
        assert_eq!(round_shift(i128::MIN, 127, Quant::Rnd), -1);
        assert_eq!(round_shift(i128::MIN, 126, Quant::Rnd), -2);
    }

    #[test]
    fn overflow_modes() {
        let f = QFormat::new(true, 4, 0); // -8..=7
        let h = |o, v| Quantizer::new(f, Quant::Trn, o).handle_overflow(v);
        assert_eq!(
            h(Overflow::Wrap, 8),
            Quantized {
                code: -8,
                overflow: true
            }
        );
        assert_eq!(
            h(Overflow::Sat, -9),
            Quantized {
                code: -8,
                overflow: true
            }
        );
        assert_eq!(
            h(Overflow::SatSym, -8),
            Quantized {
                code: -7,
                overflow: true
            }
        );
        assert_eq!(
            h(Overflow::SatSym, -7),
            Quantized {
                code: -7,
                overflow: false
            }
        );
        assert_eq!(
            h(Overflow::SatZero, 100),
            Quantized {
                code: 0,
                overflow: true
            }
        );
        assert_eq!(
            h(Overflow::Error, 100),
            Quantized {
                code: 7,
                overflow: true
            }
        );
        let q = Quantizer::new(f, Quant::Trn, Overflow::Wrap);
        // 3 * 2^200 wraps to 0 modulo 16; 3 * 2^2 = 12 wraps to -4.
        assert_eq!(
            q.quantize_raw(3, -200),
            Quantized {
                code: 0,
                overflow: true
            }
        );
        assert_eq!(
            q.quantize_raw(3, -2),
            Quantized {
                code: -4,
                overflow: true
            }
        );
        assert_eq!(q.quantize_raw(-3, -125).code, 0);
    }
}
