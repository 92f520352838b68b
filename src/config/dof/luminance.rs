//! `[dof.luminance]`: the luminance-aware method (`dof.kind = "luminance"`); see
//! docs/dof-luminance.md.

use super::super::set;
use serde::{Deserialize, Serialize};
use std::ops::RangeInclusive;

/// `dof.luminance.radius`: half-width r of the `(2r+1)^2` mean pre-blur window (0: none).
pub const LUM_RADIUS: RangeInclusive<u32> = 0..=8;
/// `dof.luminance.pre_bits`: width of the pre-blur window sum.
pub const LUM_PRE_BITS: RangeInclusive<u32> = 8..=48;
/// `dof.luminance.guard_bits`: fraction bits below the frame LSB of the pre-blurred image and
/// of the bleed result.
pub const LUM_GUARD_BITS: RangeInclusive<u32> = 0..=16;
/// `dof.luminance.alpha_bits`: fraction bits of the blend factor alpha (`UQ1.<alpha_bits>`).
pub const LUM_ALPHA_BITS: RangeInclusive<u32> = 2..=16;
/// `dof.luminance.alpha_rom_bits`: depth-code bits indexing the alpha ROM.
pub const LUM_ALPHA_ROM_BITS: RangeInclusive<u32> = 2..=16;
/// `dof.luminance.ramp`: width of the in-focus factor's ramp beyond the band, pixels of
/// circle of confusion.
pub const LUM_RAMP: RangeInclusive<f64> = 0.0..=1000.0;
/// `dof.luminance.focus_scale`: the factor of alpha inside the depth of field.
pub const LUM_FOCUS_SCALE: RangeInclusive<f64> = 0.0..=1.0;

/// `[dof.luminance]`: the luminance-aware blur's widths and constants.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LuminanceCfg {
    /// Half-width r of the mean pre-blur window `(2r+1) x (2r+1)` (0: no pre-blur).
    pub radius: u32,
    /// Width of the pre-blur window sum (`UQ<pre_bits>.0` frame codes); a sum that does not
    /// fit is saturated and counted (signal `dof.lum.pre`), or stops the run (ERROR).
    pub pre_bits: u32,
    /// Fraction bits below the frame LSB of the pre-blurred image and of the bleed result.
    pub guard_bits: u32,
    /// Fraction bits of alpha, `UQ1.<alpha_bits>` (alpha = 1 is representable).
    pub alpha_bits: u32,
    /// Depth-code bits indexing the alpha ROM (`2^bits` entries plus one for infinity; at
    /// most the depth code's own bits are used).
    pub alpha_rom_bits: u32,
    /// Factor of alpha inside the depth-of-field band `[U - deep, U + deep]` (the paper's 2/3).
    pub focus_scale: f64,
    /// Width (pixels of circle of confusion) over which the factor ramps linearly from
    /// `focus_scale` at the band's edge to 1 (0: a step at the edge).
    pub ramp: f64,
}

impl Default for LuminanceCfg {
    fn default() -> Self {
        Self {
            radius: 1,
            pre_bits: 16,
            guard_bits: 4,
            alpha_bits: 10,
            alpha_rom_bits: 10,
            focus_scale: 2.0 / 3.0,
            ramp: 2.0,
        }
    }
}

fn int_range(r: &RangeInclusive<u32>) -> String {
    format!("{}..={}", r.start(), r.end())
}

fn real_range(r: &RangeInclusive<f64>) -> String {
    format!("[{:?}, {:?}]", r.start(), r.end())
}

/// The integer fields: name, range, what it is.
const INTEGERS: [(&str, RangeInclusive<u32>, &str); 5] = [
    (
        "radius",
        LUM_RADIUS,
        "the pre-blur window's half-width, pixels",
    ),
    ("pre_bits", LUM_PRE_BITS, "the pre-blur window sum's width"),
    (
        "guard_bits",
        LUM_GUARD_BITS,
        "fraction bits below the frame LSB",
    ),
    ("alpha_bits", LUM_ALPHA_BITS, "alpha's fraction bits"),
    (
        "alpha_rom_bits",
        LUM_ALPHA_ROM_BITS,
        "depth-code bits indexing the alpha ROM",
    ),
];

/// The real fields: name, range, what it is.
const REALS: [(&str, RangeInclusive<f64>, &str); 2] = [
    (
        "focus_scale",
        LUM_FOCUS_SCALE,
        "alpha's factor inside the depth of field",
    ),
    (
        "ramp",
        LUM_RAMP,
        "pixels of circle of confusion beyond the band's edge",
    ),
];

impl LuminanceCfg {
    /// Checks the fields; returns the failing field (without the `dof.luminance.` prefix) and
    /// the allowed range.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let ints = [
            self.radius,
            self.pre_bits,
            self.guard_bits,
            self.alpha_bits,
            self.alpha_rom_bits,
        ];
        for ((field, r, what), v) in INTEGERS.into_iter().zip(ints) {
            if !r.contains(&v) {
                return Err((
                    field.into(),
                    format!("must be in {} ({what}), got {v}", int_range(&r)),
                ));
            }
        }
        for ((field, r, what), v) in REALS.into_iter().zip([self.focus_scale, self.ramp]) {
            if !(v.is_finite() && r.contains(&v)) {
                return Err((
                    field.into(),
                    format!(
                        "must be a finite number in {} ({what}), got {}",
                        real_range(&r),
                        crate::files::num(v)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// What a field (without the `dof.luminance.` prefix) expects: the message hint.
    pub(crate) fn hint(field: &str) -> Option<String> {
        if field.is_empty() {
            let names: Vec<&str> = INTEGERS
                .iter()
                .map(|f| f.0)
                .chain(REALS.iter().map(|f| f.0))
                .collect();
            return Some(format!(
                "a table [dof.luminance] with {} (each optional)",
                names.join(", ")
            ));
        }
        if let Some((_, r, what)) = INTEGERS.iter().find(|f| f.0 == field) {
            return Some(format!("an integer in {} ({what})", int_range(r)));
        }
        let (_, r, what) = REALS.iter().find(|f| f.0 == field)?;
        Some(format!("a finite number in {} ({what})", real_range(r)))
    }
}

/// `[dof.luminance]` as written in the hardware file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLuminance {
    radius: Option<u32>,
    pre_bits: Option<u32>,
    guard_bits: Option<u32>,
    alpha_bits: Option<u32>,
    alpha_rom_bits: Option<u32>,
    focus_scale: Option<f64>,
    ramp: Option<f64>,
}

impl RawLuminance {
    /// Overrides the given fields.
    pub(crate) fn apply(self, c: &mut LuminanceCfg) {
        set(&mut c.radius, self.radius);
        set(&mut c.pre_bits, self.pre_bits);
        set(&mut c.guard_bits, self.guard_bits);
        set(&mut c.alpha_bits, self.alpha_bits);
        set(&mut c.alpha_rom_bits, self.alpha_rom_bits);
        set(&mut c.focus_scale, self.focus_scale);
        set(&mut c.ramp, self.ramp);
    }
}
