//! Per-pixel accumulation in log code (structure b, docs/reference.md §1, Fig. 7): the term
//! floor, the Gaussian-log sums with their overflow counts, the work counts, and the exact
//! reference sums for the stage-local error.

use super::adder::{LogAdder, ZERO};
use super::code::LogCode;
use crate::fixed::SignalStats;
use crate::stage::LocalError;

/// Work and signals of the log stage.
#[derive(Clone, Debug)]
pub struct LogWork {
    /// Samples encoded to log code.
    pub encoded: u64,
    /// Potentiation LUT lookups (structure a).
    pub potentiations: u64,
    /// `log I + log S` additions (structure b).
    pub term_adds: u64,
    /// Gaussian-log additions (sb lookups) (structure b).
    pub log_adds: u64,
    /// Pixels (structure b).
    pub pixels: u64,
    /// Pixel sums that reached full scale in [`accumulate_pixel`]: a sum equal to `max`
    /// whose previous sum was below it. This counts "hit full white", including sums that
    /// land exactly on it, and not repeated overflows of a sum already at full scale; the
    /// overflow count (sums above full white) is `frame.overflows`.
    pub saturations: u64,
    /// `logdomain.frame` (format [`LogAdder::frame_format`]): every Gaussian-log sum rounded
    /// to the frame LSB before overflow handling (range), and the overflows: sums above full
    /// white, clamped to it.
    pub frame: SignalStats,
    /// `logdomain.term` (format [`LogAdder::frame_format`]): every term `c 2^fa + log_w + off`
    /// before the floor (range; a term below 1 makes the minimum 0 or negative), and as
    /// overflows the terms the floor raised to code 1 (the zero code is reserved for the
    /// empty sum).
    pub term: SignalStats,
}

impl LogWork {
    /// No work yet; the signals in the adder's frame format.
    pub fn new(add: &LogAdder) -> Self {
        Self {
            encoded: 0,
            potentiations: 0,
            term_adds: 0,
            log_adds: 0,
            pixels: 0,
            saturations: 0,
            frame: SignalStats::new("logdomain.frame", add.frame_format()),
            term: SignalStats::new("logdomain.term", add.frame_format()),
        }
    }

    /// Adds another part's work and signals (e.g. one row of pixels).
    pub fn merge(&mut self, o: &LogWork) {
        self.encoded += o.encoded;
        self.potentiations += o.potentiations;
        self.term_adds += o.term_adds;
        self.log_adds += o.log_adds;
        self.pixels += o.pixels;
        self.saturations += o.saturations;
        self.frame.merge(&o.frame);
        self.term.merge(&o.term);
    }
}

/// Adds the term of sample code `c` with weight `w` to the frame code `acc`: the term is
/// floored to code 1 (counted in `work.term`), the sum's overflow above full white is counted
/// in `work.frame` and saturated. Work counts are the caller's.
#[inline]
pub fn add_term(add: &LogAdder, acc: i64, c: u32, w: u32, work: &mut LogWork) -> i64 {
    let t = add.term(c, w);
    work.term.record_code(i128::from(t));
    if t < 1 {
        work.term.add_overflows(1);
    }
    let (rounded, q) = add.add_checked(acc, t.max(1));
    work.frame.record_code(i128::from(rounded));
    if q.overflow {
        work.frame.add_overflows(1);
    }
    q.code
}

/// Accumulates one pixel in log code: `terms` are `(sample code, weight)` pairs in arrival
/// order. Returns the frame code; counts work and records the signals.
pub fn accumulate_pixel(
    add: &LogAdder,
    terms: impl Iterator<Item = (u32, u32)>,
    work: &mut LogWork,
) -> i64 {
    let mut acc = ZERO;
    for (c, w) in terms {
        if w == 0 {
            continue;
        }
        work.term_adds += 1;
        if acc != ZERO {
            work.log_adds += 1;
        }
        let r = add_term(add, acc, c, w, work);
        if r == add.max && acc != add.max {
            work.saturations += 1;
        }
        acc = r;
    }
    acc
}

/// Exact reference of [`accumulate_pixel`]: `sum S K^(c/G)` (relative luminance) with the
/// same quantised codes and weights.
pub fn accumulate_pixel_f64(
    code: LogCode,
    wf: u32,
    terms: impl Iterator<Item = (u32, u32)>,
) -> f64 {
    let g = code.grades() as f64;
    terms
        .map(|(c, w)| w as f64 / (1u64 << wf) as f64 * code.k.powf(c as f64 / g))
        .sum()
}

/// Adds one fixed/exact pair of log frame positions to a stage-local error (frame LSBs).
pub fn local_add(e: &mut LocalError, add: &LogAdder, fixed: i64, exact_value: f64) {
    if exact_value <= 0.0 {
        e.add(fixed as f64, 0.0);
    } else {
        e.add(fixed as f64, add.position(exact_value).min(add.max as f64));
    }
}
