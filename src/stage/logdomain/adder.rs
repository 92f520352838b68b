//! Structure (b) arithmetic (docs/reference.md §1, Fig. 7): the log frame word, the weight
//! ROM `log_w`, the sb table and the Gaussian-log adder `max + sb(|a - b|)`.
//!
//! Fixed-point discipline: both ROMs are built through [`Quantizer`] with named formats
//! (`log_w`: signed `Q<n>.0` in frame LSBs; sb: `UQ<i>.<table_frac_bits>` in frame LSBs) and
//! record their quantisation (`logdomain.log_w`, `logdomain.sb`); the sum is rounded to the
//! frame LSB by [`round_shift_i64`] with `coding.quant`, and its overflow above full white
//! (the frame word's range is `[0, max]`, `max = off + G 2^fa`, not a power of two, so no
//! format's range expresses it) is flagged by [`LogAdder::saturate`] for the caller to count.

use super::code::LogCode;
use crate::config::CodingCfg;
use crate::fixed::{
    Overflow, QFormat, Quant, Quantized, Quantizer, SignalStats, quantize_slice_f64,
    round_shift_i64,
};
use crate::stage::{Cost, MemImage, Memory, Unit};
use std::sync::Arc;

/// Name of the log frame memory (structure b): the accumulate stage's frame memory.
pub const LOG_FRAME_MEMORY: &str = "frame memory";
/// Name of the log-weight ROM.
pub const LOG_WEIGHT_ROM: &str = "log weight ROM";
/// Name of the Gaussian-logarithm table.
pub const SB_TABLE: &str = "sb table";

/// Rounding of the sb-table address (direct lookup) and of the interpolated slope: `RND`
/// (ties up), fixed, as the RTL `log_adder.v` computes them.
pub const ADDRESS_QUANT: Quant = Quant::Rnd;

/// Structure (b): the log frame word, weight ROM and Gaussian-log adder.
#[derive(Clone, Debug)]
pub struct LogAdder {
    /// The sample code.
    pub code: LogCode,
    /// Extra fraction bits of the frame word.
    pub fa: u32,
    /// Code offset: code `a` holds `L = (a - off) / (G 2^fa)`.
    pub off: i64,
    /// Full-scale (full white) code; sums above it overflow (see [`LogAdder::saturate`]).
    pub max: i64,
    /// sb table, in frame LSBs times `2^tf`.
    pub sb: Vec<i64>,
    /// Data fraction bits.
    pub tf: u32,
    /// Address shift `s`: entry `j` is `sb(j 2^s)`.
    pub shift: u32,
    /// Address bits.
    pub addr_bits: u32,
    /// Linear interpolation.
    pub interpolate: bool,
    /// `log_K(w / 2^f)` in frame LSBs for `w` in 0..=2^f (entry 0 unused).
    pub log_w: Vec<i64>,
    /// Weight fraction bits `f`.
    pub wf: u32,
    /// Rounding of the sum `max 2^tf + sb` to the frame LSB (`coding.quant`).
    pub quant: Quant,
    /// Overflow mode of the frame word (`coding.overflow`: `SAT` or `ERROR`; [`LogAdder::add`]
    /// gives the saturated code either way, the caller stops on `ERROR`).
    pub overflow: Overflow,
    /// `logdomain.sb`: the sb table's quantisation (see [`LogAdder::sb_format`]).
    pub sb_stats: SignalStats,
    /// `logdomain.log_w`: the weight ROM's quantisation (entries `1..=2^f`, see
    /// [`LogAdder::log_w_format`]).
    pub log_w_stats: SignalStats,
}

/// The zero code of the log frame word.
pub const ZERO: i64 = 0;

/// Bits of a non-negative value (0 for 0).
fn ubits(v: i128) -> u32 {
    128 - v.leading_zeros()
}

