//! `[accumulate]`: the filter and the frame-memory word.

use super::set;
use crate::fixed::{Overflow, QFormat, Quant, Quantizer};
use serde::{Deserialize, Serialize};

/// `accumulate.weight_bits` at most (the lower bound is `2 log2(samples)`).
pub const MAX_WEIGHT_BITS: u32 = 16;
/// `accumulate.gaussian_sigma`, pixels.
pub const GAUSSIAN_SIGMA: std::ops::RangeInclusive<f64> = 0.1..=2.0;

/// Filter used to turn sub-pixel samples into pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FilterKind {
    /// 1-pixel base box (area sampling); equal energy.
    Box,
    /// 2x2-pixel base separable tent ("bed of nails"); equal energy.
    Tent,
    /// Gaussian over a 3x3-pixel base; not equal energy (the counter-example).
    Gaussian,
}

impl FilterKind {
    /// Base of the filter in pixels per axis.
    pub fn base(self) -> u32 {
        match self {
            FilterKind::Box => 1,
            FilterKind::Tent => 2,
            FilterKind::Gaussian => 3,
        }
    }
    /// Whether the filter is a partition of unity (equal energy).
    pub fn equal_energy(self) -> bool {
        !matches!(self, FilterKind::Gaussian)
    }
}

/// Filtering and frame-memory accumulation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AccumulateCfg {
    /// The filter.
    pub filter: FilterKind,
    /// Fraction bits of the filter weights S: the weights of one pixel sum to exactly 2^weight_bits.
    pub weight_bits: u32,
    /// Gaussian sigma in pixels.
    pub gaussian_sigma: f64,
    /// Frame-memory word: rounding of each `I*S` product and overflow of the running sum.
    pub frame: Quantizer,
}

/// `[accumulate]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawAccumulate {
    filter: Option<FilterKind>,
    weight_bits: Option<u32>,
    gaussian_sigma: Option<f64>,
    pub(super) frame: Option<super::PerChannel<QFormat>>,
    quant: Option<Quant>,
    overflow: Option<Overflow>,
}

impl RawAccumulate {
    /// Overrides the given fields.
    pub(super) fn apply(self, c: &mut AccumulateCfg) {
        set(&mut c.filter, self.filter);
        set(&mut c.weight_bits, self.weight_bits);
        set(&mut c.gaussian_sigma, self.gaussian_sigma);
        set(&mut c.frame.format, self.frame.map(|f| f.first()));
        set(&mut c.frame.quant, self.quant);
        set(&mut c.frame.overflow, self.overflow);
    }
}
