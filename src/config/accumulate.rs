//! `[accumulate]`: the filter and the frame-memory word.

use super::set;
use crate::fixed::{Overflow, QFormat, Quant, Quantizer};
use serde::{Deserialize, Serialize};

/// `accumulate.weight_bits` at most (the lower bound is `2 log2(samples)`).
pub const MAX_WEIGHT_BITS: u32 = 16;
/// `accumulate.gaussian_sigma`, pixels.
pub const GAUSSIAN_SIGMA: std::ops::RangeInclusive<f64> = 0.1..=2.0;
/// `accumulate.mitchell.b` and `.c`: the Mitchell-Netravali family's parameters.
pub const MITCHELL_BC: std::ops::RangeInclusive<f64> = 0.0..=1.0;

/// Filter used to turn sub-pixel samples into pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FilterKind {
    /// 1-pixel base box (area sampling); equal energy.
    Box,
    /// 2x2-pixel base separable tent ("bed of nails"); equal energy.
    Tent,
    /// Gaussian over a 3x3-pixel base; not equal energy (the counter-example).
    Gaussian,
    /// Cubic B-spline (Mitchell-Netravali B = 1, C = 0), radius 2: no negative lobe.
    CubicBspline,
    /// Catmull-Rom (B = 0, C = 1/2), radius 2: interpolating, negative lobes.
    CatmullRom,
    /// Mitchell-Netravali with `accumulate.mitchell` (B = C = 1/3 by default), radius 2.
    Mitchell,
}

/// The (B, C) parameters of the Mitchell-Netravali cubic family.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MitchellBc {
    /// B (1 for the B-spline).
    pub b: f64,
    /// C (1/2 for Catmull-Rom).
    pub c: f64,
}

impl MitchellBc {
    /// The recommended compromise, B = C = 1/3.
    pub const THIRD: MitchellBc = MitchellBc {
        b: 1.0 / 3.0,
        c: 1.0 / 3.0,
    };

    /// The filter at distance `x` (pixels) from its centre: the piecewise cubic of radius 2
    /// (docs/reference.md, "Cubic filters").
    pub fn eval(self, x: f64) -> f64 {
        let (b, c) = (self.b, self.c);
        let x = x.abs();
        let v = if x < 1.0 {
            (12.0 - 9.0 * b - 6.0 * c) * x * x * x
                + (-18.0 + 12.0 * b + 6.0 * c) * x * x
                + (6.0 - 2.0 * b)
        } else if x < 2.0 {
            (-b - 6.0 * c) * x * x * x
                + (6.0 * b + 30.0 * c) * x * x
                + (-12.0 * b - 48.0 * c) * x
                + (8.0 * b + 24.0 * c)
        } else {
            0.0
        };
        v / 6.0
    }

    /// Whether the filter goes below zero anywhere on its support (checked on a grid of
    /// 1/256 pixel, finer than any sample grid modelled).
    pub fn negative_lobes(self) -> bool {
        (0..512).any(|i| self.eval(i as f64 / 256.0) < -1e-12)
    }
}

impl FilterKind {
    /// Base of the filter in pixels per axis.
    pub fn base(self) -> u32 {
        match self {
            FilterKind::Box => 1,
            FilterKind::Tent => 2,
            FilterKind::Gaussian => 3,
            FilterKind::CubicBspline | FilterKind::CatmullRom | FilterKind::Mitchell => 4,
        }
    }
    /// Whether the filter is a partition of unity (equal energy): every member of the
    /// cubic family is (`sum_i f(x + i) = 1` for all x), the Gaussian is not.
    pub fn equal_energy(self) -> bool {
        !matches!(self, FilterKind::Gaussian)
    }
    /// The cubic's (B, C), `mitchell` giving them for [`FilterKind::Mitchell`]; `None` for
    /// box, tent and Gaussian.
    pub fn cubic(self, mitchell: MitchellBc) -> Option<MitchellBc> {
        match self {
            FilterKind::CubicBspline => Some(MitchellBc { b: 1.0, c: 0.0 }),
            FilterKind::CatmullRom => Some(MitchellBc { b: 0.0, c: 0.5 }),
            FilterKind::Mitchell => Some(mitchell),
            _ => None,
        }
    }
    /// The name in the hardware file.
    pub const fn name(self) -> &'static str {
        match self {
            FilterKind::Box => "box",
            FilterKind::Tent => "tent",
            FilterKind::Gaussian => "gaussian",
            FilterKind::CubicBspline => "cubic_bspline",
            FilterKind::CatmullRom => "catmull_rom",
            FilterKind::Mitchell => "mitchell",
        }
    }
    /// Every filter.
    pub const ALL: [FilterKind; 6] = [
        FilterKind::Box,
        FilterKind::Tent,
        FilterKind::Gaussian,
        FilterKind::CubicBspline,
        FilterKind::CatmullRom,
        FilterKind::Mitchell,
    ];
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
    /// B and C of `filter = "mitchell"` (`accumulate.mitchell = { b = 0.5, c = 0.25 }`).
    pub mitchell: MitchellBc,
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
    mitchell: Option<MitchellBc>,
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
        set(&mut c.mitchell, self.mitchell);
        set(&mut c.frame.format, self.frame.map(|f| f.first()));
        set(&mut c.frame.quant, self.quant);
        set(&mut c.frame.overflow, self.overflow);
    }
}
