//! Per-signal instrumentation: range, overflow count and quantisation error.

use super::QFormat;

/// Statistics of one named signal (one quantisation point).
///
/// `min`/`max` are of the rounded value *before* overflow handling, in LSBs of `format`, so a
/// range report can propose a format that would not have overflowed. Errors are
/// `rounded - exact` in LSBs (quantisation error only; overflow handling is counted in
/// `overflows`, not in the error sums).
#[derive(Clone, Debug, serde::Serialize)]
pub struct SignalStats {
    /// Signal name (`accumulate.frame`).
    pub name: String,
    /// Format of the quantisation point (serialised as its string, e.g. `Q4.12`).
    pub format: QFormat,
    /// Values recorded.
    pub count: u64,
    /// Smallest rounded value seen, in LSBs (before overflow handling).
    pub min: Option<i128>,
    /// Largest rounded value seen, in LSBs (before overflow handling).
    pub max: Option<i128>,
    /// Number of values the overflow mode had to act on.
    pub overflows: u64,
    /// Sum of quantisation errors, in LSBs.
    pub err_sum: f64,
    /// Sum of squared quantisation errors, in LSB².
    pub err_sq_sum: f64,
    /// Whether the signal is an overflow counter only ([`SignalStats::overflow_counter`]):
    /// its datapath counts the values the overflow mode acted on, not each value, so `count`,
    /// `min`, `max` and the error sums stay empty by design.
    pub overflow_only: bool,
}

impl SignalStats {
    /// Empty statistics for a signal.
    pub fn new(name: &str, format: QFormat) -> Self {
        Self {
            name: name.to_string(),
            format,
            count: 0,
            min: None,
            max: None,
            overflows: 0,
            err_sum: 0.0,
            err_sq_sum: 0.0,
            overflow_only: false,
        }
    }

    /// A signal whose datapath counts only its `overflows` (a saturating sum in a hot loop
    /// that records no value, to stay fast): reports show why it has no values.
    pub fn overflow_counter(name: &str, format: QFormat, overflows: u64) -> Self {
        Self {
            overflows,
            overflow_only: true,
            ..Self::new(name, format)
        }
    }

    /// Records one quantisation: the exact value in LSBs of the format, the rounded integer
    /// before overflow handling and whether the overflow mode acted.
    #[inline]
    pub fn record(&mut self, exact_lsb: f64, rounded: i128, overflow: bool) {
        self.record_code(rounded);
        self.overflows += u64::from(overflow);
        let e = rounded as f64 - exact_lsb;
        self.err_sum += e;
        self.err_sq_sum += e * e;
    }

    /// Records a value with no quantisation error (e.g. the result of a saturating add):
    /// counts it and extends the range only.
    #[inline]
    pub fn record_code(&mut self, code: i128) {
        self.count += 1;
        self.min = Some(self.min.map_or(code, |m| m.min(code)));
        self.max = Some(self.max.map_or(code, |m| m.max(code)));
    }

    /// Records a block of `count` error-free values whose range is `[min, max]` (what
    /// `count` calls of [`SignalStats::record_code`] would record); nothing when `count` is 0.
    #[inline]
    pub fn record_range(&mut self, count: u64, min: i128, max: i128) {
        if count == 0 {
            return;
        }
        self.count += count;
        self.min = Some(self.min.map_or(min, |m| m.min(min)));
        self.max = Some(self.max.map_or(max, |m| m.max(max)));
    }

    /// Adds overflows detected elsewhere (e.g. by a saturating accumulator).
    #[inline]
    pub fn add_overflows(&mut self, n: u64) {
        self.overflows += n;
    }

    /// Merges partial statistics (e.g. per thread). Counts, range and overflows do not depend
    /// on the merge order; the float error sums may differ in the last bits with the order
    /// (floating-point addition is not associative), so merge in a fixed order when the sums
    /// must be bit-identical. `self` keeps its name and format.
    pub fn merge(&mut self, other: &SignalStats) {
        self.count += other.count;
        self.min = match (self.min, other.min) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        self.max = match (self.max, other.max) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
        self.overflows += other.overflows;
        self.err_sum += other.err_sum;
        self.err_sq_sum += other.err_sq_sum;
        self.overflow_only &= other.overflow_only;
    }

    /// Root-mean-square quantisation error in LSBs (0 when nothing was recorded).
    pub fn rms_error(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            (self.err_sq_sum / self.count as f64).sqrt()
        }
    }

    /// Mean quantisation error (bias) in LSBs (0 when nothing was recorded).
    pub fn mean_error(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.err_sum / self.count as f64
        }
    }

    /// The narrowest format with the same signedness and `frac_bits` as `self.format` that holds
    /// `[min, max]`; `None` if nothing was recorded.
    ///
    /// Exceptions: an unsigned signal that saw negative values gets a *signed* proposal (no
    /// unsigned format holds them); the proposal may be wider than 32 bits (then it does not
    /// validate, and the report should say the range does not fit a signal format).
    pub fn proposed_format(&self) -> Option<QFormat> {
        let (min, max) = (self.min?, self.max?);
        let frac = i64::from(self.format.frac_bits);
        // Bits of a non-negative value.
        let ubits = |v: i128| i64::from(128 - v.leading_zeros());
        // Two's complement bits needed for v (including the sign bit).
        let sbits = |v: i128| if v >= 0 { ubits(v) + 1 } else { ubits(!v) + 1 };
        if self.format.signed || min < 0 {
            let w = sbits(min).max(sbits(max));
            let int = (w - frac).max(1);
            Some(QFormat::new(true, int as u32, frac as u32))
        } else {
            let w = ubits(max);
            let mut int = (w - frac).max(0);
            if int + frac == 0 {
                int = 1;
            }
            Some(QFormat::new(false, int as u32, frac as u32))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proposals() {
        let mut s = SignalStats::new("x", QFormat::new(true, 4, 4));
        assert_eq!(s.proposed_format(), None);
        s.record_code(-128);
        s.record_code(127);
        assert_eq!(s.proposed_format(), Some(QFormat::new(true, 4, 4)));
        s.record_code(128);
        assert_eq!(s.proposed_format(), Some(QFormat::new(true, 5, 4)));
        let mut u = SignalStats::new("u", QFormat::new(false, 0, 8));
        u.record_code(0);
        assert_eq!(u.proposed_format(), Some(QFormat::new(false, 0, 8)));
        let mut z = SignalStats::new("z", QFormat::new(false, 8, 0));
        z.record_code(0);
        assert_eq!(z.proposed_format(), Some(QFormat::new(false, 1, 0)));
    }
}
