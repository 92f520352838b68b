//! The accumulate stage's product statistics per row of pixels, recorded without a float
//! add per value where every partial sum is exact.

use crate::fixed::SignalStats;

/// The product statistics of one row of pixels, recorded exactly as
/// [`SignalStats::record`] would (same values, same order of the float sums) but without
/// its optional 128-bit range per value; [`ProductStats::into_stats`] gives the
/// `SignalStats`.
///
/// A rounding that drops `sh` bits errs by `k * 2^-sh` for an integer `|k| < 2^sh`. Where
/// every partial sum of those errors and of their squares stays below `2^53` units of
/// `2^-sh` and `2^-2sh` (the caller's bound, [`ProductStats::new`] with `exact`), each
/// float add is exact, so the float sums equal the integer sums of `k` and `k^2` scaled
/// once at the end: the same bits, without a float add per value.
pub(super) struct ProductStats {
    count: u64,
    min: i64,
    max: i64,
    err_sum: f64,
    err_sq_sum: f64,
    /// Bits the roundings recorded by [`ProductStats::record_rounding`] drop.
    sh: u32,
    /// The errors of those roundings are summed as integers in `k_sum` and `k_sq`.
    exact: bool,
    k_sum: i64,
    k_sq: u64,
}

impl ProductStats {
    /// Nothing recorded, for roundings that drop `sh` bits; `exact`: their errors are
    /// summed as integers (only where the caller proved every partial sum exact, see
    /// above).
    pub fn new(sh: u32, exact: bool) -> Self {
        Self {
            count: 0,
            min: i64::MAX,
            max: i64::MIN,
            err_sum: 0.0,
            err_sq_sum: 0.0,
            sh,
            exact,
            k_sum: 0,
            k_sq: 0,
        }
    }

    /// Records one rounding (as `SignalStats::record(exact_lsb, rounded, false)`).
    #[inline(always)]
    pub fn record(&mut self, exact_lsb: f64, rounded: i64) {
        self.count += 1;
        self.min = self.min.min(rounded);
        self.max = self.max.max(rounded);
        let e = rounded as f64 - exact_lsb;
        self.err_sum += e;
        self.err_sq_sum += e * e;
    }

    /// Records `rounded`, the rounding of `sum * 2^-sh` (`0 < sh < 63`, the statistics'
    /// `sh`): as [`ProductStats::record`] of `sum * 2^-sh` (a multiplication by the power
    /// of two, exact like the division), in integers when `exact`.
    #[inline(always)]
    pub fn record_rounding(&mut self, rounded: i64, sum: i64) {
        let sh = self.sh;
        if self.exact {
            self.count += 1;
            self.min = self.min.min(rounded);
            self.max = self.max.max(rounded);
            let k = (rounded << sh).wrapping_sub(sum);
            self.k_sum += k;
            self.k_sq += k.unsigned_abs() * k.unsigned_abs();
        } else {
            // 2^-sh from its exponent bits.
            let scale = f64::from_bits((1023 - u64::from(sh)) << 52);
            self.record(sum as f64 * scale, rounded);
        }
    }

    /// The statistics as a `SignalStats` named and formatted like `template`.
    pub fn into_stats(self, template: &SignalStats) -> SignalStats {
        let mut s = template.clone();
        s.count = self.count;
        if self.count > 0 {
            s.min = Some(self.min.into());
            s.max = Some(self.max.into());
        }
        s.err_sum = self.err_sum;
        s.err_sq_sum = self.err_sq_sum;
        if self.exact {
            let sh = self.sh;
            // Exact conversions (below 2^53) and exact power-of-two scalings.
            s.err_sum = self.k_sum as f64 * f64::from_bits((1023 - u64::from(sh)) << 52);
            s.err_sq_sum = self.k_sq as f64 * f64::from_bits((1023 - 2 * u64::from(sh)) << 52);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::ProductStats;
    use crate::fixed::{QFormat, Quant, RoundShift, SignalStats};
    use proptest::prelude::*;

    proptest! {
        /// The integer error sums give the float recording's bits: roundings by 1 to 15
        /// bits of sums below 2^53 in every mode, mostly near ties and near zero.
        #[test]
        fn integer_error_sums_equal_the_float_recording(
            sh in 1u32..=15,
            q in 0usize..7,
            sums in proptest::collection::vec(
                prop_oneof![
                    -(1i64 << 52)..(1i64 << 52),
                    -4096i64..4096,
                    (-(1i64 << 30)..(1i64 << 30)).prop_map(|v| v << 14),
                ],
                0..400,
            ),
        ) {
            let round = RoundShift::new(sh, Quant::ALL[q]);
            let (mut int, mut float) = (ProductStats::new(sh, true), ProductStats::new(sh, false));
            for &s in &sums {
                let v = round.apply(s);
                int.record_rounding(v, s);
                float.record_rounding(v, s);
            }
            let t = SignalStats::new("p", QFormat::new(true, 40, 0));
            let (a, b) = (int.into_stats(&t), float.into_stats(&t));
            prop_assert_eq!(a.err_sum.to_bits(), b.err_sum.to_bits());
            prop_assert_eq!(a.err_sq_sum.to_bits(), b.err_sq_sum.to_bits());
            prop_assert_eq!(format!("{a:?}"), format!("{b:?}"));
        }
    }
}