impl LogAdder {
    /// Builds the adder for weights with `wf` fraction bits whose smallest nonzero weight is
    /// `w_min`.
    pub fn new(code: LogCode, cfg: &CodingCfg, wf: u32, w_min: u32) -> Self {
        let fa = cfg.acc_frac_bits;
        let unit = code.grades() as f64 * (1u64 << fa) as f64; // frame LSBs per log_K unit
        let lnk = code.k.ln();
        let lw_min = (w_min.max(1) as f64 / (1u64 << wf) as f64).ln() / lnk * unit;
        let off = (-lw_min).ceil() as i64 + 1;
        let max = off + unit as i64;
        let tf = cfg.table_frac_bits;
        let data_unit = unit * (1u64 << tf) as f64;
        let sbf = |d: f64| (1.0 + (-d / unit * lnk).exp()).ln() / lnk * data_unit;
        // Essential zero: first d (frame LSBs) with sb rounding to 0.
        let mut ez = 1i64;
        while sbf(ez as f64) >= 0.5 {
            ez *= 2;
        }
        let (mut lo, mut hi) = (ez / 2, ez);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if sbf(mid as f64) >= 0.5 {
                lo = mid
            } else {
                hi = mid
            }
        }
        let ez = hi.max(1);
        let a = cfg.table_addr_bits;
        let mut shift = 0;
        while ((1i64 << a) << shift) < ez {
            shift += 1;
        }
        let n = (1usize << a) + usize::from(cfg.interpolate);
        // sb in frame LSBs (dividing by 2^tf is exact); the quantiser rounds to 2^-tf.
        let sb_x: Vec<f64> = (0..n)
            .map(|j| sbf((j as i64 * (1 << shift)) as f64) / (1u64 << tf) as f64)
            .collect();
        let probe = Quantizer::new(QFormat::new(false, 0, tf), Quant::RndInf, Overflow::Sat);
        let top = probe.round_f64(sb_x[0]).unwrap_or(0);
        let sb_q = Quantizer::new(
            Self::sb_format(ubits(top), tf),
            Quant::RndInf,
            Overflow::Sat,
        );
        let mut sb = vec![0i64; n];
        let mut sb_stats = SignalStats::new("logdomain.sb", sb_q.format);
        quantize_slice_f64(&sb_q, &sb_x, &mut sb, &mut sb_stats);
        // log_K(w / 2^f) in frame LSBs, w = 1..=2^f; the most negative is w = 1.
        let lw_x: Vec<f64> = (1..=(1u64 << wf))
            .map(|w| (w as f64 / (1u64 << wf) as f64).ln() / lnk * unit)
            .collect();
        let wide = Quantizer::new(QFormat::new(true, 1, 0), Quant::RndInf, Overflow::Sat);
        let lowest = wide.round_f64(lw_x[0]).unwrap_or(0);
        let lw_q = Quantizer::new(Self::log_w_format(lowest), Quant::RndInf, Overflow::Sat);
        let mut log_w = vec![0i64; lw_x.len() + 1];
        let mut log_w_stats = SignalStats::new("logdomain.log_w", lw_q.format);
        quantize_slice_f64(&lw_q, &lw_x, &mut log_w[1..], &mut log_w_stats);
        Self {
            code,
            fa,
            off,
            max,
            sb,
            tf,
            shift,
            addr_bits: a,
            interpolate: cfg.interpolate,
            log_w,
            wf,
            quant: cfg.quant,
            overflow: cfg.overflow,
            sb_stats,
            log_w_stats,
        }
    }

    /// The sb table's data format in frame LSBs: `UQ<db - tf>.<tf>`, where `db` is the bits of
    /// the largest entry `sb(0)` in data LSBs (= [`LogAdder::table_data_bits`]). When `sb(0)`
    /// is below one frame LSB (`db < tf`) the format is `UQ0.<tf>` (the ROM word is its low
    /// `db` bits); `UQ1.0` when everything rounds to 0. Entries are rounded `RND_INF` (as
    /// `f64::round`; they are non-negative, so `RND` would give the same).
    pub fn sb_format(db: u32, tf: u32) -> QFormat {
        let int = db.saturating_sub(tf);
        QFormat::new(false, if int + tf == 0 { 1 } else { int }, tf)
    }

    /// The weight ROM's format in frame LSBs: `Q<n>.0` with `n` the two's complement bits of
    /// the most negative entry `lowest` (`log_K(2^-f)`, rounded). Entries are rounded
    /// `RND_INF` (ties away from zero, as `f64::round`, for these negative values).
    pub fn log_w_format(lowest: i128) -> QFormat {
        let n = if lowest < 0 { ubits(!lowest) + 1 } else { 1 };
        QFormat::new(true, n, 0)
    }

    /// Frame LSBs per `log_K` unit, `G 2^fa`.
    pub fn unit(&self) -> f64 {
        self.code.grades() as f64 * (1u64 << self.fa) as f64
    }
    /// Bits of the frame word.
    pub fn frame_bits(&self) -> u32 {
        64 - (self.max as u64).leading_zeros()
    }
    /// The frame word's format, `UQ<frame_bits>.0` (its codes run only to `max`).
    pub fn frame_format(&self) -> QFormat {
        QFormat::new(false, self.frame_bits(), 0)
    }
    /// Data width of the sb table.
    pub fn table_data_bits(&self) -> u32 {
        64 - (self.sb[0] as u64).leading_zeros()
    }
    /// sb(d) for `d` in frame LSBs, in frame LSBs times `2^tf`.
    #[inline]
    pub fn sb_lookup(&self, d: i64) -> i64 {
        let n = 1i64 << self.addr_bits;
        if self.interpolate {
            let j = d >> self.shift;
            if j >= n {
                return 0;
            }
            let fr = d & ((1 << self.shift) - 1);
            let (a, b) = (self.sb[j as usize], self.sb[j as usize + 1]);
            a + round_shift_i64((b - a) * fr, self.shift, ADDRESS_QUANT)
        } else {
            let j = round_shift_i64(d, self.shift, ADDRESS_QUANT);
            if j >= n { 0 } else { self.sb[j as usize] }
        }
    }
    /// Gaussian-log sum of two frame codes: `(rounded, result)`, the sum rounded to the frame
    /// LSB before overflow handling and the frame code with its overflow flag. The zero code
    /// is the identity (the other operand passes unchanged and is never flagged).
    #[inline]
    pub fn add_checked(&self, a: i64, b: i64) -> (i64, Quantized) {
        let pass = |v: i64| {
            (
                v,
                Quantized {
                    code: v,
                    overflow: false,
                },
            )
        };
        if a == ZERO {
            return pass(b);
        }
        if b == ZERO {
            return pass(a);
        }
        let (m, d) = if a >= b { (a, a - b) } else { (b, b - a) };
        let r = round_shift_i64((m << self.tf) + self.sb_lookup(d), self.tf, self.quant);
        (r, self.saturate(r))
    }
    /// Overflow handling of a rounded sum: above full white (`max`) it is clamped to `max`
    /// and flagged (with `ERROR` too: the caller stops). Sums are never negative.
    #[inline]
    pub fn saturate(&self, r: i64) -> Quantized {
        Quantized {
            code: r.min(self.max),
            overflow: r > self.max,
        }
    }
    /// Gaussian-log sum of two frame codes (zero code is the identity; saturates at full
    /// white, see [`LogAdder::add_checked`] for the overflow flag).
    #[inline]
    pub fn add(&self, a: i64, b: i64) -> i64 {
        self.add_checked(a, b).1.code
    }
    /// The term `S K^I` in frame code: sample code `c` plus `log_K(w/2^f)` (an adder). Not
    /// floored: [`super::add_term`] floors it to code 1 (the zero code is reserved).
    #[inline]
    pub fn term(&self, c: u32, w: u32) -> i64 {
        if w == 0 {
            return ZERO;
        }
        ((c as i64) << self.fa) + self.log_w[w as usize] + self.off
    }
    /// Exact relative luminance `B / B_min` of a frame code (0 for the zero code).
    pub fn value(&self, a: i64) -> f64 {
        if a == ZERO {
            0.0
        } else {
            self.code.k.powf((a - self.off) as f64 / self.unit())
        }
    }
    /// Exact frame-code position (real) of a relative luminance `v > 0`.
    pub fn position(&self, v: f64) -> f64 {
        v.ln() / self.code.k.ln() * self.unit() + self.off as f64
    }
    /// Cost of the log arithmetic: weight ROM, sb table, adders (and the interpolation
    /// multiplier if enabled); storage is the frame memory of `pixels` words.
    pub fn cost(&self, pixels: u64) -> Cost {
        let fb = self.frame_bits();
        let db = self.table_data_bits();
        let mut adders = vec![
            Unit::adder("log I + log S", 1, fb),
            Unit::adder("|la - lb| and max", 1, fb),
            Unit::adder("max + sb", 1, fb + self.tf),
        ];
        let mut multipliers = vec![];
        if self.interpolate && self.shift > 0 {
            adders.push(Unit::adder("sb interpolation", 2, db));
            multipliers.push(Unit::mul("sb slope x offset", 1, db, self.shift));
        }
        Cost::new(
            vec![
                Memory::ram(LOG_FRAME_MEMORY, pixels, fb),
                Memory::rom(LOG_WEIGHT_ROM, self.log_w.len() as u64, fb),
                Memory::rom(SB_TABLE, self.sb.len() as u64, db),
            ],
            adders,
            multipliers,
        )
    }

    /// The log-weight ROM (two's complement in the frame word's width) and the sb table.
    pub fn images(&self) -> Vec<MemImage> {
        let fb = self.frame_bits();
        let mask = if fb >= 64 { u64::MAX } else { (1u64 << fb) - 1 };
        let lw = Arc::new(self.log_w.clone());
        let sb = Arc::new(self.sb.clone());
        vec![
            MemImage {
                name: LOG_WEIGHT_ROM.into(),
                fields: vec![fb],
                words: lw.len(),
                region_only: false,
                get: Arc::new(move |w, _| (lw[w] as u64) & mask),
            },
            MemImage {
                name: SB_TABLE.into(),
                fields: vec![self.table_data_bits()],
                words: sb.len(),
                region_only: false,
                get: Arc::new(move |w, _| sb[w] as u64),
            },
        ]
    }
}
